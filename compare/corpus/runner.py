"""Running a corpus: each robot in this process, in parallel worker processes, or on a Dask cluster.

:func:`run_corpus` evaluates every :class:`~urdf2links.compare.corpus.rows.RobotFile` with
:func:`~urdf2links.compare.corpus.rows.evaluate_robot` and returns the results in the corpus' order, calling
``on_result`` as each robot finishes (progress lines). Three ways, one answer (a robot's row does
not depend on where it ran, apart from ``wall_time`` and ``worker``):

* ``jobs=1``: one robot after the other in this process (warmed like a worker first);
* ``jobs=N`` (default: every core, :func:`urdf2links.integration.distributed.cores`): N worker processes on this
  machine (``spawn``: a fresh interpreter each, nothing inherited from this one's threads). Each
  worker first loads what a robot needs (:func:`warm_worker`: the compiled kernels from numba's
  on-disk cache -- compiled once per installation, never per robot --, MuJoCo, matplotlib), then
  takes robots one at a time. A worker that dies (a crash inside MuJoCo, the memory killer) does
  not stop the run: the robots it may have been running are run again one by one in a fresh
  worker, and the one that kills it again gets a ``failed`` row saying so;
* ``client`` (a ``dask.distributed.Client``, e.g. from ``--scheduler ADDRESS``): one task per robot on
  the cluster's workers, each warmed first (``client.run(warm_worker)``). Workers need urdf2links
  installed and the robot files at the same paths (a shared folder); the rows and pages come back
  to this process, which writes them. A robot whose worker died on every retry Dask allows gets a
  ``failed`` row.

A process runs one robot at a time (:data:`urdf2links.integration.distributed.ONE_AT_A_TIME`): MuJoCo's control
callback is global to a process.
"""

from __future__ import annotations

import multiprocessing
import time
import uuid
from concurrent.futures import ProcessPoolExecutor, as_completed
from concurrent.futures.process import BrokenProcessPool
from typing import Callable

from urdf2links.compilation import clock  # durations without numba's compilation
from urdf2links.integration.distributed import ONE_AT_A_TIME, cores

from .rows import CorpusSettings, RobotFile, RobotResult, evaluate_robot, failed_result

__all__ = ["run_corpus", "warm_worker", "robot_task"]


def warm_worker() -> float:
    """Load into this process everything a robot's evaluation uses -- the compiled kernels (numba
    reads them from its disk cache; the first process of a fresh installation compiles them, a few
    minutes), MuJoCo, matplotlib, the mesh reader -- by evaluating the shipped double pendulum for
    5 ms with its page and thumbnail, so that no robot's wall time pays for it. Returns the seconds
    it took, compilation included (``time.perf_counter``: this is the warm-up that every other time leaves out)."""
    start = time.perf_counter()
    from urdf2links.locations import shipped_robots_dir

    pendulum = shipped_robots_dir() / "double_pendulum.urdf"
    robot_task(RobotFile(id=pendulum.name, path=str(pendulum)), CorpusSettings(t_end=0.005, states=1))
    return time.perf_counter() - start


def robot_task(robot: RobotFile, settings: CorpusSettings) -> RobotResult:
    """One robot, alone in its process while it runs (what a worker process or a Dask worker runs)."""
    with ONE_AT_A_TIME:
        return evaluate_robot(robot, settings)


def run_corpus(robots: list[RobotFile], settings: CorpusSettings, *, jobs: int | None = None, client=None,
               on_result: Callable[[RobotResult], None] | None = None,
               log: Callable[[str], None] | None = None, timing: dict | None = None) -> list[RobotResult]:
    """Every robot's result, in the order of ``robots`` (module doc). ``jobs``: worker processes on
    this machine (default every core; 1 runs here); ``client``: a Dask client to run on instead.
    ``on_result(result)`` is called in this process as each robot finishes; ``log(message)`` gets
    what the workers' warm-up took. ``timing`` (a dict) gets ``warm_s``: the seconds this process waited
    for the warm-up (:func:`warm_worker`: numba's compilation in a fresh installation), which a run's
    wall time leaves out: here, the warm-up on this process's clock; in workers, the wait for the first
    result less that robot's own seconds (the workers warm up at once, before their first robot)."""
    say = log or (lambda _m: None)
    started, first = clock(), {}

    def done(res: RobotResult) -> None:
        if not first:
            own = float((res.row.get("wall_time") or {}).get("total_s") or 0.0)
            first["wait"] = max(0.0, clock() - started - own)
        (on_result or (lambda _r: None))(res)

    if client is not None:
        results = _on_dask(robots, settings, client, done, say)
    else:
        jobs = min(cores() if jobs is None else max(1, int(jobs)), max(1, len(robots)))
        if jobs == 1:
            warm = clock()
            warm_worker()   # as a worker process does: no robot's wall time pays for loading the kernels
            first["wait"] = clock() - warm
            results = _here(robots, settings, on_result or (lambda _r: None))
        else:
            results = _in_processes(robots, settings, jobs, done, say)
    if timing is not None:
        timing["warm_s"] = first.get("wait", 0.0)
    return [results[r.id] for r in robots]


def _here(robots, settings, done) -> dict:
    results = {}
    for r in robots:
        results[r.id] = res = robot_task(r, settings)
        done(res)
    return results


def _pool(jobs: int) -> ProcessPoolExecutor:
    return ProcessPoolExecutor(max_workers=jobs, mp_context=multiprocessing.get_context("spawn"),
                               initializer=warm_worker)


def _in_processes(robots, settings, jobs, done, say) -> dict:
    """``jobs`` spawned worker processes; robots whose worker died are run again one by one."""
    results: dict[str, RobotResult] = {}
    lost: list[RobotFile] = []
    with _pool(jobs) as pool:
        futures = {pool.submit(robot_task, r, settings): r for r in robots}
        for fut in as_completed(futures):
            r = futures[fut]
            try:
                res = fut.result()
            except BrokenProcessPool:
                lost.append(r)
                continue
            except Exception as exc:  # noqa: BLE001 - the row says why (an unpicklable result, ...)
                res = failed_result(r, settings, "worker", exc)
            results[r.id] = res
            done(res)
    if lost:
        say(f"a worker process died; running its {len(lost)} unfinished robot(s) again one at a time")
        results.update(_one_by_one(sorted(lost, key=lambda x: x.id), settings, done))
    return results


def _one_by_one(robots, settings, done) -> dict:
    """Each robot alone in one worker process (a new one after a death): a robot that kills it is a
    failed row."""
    results = {}
    pool = _pool(1)
    try:
        for r in robots:
            try:
                res = pool.submit(robot_task, r, settings).result()
            except BrokenProcessPool as exc:
                res = failed_result(r, settings, "worker", RuntimeError(
                    "the worker process died while running this robot, alone (a crash in MuJoCo or numba, or the "
                    f"system ran out of memory): {exc}"))
                pool.shutdown()
                pool = _pool(1)
            results[r.id] = res
            done(res)
    finally:
        pool.shutdown()
    return results


def _on_dask(robots, settings, client, done, say) -> dict:
    """One Dask task per robot; a task Dask gave up on (its worker died too often) is a failed row."""
    from dask.distributed import as_completed as dask_completed

    warm = client.run(warm_worker)
    say(f"{len(warm)} Dask worker(s) warmed (kernels, MuJoCo, matplotlib loaded in {max(warm.values(), default=0.0):.1f} "
        "s at most)")
    run_id = uuid.uuid4().hex[:8]
    futures = client.map(robot_task, robots, settings=settings, pure=False,
                         key=[f"urdf2links-corpus-{run_id}-{i}" for i in range(len(robots))])
    robot_of = {f.key: r for f, r in zip(futures, robots)}
    results: dict[str, RobotResult] = {}
    for fut in dask_completed(futures):
        r = robot_of[fut.key]
        try:
            res = fut.result()
        except Exception as exc:  # noqa: BLE001 - KilledWorker, a lost connection: the row says why
            res = failed_result(r, settings, "worker", exc)
        results[r.id] = res
        done(res)
        fut.release()
    return results
