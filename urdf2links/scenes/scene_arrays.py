"""A compiled plan (:mod:`urdf2links.scenes.plan`) as two flat arrays for :mod:`urdf2links.scenes.scene_kernels`.

:func:`compile_scene` turns a :class:`~urdf2links.scenes.plan.Plan` into one int64 array ``SI`` and one
float64 array ``SF``; the compiled right-hand side reads them at the offsets stored in the header
of ``SI`` (the ``S_*`` constants), so that an evaluation builds no views. :func:`scene_view` names
the blocks (numpy views, for tests and inspection; not used by the kernels).

Time functions (:mod:`urdf2links.scenes.functions`) are compiled as data: sums of sines
``offset + rate t + sum a sin(w t + phase)`` (constants have no terms) and piecewise polynomials
(tables: the spline's :class:`scipy.interpolate.PPoly` form), held at the end values outside their
interval with zero derivatives, exactly as the Python functions.
"""

from __future__ import annotations

import math
from collections import namedtuple

import numpy as np

from .constraint_arrays import CX_SIZE, KA, S_CON, S_XSIZE, constraint_arrays
from .contact import contact_arrays
from .functions import Constant, Sines, Table

__all__ = ["Scene", "SceneArrays", "compile_scene", "scene_view", "function_data", "scratch_size", "ct_offset", "SHEAD",
           "KA"]

# SI header: sizes, then the offsets of the blocks of SI and SF; the actuators' and the computed
# torque's (issue 26) after the first ones, so that the earlier offsets stay where they were
(S_N, S_NT, S_BASE, S_G, S_COUPLED, S_K, S_M, S_NS, S_ND, S_NF) = range(10)
(S_BASE_FN, S_LOAD_LINK, S_LOAD_KIND, S_LOAD_LOCAL, S_LOAD_FN, S_TORQUE_IDX, S_TORQUE_FN, S_SPRING_IDX,
 S_DAMPER_IDX, S_FN_KIND, S_FN_PTR) = range(10, 21)
(S_LOAD_X, S_LOAD_POINT, S_STIFFNESS, S_REST, S_DAMPING, S_GRAV, S_C, S_D, S_FN_DATA) = range(21, 30)
(S_NA, S_CT) = range(30, 32)                        # actuators; 1 with a computed torque
(S_ACT_IDX, S_ACT_FN, S_ACT_FLAGS, S_CT_FN) = range(32, 36)
S_ACT_PRM = 36                                      # per actuator: gain, b0, b1, b2, gear, cmin, cmax, fmin, fmax
# issue 37: ground contact, a block after every other (urdf2links.scenes.contact_kernels reads it)
(S_NCONTACT, S_CONTACT_LINK, S_CONTACT_DATA) = range(37, 40)
# issue 45: constraints and fixed tendons, compiled (urdf2links.scenes.constraint_kernels reads the block at
# SI[S_CON]; 0 without one); S_XSIZE the scratch's size (scratch_size plus the constraints' part)
# (S_CON, S_XSIZE) = 40, 41: defined in urdf2links.scenes.constraint_arrays (no import circle), imported above
SHEAD = 42
# KA = 9: floats per actuator, defined in urdf2links.scenes.constraint_arrays (tendon actuators use it too)
ACT_CTRL_LIMITED, ACT_FORCE_LIMITED = 1, 2          # act_flags bits

Scene = namedtuple("Scene", ["SI", "SF", "X"])
"""The compiled scene as one record between the right-hand side's kernels: ``SI`` (int64) its header,
counts and indices, ``SF`` (float64) its numbers, ``X`` (float64) its scratch of one thread
(:func:`scratch_size`). Built inside the compiled right-hand side (free there, docs/speed.md); the
C function and the Python-facing entries take the arrays."""

SceneArrays = namedtuple("SceneArrays", [
    "n", "nt", "has_base", "has_g", "coupled",
    "base_fn",                       # (6,) function index of each base parameter
    "load_link", "load_kind", "load_local", "load_fn",   # (k,), (k,) 0 force 1 moment, (k,), (k, 3)
    "torque_idx", "torque_fn",       # (m,), (m,)
    "spring_idx", "damper_idx",
    "fn_kind", "fn_ptr",             # compiled time functions: kind (nf,), start in fn_data (nf + 1,)
    "load_X", "load_point",          # (k, 3, 4) URDF -> tree frame, (k, 3)
    "stiffness", "rest", "damping",
    "g",                             # (3,)
    "C", "d",                        # (nt, n), (nt,) coupling q_tree = C q + d
    "fn_data",
    "na", "act_idx", "act_fn", "act_flags", "act_prm",   # actuators: (na,) x 3, (na, KA)
    "ct", "ct_fn",                   # computed torque: 1 or 0; (n,) reference function of every coordinate
])


def function_data(fn) -> tuple[int, np.ndarray]:
    """``(kind, data)`` of a scalar time function: kind 0 sines ``[offset, rate, K, (a, w, phase)*K]``,
    kind 1 piecewise polynomial ``[m, k, x_0..x_m, c (k + 1, m) row-major]`` (scipy PPoly layout)."""
    if isinstance(fn, Constant):
        return 0, np.array([fn.value, 0.0, 0.0])
    if isinstance(fn, Sines):
        data = [fn.offset, fn.rate, float(len(fn.terms))]
        for a, f, p in fn.terms:
            data += [a, 2.0 * math.pi * f, p]
        return 0, np.array(data)
    if isinstance(fn, Table):
        spl = fn._spline
        from scipy.interpolate import BSpline, PPoly     # here: only tables need it (a slow import)

        pp = PPoly.from_spline(spl) if isinstance(spl, BSpline) else PPoly(spl.c, spl.x)
        x, c = np.asarray(pp.x, float), np.asarray(pp.c, float)
        # keep the intervals inside [t0, t1] (from_spline adds empty ones at the ends)
        t0, t1 = fn.times[0], fn.times[-1]
        keep = [i for i in range(c.shape[1]) if x[i + 1] > x[i] and x[i] >= t0 and x[i + 1] <= t1]
        xs = np.r_[x[keep], x[keep[-1] + 1]]
        cs = c[:, keep]
        return 1, np.r_[float(cs.shape[1]), float(cs.shape[0] - 1), xs, cs.ravel()]
    raise TypeError(f"cannot compile time function {fn!r}")


def scratch_size(n: int, nt: int) -> int:
    """The right-hand side's scratch: q_tree, q'_tree (nt,), the base values (18,), and for coupled
    coordinates the model's A and its factor (n, n), Q and the applied forces (n,); then the computed
    torque's (:func:`ct_offset`): the reference ``(r, r')`` (2n,), ``r''`` (n,), the tree's ``r''`` (nt,),
    the torque (n,) and the other forces at the reference (n,)."""
    return 2 * nt + 18 + 2 * n * n + 2 * n + 5 * n + nt


def ct_offset(n: int, nt: int) -> int:
    """Where the computed torque's part of the scratch starts (:func:`scratch_size`)."""
    return 2 * nt + 18 + 2 * n * n + 2 * n


def _blocks(plan):
    """The int and float blocks of a plan, in header order, and the sizes."""
    model = plan.model
    fns: list = []

    def fid(f):
        fns.append(function_data(f))
        return len(fns) - 1

    has_base = plan.base is not None
    base_fn = [fid(f) for f in plan.base] if has_base else [0] * 6
    link, kind, local, lfn, X, point = [], [], [], [], [], []
    for li, Xl, load in plan.loads:
        link.append(li)
        kind.append(0 if load.kind == "force" else 1)
        local.append(1 if load.frame == "link" else 0)
        lfn.append([fid(c) for c in load.value.components])
        X.append(np.asarray(Xl, float)[:3, :4])
        point.append(np.asarray(load.point, float))
    torque_fn = [fid(f) for f in plan.torque_funcs]
    acts = plan.actuator_set.actuators
    act_fn = [fid(a.ctrl) for a in acts]
    act_flags = [(ACT_CTRL_LIMITED if a.ctrlrange is not None else 0) | (ACT_FORCE_LIMITED if a.forcerange is not None
                                                                         else 0) for a in acts]
    act_prm = [[a.gain, *a.bias, a.gear, *(a.ctrlrange or (0.0, 0.0)), *(a.forcerange or (0.0, 0.0))] for a in acts]
    ct_fn = [fid(f) for f in plan.reference_funcs] if plan.reference_funcs else []
    closure = getattr(plan, "constraints", None)      # issue 45: the fixed tendons' actuators' controls
    tendon_fn = [fid(a.ctrl) for td in (closure.tendons if closure is not None else ()) for a in td.actuators]
    coupled = model.coupling is not None
    C, d = model.coupling if coupled else (np.zeros((0, 0)), np.zeros(0))
    g = np.zeros(3) if plan.gravity_vector is None else np.asarray(plan.gravity_vector, float)
    ptr = np.cumsum([0] + [len(v) for _, v in fns])
    data = np.concatenate([v for _, v in fns]) if fns else np.zeros(0)
    sizes = [model.n, model.tree.n, int(has_base), int(plan.gravity_vector is not None), int(coupled), len(link),
             len(torque_fn), plan.spring_index.size, plan.damper_index.size, len(fns)]
    ints = [base_fn, link, kind, local, np.reshape(lfn, (-1,)), plan.torque_index, torque_fn, plan.spring_index,
            plan.damper_index, [k for k, _ in fns], ptr]
    floats = [np.reshape(X, (-1,)), np.reshape(point, (-1,)), plan.stiffness, plan.rest, plan.damping, g,
              np.ravel(C), np.ravel(d), data]
    more_sizes = [len(acts), int(bool(ct_fn))]
    more_ints = [[a.index for a in acts], act_fn, act_flags, ct_fn]
    more_floats = [np.reshape(act_prm, (-1,))]
    return sizes, ints, floats, more_sizes, more_ints, more_floats, tendon_fn


def compile_scene(plan, *, constraints: bool = True, rows: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """``(SI, SF)`` of a :class:`~urdf2links.scenes.plan.Plan` (see the module doc); ``constraints`` False: the
    free scene, without the constraints' and tendons' block (the oracle's free forces); ``rows`` False: the
    fixed tendons kept, the constraint rows left out (the scene with its constraints removed, for benchmarks)."""
    sizes, ints, floats, more_sizes, more_ints, more_floats, tendon_fn = _blocks(plan)
    ints = [np.asarray(a, dtype=np.int64).ravel() for a in ints + more_ints]
    floats = [np.asarray(a, dtype=float).ravel() for a in floats + more_floats]
    head = np.zeros(SHEAD, np.int64)
    head[:10] = sizes
    head[S_NA:S_CT + 1] = more_sizes
    at_i = SHEAD + np.cumsum([0] + [a.size for a in ints[:-1]])
    at_f = np.cumsum([0] + [a.size for a in floats[:-1]])
    head[S_BASE_FN:S_FN_PTR + 1] = at_i[:11]
    head[S_ACT_IDX:S_CT_FN + 1] = at_i[11:]
    head[S_LOAD_X:S_FN_DATA + 1] = at_f[:9]
    head[S_ACT_PRM] = at_f[9]
    # issue 37: the contact spheres (links, KC floats each) appended after every other block
    c_links, c_data = contact_arrays(plan.contact_set)
    head[S_NCONTACT] = c_links.size
    head[S_CONTACT_LINK] = SHEAD + sum(a.size for a in ints)
    head[S_CONTACT_DATA] = sum(a.size for a in floats)
    SI, SF = np.concatenate([head] + ints + [c_links]), np.concatenate(floats + [c_data])
    head_x = scratch_size(plan.model.n, plan.model.tree.n)
    SI[S_XSIZE] = head_x
    if constraints and getattr(plan, "constraints", None) is not None:     # issue 45: the constraints' block, last
        ci, cf = constraint_arrays(plan, tendon_fn, sf_at=SF.size, x_at=head_x, rows=rows)
        SI[S_CON] = SI.size
        SI[S_XSIZE] = head_x + int(ci[CX_SIZE])
        SI, SF = np.concatenate([SI, ci]), np.concatenate([SF, cf])
    return SI, SF


def scene_view(SI, SF) -> SceneArrays:
    """The blocks of ``(SI, SF)`` as named numpy views (tests and inspection)."""
    n, nt, has_base, has_g, coupled, k, m, ns, nd, nf = (int(x) for x in SI[:10])
    lens_i = [6, k, k, k, 3 * k, m, m, ns, nd, nf, nf + 1]
    vi = [SI[SI[S_BASE_FN + j]:SI[S_BASE_FN + j] + lens_i[j]] for j in range(11)]
    vi[4] = vi[4].reshape(k, 3)
    nc = nt * n if coupled else 0
    lens_f = [12 * k, 3 * k, ns, ns, nd, 3, nc, nt if coupled else 0]
    vf = [SF[SI[S_LOAD_X + j]:SI[S_LOAD_X + j] + lens_f[j]] for j in range(8)] + [SF[SI[S_FN_DATA]:SI[S_ACT_PRM]]]
    vf[0], vf[1] = vf[0].reshape(k, 3, 4), vf[1].reshape(k, 3)
    vf[6] = vf[6].reshape((nt, n) if coupled else (0, 0))
    na, ct = int(SI[S_NA]), int(SI[S_CT])
    va = [SI[SI[S_ACT_IDX + j]:SI[S_ACT_IDX + j] + na] for j in range(3)]
    prm = SF[SI[S_ACT_PRM]:SI[S_ACT_PRM] + KA * na].reshape(na, KA)
    ct_fn = SI[SI[S_CT_FN]:SI[S_CT_FN] + (n if ct else 0)]
    return SceneArrays(n, nt, has_base, has_g, coupled, *vi, *vf, na, *va, prm, ct, ct_fn)
