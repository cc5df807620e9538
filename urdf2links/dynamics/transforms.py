"""Elementary homogeneous transformations, docs/equations.md (E1)-(E3), and base motion {A} (E13).

A link's transform relative to its parent is ``T~ = T1(x) T2(y) T3(z) T4(phi_x) T5(phi_y) T6(phi_z)``:
three translations along the parent's axes, then ``R = Rx(phi_x) Ry(phi_y) Rz(phi_z)``.
The six parameters are always listed in this order; ``PARAMETERS[k]`` names slot ``k``.

Every elementary matrix is a one-parameter group ``E_k(v) = exp(v * D_k)`` (E2), so
``dE_k/dv = E_k D_k = D_k E_k`` and ``d2E_k/dv2 = E_k D_k D_k``, with ``D_k = GENERATORS[k]``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = [
    "PARAMETERS",
    "GENERATORS",
    "elementary",
    "elementary_derivative",
    "elementary_second_derivative",
    "link_transform",
    "BaseState",
    "base_transforms",
    "resolve_base",
    "base_state_at",
]

PARAMETERS = ("x", "y", "z", "phi_x", "phi_y", "phi_z")

GENERATORS = np.zeros((6, 4, 4))
"""D_k (6, 4, 4): derivative of E_k at 0. Slots 0-2 translate, 3-5 rotate."""
for _k in range(3):
    GENERATORS[_k, _k, 3] = 1.0
GENERATORS[3, 2, 1], GENERATORS[3, 1, 2] = 1.0, -1.0  # about x
GENERATORS[4, 0, 2], GENERATORS[4, 2, 0] = 1.0, -1.0  # about y
GENERATORS[5, 1, 0], GENERATORS[5, 0, 1] = 1.0, -1.0  # about z
GENERATORS.setflags(write=False)

_ROT_PLANE = {3: (1, 2), 4: (2, 0), 5: (0, 1)}


def elementary(k: int, v: float) -> np.ndarray:
    """``T_{k+1}(v)`` of (E1), (4, 4): translation along axis k (k < 3) or rotation about axis k-3."""
    E = np.eye(4)
    if k < 3:
        E[k, 3] = v
    else:
        a, b = _ROT_PLANE[k]
        c, s = np.cos(v), np.sin(v)
        E[a, a] = c
        E[b, b] = c
        E[b, a] = s
        E[a, b] = -s
    return E


def elementary_derivative(k: int, v: float) -> np.ndarray:
    """``dT_{k+1}/dv`` (4, 4) = E_k(v) D_k."""
    return elementary(k, v) @ GENERATORS[k]


def elementary_second_derivative(k: int, v: float) -> np.ndarray:
    """``d2T_{k+1}/dv2`` (4, 4) = E_k(v) D_k D_k (zero for translations)."""
    return elementary(k, v) @ GENERATORS[k] @ GENERATORS[k]


def link_transform(params) -> np.ndarray:
    """``T~ = T1 T2 T3 T4 T5 T6`` (E3) from the six parameters ``(x, y, z, phi_x, phi_y, phi_z)``."""
    T = np.eye(4)
    for k in range(6):
        T = T @ elementary(k, params[k])
    return T


@dataclass(frozen=True)
class BaseState:
    """State of the moving base {A} at one instant: its six parameters (x, y, z, phi_x, phi_y,
    phi_z) of (E13) as ``pose`` (6,), their first and second time derivatives ``rate`` (6,) and
    ``accel`` (6,)."""

    pose: np.ndarray
    rate: np.ndarray
    accel: np.ndarray

    @staticmethod
    def fixed(pose=None) -> "BaseState":
        z = np.zeros(6)
        return BaseState(z.copy() if pose is None else np.asarray(pose, float), z.copy(), z.copy())


def base_transforms(state: BaseState) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(0_A T, its first, its second time derivative)``, each (4, 4), by the product rule (E13).

    With ``E_k' = E_k D_k v'`` and ``E_k'' = E_k (D_k v'' + D_k D_k v'^2)``.
    """
    P, Pd, Pdd = np.eye(4), np.zeros((4, 4)), np.zeros((4, 4))
    for k in range(6):
        v, vd, vdd = state.pose[k], state.rate[k], state.accel[k]
        E = elementary(k, v)
        D = GENERATORS[k]
        Ed = E @ D * vd
        Edd = E @ (D * vdd + D @ D * vd * vd)
        Pdd = Pdd @ E + 2.0 * Pd @ Ed + P @ Edd
        Pd = Pd @ E + P @ Ed
        P = P @ E
    return P, Pd, Pdd


BaseLike = "BaseState | Callable[[float], BaseState] | None"


def resolve_base(base, t: float):
    """``(B, B', B'')`` for ``base`` at time ``t``, or None for a fixed base.

    ``base`` is None (fixed base: ``B = I`` (E4), no base terms computed), a :class:`BaseState`,
    or a callable ``t -> BaseState`` (a prescribed motion ``0_A T(t)``).
    """
    state = base_state_at(base, t)
    return None if state is None else base_transforms(state)


def base_state_at(base, t: float) -> "BaseState | None":
    """The :class:`BaseState` of ``base`` (None, a BaseState or a callable ``t -> BaseState``) at
    time ``t``, or None for a fixed base; anything else raises TypeError naming what it got."""
    if base is None:
        return None
    state = base(t) if callable(base) else base
    if not isinstance(state, BaseState):
        raise TypeError(
            f"base must be None, a BaseState or a callable t -> BaseState; got {type(state).__name__}"
        )
    return state
