"""``method = "auto"``: DOP853 while the scene is not stiff, Radau5 while it is, switching both ways.

The run starts explicit (DOP853, compiled, with Hairer's stiffness test after every step), and
alternates stretches: a stretch runs one loop until its status says stop; status 4 (DOP853's step
held by stability, :func:`~urdf2links.integration.loops.stiffness.explicit_stiff`) hands over to
Radau5 at the same state, status 5 (DOP853 would cost less,
:func:`~urdf2links.integration.loops.stiffness.explicit_cheaper`) hands back. Once Radau5 has been
measured costlier than DOP853 and handed back, a later stiff verdict is followed only if DOP853's own
cost (evaluations per second of simulated time over its stretch) exceeds Radau5's measured one by
the same factor 2 (``1 / SWITCH_BACK``); otherwise DOP853 goes on and the next verdict needs 4x more
tests (on TIAGo dual, n = 101, mildly stiff, auto went back and forth four times in 0.5 s without
this). Python runs once per stretch, never per step. Each stretch is recorded (:func:`drive_auto`): method, interval, steps,
evaluations, Jacobians, rejected attempts, why it started and why it ended, in words and figures.
"""

from __future__ import annotations

import numpy as np

from ..dense import DenseOutput
from .erk import TABLEAUX
from .stretches import run_erk, run_radau
from .stiffness import (BACKOFF, E_HLAMB, E_HSUM, E_IASTI, E_RATIO, RATIO_HLAMBDA, STIFF_HLAMBDA, STIFF_RATIO,
                        STIFF_TESTS, SWITCH_BACK)

__all__ = ["drive_auto", "ENDS"]

#: What a stretch's final status means, for its record.
ENDS = {1: "t_end", 2: "angle guard", 4: "stiff", 5: "non-stiff", 0: "budget", -1: "step size too small",
        -2: "right-hand side failed", -4: "singular iteration matrix"}


def _stiff_reason(out, tests: int, record: dict) -> tuple[str, dict]:
    st, ts = out.st, out.t
    h = float(ts[-1] - ts[-2]) if ts.size > 1 else float(st[1])
    hl, ratio = float(st[E_HLAMB]), float(st[E_RATIO])
    mean = float(st[E_HSUM] / max(st[E_IASTI], 1.0))
    per_step = record["nfev"] / max(record["steps"], 1)        # evaluations per accepted step, rejections included
    figures = {"h_lambda": hl, "mean_h_lambda": mean, "stiffness_ratio": ratio, "lambda": hl / h if h > 0 else
               float("inf"), "h": h, "tests": tests, "evals_per_step": per_step}
    text = (f"stiff at t={float(ts[-1]):.6g}: DOP853's step was held by a stiff mode at {tests} tests (h|lambda| > "
            f"{STIFF_HLAMBDA:g}, or > {RATIO_HLAMBDA:g} with a stiffness ratio > {STIFF_RATIO:g}; last h|lambda| = {hl:.3g}, "
            f"ratio {ratio:.3g}: |lambda| ~ {figures['lambda']:.3g} /s at h = {h:.3g} s)")
    return text, figures


def _nonstiff_reason(out) -> tuple[str, dict]:
    from .radau import R_HDOP, R_HOLD, R_RATE_D, R_RATE_I, R_RHO, R_RHO0, R_T    # Radau5 ran: imported

    st = out.st
    rho, dop, imp = float(st[R_RHO]), float(st[R_RATE_D]), float(st[R_RATE_I])
    figures = {"rho": rho, "rho0": float(st[R_RHO0]), "dop853_evals_per_s": dop, "radau5_evals_per_s": imp,
               "h": float(st[R_HOLD]), "dop853_h": float(st[R_HDOP]) * (float(st[R_RHO0]) / rho if rho > 0 else 1.0)}
    text = (f"non-stiff at t={float(st[R_T]):.6g}: spectral radius of the Jacobian {rho:.3g} /s (at the switch "
            f"{figures['rho0']:.3g} /s): DOP853 would cost ~{dop:.3g} evaluations per second of motion against "
            f"Radau5's {imp:.3g} (at h = {float(st[R_HOLD]):.3g} s)")
    return text, figures


def drive_auto(drv, loops, args, f0, t0, t1, y0, rtol, atol, dt, need_dense, structure):
    """Alternate DOP853 and Radau5 stretches from ``(t0, y0)`` (module doc) with one driver ``drv``
    (counters, budgets, guard and callback shared by all stretches). Returns ``(status, t, y, sol,
    njev, stretches)``: the last stretch's status, the steps of all stretches (each junction once),
    their dense outputs joined, and one dict per stretch (``method``, ``t0``, ``t1``, ``steps``,
    ``nfev``, ``njev``, ``rejected``, ``started``, ``start_figures``, ``ended``, ``end_figures``, and
    ``declined``: the stiff verdicts a DOP853 stretch did not follow, with the rates compared)."""
    nq, nv = structure
    tab = TABLEAUX["DOP853"]
    t, y, f, h = t0, y0, f0, None
    method, started, start_fig = "DOP853", "start: auto begins explicit (DOP853) and tests for stiffness", {}
    backoffs, radau_rate = 0, None
    pieces, stretches, njev = [], [], 0
    record = None
    while True:
        before = drv.cnt.copy()
        if method == "DOP853":
            tests = int(STIFF_TESTS * BACKOFF ** backoffs)
            out = run_erk(drv, loops, tab, args, f, t, t1, y, rtol, atol, dt, need_dense, h0=h, stiff_tests=tests,
                          nd=nq + nv)
        else:
            out = run_radau(drv, loops, args, f, t, t1, y, rtol, atol, dt, need_dense, structure, h0=h,
                            detect=(start_fig["h"], start_fig["evals_per_step"]))
        njev += out.njev
        pieces.append(out)
        part = {"t1": float(out.t[-1]), "steps": int(drv.cnt[1] - before[1]), "nfev": int(drv.cnt[0] - before[0]),
                "njev": int(out.njev), "rejected": int(drv.cnt[2] - before[2]),
                "ended": ENDS.get(int(out.status), str(out.status)), "end_figures": {}}
        if record is not None and record.get("continues"):      # a declined verdict: the same stretch goes on
            del record["continues"]
            for k in ("steps", "nfev", "njev", "rejected"):
                record[k] += part[k]
            record.update(t1=part["t1"], ended=part["ended"], end_figures={})
        else:
            record = {"method": method, "t0": float(t), **part, "started": started, "start_figures": start_fig}
            stretches.append(record)
        t, y, f = float(out.t[-1]), out.y[-1].copy(), out.f.copy()
        if out.status == 4:
            reason, figures = _stiff_reason(out, tests, record)
            h = float(out.t[-1] - out.t[-2]) if out.t.size > 1 else None
            dop_rate = record["nfev"] / max(record["t1"] - record["t0"], 1e-300)
            if radau_rate is not None and dop_rate < radau_rate / SWITCH_BACK:
                # Radau5 was measured costlier than this: stay explicit, and ask for more verdicts next time
                record.setdefault("declined", []).append(
                    {"t": t, "dop853_evals_per_s": dop_rate, "radau5_evals_per_s": radau_rate, **figures})
                record["continues"] = True
                backoffs += 1
                continue
            started, start_fig = reason, figures
            record["end_figures"] = figures
            method = "Radau5"
            continue
        if out.status == 5:
            started, start_fig = _nonstiff_reason(out)
            record["end_figures"] = start_fig
            radau_rate = start_fig["radau5_evals_per_s"]
            from .radau import R_HNEW, R_HOLD

            h = min(max(float(out.st[R_HOLD]), float(out.st[R_HNEW])), start_fig["dop853_h"])
            method, backoffs = "DOP853", backoffs + 1
            continue
        break
    ts = np.concatenate([pieces[0].t] + [p.t[1:] for p in pieces[1:]])
    ys = np.concatenate([pieces[0].y] + [p.y[1:] for p in pieces[1:]])
    sol = None
    if need_dense:
        parts = [p.sol for p in pieces if p.sol is not None]
        sol = parts[0] if len(parts) == 1 else DenseOutput(ts, ys, pieces=parts) if parts else None
    return out.status, ts, ys, sol, njev, tuple(stretches)
