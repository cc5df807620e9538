"""Ground contact (issue 37, docs/equations.md (E77)-(E81)): the law against closed forms, its Q against the
literal oracle, the energy balance with the dissipated work, the stiff solver, the scene's errors."""

from __future__ import annotations

import numpy as np
import pytest

from urdf2links import load_urdf, urdf_link_poses
from urdf2links.integration.simulate import simulate
from urdf2links.dynamics.loads import Wrench
from urdf2links.errors import SceneError
from urdf2links.locations import shipped_robots_dir
from urdf2links.scenes.plan import compile_plan
from urdf2links.scenes.scene_read import scene_from_dict

ROBOTS = shipped_robots_dir()
G = 9.81
M_BODY, R_BALL = 3.0, 0.15      # free_body.urdf's mass; the contact sphere's radius at its centre


def ball_scene(*, z, vx=0.0, law="spring_damper", k=2e4, c=0.0, e=1.0, mu=0.0, vs=0.01, t_end=0.1, method="auto"):
    """free_body as a ball: one sphere of radius R_BALL at its centre on the plane z = 0."""
    return scene_from_dict({
        "robot": {"urdf": str(ROBOTS / "free_body.urdf"), "floating_base": True},
        "gravity": {"magnitude": G},
        "contact": [{"law": law, "stiffness": k, "damping": c, "exponent": e, "friction": mu, "slip_speed": vs,
                     "spheres": [{"link": "body", "centre": [0, 0, 0], "radius": R_BALL}]}],
        "initial": {"q": {"body.z": z}, "qd": {"body.x": vx}},
        "run": {"t_end": t_end, "samples": 51, "method": method, "rtol": 1e-11, "atol": 1e-13}}, name="ball")


def test_normal_law_is_a_damped_oscillator():
    """Linear spring-damper, dropped from touching at rest: depth d(t) of m d'' = m g - k d - c d' in closed
    form. The force never clamps (d'' < g after t = 0)."""
    k, zeta = 2e4, 0.3
    w = np.sqrt(k / M_BODY)
    c = 2 * zeta * np.sqrt(k * M_BODY)
    traj = simulate(ball_scene(z=R_BALL, k=k, c=c, t_end=0.3))
    t = traj.t
    wd = w * np.sqrt(1 - zeta ** 2)
    d = M_BODY * G / k * (1 - np.exp(-zeta * w * t) * (np.cos(wd * t) + zeta * w / wd * np.sin(wd * t)))
    z = traj.q[:, 2]
    # measured 2e-12 m (rtol 1e-11); the depth is ~1.5e-3 m
    assert np.max(np.abs((R_BALL - z) - d)) < 1e-9
    assert np.max(d) > 1e-3


def test_friction_decelerates_at_mu_g_and_spins_the_ball():
    """Sliding at the static depth: x' = v0 - mu g t, phi_y' = mu m g r t / I_yy while the ball slips
    (regularisation error ~ (v_s / slip)^2 = 1e-10)."""
    k, mu, v0 = 2e4, 0.5, 1.0
    traj = simulate(ball_scene(z=R_BALL - M_BODY * G / k, vx=v0, k=k, mu=mu, vs=1e-5, t_end=0.1))
    t = traj.t
    # measured 4e-11 m/s; the ball slips until t = 0.17 s
    assert np.max(np.abs(traj.qd[:, 0] - (v0 - mu * G * t))) < 1e-8
    assert np.max(np.abs(traj.qd[:, 4] - mu * M_BODY * G * R_BALL / 0.35 * t)) < 1e-7
    assert np.max(np.abs(traj.q[:, 2] - traj.q[0, 2])) < 1e-9


# --------------------------------------------------------------------------- Q against the literal oracle


@pytest.fixture(scope="module")
def quad():
    return load_urdf(ROBOTS / "quad12.urdf", floating_base=True, inertia="strict")


def quad_scene(contact: bool, law="hunt_crossley"):
    data = {"robot": {"urdf": str(ROBOTS / "quad12.urdf"), "floating_base": True, "inertia": "strict"},
            "gravity": {"magnitude": G}}
    if contact:
        data["contact"] = [{"law": law, "stiffness": 3e5, "damping": 40.0, "exponent": 1.5 if law == "hunt_crossley"
                            else 1.0, "friction": 0.8, "slip_speed": 0.05, "height": 0.02,
                            "links": ["FL_calf", "FR_calf", "RL_calf", "RR_calf"]}]
    return scene_from_dict(data, name="quad")


def _oracle_Q(model, q, qd, law, h=1e-6):
    """Q of the contact from numpy: sphere points from the URDF links' poses, their material velocities by central
    differences,
    the law (E78, E79) written out, and the generalized forces by the literal trace form (E23)."""
    spec = dict(k=3e5, c=40.0, e=1.5 if law == "hunt_crossley" else 1.0, mu=0.8, vs=0.05, height=0.02, r=0.02)
    names = list(model.link_names)
    loads = []
    for leg in ("FL", "FR", "RL", "RR"):
        p = names.index(f"{leg}_calf")
        centre = np.array([0.0, 0.0, -0.18])

        def pose(qq):
            return urdf_link_poses(model, qq)[f"{leg}_calf"]       # the URDF link's frame
        T, Td = pose(q), (pose(q + h * qd) - pose(q - h * qd)) / (2 * h)
        Om = Td[:3, :3] @ T[:3, :3].T                                # omega^ = R' R^T
        x = T[:3, :3] @ centre + T[:3, 3] - np.array([0, 0, spec["r"]])
        # the velocity of the sphere's material point at x (not of the moving lowest point)
        v = Td[:3, :3] @ centre + Td[:3, 3] + np.cross([Om[2, 1], Om[0, 2], Om[1, 0]], [0, 0, -spec["r"]])
        d, rate = spec["height"] - x[2], -v[2]
        if d <= 0:
            continue
        if law == "hunt_crossley":
            fn = max(d ** spec["e"] * (spec["k"] + spec["c"] * rate), 0.0)
        else:
            fn = max(spec["k"] * d ** spec["e"] + spec["c"] * rate, 0.0)
        vt = np.array([v[0], v[1], 0.0])
        F = fn * np.array([0, 0, 1.0]) - spec["mu"] * fn * vt / np.sqrt(vt @ vt + spec["vs"] ** 2)
        T = model.link_poses(q)[p]           # the tree link's frame, which the Wrench's point is in
        loads.append(Wrench(f"{leg}_calf", force=F, point=T[:3, :3].T @ (x - T[:3, 3]), frame="world"))
    assert len(loads) >= 3
    return model.generalized_forces(q, loads, method="literal")


@pytest.mark.parametrize("law", ["hunt_crossley", "spring_damper"])
def test_contact_Q_is_the_literal_trace_form(quad, law):
    """The compiled right-hand side's contact Q = A (q''_contact - q''_free) against the literal oracle at a
    seeded state with three or four feet in the ground, sliding."""
    rng = np.random.default_rng(37)
    with_c, without = compile_plan(quad_scene(True, law), quad), compile_plan(quad_scene(False), quad)
    q = np.zeros(quad.n)
    q[2] = 0.325
    q[3:6] = rng.uniform(-0.05, 0.05, 3)
    q[6:] = np.tile([0.0, 0.6, -1.2], 4) + rng.uniform(-0.05, 0.05, 12)
    qd = rng.uniform(-0.5, 0.5, quad.n)
    y = np.r_[q, qd, 0.0]
    dq = with_c.rhs(0.0, y)[quad.n:2 * quad.n] - without.rhs(0.0, y)[quad.n:2 * quad.n]
    Q = quad.mass_matrix(q) @ dq
    ref = _oracle_Q(quad, q, qd, law)
    # measured 3e-9 relative (the central differences' error); Q is ~100 N
    assert np.max(np.abs(Q - ref)) < 1e-7 * np.max(np.abs(ref))
    assert np.max(np.abs(ref)) > 10.0


# --------------------------------------------------------------------------- energy balance, stiff solvers


def box_drop(method="auto", t_end=0.25):
    corners = [{"link": "body", "centre": [x, y, -0.15], "radius": 0.0} for x in (0.3, -0.3) for y in (0.25, -0.25)]
    return scene_from_dict({
        "robot": {"urdf": str(ROBOTS / "free_body.urdf"), "floating_base": True},
        "gravity": {"magnitude": G},
        "contact": [{"stiffness": 1e6, "damping": 5.0, "exponent": 1.5, "friction": 0.5, "slip_speed": 0.01,
                     "spheres": corners}],
        "initial": {"q": {"body.z": 0.17, "body.phi_x": 0.1}, "qd": {"body.x": 1.0, "body.phi_z": 2.0}},
        "run": {"t_end": t_end, "samples": 51, "method": method, "rtol": 1e-10, "atol": 1e-12}}, name="box_drop")


@pytest.fixture(scope="module")
def drop():
    return simulate(box_drop())


def test_energy_balance_counts_the_dissipated_work(drop):
    """h = E + V + V_c (E81) and W the dissipated work: h - h(0) - W stays at the integration's error while h
    itself falls by the dissipation (E82)."""
    e = drop.energy
    h, W = e["function"], e["work"]
    scale = max(np.abs(e["kinetic"]).max(), np.abs(W).max())
    # measured 2e-9 relative at rtol 1e-10
    assert np.max(np.abs(h - h[0] - W)) < 1e-8 * scale
    assert W[-1] < -0.05 * scale            # the contact dissipated: friction and damping
    assert drop.stats["terms"][-1] == "contact"


def test_radau5_carries_the_contact(drop):
    """Radau5 (the stiff solver auto switches to) gives the same run."""
    r = simulate(box_drop("Radau5"))
    # measured 3e-8 (rtol 1e-10 on a run with 4 contact onsets)
    assert np.max(np.abs(r.q - drop.q)) < 1e-6


# --------------------------------------------------------------------------- the scene's errors


@pytest.mark.parametrize("contact, says", [
    ({"links": ["trunk"]}, "has no collision sphere"),
    ({"links": ["FL_claf"]}, "not a link of robot"),
    ({"stiffness": 1e5}, "names no contact sphere"),
    ({"links": ["FL_calf"], "law": "hertz"}, "'hertz' is not one of"),
    ({"links": ["FL_calf"], "normal": [0, 0, 0]}, "must not be zero"),
    ({"links": ["FL_calf"], "slip_speed": 0.0}, "contact[0].slip_speed"),
])
def test_bad_contact_is_refused_by_name(quad, contact, says):
    data = {"robot": {"urdf": str(ROBOTS / "quad12.urdf"), "floating_base": True}, "contact": [contact]}
    with pytest.raises(SceneError, match=None) as err:
        compile_plan(scene_from_dict(data, where="quad.toml", name="quad.toml"), quad)
    assert says in str(err.value) and "quad.toml" in str(err.value)


# --------------------------------------------------------------------------- the robot's own spheres, --ground

CAPSULE_BODY = """<mujoco model="capsule_body">
  <worldbody>
    <body name="torso" pos="0.1 0.2 0.5" euler="0.3 -0.2 0.5">
      <freejoint/>
      <geom type="capsule" fromto="-0.2 0.05 0 0.3 -0.05 0.1" size="0.03" density="800"/>
      <geom type="sphere" pos="0 0 -0.1" size="0.04" density="800"/>
      <geom type="sphere" pos="0 0 0.2" size="0.05" contype="0" conaffinity="0" density="800"/>
    </body>
  </worldbody>
</mujoco>"""


def test_mjcf_capsule_ends_and_spheres_are_contact_spheres():
    """MJCF: a colliding sphere geom and both ends of a capsule (the visual sphere left out), at the places
    MuJoCo puts them (geom_xpos +- half-length along geom_xmat's z) at qpos0."""
    import mujoco

    from urdf2links.parsers.mjcf import load_mjcf_string
    from urdf2links.scenes.contact import _link_poses

    model = load_mjcf_string(CAPSULE_BODY)
    spheres = model.info["collision_spheres"]
    assert [(b, r) for b, _, r in spheres] == [("torso", 0.03), ("torso", 0.03), ("torso", 0.04)]
    m = mujoco.MjModel.from_xml_string(CAPSULE_BODY)
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    axis = d.geom_xmat[0].reshape(3, 3)[:, 2] * m.geom_size[0, 1]
    want = [d.geom_xpos[0] + axis, d.geom_xpos[0] - axis, d.geom_xpos[1]]
    T = _link_poses(model, model.info["q0"])["torso"]
    got = [T[:3, :3] @ np.asarray(c) + T[:3, 3] for _, c, _ in spheres]
    # measured 1e-16 m
    assert np.max(np.abs(np.array(got) - np.array(want))) < 1e-12


def test_ground_stands_the_robot_on_its_feet_whatever_its_q0(quad):
    """--ground on quad12 (floating), from a q0 with one leg bent up: its four feet all the same (the stance
    resets the joints), the ground at 0 with the lowest foot SETTLE into it, --hold's servos replaced by the
    stance's twelve (none on the trunk); the scene written as TOML reads back the same, its sway included."""
    import tomllib

    from urdf2links.scenes.contact import SETTLE, resolve_contacts
    from urdf2links.scenes.default_scenes import default_scene
    from urdf2links.scenes.scene_toml import scene_toml
    from urdf2links.scenes.stance import with_ground

    q0 = {"FL_thigh": 0.6, "FL_knee": -1.2}
    scene = with_ground(replace_q0(default_scene(ROBOTS / "quad12.urdf", floating=True, q0="zero", hold=2.0), q0), quad)
    assert scene.name.endswith("-ground") and len(scene.actuators) == 12
    assert {a.source for a in scene.actuators} == {"stand"}
    assert all(not a.coordinate.startswith("trunk.") for a in scene.actuators)
    q = scene.initial_state(quad)[0]
    cset = resolve_contacts(scene.contacts, quad, q)
    assert sorted(s.link for s in cset.spheres) == ["FL_calf", "FR_calf", "RL_calf", "RR_calf"]
    assert cset.rows[0][4] == 0.0
    poses = urdf_link_poses(quad, q)
    bottoms = [(poses[s.link][:3, :3] @ s.centre + poses[s.link][:3, 3])[2] - s.radius for s in cset.spheres]
    # the balanced stance puts the four feet at one height (least squares to ~1e-9 m)
    assert min(bottoms) == pytest.approx(-SETTLE, abs=1e-12) and max(bottoms) - min(bottoms) < 1e-6
    back = scene_from_dict(tomllib.loads(scene_toml(scene)), name="back")
    assert _same_specs(back.contacts, scene.contacts)
    assert [a.ctrl.describe() for a in back.actuators] == [a.ctrl.describe() for a in scene.actuators]


def replace_q0(scene, q0):
    import dataclasses

    return dataclasses.replace(scene, q0=q0)


def _same_specs(a, b) -> bool:
    return len(a) == len(b) and all(x.describe() == y.describe() and x.lowest == y.lowest
                                    and [s.link for s in x.spheres] == [s.link for s in y.spheres] for x, y in zip(a, b))


def test_ground_on_a_robot_without_collision_spheres():
    """solo12 has only meshes: --ground puts 2 cm spheres at its links named foot, the four feet."""
    from corpus import ROOT

    from urdf2links.scenes.contact import resolve_contacts
    from urdf2links.scenes.default_scenes import default_scene
    from urdf2links.scenes.stance import with_ground

    scene = with_ground(default_scene(ROOT / "solo_description/robots/solo12.urdf", floating=True, q0="zero"))
    model = scene.model()
    cset = resolve_contacts(scene.contacts, model, scene.initial_state(model)[0])
    assert sorted(s.link for s in cset.spheres) == ["FL_FOOT", "FR_FOOT", "HL_FOOT", "HR_FOOT"]
    assert "no collision spheres" in " ".join(scene.notes) and "FL_FOOT" in " ".join(scene.notes)


def test_ground_refuses_a_fixed_base():
    from urdf2links.scenes.default_scenes import default_scene
    from urdf2links.scenes.stance import with_ground

    with pytest.raises(SceneError, match="fixed base.*--floating"):
        with_ground(default_scene(ROBOTS / "quad12.urdf"))
