"""The file of ``urdf2links report --pairs PAIRS.toml``: which pairs of descriptions to compare, and how close
they must stay.

Schema (every key checked; paths relative to the file's folder)::

    description = "what these pairs are"    # optional: the line `urdf2links list` shows

    # optional: what every pair gets unless it says otherwise
    [defaults]
    root = "$ROBOT_FILES"    # where the pairs' relative paths start (default: this file's folder);
                             #   ~ and $VARIABLES expanded, itself relative to this file's folder
    t_end = 1.0              # s of motion in each file's default scene (0: no motion, descriptions only)
    q0 = "zero"              # or "random": the first description's initial state (seeded by seed)
    seed = 0                 # seed of q0 random and of the states A and G are compared at
    states = 8               # seeded states of the A and G comparison
    tolerances = { mass = 1e-3 }

    [[pair]]
    name = "ur5_like"                   # optional (default: the first file's stem); names the report folder
    urdf = "../ur5_like.urdf"           # the first description (.urdf, .xacro or .xml)
    mjcf = "../ur5_like_mujoco.xml"     # the second (.xml, or another .urdf)
    map = { shoulder = "joint1" }       # optional: urdf joint = mjcf joint, for names that differ
    tolerances = { armature = 0.05, A = 0.1 }
    floating_base = false               # optional loading options of the first file:
    package_dirs = ["../meshes"]        #   as on the command line (--floating, --package-dir,
    xacro_args = { prefix = "left_" }   #   --xacro-arg)

``tolerances`` (the pair's, over the defaults'): a number per kind of difference
(:data:`~urdf2links.compare.pairs.differences.KINDS`, in the kind's unit: relative for ``mass`` and
``inertia``, m for ``com`` and ``origin``, rad for ``axis``, the joint's units for ``armature``,
``damping``, ``stiffness``, ``limits``, a count for ``joint_missing``, ``link_missing`` and ``type``) and
``A``, ``G`` (their largest relative difference, mapped); ``inf`` accepts any. A kind not given is held to
its rounding level (:data:`~urdf2links.compare.pairs.differences.ROUNDING`): any difference of it fails.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from pathlib import Path

from urdf2links.locations import read_toml

from .differences import KINDS
from .pair import TERM_KEYS

__all__ = ["PairSpec", "read_pairs_file", "DEFAULTS"]

#: What a pair gets when neither it nor ``[defaults]`` says.
DEFAULTS = {"t_end": 1.0, "q0": "zero", "seed": 0, "states": 8}
_PAIR_KEYS = {"name", "urdf", "mjcf", "map", "tolerances", "floating_base", "package_dirs", "xacro_args", *DEFAULTS}


@dataclass(frozen=True)
class PairSpec:
    """One ``[[pair]]``: ``name``, the two files, ``map``, ``tolerances``, ``load`` (the first file's loading
    options) and the run settings (``t_end``, ``q0``, ``seed``, ``states``)."""

    name: str
    urdf: Path
    mjcf: Path
    map: dict = field(default_factory=dict)
    tolerances: dict = field(default_factory=dict)
    load: dict = field(default_factory=dict)
    t_end: float = 1.0
    q0: str = "zero"
    seed: int = 0
    states: int = 8


def _fail(where: str, msg: str):
    raise ValueError(f"{where}: {msg}")


def _tolerances(where: str, value) -> dict:
    if not isinstance(value, dict):
        _fail(where, f"tolerances must be a table {{kind = number}}, got {value!r}")
    out = {}
    for k, v in value.items():
        if k not in KINDS and k not in TERM_KEYS:
            _fail(where, f"tolerances: unknown key {k!r}; the kinds are {', '.join(KINDS)}, and A, G for the terms")
        if isinstance(v, bool) or not isinstance(v, (int, float)) or math.isnan(v) or v < 0:
            _fail(where, f"tolerances.{k} = {v!r}: give a number >= 0 (inf accepts any difference)")
        out[k] = float(v)
    return out


def _settings(where: str, table: dict) -> dict:
    out = {}
    for k in DEFAULTS:
        if k not in table:
            continue
        v = table[k]
        if k == "t_end" and (isinstance(v, bool) or not isinstance(v, (int, float)) or not (0 <= v <= 60)):
            _fail(where, f"t_end = {v!r}: give seconds in [0, 60] (0: no motion)")
        if k == "q0" and v not in ("zero", "random"):
            _fail(where, f"q0 = {v!r}: give \"zero\" or \"random\"")
        if k in ("seed", "states") and (isinstance(v, bool) or not isinstance(v, int) or v < (1 if k == "states" else 0)):
            _fail(where, f"{k} = {v!r}: give a whole number" + (" >= 1" if k == "states" else " >= 0"))
        out[k] = v
    return out


def _root(path: Path, root) -> Path:
    """The folder the pairs' paths start from: ``root`` (``~``, ``$VARIABLES`` expanded; relative to the file's
    folder) or the file's folder."""
    if root is None:
        return path.parent
    if not isinstance(root, str):
        _fail(f"{path} [defaults]", f"root = {root!r}: give a folder (a string)")
    text = os.path.expanduser(os.path.expandvars(root))
    if "$" in text:
        _fail(f"{path} [defaults]", f"root = {root!r}: the environment variable in it is not set")
    folder = (path.parent / text).resolve()
    if not folder.is_dir():
        _fail(f"{path} [defaults]", f"root = {root!r}: {folder} is not a folder")
    return folder


def read_pairs_file(path) -> list[PairSpec]:
    """The pairs of a pairs file (module doc); a ValueError names the file, the pair and the key."""
    path = Path(path)
    data = read_toml(path, error=ValueError, what="pairs file")
    unknown = [k for k in data if k not in ("defaults", "pair", "description")]
    if unknown:
        _fail(str(path), f"unknown top-level key(s) {unknown}: a pairs file has a description, [defaults] and "
                         "[[pair]] tables")
    defaults = data.get("defaults", {})
    bad = [k for k in defaults if k not in (*DEFAULTS, "tolerances", "root")]
    if bad:
        _fail(f"{path} [defaults]", f"unknown key(s) {bad}; allowed: {', '.join((*DEFAULTS, 'tolerances', 'root'))}")
    folder = _root(path, defaults.get("root"))
    base = {**DEFAULTS, **_settings(f"{path} [defaults]", defaults)}
    base_tol = _tolerances(f"{path} [defaults]", defaults.get("tolerances", {}))
    pairs = data.get("pair", [])
    if not isinstance(pairs, list) or not pairs:
        _fail(str(path), "no [[pair]] table: give at least one pair (urdf = ..., mjcf = ...)")
    out, names = [], set()
    for i, p in enumerate(pairs, 1):
        where = f"{path} [[pair]] #{i}"
        bad = [k for k in p if k not in _PAIR_KEYS]
        if bad:
            _fail(where, f"unknown key(s) {bad}; allowed: {', '.join(sorted(_PAIR_KEYS))}")
        files = []
        for key in ("urdf", "mjcf"):
            if not isinstance(p.get(key), str):
                _fail(where, f"{key} = <path of a robot file> is required")
            f = (folder / p[key]).resolve() if not Path(p[key]).is_absolute() else Path(p[key])
            if not f.is_file():
                _fail(where, f"{key} = {p[key]!r}: no such file ({f})")
            files.append(f)
        name = str(p.get("name") or files[0].stem)
        if name in names:
            _fail(where, f"name {name!r} is used by another pair: names must differ (they name the report folders)")
        names.add(name)
        mp = p.get("map", {})
        if not isinstance(mp, dict) or not all(isinstance(v, str) for v in mp.values()):
            _fail(where, "map must be a table {urdf_joint = \"mjcf_joint\"}")
        load = {}
        if p.get("floating_base"):
            load["floating_base"] = True
        if p.get("package_dirs"):
            load["package_dirs"] = tuple(str((folder / d).resolve()) for d in p["package_dirs"])
        if p.get("xacro_args"):
            load["xacro_args"] = {str(k): str(v) for k, v in p["xacro_args"].items()}
        settings = {**base, **_settings(where, p)}
        out.append(PairSpec(name, files[0], files[1], dict(mp), {**base_tol, **_tolerances(where, p.get("tolerances", {}))},
                            load, float(settings["t_end"]), settings["q0"], int(settings["seed"]), int(settings["states"])))
    return out
