"""One entry point for every log format: :func:`read_log` by the file's suffix, its times checked, its
segment chosen."""

from __future__ import annotations

from pathlib import Path

from .bags import bag_folder, read_bag
from .checks import check_times
from .errors import LogFormatError
from .log import RobotLog, segment
from .tables import read_csv, read_npz

__all__ = ["read_log"]


def read_log(path, *, topic: str = "/joint_states", wrench_topic: str | None = None,
             base_topic: str | None = None, t_from: float | None = None, t_to: float | None = None) -> RobotLog:
    """The log in ``path``: a ``.csv`` or ``.npz`` table, or a ROS 2 bag (its folder, or the ``.mcap`` /
    ``.db3`` file inside it) read on ``topic`` (and ``wrench_topic``, ``base_topic``). Its time stamps are checked
    (finite, strictly increasing: :func:`~urdf2links.robot_logs.checks.check_times`) over the whole file,
    then the segment ``t_from <= t <= t_to`` is kept (noted).

    ``topic``, ``wrench_topic`` and ``base_topic`` apply to bags only (a table's base pose is its
    ``base.*`` columns); given with a table, they are an error (a table has
    no topics), never ignored."""
    p = Path(path)
    if not p.exists():
        raise LogFormatError(f"{p}: no such file or folder", source=str(p))
    folder = bag_folder(p)
    if folder is not None:
        log = read_bag(folder, topic=topic, wrench_topic=wrench_topic, base_topic=base_topic)
    elif p.suffix.lower() in (".csv", ".npz"):
        if topic != "/joint_states" or wrench_topic is not None or base_topic is not None:
            raise LogFormatError(f"{p}: a {p.suffix} table has no topics; --topic, --wrench-topic and "
                                 "--base-topic apply to ROS 2 bags", source=str(p))
        log = read_csv(p) if p.suffix.lower() == ".csv" else read_npz(p)
    else:
        raise LogFormatError(f"{p}: unknown log format; expected a .csv or .npz table, or a ROS 2 bag folder "
                             "(with metadata.yaml; MCAP or sqlite3 storage)", source=str(p))
    check_times(log)
    return segment(log, t_from=t_from, t_to=t_to)
