"""Batched forward dynamics in SIMD lanes: the block width, and the compiled batch entry.

:func:`fd_lanes` computes ``q''`` (E24) of B states in blocks of ``LW`` states: a block's ``q`` and ``q'``
are loaded transposed, ``(LW, n)`` rows to ``(n, LW)`` lanes, the passes of
:mod:`urdf2links.dynamics.lane_kernels` and :mod:`urdf2links.dynamics.lane_factor` run on the block's
scratch ``WL`` (W_SIZE, LW), and ``q''`` goes back to ``(LW, n)`` rows. The blocks are split into chunks,
``prange`` over the chunks (one scratch per chunk), so ``numba.set_num_threads`` works as for the scalar
rows. The tail (B not a multiple of LW) is one more block padded with copies of the last state, whose
results are discarded: every row goes through the same code, whatever its place in the batch.

Scope: the plain case of :func:`~urdf2links.dynamics.model_kernels.fd_plain` (a fixed base, no loads, no
coupled coordinates, no armature), with or without ``tau`` and gravity.
:meth:`~urdf2links.dynamics.model.Model.forward_dynamics` sends every other batch to the scalar rows
(:func:`~urdf2links.dynamics.model_kernels.fd_batch`), and any batch when called with ``lanes=False``.
This module is imported at the first batch only: ``import urdf2links`` and single-state calls neither
import nor compile it.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from numba import get_num_threads, njit, prange

from .lane_factor import lane_ltdl, lane_solve
from .lane_kernels import angles, lane_dynamics, lane_kinematics, small
from .tree_arrays import W_B, W_SIZE

__all__ = ["LaneWidth", "lane_width", "fd_lanes", "chunks"]

#: Blocks per vector register: a block of two registers' worth of doubles measured fastest (docs/speed.md, "Lanes").
REGISTERS_PER_BLOCK = 4


@dataclass(frozen=True)
class LaneWidth:
    """The block width :func:`fd_lanes` uses: ``width`` states per block, from the CPU's ``vector_doubles``
    (doubles per vector register) and the instruction set ``isa`` that gave it; ``reason`` says why."""

    width: int
    vector_doubles: int
    isa: str
    reason: str


@lru_cache(maxsize=1)
def lane_width() -> LaneWidth:
    """The block width for this CPU, from the target features numba compiles for (llvmlite's host
    features, or ``NUMBA_CPU_FEATURES`` when set): 8 doubles per register with AVX-512F, 4 with AVX, 2
    otherwise (SSE2), times :data:`REGISTERS_PER_BLOCK`."""
    import numba
    from llvmlite import binding as ll

    forced = numba.config.CPU_FEATURES
    if forced:
        features = {f[1:] for f in forced.split(",") if f.startswith("+")}
    else:
        features = {k for k, v in ll.get_host_cpu_features().items() if v}
    isa, doubles = next(((k, d) for k, d in (("avx512f", 8), ("avx", 4)) if k in features), ("sse2", 2))
    w = doubles * REGISTERS_PER_BLOCK
    return LaneWidth(w, doubles, isa, f"{isa}: {doubles} doubles per vector register, x {REGISTERS_PER_BLOCK} "
                     f"registers per block = {w} states")


def chunks(B: int, LW: int) -> int:
    """Chunks of the ``ceil(B / LW)`` blocks of a batch: a few per thread, each with its own scratch
    (:func:`urdf2links.dynamics.model_kernels.chunks` for blocks)."""
    return max(1, min(-(-B // LW), 4 * get_num_threads()))


@njit(cache=True)
def _load(Q, b0, B, XL, lanes):
    """Rows ``b0 .. b0 + LW`` of ``Q`` (B, n) transposed into ``XL`` (n, LW); rows past the batch repeat
    its last state (the padded tail)."""
    LW = len(lanes)
    for l in range(LW):
        b = min(b0 + l, B - 1)
        for i in range(Q.shape[1]):
            XL[i * LW + l] = Q[b, i]


@njit(cache=True)
def _block(TI, TF, Q, QD, TAU, has_tau, gx, gy, gz, OUT, status, b0, S, lanes):
    """``q''`` of the rows ``b0 .. b0 + LW`` (those in the batch) into ``OUT``, their pivots into ``status``."""
    LW = len(lanes)
    B, n = Q.shape
    WL, CL, SL, QL, QDL, XL, T, ST = S
    for l in range(LW):
        ST[l] = -1
    _load(Q, b0, B, QL, lanes)
    _load(QD, b0, B, QDL, lanes)
    angles(TI, TF, QL, CL, SL, lanes)
    lane_kinematics(TI, TF, WL, CL, SL, QDL, gx, gy, gz, lanes)
    lane_dynamics(TI, WL, lanes)
    wb = small(TI[W_B])
    for i in range(n):
        for l in range(LW):
            XL[i * LW + l] = WL[(wb + i) * LW + l]
    if has_tau:
        _load(TAU, b0, B, QL, lanes)
        for i in range(n):
            for l in range(LW):
                XL[i * LW + l] = XL[i * LW + l] + QL[i * LW + l]
    lane_ltdl(TI, WL, T, ST, lanes)
    lane_solve(TI, WL, XL, lanes)
    for l in range(min(LW, B - b0)):
        status[b0 + l] = ST[l]
        for i in range(n):
            OUT[b0 + l, i] = XL[i * LW + l]


@njit(cache=True, parallel=True)
def fd_lanes(TI, TF, Q, QD, TAU, has_tau, gx, gy, gz, OUT, status, nc, lanes):
    """``q''`` (E24) of every row of ``Q``, ``QD`` (and ``TAU`` when ``has_tau``) (B, n) into ``OUT`` (B, n),
    ``status[b]`` the failing pivot of row ``b`` or -1; blocks of ``LW`` rows, ``lanes`` a tuple of ``LW``
    booleans (its length is a compile-time constant: one compiled variant per width, :func:`lane_width`), in
    ``nc`` chunks (``prange``, :func:`chunks`)."""
    LW = len(lanes)
    B = Q.shape[0]
    nb = (B + LW - 1) // LW
    for c in prange(nc):
        n = Q.shape[1]
        S = (np.empty(TI[W_SIZE] * LW), np.empty(TI[2] * LW), np.empty(TI[2] * LW), np.empty(n * LW),
             np.empty(n * LW), np.empty(n * LW), np.empty(4 * LW), np.empty(LW, np.int64))
        for k in range(c * nb // nc, (c + 1) * nb // nc):
            _block(TI, TF, Q, QD, TAU, has_tau, gx, gy, gz, OUT, status, k * LW, S, lanes)
