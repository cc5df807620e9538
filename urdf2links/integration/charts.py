"""Re-charting the ZYX angles of floating links, so that a simulation passes through ``phi_y = +-pi/2``.

The problem
-----------
A link whose three angle slots are coordinates (a free or floating body, six coordinates, or a
ball made of three angles) has the rotation ``R = Rx(phi_x) Ry(phi_y) Rz(phi_z)`` relative to its
parent (docs/equations.md (E3)). Its angular velocity in its own axes is (E43)
``omega = E(phi) phi'`` with

    E(phi) = [Rz^T Ry^T e_x,  Rz^T e_y,  e_z]      (3, 3),   E^T E = [[1, 0, s_y], [0, 1, 0], [s_y, 0, 1]],

(``s_y = sin phi_y``), so ``det E = cos phi_y`` and the chart is singular at ``phi_y = +-pi/2``:
there the axes of ``phi_x`` and ``phi_z`` coincide. The block of ``A`` (E44) that belongs to the
three angles is ``E^T J E`` for a single body (``J`` its inertia tensor about the origin, in its own
axes), of condition up to ``cond(J) (1 + |s_y|) / (1 - |s_y|) <= 4 cond(J) / cos^2 phi_y``: ``A``
loses rank, ``phi_x'`` and ``phi_z'`` grow like ``|omega| / |cos phi_y|`` and ``q''`` like their
square; the motion itself is regular.

Detection
---------
An :class:`~urdf2links.integration.integrators.AngleGuard` on the ``phi_y`` coordinates ends an integration
segment at the first accepted step with ``|cos phi_y| < cos_min`` (:data:`CHART_COS_MIN` = 0.3).
At 0.3 the angle block's condition is at most ``42.4 cond(J)`` (``(1 + s) / (1 - s)`` with
``s = sin(arccos 0.3) = 0.954``; the looser bound ``4 / cos^2 phi_y`` gives 44.4; less than two
digits lost) and the angle rates at most ``3.3 |omega|``: the integrator has not yet had to shrink
its steps, while a fresh chart (``|cos| = 1``) is a rotation of at least
``arccos 0.3 = 1.27 rad`` away from the next guard, so the switches never chatter. The condition
number of the angle block before and after each switch is reported (:func:`angle_block_condition`).
The guard is tested at accepted steps: a single step that moves ``phi_y`` by more than
``2 (pi/2 - arccos cos_min) = 0.61 rad`` could step over the band unnoticed (not at the tolerances
the scenes use, where a step turns the body by a few hundredths of a radian).

The new chart (design)
----------------------
A link has six slots and a free link uses them all, so the constant rotation cannot go into the
link itself. :func:`recharted_model` splits each re-charted link ``p`` into two links of the tree:

* ``p~chart`` (massless, parent = ``p``'s parent): ``p``'s translational slots (coordinates or
  constants, offsets kept) and the constant rotation ``R_c`` as three constant angles
  (``matrix_to_xyz_angles``, exact at every pitch): ``T~ = T1(x) T2(y) T3(z) Rx Ry Rz(c)``;
* ``p`` (parent ``p~chart``, its ``H`` and children unchanged): the three angle coordinates, no
  translation: ``T~ = Rx(psi_x) Ry(psi_y) Rz(psi_z)``.

The pose of ``p`` is ``T^(s) Trans(x, y, z) R_c R(psi)`` (E4, E45): the same frame as before, so its
children, ``H``, loads and recorded poses need no change, and the coordinates keep their names and
their order (``x, y, z`` then the angles: the numbering (E5) is link by link, slot by slot).
The translational coordinates keep their values and rates (they are along the parent's axes in
both charts). At a switch ``R_c <- R_c R(psi)`` and ``psi <- 0``; since ``E(0) = 1`` the new angle
rates are the angular velocity ``psi' <- omega = E(psi) psi'`` (:func:`rechart`). ``T`` and ``T'``
of every link are then unchanged, and with them the energy (E17) and the momenta; the
work ``W`` carries over.

Original coordinates
--------------------
The user's trajectory is reported in the coordinates of the model as loaded: the angles are found
from the relative rotation ``R_c R(psi)`` (:func:`~urdf2links.dynamics.rotations.matrix_to_xyz_angles`),
on the branch (``(a, b, c)`` or ``(a + pi, pi - b, c + pi)``, plus multiples of ``2 pi``) nearest
the previous value, tracked along the dense output with bisection so that no step of the tracked
angles exceeds :data:`_TRACK_STEP`; their rates are ``E(phi)^{-1} omega``. Near the passage itself
the original chart is singular: the original ``phi_x``, ``phi_z`` and their rates are as large as
``1 / cos phi_y`` makes them (undefined at exactly ``+-pi/2``), while the link poses stay regular,
so a re-charted run records the poses of the re-charted links (``Trajectory.poses``).

Forces that act on a chart's angles as coordinates (``[[torque]]`` or ``[[spring]]`` on an angle
coordinate) would change meaning with the chart: such links are not re-charted
(:func:`integrate_charted` ``exclude``); like every link without re-charting, they stop the run with a
:class:`~urdf2links.errors.DynamicsError` at ``|cos phi_y| <`` :data:`SINGULAR_COS_MIN`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .. import compilation
from ..dynamics.model import Model
from ..dynamics.rotations import matrix_to_xyz_angles, xyz_angles_to_matrix
from ..dynamics.transforms import PARAMETERS
from ..dynamics.tree import LinkSpec, build_tree
from .integrators import AngleGuard, integrate
from .loops import wall_message

__all__ = ["CHART_COS_MIN", "SINGULAR_COS_MIN", "FloatingLink", "Chart", "floating_links",
           "recharted_model", "rate_matrix", "rechart", "angle_block_condition", "ChartedRun",
           "integrate_charted", "link_poses"]

#: ``|cos phi_y|`` below which a floating link is re-charted (module doc: why 0.3).
CHART_COS_MIN = 0.3
#: Without re-charting, ``|cos phi_y|`` below which the run stops with a DynamicsError: the angle
#: block's condition is then ~``4e6 cond(J)``, about half the digits of ``q''`` lost.
SINGULAR_COS_MIN = 1e-3
#: Largest change (rad) of a tracked original angle between two tracking points.
_TRACK_STEP = 0.5
_SUFFIX = "~chart"


@dataclass(frozen=True, eq=False)
class FloatingLink:
    """A tree link whose three angle slots are coordinates: ``link`` its index, ``name``,
    ``angles`` (3,) the model coordinate indices of ``phi_x, phi_y, phi_z``, ``offsets`` (3,) the
    angle slots' constant offsets in the loaded model (``params[link, 3:6]``)."""

    link: int
    name: str
    angles: np.ndarray
    offsets: np.ndarray


def floating_links(model: Model) -> tuple[FloatingLink, ...]:
    """The links of ``model`` whose three angle slots are coordinates that are model coordinates of
    their own (not coupled to others): the links that can be re-charted."""
    tree, names = model.tree, model.coordinate_names
    C, d = model.coupling or (None, None)
    out = []
    for p in range(tree.n_links):
        tc = tree.coord[p, 3:6]
        if np.any(tc < 0):
            continue
        idx = []
        for j in tc:
            nm = tree.coordinate_names[j]
            if nm not in names:
                break
            i = names.index(nm)
            if C is not None and not (C[j, i] == 1 and d[j] == 0 and np.count_nonzero(C[:, i]) == 1
                                      and np.count_nonzero(C[j]) == 1):
                break
            idx.append(i)
        if len(idx) == 3:
            out.append(FloatingLink(p, tree.link_names[p], np.array(idx), tree.params[p, 3:6].copy()))
    return tuple(out)


def rate_matrix(phi) -> np.ndarray:
    """``E(phi)`` (3, 3) of the module doc: angular velocity in the link's axes ``omega = E phi'``
    for ``R = Rx Ry Rz(phi)``; ``det E = cos phi_y``; ``E(0) = 1``."""
    _, b, c = phi
    cb, sb, cc, sc = math.cos(b), math.sin(b), math.cos(c), math.sin(c)
    return np.array([[cb * cc, sc, 0.0], [-cb * sc, cc, 0.0], [sb, 0.0, 1.0]])


def recharted_model(original: Model, rotations: dict) -> Model:
    """``original`` with each link named in ``rotations`` (name -> ``R_c`` (3, 3)) split into a
    massless ``<name>~chart`` link (translational slots, constant rotation ``R_c``) and the link
    itself (the three angle coordinates, offsets 0, its ``H``); see the module doc. The new model
    shares name, gravity, coupling, audit and info with ``original``; same coordinates, same order."""
    tree = original.tree
    specs = []
    for p, name in enumerate(tree.link_names):
        parent = None if tree.parent[p] < 0 else tree.link_names[tree.parent[p]]
        coords = {PARAMETERS[k]: tree.coordinate_names[tree.coord[p, k]] for k in range(6) if tree.coord[p, k] >= 0}
        arm = {PARAMETERS[k]: float(tree.armature[tree.coord[p, k]]) for k in range(6)
               if tree.coord[p, k] >= 0 and tree.armature[tree.coord[p, k]] != 0.0}
        H = tree.H[p]
        if name not in rotations:
            specs.append(LinkSpec(name, parent, tuple(tree.params[p]), coords, H, arm))
            continue
        c = matrix_to_xyz_angles(rotations[name])
        # the angles' armature acts on the angular velocity relative to the parent (E49), which p~chart
        # (constant rotation, translations only) does not change
        specs.append(LinkSpec(name + _SUFFIX, parent, (*tree.params[p, :3], *c),
                              {s: v for s, v in coords.items() if s in PARAMETERS[:3]}, None,
                              {s: v for s, v in arm.items() if s in PARAMETERS[:3]}))
        specs.append(LinkSpec(name, name + _SUFFIX, (0.0,) * 6,
                              {s: v for s, v in coords.items() if s in PARAMETERS[3:]}, H,
                              {s: v for s, v in arm.items() if s in PARAMETERS[3:]}))
    new = build_tree(specs)
    if new.coordinate_names != tree.coordinate_names:  # the original numbering was not link by link
        raise ValueError(f"re-charting {sorted(rotations)} would reorder the coordinates of {original.name!r}")
    coupling = None if original.coupling is None else (*original.coupling, original.coordinate_names)
    return Model(new, gravity=original.gravity_vector, coupling=coupling, name=original.name,
                 source=original.source, audit=original.audit, info=original.info)


@dataclass(frozen=True, eq=False)
class Chart:
    """One chart: ``model`` (the model integrated in it) and ``rotations`` (link name -> ``R_c``
    (3, 3)) folded in; ``rotations`` empty is the model as loaded."""

    model: Model
    rotations: dict = field(default_factory=dict)

    def relative_rotation(self, link: FloatingLink, q) -> np.ndarray:
        """(3, 3) rotation of ``link`` relative to its parent at chart coordinates ``q`` (n,)."""
        phi = q[link.angles]
        if link.name in self.rotations:
            return self.rotations[link.name] @ xyz_angles_to_matrix(phi)
        return xyz_angles_to_matrix(phi + link.offsets)

    def angular_velocity(self, link: FloatingLink, q, qd) -> np.ndarray:
        """(3,) ``omega`` of ``link`` relative to its parent, in its own axes."""
        off = 0.0 if link.name in self.rotations else link.offsets
        return rate_matrix(q[link.angles] + off) @ qd[link.angles]


def rechart(original: Model, chart: Chart, links, q, qd) -> tuple[Chart, np.ndarray, np.ndarray]:
    """Fold the attitude of each of ``links`` into a new chart: ``R_c <- R_c R(psi)``, ``psi <- 0``,
    ``psi' <- omega`` (module doc). Returns the new chart and the state ``(q, qd)`` (n,) in it."""
    rotations = dict(chart.rotations)
    q, qd = np.array(q, float), np.array(qd, float)
    for link in links:
        omega = chart.angular_velocity(link, q, qd)
        rotations[link.name] = chart.relative_rotation(link, q)
        q[link.angles] = 0.0
        qd[link.angles] = omega
    return Chart(recharted_model(original, rotations), rotations), q, qd


def to_original(chart: Chart, links, q, qd, reference) -> tuple[np.ndarray, np.ndarray]:
    """State ``(q, qd)`` of ``chart`` in the coordinates of the loaded model, the angles on the branch
    nearest ``reference`` (n,), their rates ``E(phi)^{-1} omega`` (inf where singular)."""
    q_o, qd_o = np.array(q, float), np.array(qd, float)
    if not chart.rotations:
        return q_o, qd_o
    for link in links:
        if link.name not in chart.rotations:
            continue
        a, b, c = matrix_to_xyz_angles(chart.relative_rotation(link, q))
        ref = reference[link.angles] + link.offsets
        best = None
        for cand in (np.array([a, b, c]), np.array([a + math.pi, math.pi - b, c + math.pi])):
            cand = cand + 2 * math.pi * np.round((ref - cand) / (2 * math.pi))
            if best is None or np.sum((cand - ref) ** 2) < np.sum((best - ref) ** 2):
                best = cand
        q_o[link.angles] = best - link.offsets
        try:
            qd_o[link.angles] = np.linalg.solve(rate_matrix(best), chart.angular_velocity(link, q, qd))
        except np.linalg.LinAlgError:
            qd_o[link.angles] = math.inf
    return q_o, qd_o


def angle_block_condition(model: Model, link: FloatingLink, q, *, t: float = 0.0, base=None) -> float:
    """2-norm condition number of the 3 x 3 block of ``A`` (E44) of ``link``'s angles at ``q``."""
    A = model.mass_matrix(q, t=t, base=base)
    return float(np.linalg.cond(A[np.ix_(link.angles, link.angles)]))


def link_poses(model: Model, names, q, *, t: float = 0.0, base=None) -> dict:
    """{0}-poses (4, 4) of links by name: URDF links through ``model.info['frame_of']`` when the model
    was imported, else tree links."""
    T = model.link_poses(q, t=t, base=base)
    frame_of = model.info.get("frame_of") or {}
    out = {}
    for nm in names:
        tname, X = frame_of.get(nm, (nm, None))
        P = T[model.link_names.index(tname)]
        out[nm] = P if X is None else P @ np.asarray(X)
    return out


@dataclass(frozen=True, eq=False)
class Segment:
    """One integration in one chart over ``[t0, t1]``: its ``chart``, ``plan`` and the integrator's
    ``result`` (samples in the chart's coordinates, ``sol`` its dense output)."""

    chart: Chart
    plan: object
    t0: float
    t1: float
    result: object


class ChartedSolution:
    """Dense output over all segments in the ORIGINAL coordinates: ``t -> (q, qd, W)`` ((dim,) or
    (k, dim)); angles tracked from the nearest earlier known value of their segment."""

    def __init__(self, segments, links, anchors):
        self.segments, self.links = segments, links
        self.anchors = anchors    # per segment: (times (a,), original states (a, dim)), sorted
        self.starts = np.array([s.t0 for s in segments])
        self.t_min, self.t_max = segments[0].t0, segments[-1].t1

    def __call__(self, t):
        tt = np.atleast_1d(np.asarray(t, float))
        out = np.empty((tt.size, self.segments[0].result.sol(self.t_min).size))
        for m, ti in enumerate(tt):
            k = int(np.clip(np.searchsorted(self.starts, ti, side="right") - 1, 0, len(self.segments) - 1))
            ta, ya = self.anchors[k]
            j = max(int(np.searchsorted(ta, ti, side="right")) - 1, 0)
            out[m] = _track(self.segments[k], self.links, ta[j], ya[j], ti)
        return out[0] if np.ndim(t) == 0 else out


def _convert(seg: Segment, links, y, reference) -> np.ndarray:
    n = seg.chart.model.n
    q, qd = to_original(seg.chart, links, y[:n], y[n:2 * n], reference[:n])
    return np.r_[q, qd, y[2 * n:]]


def _track(seg: Segment, links, ta: float, ya: np.ndarray, tb: float, depth: int = 0) -> np.ndarray:
    """Original state at ``tb`` from the known original state ``ya`` at ``ta`` (same segment),
    bisecting until the tracked angles change by at most ``_TRACK_STEP`` per step."""
    yb = _convert(seg, links, seg.result.sol(tb), ya)
    if not seg.chart.rotations or tb == ta:
        return yb
    n = seg.chart.model.n
    jump = max((np.max(np.abs(yb[ln.angles] - ya[ln.angles])) for ln in links), default=0.0)
    if jump <= _TRACK_STEP or depth >= 40 or not n:
        return yb
    tm = 0.5 * (ta + tb)
    ym = _track(seg, links, ta, ya, tm, depth + 1)
    return _track(seg, links, tm, ym, tb, depth + 1)


@dataclass(frozen=True, eq=False)
class ChartedRun:
    """Outcome of :func:`integrate_charted`. ``t`` (m,) samples; ``y`` (m, dim) the state at each
    sample in the ORIGINAL coordinates; ``y_chart`` (m, dim) the same in the chart that computed it;
    ``segment_of`` (m,) that chart's segment; ``segments``; ``recharts`` one dict per switch (time,
    link, ``phi_y`` and ``|cos phi_y|`` where the guard fired, condition of the angle block before
    and after); ``sol`` the dense output (original coordinates); counts summed; ``wall_time`` the
    segments' integrations (:attr:`IntegrationResult.wall_time`) and the chart switches, not the
    sampling; ``njev`` Jacobians; ``stretches`` (``auto``) every segment's stretches in order, each
    with its ``segment``."""

    t: np.ndarray
    y: np.ndarray
    y_chart: np.ndarray
    segment_of: np.ndarray
    segments: list
    recharts: list
    sol: object
    nfev: int
    nsteps: int
    wall_time: float
    success: bool
    message: str
    njev: int = 0
    stretches: tuple = ()


def integrate_charted(original: Model, make_plan, y0, t_span, *, t_eval, method, rtol, atol, dt=None,
                      callback=None, recharting: bool = True, cos_min: float = CHART_COS_MIN,
                      exclude=(), base_state=lambda t: None, max_steps: int | None = None,
                      max_wall: float | None = None) -> ChartedRun:
    """Integrate ``y = (q, qd, W)`` (2n + 1,) of ``original`` over ``t_span`` in segments: each runs
    ``make_plan(model).rhs`` until an :class:`AngleGuard` on the floating links' ``phi_y`` fires, then
    the links whose guard fired are re-charted (:func:`rechart`) and the next segment starts from the
    same ``t``. Links not re-charted (``recharting=False``, or a coordinate of theirs in ``exclude``)
    raise :class:`~urdf2links.errors.DynamicsError` at ``|cos phi_y| < SINGULAR_COS_MIN``. ``base_state(t)``: the base for the reported condition
    numbers. ``max_steps`` and ``max_wall`` bound the whole run (all segments). Other arguments as
    :func:`~urdf2links.integration.integrators.integrate`."""
    run_start, busy = compilation.clock(), 0.0
    t0, t1 = float(t_span[0]), float(t_span[1])
    t_eval = np.asarray(t_eval, float)
    links = floating_links(original)
    movable = [ln for ln in links if recharting and not set(original.coordinate_names[i] for i in ln.angles) & set(exclude)]
    fixed = [ln for ln in links if ln not in movable]
    n = original.n
    chart = Chart(original)
    y = np.array(y0, float)
    guards = [AngleGuard([ln.angles[1] for ln in group], c) for group, c in ((movable, cos_min),
                                                                             (fixed, SINGULAR_COS_MIN)) if group]
    guard = None if not guards else guards[0] if len(guards) == 1 else guards[0] | guards[1]
    segments, recharts, pieces, stretches = [], [], [], []
    nfev = nsteps = njev = 0
    success, message = True, "reached t_end"
    t = t0
    while True:
        # the budgets bound the whole run: a run that re-charts at every step (rates of ~1e6 rad/s) has
        # segments of one step each, every one inside its own integrate() budget
        if segments and max_wall is not None and compilation.clock() - run_start > max_wall:
            success, message = False, wall_message(max_wall, float(t), nsteps)
            break
        if segments and max_steps is not None and nsteps >= max_steps:
            success, message = False, f"max_steps={max_steps} reached at t={float(t)!r}"
            break
        if movable and _due(movable, y, cos_min):  # at the start of a segment: switch at once
            start = compilation.clock()
            chart, y = _switch(original, chart, movable, t, y, cos_min, recharts, base_state)
            busy += compilation.clock() - start
            continue
        plan = make_plan(chart.model)
        te = t_eval[(t_eval >= t) if not segments else (t_eval > t)]
        budget = {"max_steps": None if max_steps is None else max(1, max_steps - nsteps),
                  "max_wall": None if max_wall is None else max(1e-3, max_wall - (compilation.clock() - run_start))}
        res = integrate(plan.rhs, (t, t1), y, method=method, rtol=rtol, atol=atol, dt=dt, t_eval=te,
                        dense=True, callback=callback, stop=guard, **budget)
        nfev, nsteps, njev, busy = nfev + res.nfev, nsteps + res.nsteps, njev + res.njev, busy + res.wall_time
        stretches += [{"segment": len(segments), **x} for x in res.stretches]
        seg = Segment(chart, plan, t, float(res.sol.t_max), res)
        segments.append(seg)
        pieces.append((np.asarray(res.t), np.asarray(res.y)))
        if not res.success:
            success, message = False, res.message
            if max_wall is not None and res.message.startswith("max_wall="):   # the whole run's budget, not the segment's
                message = wall_message(max_wall, float(res.sol.t_max), nsteps)
            break
        if not res.stopped or seg.t1 >= t1:
            break
        t, y = seg.t1, np.array(res.sol(seg.t1))
        stuck = _due(fixed, y, SINGULAR_COS_MIN)
        if stuck:
            raise _singular(original, chart, stuck[0], t, y, recharting=recharting, base_state=base_state)
        start = compilation.clock()
        chart, y = _switch(original, chart, movable, t, y, cos_min, recharts, base_state)
        busy += compilation.clock() - start
    ts, ys, yc, seg_of, anchors = _samples_in_original(original, segments, pieces, links, y0, t_eval.size,
                                                       run_start=run_start, max_wall=max_wall)
    sol = segments[0].result.sol if len(segments) == 1 else ChartedSolution(segments, links, anchors)
    dim = y.size
    return ChartedRun(t=np.array(ts), y=np.array(ys).reshape(-1, dim), y_chart=np.array(yc).reshape(-1, dim),
                      segment_of=np.array(seg_of, dtype=int), segments=segments, recharts=recharts, sol=sol,
                      nfev=nfev, nsteps=nsteps, wall_time=busy, success=success,
                      message=message, njev=njev, stretches=tuple(stretches))


def _singular(original: Model, chart, ln, t, y, *, recharting: bool, base_state):
    """The DynamicsError of a link that reaches ``phi_y = +-pi/2`` and may not be re-charted."""
    from ..errors import DynamicsError

    n = original.n
    why = ("re-charting is off" if not recharting else
           "it is not re-charted because [[torque]], [[spring]], [[actuator]] or [[computed_torque]] acts on its angles")
    return DynamicsError(
        f"ZYX angles of link {ln.name!r} of model {original.name!r} reach the singularity of their chart at "
        f"t={t:.6g}: phi_y = {y[ln.angles[1]]:.6f}, |cos phi_y| = {abs(math.cos(y[ln.angles[1]])):.2e} < "
        f"{SINGULAR_COS_MIN:g}, condition of the angle block of A "
        f"{angle_block_condition(chart.model, ln, y[:n], t=t, base=base_state(t)):.2e}; {why}, and past this "
        f"point q'' would lose most of its digits (recharting passes through: urdf2links.integration.charts)",
        q=y[:n], coordinates=tuple(original.coordinate_names[i] for i in ln.angles))


def _samples_in_original(original: Model, segments, pieces, links, y0, n_eval: int, *, run_start: float,
                         max_wall: float | None):
    """The samples of every segment in the original coordinates, the angles tracked segment by segment:
    lists of times, states, states in their own chart, segment indices, and each segment's anchors
    for the dense output. The wall-clock budget bounds this too."""
    from ..errors import IntegrationError

    anchors, ts, ys, yc, seg_of = [], [], [], [], []
    y_prev = np.array(y0, float)
    for k, (seg, (tk, yk)) in enumerate(zip(segments, pieces)):
        at, ay = [seg.t0], [_convert(seg, links, seg.result.sol(seg.t0), y_prev)]
        for i, (ti, yi) in enumerate(zip(tk, yk)):
            if i % 1000 == 999 and max_wall is not None and compilation.clock() - run_start > max_wall:
                raise IntegrationError(f"model {original.name!r}: max_wall={max_wall:g} s spent while converting the "
                                       f"samples back to the loaded chart's angles ({len(ts)} of {n_eval} done; "
                                       f"{len(segments)} charts): fewer samples would do")
            # the loaded chart's states are the original ones (no per-sample dense evaluation: 1e6 samples took
            # ~10 minutes through _track)
            ay.append(np.array(yi, float) if not seg.chart.rotations else _track(seg, links, at[-1], ay[-1], ti))
            at.append(ti)
            ts.append(ti), ys.append(ay[-1]), yc.append(yi), seg_of.append(k)
        end = _track(seg, links, at[-1], ay[-1], seg.t1)
        anchors.append((np.array(at), np.array(ay)))
        y_prev = end
    return ts, ys, yc, seg_of, anchors


def _due(links, y, threshold):
    return [ln for ln in links if abs(math.cos(y[ln.angles[1]])) < threshold]


def _switch(original, chart, links, t, y, threshold, recharts, base_state):
    n = original.n
    due = _due(links, y, threshold)
    before = {ln.name: angle_block_condition(chart.model, ln, y[:n], t=t, base=base_state(t)) for ln in due}
    new, q, qd = rechart(original, chart, due, y[:n], y[n:2 * n])
    for ln in due:
        recharts.append({"t": float(t), "link": ln.name, "phi_y": float(y[ln.angles[1]]),
                         "cos_phi_y": abs(math.cos(y[ln.angles[1]])), "cond_before": before[ln.name],
                         "cond_after": angle_block_condition(new.model, ln, q, t=t, base=base_state(t))})
    return new, np.r_[q, qd, y[2 * n:]]
