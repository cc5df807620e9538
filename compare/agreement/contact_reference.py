"""A ``[[contact]]`` scene's ground in the comparison (issue 37): the law, and MuJoCo's native contact beside it.

The comparison itself runs the project's law in both engines (:mod:`urdf2links.compare.mujoco_side.contact_inputs`,
E83). :func:`contact_reference` adds the figure users need when they move a policy between engines: the same
scene with MuJoCo's own contacts (:mod:`urdf2links.compare.mujoco_side.native_contact`, E84) and how far it
lands from the compliant law (base height, feet positions and slip, the time to settle). It is a reference,
not an error: the two are different models of the ground.
"""

from __future__ import annotations

import numpy as np

from ..mujoco_side.native_contact import contact_points, native_figures, native_run

__all__ = ["contact_reference"]


def contact_reference(plan, mj, t, q_o, qd_o, T: float, samples: int) -> tuple[dict, dict]:
    """``(summary, series)``: the summary's ``contact`` entry (JSON-ready: the law of every block, the spheres,
    MuJoCo's native parameters and :func:`native_figures`) and the time series of its figure (the root link's
    height and the lowest contact point's height, for the law and for MuJoCo's native contact) at ``t``."""
    rows = plan.contact_set.rows
    specs = list({id(r[3]): r[3] for r in rows}.values())
    run, notes = native_run(mj, plan, t_end=T, samples=samples)
    kinetic = plan.energies(t, q_o, qd_o)[0]
    n = min(len(t), len(run.t))
    figures = native_figures(plan, t[:n], q_o[:n], kinetic[:n], run)
    summary = {
        "law": [s.describe() for s in specs],
        "spheres": [{"link": s.link, "radius": float(s.radius), "source": s.source} for s in plan.contact_set.spheres],
        "notes": list(plan.contact_set.notes),
        "native": {**figures, "parameters": notes, "integrator": run.integrator, "timestep": float(run.timestep),
                   "notes": list(run.notes)},
    }
    heights = np.array([r[4] for r in rows])
    normals = np.array([r[3].normal for r in rows])

    def lowest(q):
        p = contact_points(plan, q)
        return np.max(heights - np.einsum("skj,kj->sk", p, normals), axis=1)     # the deepest sphere's depth
    series = {"t": t[:n], "base_ours": np.array([plan.model.link_poses(q)[0, 2, 3] for q in q_o[:n]]),
              "base_native": np.array([plan.model.link_poses(q)[0, 2, 3] for q in run.q[:n]]),
              "depth_ours": lowest(q_o[:n]), "depth_native": lowest(run.q[:n])}
    return summary, series
