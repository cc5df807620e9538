"""Every example-robot-data robot that loads, against MuJoCo's own import of itself (issue 25): no difference above
rounding, or each one explained in the report (an inertia MuJoCo had to balance, a massless moving link MuJoCo
had to bound, a massless inertia MuJoCo's merge drops, a URDF limit of zero width MuJoCo leaves unlimited).

MuJoCo imports each file as written (its inertias as they are: ``balanceinertia`` off); a file it refuses so is
imported again with its compiler allowed to repair inertias (``balanceinertia``, ``boundmass``,
``boundinertia``), as a user's conversion would have to. A file this project's reader refuses, or that MuJoCo
refuses even then, does not load and is counted, not compared. The table is printed (``pytest -s``) and in
docs/pairs.md.
"""

from __future__ import annotations

import warnings

import pytest

from urdf2links.compare.mujoco_side.mujoco_urdf import MujocoRefused
from urdf2links.compare.pairs.mujoco_import import save_mujoco_import
from urdf2links.compare.pairs.pair import compare_descriptions_of
from urdf2links.errors import DescriptionError
from urdf2links.locations import example_robot_data_dir
from urdf2links.parsers.parts import robot_parts

ROOT = example_robot_data_dir()
# The corpus is in the test extra: without it every test here fails at its setup, naming what to install
# (tests/corpus.py), instead of skipping and passing on nothing.
pytestmark = pytest.mark.usefixtures("corpus_installed")


def _self_comparison(path, folder):
    """``(status, comparison or reason)``: ``as written``, ``balanced``, or why it does not load."""
    try:
        robot_parts(path)
    except DescriptionError as exc:
        return "not read", str(exc).splitlines()[0]
    out = folder / (path.name + ".xml")
    status = "as written"
    try:
        save_mujoco_import(path, out, keep_geometry=False)
    except MujocoRefused:
        status = "balanced"
        try:
            save_mujoco_import(path, out, keep_geometry=False, balance=True)
        except MujocoRefused as exc:
            return "refused by MuJoCo", exc.reason.splitlines()[0]
    return status, compare_descriptions_of(path, out)


def _beyond_frames(c) -> list:
    """The differences besides the massless frames MuJoCo's import fuses by design (``frame_missing``, explained)."""
    return [d for d in c.differences if d.kind != "frame_missing"]


def test_every_robot_against_mujocos_import_of_itself(tmp_path, capsys):
    files = sorted([*ROOT.rglob("*.urdf"), *ROOT.rglob("*.xacro")])
    rows, compared = [], {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for f in files:
            status, c = _self_comparison(f, tmp_path)
            rel = f.relative_to(ROOT).as_posix()
            if isinstance(c, str):
                rows.append((rel, status, c))
                continue
            compared[rel] = (status, c)
            unexplained = [d.label() for d in c.differences if not d.explanation]
            assert not unexplained, f"{rel} ({status}): differences nobody explained: {unexplained}"
            rows.append((rel, status, f"{len(c.differences)} difference(s), all explained" if c.differences else "clean"))
            if status == "as written" and not _beyond_frames(c):
                # MuJoCo's 6 written digits: A and G agree to rounding (relative, the largest entry)
                assert c.effects["mapped"]["A"]["max_rel_difference"] < 1e-5, rel
                assert c.effects["mapped"]["G"]["max_rel_difference"] < 1e-5, rel
            assert c.mapping.mapped_fraction == 1.0, rel
    clean = sum(not _beyond_frames(c) for _s, c in compared.values())
    frames = sum(d.kind == "frame_missing" for _s, c in compared.values() for d in c.differences)
    with capsys.disabled():
        print(f"\n{len(files)} files, {len(compared)} compared ({clean} clean but for {frames} frames MuJoCo fused), "
              f"{sum(s == 'balanced' for s, _ in compared.values())} needed MuJoCo's balancing")
        for r in rows:
            print("  " + " | ".join(r))
    assert len(compared) >= 60 and clean >= 45
