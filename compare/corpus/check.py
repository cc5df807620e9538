"""Try MuJoCo's own URDF import on every URDF of example-robot-data; print what it says.

    python -m urdf2links.compare.corpus.check [--floating] [--no-fusestatic]

Each file is reported as ``loaded`` (with its number of hinge/slide dofs), ``refused``
(MuJoCo's own reason, first line) or ``error`` (not MuJoCo: unreadable XML, unsupported
joint type...).  A summary groups the refusals by reason.
"""

from __future__ import annotations

import argparse
import re
import sys
from collections import Counter
from pathlib import Path

from urdf2links.locations import example_robot_data_dir

from ..mujoco_side.mujoco_urdf import MujocoRefused, mujoco_from_urdf


def corpus_root() -> Path | None:
    return example_robot_data_dir()


def _reason_kind(reason: str) -> str:
    """MuJoCo's message without the element name/id, to group refusals."""
    first = reason.strip().splitlines()[0]
    return re.sub(r"\s+", " ", first)


def check(root: Path, *, floating_base: bool = False, fusestatic: bool = True):
    """Yield (relative path, status, detail) for every URDF under ``root``."""
    for path in sorted(root.rglob("*.urdf")):
        rel = path.relative_to(root).as_posix()
        try:
            mj = mujoco_from_urdf(path, floating_base=floating_base, fusestatic=fusestatic)
        except MujocoRefused as err:
            yield rel, "refused", err.reason
        except Exception as err:  # noqa: BLE001 - a survey: report, never stop
            yield rel, "error", f"{type(err).__name__}: {err}"
        else:
            yield rel, "loaded", f"{len(mj.joint_names)} hinge/slide dofs, nbody={mj.model.nbody}"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--floating", action="store_true", help="add a free joint to the root")
    ap.add_argument("--no-fusestatic", action="store_true")
    args = ap.parse_args(argv)
    root = corpus_root()
    if root is None:
        print("example-robot-data is not installed (pip install example-robot-data)")
        return 2
    results = list(check(root, floating_base=args.floating, fusestatic=not args.no_fusestatic))
    for rel, status, detail in results:
        print(f"{status:8s} {rel}: " + detail.replace("\n", " | "))
    counts = Counter(status for _, status, _ in results)
    print(f"\n{len(results)} URDF files under {root}"
          f" (floating_base={args.floating}, fusestatic={not args.no_fusestatic}): "
          + ", ".join(f"{counts[s]} {s}" for s in ("loaded", "refused", "error")))
    kinds = Counter(_reason_kind(d) for _, s, d in results if s != "loaded")
    for kind, n in kinds.most_common():
        print(f"  {n:3d} x {kind}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
