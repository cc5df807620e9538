"""Baselines of the MuJoCo comparison: accepted figures per scene and run, and the regression check.

:func:`check_baseline` compares a summary with the accepted figures of ``baselines.json``
(:func:`baseline_entry`, :func:`write_baselines`): a figure fails when it grows past ``factor``
(default :data:`DEFAULT_FACTOR`) times its baseline (or times a floor, for figures at rounding
level that jitter); a divergence time fails when it comes earlier than the baseline's by more than
the time the error needs to grow by ``factor``. Wall times are not checked.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

from ..formatting import get, json_ready

__all__ = ["DEFAULT_FACTOR", "CHECKED_FIGURES", "baseline_entry", "write_baselines", "select_run", "load_baselines",
           "CheckResult", "check_baseline"]

#: Allowed growth of an error figure over its baseline before ``--check`` fails.
DEFAULT_FACTOR = 10.0

#: Figures ``--check`` compares, with the floor under which a baseline is treated as the floor
#: (numbers at rounding level jitter between machines). A floor given as ``("energy", x)`` is
#: ``x`` times the scene's energy scale ``energy.scale`` (J).
CHECKED_FIGURES = {
    "terms.max_rel_error": 1e-14,
    "terms.max_rel_error_route1": 1e-14,
    "terms.max_rel_error_route2": 1e-14,
    "trajectory.max_abs_error": 1e-12,
    "energy.project_drift": ("energy", 1e-13),
    "energy.mujoco_drift": ("energy", 1e-13),
    "base.tracking_error": 1e-12,
}


def baseline_entry(summary: dict) -> dict:
    """The accepted figures of one scene (for ``baselines.json``): the checked figures, the
    divergence time and growth rate, and the run's settings."""
    figs = {k: get(summary, k) for k in CHECKED_FIGURES}
    return {
        "settings": {"t_end": summary["t_end"], "mujoco.integrator": summary["mujoco"]["integrator"],
                     "mujoco.timestep": summary["mujoco"]["timestep"], "project.method": summary["project"]["method"],
                     "project.rtol": summary["project"]["rtol"], "samples": summary["samples"]},
        "figures": {k: v for k, v in figs.items() if v is not None},
        "energy.scale": summary["energy"]["scale"],
        "trajectory.divergence_time": summary["trajectory"]["divergence_time"],
        "trajectory.growth_rate": summary["trajectory"].get("growth_rate"),
        "wall_time (not checked)": {"project_s": round(summary["wall_time"]["project_s"], 3),
                                    "mujoco_s": round(summary["wall_time"]["mujoco_s"], 3)},
    }


def _runs(scene_entry: dict) -> list[dict]:
    """The accepted runs of one scene: ``{"runs": [...]}``, or a single flat entry."""
    return list(scene_entry["runs"]) if "runs" in scene_entry else [scene_entry]


def _run_id(entry: dict) -> tuple:
    st = entry.get("settings", {})
    return (st.get("t_end"), st.get("mujoco.integrator"), st.get("mujoco.timestep"))


def write_baselines(summaries, path, *, factor: float | None = None, about: str | None = None) -> Path:
    """Write ``baselines.json``: ``{"about", "factor", "floors", "scenes": {"<robot>/<scene>":
    {"runs": [entry, ...]}}}``, one entry (:func:`baseline_entry`) per accepted run length and MuJoCo
    setting. Runs already in an existing file are kept unless this run replaces them (same
    ``t_end``, integrator and timestep): a capped run and a whole-scene run can both be accepted.
    ``about`` replaces the file's description (a corpus' baselines say how they were made). Keys of an existing
    file that are not these (``urdf2links check``'s ``fingerprints``) are kept."""
    path = Path(path)
    old = load_baselines(path) if path.is_file() else {"scenes": {}}
    scenes = {k: {"runs": _runs(v)} for k, v in old.get("scenes", {}).items()}
    for summ in summaries:
        entry = baseline_entry(summ)
        runs = [r for r in scenes.get(summ["key"], {"runs": []})["runs"] if _run_id(r) != _run_id(entry)]
        runs.append(entry)
        runs.sort(key=lambda r: (r["settings"].get("t_end") or 0.0))
        scenes[summ["key"]] = {"runs": runs}
    data = {
        "about": about or ("Accepted figures of the MuJoCo cross-validation per shipped scene and run length (urdf2links "
                  "report --write-baselines). `urdf2links compare SCENE --check THIS_FILE` compares a run with the "
                  "shortest accepted run at least as long (same MuJoCo integrator and timestep preferred) and fails "
                  "when a figure grows past factor x max(baseline, floor) or a divergence comes earlier than the "
                  "baseline's by more than ln(factor) / growth rate. Wall times are recorded, not checked."),
        "factor": float(factor if factor is not None else old.get("factor", DEFAULT_FACTOR)),
        "floors": {k: (f"{v[1]:g} x energy.scale" if isinstance(v, tuple) else v) for k, v in CHECKED_FIGURES.items()},
        "scenes": dict(sorted(scenes.items())),
    }
    data.update({k: v for k, v in old.items() if k not in data})
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(json_ready(data), indent=2) + "\n")
    return path


def select_run(summary: dict, scene_entry: dict) -> tuple[dict, list[str]]:
    """The accepted run to compare ``summary`` with: among the runs with the same MuJoCo integrator
    and timestep (else all), the shortest whose ``t_end`` is at least the summary's (errors and
    drifts grow with time, so it bounds a shorter run); else the longest, with a warning."""
    runs = _runs(scene_entry)
    same = [r for r in runs if _run_id(r)[1:] == (summary["mujoco"]["integrator"], summary["mujoco"]["timestep"])]
    pool = same or runs
    T = float(summary["t_end"])
    longer = [r for r in pool if (r.get("settings", {}).get("t_end") or 0.0) >= T * (1 - 1e-9)]
    if longer:
        return min(longer, key=lambda r: r["settings"]["t_end"]), []
    chosen = max(pool, key=lambda r: r.get("settings", {}).get("t_end") or 0.0)
    return chosen, [f"this run ({T:g} s) is longer than every accepted run: compared with the longest "
                    f"({chosen.get('settings', {}).get('t_end')} s)"]


def load_baselines(path) -> dict:
    path = Path(path)
    data = json.loads(path.read_text())
    if not isinstance(data, dict) or "scenes" not in data:
        raise ValueError(f"{path}: not a baselines file (no 'scenes' table)")
    return data


@dataclass
class CheckResult:
    """Outcome of :func:`check_baseline`: ``ok``, the failing figure names, one line per figure,
    warnings (settings that differ from the baseline's), ``source`` (file and key), ``ratios``: each
    checked figure over what it is allowed (above 1: failed; a divergence time: how much of its margin
    it used up, above 1 when it came too early)."""

    ok: bool
    failures: list[str] = field(default_factory=list)
    lines: list[str] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    source: str = ""
    ratios: dict = field(default_factory=dict)

    def record(self, name: str, ratio: float, *, failed: bool, fail: str, ok: str) -> None:
        """One checked figure: its ``ratio`` (:attr:`ratios`), and its line, ``fail`` when ``failed`` (the result
        fails then), else ``ok``."""
        self.ratios[name] = ratio
        if failed:
            self.ok = False
            self.failures.append(name)
        self.lines.append(f"FAIL  {name} {fail}" if failed else f"ok    {name} {ok}")

    def text(self) -> str:
        head = f"baseline check {'passed' if self.ok else 'FAILED'} ({self.source})"
        return "\n".join([head] + [f"  warning: {w}" for w in self.warnings] + [f"  {x}" for x in self.lines])


def _number(v):
    if isinstance(v, bool) or v is None:
        return None
    if isinstance(v, (int, float)):
        return float(v)
    if isinstance(v, str):
        try:
            return float(v)
        except ValueError:
            return None
    return None


def check_baseline(summary: dict, baselines: dict, *, factor: float | None = None, source: str = "") -> CheckResult:
    """Compare ``summary`` with its entry (key ``summary["key"]``) of ``baselines`` (see module doc).
    The accepted run is chosen by :func:`select_run`. A missing entry raises ``KeyError``."""
    key = summary["key"]
    scenes = baselines.get("scenes", {})
    if key not in scenes:
        raise KeyError(f"no baseline for {key!r} in {source or 'the baselines'} (it has {sorted(scenes)})")
    base, warn = select_run(summary, scenes[key])
    f = float(factor if factor is not None else baselines.get("factor", DEFAULT_FACTOR))
    st = base.get("settings", {})
    what = f"{key} (accepted run of {st.get('t_end', '?')} s), factor {f:g}"
    res = CheckResult(ok=True, source=f"{source}: {what}" if source else what, warnings=warn)
    now = {"t_end": summary["t_end"], "mujoco.integrator": summary["mujoco"]["integrator"],
           "mujoco.timestep": summary["mujoco"]["timestep"], "project.method": summary["project"]["method"],
           "project.rtol": summary["project"]["rtol"]}
    for k, v in now.items():
        if k in st and st[k] != v:
            res.warnings.append(f"{k} is {v!r}, the baseline's is {st[k]!r}: figures compared anyway")
    scale = _number(get(summary, "energy.scale")) or _number(base.get("energy.scale")) or 0.0
    for name, floor in CHECKED_FIGURES.items():
        b = _number(base.get("figures", {}).get(name))
        raw = get(summary, name)
        if b is None:
            continue
        v = _number(raw)
        if raw is None:
            res.lines.append(f"skip  {name}: not measured in this run (baseline {b:.3g})")
            continue
        fl = floor[1] * scale if isinstance(floor, tuple) else floor
        allowed = f * max(b, fl)
        bad = v is None or not math.isfinite(v)
        res.record(name, math.inf if bad else v / allowed, failed=bad or v > allowed,
                   fail=f"= {raw if v is None else f'{v:.3g}'} grew past its baseline {b:.3g} "
                        f"(allowed {f:g} x max(baseline, floor {fl:.2g}) = {allowed:.3g})",
                   ok="" if bad else f"= {v:.3g} (baseline {b:.3g}, allowed {allowed:.3g})")
    d0 = _number(base.get("trajectory.divergence_time"))
    d = _number(get(summary, "trajectory.divergence_time"))
    if d0 is not None and d is not None:
        rate = _number(base.get("trajectory.growth_rate"))
        margin = math.log(f) / rate if rate and rate > 0 else 0.5 * d0
        earliest = d0 - margin
        res.record("trajectory.divergence_time",
                   (d0 - d) / margin if margin > 0 else (math.inf if d < d0 else 0.0), failed=d < earliest,
                   fail=f"= {d:.4g} s is earlier than its baseline {d0:.4g} s by more than {margin:.3g} s (the time "
                        f"the difference needs to grow {f:g}x)",
                   ok=f"= {d:.4g} s (baseline {d0:.4g} s, earliest allowed {earliest:.4g} s)")
    return res
