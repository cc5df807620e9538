"""A corpus robot that kills the process running it, for the worker-death tests (tests/test_corpus.py).

Imported in a process, it wraps the corpus runner's ``evaluate_robot`` so that a robot file whose name
starts with ``kill_me`` kills the process evaluating it (SIGKILL, as the kernel's memory killer or a
crash inside MuJoCo would: nothing in Python runs after it), every time; one whose name starts with
``die_once`` does so the first time only (it leaves ``<file>.died`` beside itself). Every other robot
is evaluated as usual.

Two ways in: run as the main script (``python tests/worker_killer.py report --corpus ...`` is
``urdf2links report --corpus ...``): ``--jobs`` workers are ``spawn``ed, and a spawned process runs the
parent's main script (as ``__mp_main__``) before its first task, so every worker is wrapped; or as a
Dask worker's ``preload`` (``LocalCluster(preload=[this file])``), run in each worker process when it
starts, again after the nanny restarts it.
"""

from __future__ import annotations

import os
import signal
import sys
from pathlib import Path

from urdf2links.compare.corpus import runner

# the original, also when this file runs twice in a process (a Dask worker runs its preloads more than once)
_evaluate = getattr(runner.evaluate_robot, "__wrapped__", runner.evaluate_robot)


def evaluate_or_die(robot, settings):
    name = Path(robot.path).name
    if name.startswith("kill_me"):
        os.kill(os.getpid(), signal.SIGKILL)
    if name.startswith("die_once"):
        marker = Path(robot.path + ".died")
        if not marker.exists():
            marker.write_text(str(os.getpid()))
            os.kill(os.getpid(), signal.SIGKILL)
    return _evaluate(robot, settings)


evaluate_or_die.__wrapped__ = _evaluate
runner.evaluate_robot = evaluate_or_die

if __name__ == "__main__":
    from urdf2links.cli import main

    sys.exit(main(sys.argv[1:]))
