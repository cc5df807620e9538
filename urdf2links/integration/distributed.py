"""Running urdf2links work in several processes and on a Dask cluster: the pieces both need.

* :func:`cores`: the cores this process may use (the default of ``--jobs``);
* :data:`ONE_AT_A_TIME`: a lock held by every corpus robot and every sweep chunk while it runs.
  MuJoCo's control callback is global to a process (:mod:`urdf2links.compare.mujoco_side.mujoco_run`) and numba's
  default threading layer must not be entered by two threads at once, so a process runs one such
  task at a time even when a Dask worker gives it several threads (start workers with
  ``--nthreads 1`` and more processes instead: ``dask worker ADDRESS --nworkers N --nthreads 1``);
* :func:`connect`: a ``dask.distributed.Client`` for a scheduler address (the optional extra
  ``pip install "urdf2links[distributed]"``; a clear error without it);
* :func:`worker_count`: how many worker processes a client has.

Nothing here imports Dask until :func:`connect` runs (``import urdf2links`` stays light).
"""

from __future__ import annotations

import os
import threading

__all__ = ["ONE_AT_A_TIME", "DISTRIBUTED_INSTALL", "cores", "connect", "worker_count"]

#: Held while one corpus robot or one sweep chunk runs in this process (module doc).
ONE_AT_A_TIME = threading.Lock()
DISTRIBUTED_INSTALL = 'pip install "urdf2links[distributed]"'


def cores() -> int:
    """The number of cores this process may run on (its CPU affinity), at least 1."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not on Linux
        return max(1, os.cpu_count() or 1)


def connect(address: str, *, timeout: float = 30.0):
    """A ``dask.distributed.Client`` connected to the scheduler at ``address`` (``tcp://host:8786``).
    ImportError says what to install when Dask is missing; OSError names the address when no
    scheduler answers within ``timeout`` seconds."""
    try:
        from dask.distributed import Client
    except ImportError:
        raise ImportError(f"--scheduler needs Dask's distributed scheduler: {DISTRIBUTED_INSTALL}") from None
    try:
        return Client(address, timeout=timeout)
    except (OSError, TimeoutError) as exc:
        raise OSError(f"--scheduler {address}: no Dask scheduler answered within {timeout:g} s ({exc}); start "
                      f"one with `dask scheduler` and give the address it prints") from None


def worker_count(client) -> int:
    """The number of worker processes the client's cluster has now (at least 1)."""
    return max(1, len(client.scheduler_info().get("workers", {})))
