"""Where one engine becomes faster than the other in a work-precision study, beyond the timing spread.

:func:`crossover` reads the rows of :func:`urdf2links.compare.tradeoff.study.run_study` (each run's error,
median wall time and the min and max of its timing rounds) and states below which error urdf2links
is faster than MuJoCo: at error levels on a grid of :data:`GRID_PER_DECADE` per decade, the fastest
run of each engine reaching the level; an engine wins a level only when its slowest round beats the
other's fastest (the spreads do not overlap), otherwise the level is a tie.
"""

from __future__ import annotations

import math

__all__ = ["crossover", "GRID_PER_DECADE"]

#: Error levels per decade at which the crossover compares the engines.
GRID_PER_DECADE = 4


def _front(rows, engine, level) -> tuple[float, dict | None]:
    best, who = math.inf, None
    for r in rows:
        if r["engine"] == engine and r["status"] == "ok" and r["wall_time_s"] is not None and r["error_max"] <= level:
            if r["wall_time_s"] < best:
                best, who = r["wall_time_s"], r
    return best, who


def _spread(r) -> tuple[float, float]:
    """(min, max) of a row's timing rounds (the median when the row has no spread recorded)."""
    lo, hi = r.get("wall_time_min_s"), r.get("wall_time_max_s")
    return (r["wall_time_s"] if lo is None else lo, r["wall_time_s"] if hi is None else hi)


def _winner(rp, rm) -> str:
    """"urdf2links" or "MuJoCo" when that engine's slowest round beats the other's fastest, else "tie"."""
    (p_lo, p_hi), (m_lo, m_hi) = _spread(rp), _spread(rm)
    if p_hi < m_lo:
        return "urdf2links"
    if m_hi < p_lo:
        return "MuJoCo"
    return "tie"


def _at(x) -> str:
    """One level in words: both engines' runs, median times with their spread, and who wins."""
    def t(med, lo, hi):
        return f"{med:.3g} s" + (f" ({lo:.3g}-{hi:.3g})" if hi > lo else "")

    r = x["mujoco_s"] / x["project_s"]
    verdict = {"urdf2links": f"urdf2links {r:.3g}x faster", "MuJoCo": f"MuJoCo {1 / r:.3g}x faster",
               "tie": f"a tie: the spreads overlap, ratio of medians {r:.3g}"}[x["winner"]]
    return (f"at {x['error']:.1e} urdf2links ({x['project_run']}) takes {t(x['project_s'], *x['project_spread'])} and "
            f"MuJoCo ({x['mujoco_run']}) {t(x['mujoco_s'], *x['mujoco_spread'])} ({verdict})")


def _levels(ok, lo, hi, per_decade) -> list[dict]:
    """Every grid level between ``lo`` and ``hi``: the fastest run of each engine reaching it and the winner."""
    out = []
    j0, j1 = math.ceil(per_decade * math.log10(lo) - 1e-9), math.floor(per_decade * math.log10(hi) + 1e-9)
    for j in range(j0, max(j1, j0) + 1):
        e = 10.0 ** (j / per_decade)
        tp, rp = _front(ok, "urdf2links", e)
        tm, rm = _front(ok, "MuJoCo", e)
        if rp is None or rm is None:
            continue
        w = _winner(rp, rm)
        out.append({"error": e, "project_s": tp, "mujoco_s": tm, "project_spread": list(_spread(rp)),
                    "mujoco_spread": list(_spread(rm)), "winner": w, "project_faster": w == "urdf2links",
                    "project_run": f"{rp['method']} {rp['param']} {rp['value']:g}",
                    "mujoco_run": f"{rm['method']} dt {rm['value']:g}"})
    return out


def _above(above: list[dict]) -> str:
    """The looser levels above the crossover, in words."""
    if not above:
        return ""
    n = {w: sum(x["winner"] == w for x in above) for w in ("MuJoCo", "tie", "urdf2links")}
    if n["MuJoCo"] == len(above):
        return "; MuJoCo is faster above it"
    parts = [f"MuJoCo is faster at {n['MuJoCo']}" if n["MuJoCo"] else "",
             f"the engines tie (within the timing spread) at {n['tie']}" if n["tie"] else "",
             f"urdf2links is faster again at {n['urdf2links']}" if n["urdf2links"] else ""]
    return "; above it " + ", ".join(p for p in parts if p) + f" of the {len(above)} looser levels"


def crossover(rows: list[dict], floor: float = 0.0, *, per_decade: int = GRID_PER_DECADE) -> dict:
    """Where the project becomes faster than MuJoCo, beyond the timing spread. At error levels ``e``
    on a grid of ``per_decade`` levels per decade (``10**(j / per_decade)``) between the tightest
    error both engines reach and the loosest any run has (errors below ``floor``, the reference's
    error estimate, count as ``floor``), the fastest run of each engine with an error (max over
    the run) <= e, by median wall time; the level's ``winner`` is the engine whose slowest timing
    round beats the other's fastest, else ``"tie"``. The crossover ``e*`` is the top of the
    tightest contiguous stretch of levels the project wins: "urdf2links is faster below e*" when
    the stretch starts at the tightest level, "between a and e*" otherwise. Returns ``statement``
    (a sentence with both times and their spread), ``error_level`` (e* or None), ``region`` [a,
    e*], ``levels`` (every grid level's fastest runs, times, spreads and winner), ``ties`` (the
    number of tied levels), the speed ratios (MuJoCo / project, medians) at e* and the largest in
    the stretch, and the tightest error each engine reached."""
    def err(r):
        return max(r["error_max"], floor)
    ok = [dict(r, error_max=err(r)) for r in rows if r["status"] == "ok" and r["wall_time_s"] is not None]
    best = {e: min((r["error_max"] for r in ok if r["engine"] == e), default=None) for e in ("urdf2links", "MuJoCo")}
    out = {"metric": f"error = max over the run, on a grid of {per_decade} levels per decade; faster = its slowest "
                     "timing round beats the other engine's fastest (else a tie); times are medians (min-max)",
           "error_level": None, "region": None, "tightest_error": best, "ratio_at_crossover": None,
           "largest_speedup": None, "levels": [], "ties": 0}
    if best["urdf2links"] is None or best["MuJoCo"] is None:
        out["statement"] = "no crossover: one of the engines has no successful run"
        return out
    lv = out["levels"] = _levels(ok, max(best.values()), max(r["error_max"] for r in ok), per_decade)
    out["ties"] = sum(x["winner"] == "tie" for x in lv)
    extra = ""
    if best["urdf2links"] < best["MuJoCo"]:
        extra = (f"; only urdf2links reached errors below {best['MuJoCo']:.1e} within the ladders and budget "
                 f"(down to {best['urdf2links']:.1e})")
    elif best["MuJoCo"] < best["urdf2links"]:
        extra = (f"; only MuJoCo reached errors below {best['urdf2links']:.1e} within the ladders and budget "
                 f"(down to {best['MuJoCo']:.1e})")
    ties = f"; {out['ties']} of the {len(lv)} levels are ties (the timing spreads overlap)" if out["ties"] else ""
    start = next((k for k, x in enumerate(lv) if x["project_faster"]), None)
    if start is None:
        out["statement"] = ("urdf2links is not (yet) faster than MuJoCo beyond the timing spread at any error level "
                            "both reach" + (f": {_at(lv[0])}" if lv else "") + ties + extra)
        return out
    end = start
    while end + 1 < len(lv) and lv[end + 1]["project_faster"]:
        end += 1
    x = lv[end]
    out["error_level"] = x["error"]
    out["region"] = [lv[start]["error"], x["error"]]
    out["ratio_at_crossover"] = x["mujoco_s"] / x["project_s"]
    top = max(lv[start:end + 1], key=lambda y: y["mujoco_s"] / y["project_s"])
    out["largest_speedup"] = {"error": top["error"], "ratio": top["mujoco_s"] / top["project_s"]}
    where = (f"below {x['error']:.1e}" if start == 0 else
             f"between {lv[start]['error']:.1e} and {x['error']:.1e} (not below: {_at(lv[0])})")
    out["statement"] = (f"urdf2links is faster than MuJoCo (beyond the timing spread) for errors {where}"
                        f"{_above(lv[end + 1:])}: {_at(x)}; largest advantage {_at(top)}" + ties + extra)
    return out
