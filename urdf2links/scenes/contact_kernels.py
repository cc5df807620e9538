"""The compliant contact law compiled (issue 37): docs/equations.md (E77)-(E81).

After :func:`urdf2links.dynamics.kernels.kinematics` every link's record holds its pose ``(R, o)`` and its
world twist ``(omega, v)``; a contact sphere (centre ``c`` in its tree link's frame, radius ``r``) against
the plane ``n . x = h`` then has (E77)

- depth ``d = h + r - n . (R c + o)`` (in contact when ``d > 0``), contact point ``p = R c + o - r n``,
- the point's velocity ``v_p = v + omega x p`` and the depth's rate ``d' = -n . v_p``;

the normal force (E78) ``f_n = max(0, d^e (k + c d'))`` (Hunt-Crossley) or ``max(0, k d^e + c d')``
(spring-damper); regularised Coulomb friction (E79) ``F_t = -mu f_n v_t / sqrt(|v_t|^2 + v_s^2)`` with
``v_t = v_p - (n . v_p) n``; the force ``F = f_n n + F_t`` acts at ``p`` and enters Q through
:func:`~urdf2links.dynamics.kernels.add_wrench` (E80 = E36: the loads' path, no second kinematics pass).
The elastic part ``k d^e`` is the gradient of the potential ``V_c = k d^(e+1) / (e + 1)`` (E81), counted in
the energies; the rest (damping, friction, the clamp) is dissipated work, counted in ``W``.

The block is read at the header slots ``S_NCONTACT``, ``S_CONTACT_LINK``, ``S_CONTACT_DATA`` of the scene's
``(SI, SF)`` (:func:`urdf2links.scenes.contact.contact_arrays`, ``KC`` floats per sphere).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..compilation import kernel
from ..dynamics.kernels import add_wrench
from ..dynamics.tree_arrays import KL, O_, W_LINK, WV, nonneg
from .scene_arrays import S_CONTACT_DATA, S_CONTACT_LINK, S_NCONTACT

__all__ = ["contact_wrenches", "contact_potential", "contact_state", "sphere_contact", "normal_force",
           "NSTATE"]

KC = 14         # floats per sphere (urdf2links.scenes.contact.KC)
NSTATE = 10     # contact_state's columns: point (3), depth, depth rate, f_n, slip speed, F (3)


@njit(cache=True, inline="always")
def sphere_contact(TI, W, p, SF, o):
    """Sphere at ``SF[o:o + KC]`` on tree link ``p`` (E77): ``(d, d', p (3), v_p (3), r_link (3))``, the
    contact point ``r_link`` in the link's frame (for add_wrench)."""
    d = nonneg(TI[W_LINK]) + KL * nonneg(p)
    R00, R01, R02, R10, R11, R12, R20, R21, R22 = W[d], W[d + 1], W[d + 2], W[d + 3], W[d + 4], W[d + 5], \
        W[d + 6], W[d + 7], W[d + 8]
    c0, c1, c2, r = SF[o], SF[o + 1], SF[o + 2], SF[o + 3]
    n0, n1, n2, h = SF[o + 4], SF[o + 5], SF[o + 6], SF[o + 7]
    x0 = R00 * c0 + R01 * c1 + R02 * c2 + W[d + O_] - r * n0
    x1 = R10 * c0 + R11 * c1 + R12 * c2 + W[d + O_ + 1] - r * n1
    x2 = R20 * c0 + R21 * c1 + R22 * c2 + W[d + O_ + 2] - r * n2
    depth = h - (n0 * x0 + n1 * x1 + n2 * x2)
    w0, w1, w2 = W[d + WV], W[d + WV + 1], W[d + WV + 2]
    v0 = W[d + WV + 3] + w1 * x2 - w2 * x1
    v1 = W[d + WV + 4] + w2 * x0 - w0 * x2
    v2 = W[d + WV + 5] + w0 * x1 - w1 * x0
    rate = -(n0 * v0 + n1 * v1 + n2 * v2)
    l0 = c0 - r * (R00 * n0 + R10 * n1 + R20 * n2)         # c - r R^T n
    l1 = c1 - r * (R01 * n0 + R11 * n1 + R21 * n2)
    l2 = c2 - r * (R02 * n0 + R12 * n1 + R22 * n2)
    return depth, rate, x0, x1, x2, v0, v1, v2, l0, l1, l2


@njit(cache=True, inline="always")
def normal_force(law, k, c, e, depth, rate):
    """(E78) ``(f_n, k d^e)``: the normal force and its elastic part (0, 0 out of contact)."""
    if depth <= 0.0:
        return 0.0, 0.0
    de = depth ** e
    el = k * de
    f = de * (k + c * rate) if law == 0.0 else el + c * rate
    return max(f, 0.0), el


@njit(cache=True, inline="always")
def _force(SF, o, depth, rate, v0, v1, v2):
    """``(F (3), f_n, elastic part, slip speed)`` of one sphere (E78, E79), in {0}."""
    n0, n1, n2 = SF[o + 4], SF[o + 5], SF[o + 6]
    fn, el = normal_force(SF[o + 13], SF[o + 8], SF[o + 9], SF[o + 10], depth, rate)
    vn = n0 * v0 + n1 * v1 + n2 * v2
    t0, t1, t2 = v0 - vn * n0, v1 - vn * n1, v2 - vn * n2
    slip = np.sqrt(t0 * t0 + t1 * t1 + t2 * t2)
    if fn == 0.0:
        return 0.0, 0.0, 0.0, 0.0, el, slip
    vs = SF[o + 12]
    s = -SF[o + 11] * fn / np.sqrt(slip * slip + vs * vs)
    return fn * n0 + s * t0, fn * n1 + s * t1, fn * n2 + s * t2, fn, el, slip


@kernel
def contact_wrenches(SI, SF, tree):
    """Every sphere's force (E80) added to its link's external wrench (after :func:`kinematics`, before
    :func:`dynamics` with loads); returns ``sum k d^e d'`` = ``dV_c/dt`` (E81), which the right-hand side
    adds to the power so that ``W`` counts only the dissipated work."""
    TI, W = tree.TI, tree.W
    links, o = SI[S_CONTACT_LINK], SI[S_CONTACT_DATA]
    Pel = 0.0
    for j in range(SI[S_NCONTACT]):
        p = SI[links + j]
        oj = o + KC * j
        depth, rate, x0, x1, x2, v0, v1, v2, l0, l1, l2 = sphere_contact(TI, W, p, SF, oj)
        if depth <= 0.0:
            continue
        F0, F1, F2, fn, el, slip = _force(SF, oj, depth, rate, v0, v1, v2)
        Pel += el * rate
        if fn != 0.0:
            add_wrench(tree, p, F0, F1, F2, 0.0, 0.0, 0.0, l0, l1, l2, False)
    return Pel


@kernel
def contact_potential(SI, SF, tree):
    """``sum k d^(e+1) / (e + 1)`` over the spheres in contact (E81), after :func:`kinematics`."""
    TI, W = tree.TI, tree.W
    links, o = SI[S_CONTACT_LINK], SI[S_CONTACT_DATA]
    V = 0.0
    for j in range(SI[S_NCONTACT]):
        oj = o + KC * j
        depth = sphere_contact(TI, W, SI[links + j], SF, oj)[0]
        if depth > 0.0:
            e = SF[oj + 10]
            V += SF[oj + 8] * depth ** (e + 1.0) / (e + 1.0)
    return V


@kernel
def contact_state(SI, SF, tree, out):
    """``out[j] = (p (3), d, d', f_n, slip speed, F (3))`` (k, NSTATE) of every sphere, after :func:`kinematics`."""
    TI, W = tree.TI, tree.W
    links, o = SI[S_CONTACT_LINK], SI[S_CONTACT_DATA]
    for j in range(SI[S_NCONTACT]):
        oj = o + KC * j
        depth, rate, x0, x1, x2, v0, v1, v2, l0, l1, l2 = sphere_contact(TI, W, SI[links + j], SF, oj)
        F0, F1, F2, fn, el, slip = _force(SF, oj, depth, rate, v0, v1, v2)
        out[j, 0], out[j, 1], out[j, 2], out[j, 3], out[j, 4] = x0, x1, x2, depth, rate
        out[j, 5], out[j, 6], out[j, 7], out[j, 8], out[j, 9] = fn, slip, F0, F1, F2
