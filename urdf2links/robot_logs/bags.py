"""ROS 2 bags (MCAP or sqlite3 storage) through the ``rosbags`` library (the ``logs`` extra).

A bag is the rosbag2 folder with its ``metadata.yaml`` (a ``.mcap`` or ``.db3`` file inside one is taken
as its folder). The joints come from a ``sensor_msgs/msg/JointState`` topic chosen by ``topic``; contact
forces, optionally, from a ``geometry_msgs/msg/WrenchStamped`` topic chosen by ``wrench_topic``; a
floating base's pose, optionally, from a ``nav_msgs/msg/Odometry`` or ``geometry_msgs/msg/PoseStamped``
topic chosen by ``base_topic`` (:mod:`urdf2links.robot_logs.base`).

Times are the messages' ``header.stamp`` (the measurement's time), counted in seconds from the first
message's stamp (kept as :attr:`RobotLog.t0_ns`); a topic whose stamps are all zero is timed by the bag's
receive times instead, and that is noted. Every message must name the same joints in the same order:
a topic that mixes publishers is an error naming the message, not merged by guess. An empty
``velocity`` or ``effort`` array (allowed by JointState) means the quantity is absent: NaN.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .base import BasePoses
from .errors import LogFormatError
from .log import QUANTITIES, RobotLog, Wrenches

__all__ = ["JOINT_STATE", "WRENCH_STAMPED", "ODOMETRY", "POSE_STAMPED", "bag_folder", "read_bag"]

JOINT_STATE = "sensor_msgs/msg/JointState"
WRENCH_STAMPED = "geometry_msgs/msg/WrenchStamped"
ODOMETRY = "nav_msgs/msg/Odometry"
POSE_STAMPED = "geometry_msgs/msg/PoseStamped"


def bag_folder(path) -> Path | None:
    """The rosbag2 folder of ``path`` (the folder itself, or the folder of a storage file in it), or None."""
    p = Path(path)
    for folder in (p, p.parent):
        if folder.is_dir() and (folder / "metadata.yaml").exists():
            return folder
    return None


def _rosbags():
    try:
        from rosbags.highlevel import AnyReader
        from rosbags.typesys import Stores, get_typestore
    except ImportError:      # an optional dependency: the message says how to get it
        raise LogFormatError("reading ROS 2 bags needs the rosbags package: pip install 'urdf2links[logs]'") from None
    return AnyReader, get_typestore(Stores.ROS2_HUMBLE)


def _connections(reader, source: str, topic: str, msgtype):
    msgtype = (msgtype,) if isinstance(msgtype, str) else tuple(msgtype)
    conns = [c for c in reader.connections if c.topic == topic]
    if not conns:
        listed = sorted(f"{c.topic} ({c.msgtype})" for c in reader.connections)
        raise LogFormatError(f"{source}: no topic {topic!r} in the bag; it has {', '.join(listed) or 'none'}",
                             source=source, topic=topic)
    bad = [c.msgtype for c in conns if c.msgtype not in msgtype]
    if bad:
        raise LogFormatError(f"{source}: topic {topic!r} holds {bad[0]}, not {' or '.join(msgtype)}; choose a "
                             f"{' or '.join(msgtype)} topic", source=source, topic=topic)
    return conns


def _stamp(msg) -> int:
    return int(msg.header.stamp.sec) * 10**9 + int(msg.header.stamp.nanosec)


def _joint_messages(reader, conns, source: str, topic: str):
    """(stamps ns, receive ns, names, {quantity: (S, n)}) of every JointState message on the topic."""
    stamps, received, names, rows = [], [], None, {q: [] for q in QUANTITIES}
    for k, (conn, t_ns, raw) in enumerate(reader.messages(connections=conns), start=1):
        msg = reader.deserialize(raw, conn.msgtype)
        these = tuple(msg.name)
        if names is None:
            names = these
        elif these != names:
            raise LogFormatError(
                f"{source}: topic {topic!r} message {k} names joints {list(these)}, the first message "
                f"{list(names)}; the topic mixes publishers or reorders joints: record one publisher's "
                "topic (or split the bag)", source=source, topic=topic, row=k)
        stamps.append(_stamp(msg))
        received.append(int(t_ns))
        for q in QUANTITIES:
            a = np.asarray(getattr(msg, q), dtype=float)
            if a.size not in (0, len(names)):
                raise LogFormatError(f"{source}: topic {topic!r} message {k}: {q} has {a.size} values for "
                                     f"{len(names)} names", source=source, topic=topic, row=k,
                                     column=f"{topic} {q}")
            rows[q].append(a if a.size else np.full(len(names), np.nan))
    if names is None:
        raise LogFormatError(f"{source}: topic {topic!r} has no message", source=source, topic=topic)
    return np.array(stamps, dtype=np.int64), np.array(received, dtype=np.int64), names, \
        {q: np.array(v) for q, v in rows.items()}


def _wrenches(reader, source: str, topic: str, t0_ns: int) -> Wrenches:
    conns = _connections(reader, source, topic, WRENCH_STAMPED)
    stamps, values, frame = [], [], ""
    for conn, _t, raw in reader.messages(connections=conns):
        msg = reader.deserialize(raw, conn.msgtype)
        frame = frame or msg.header.frame_id
        f, m = msg.wrench.force, msg.wrench.torque
        stamps.append(_stamp(msg))
        values.append((f.x, f.y, f.z, m.x, m.y, m.z))
    times = (np.array(stamps, dtype=np.int64) - t0_ns) * 1e-9
    return Wrenches(topic=topic, frame=frame, times=times, values=np.array(values, dtype=float).reshape(-1, 6))


def _base_poses(reader, source: str, topic: str, t0_ns: int) -> BasePoses:
    conns = _connections(reader, source, topic, (ODOMETRY, POSE_STAMPED))
    stamps, values, frame = [], [], ""
    for conn, _t, raw in reader.messages(connections=conns):
        msg = reader.deserialize(raw, conn.msgtype)
        pose = msg.pose.pose if conn.msgtype == ODOMETRY else msg.pose
        frame = frame or msg.header.frame_id
        p, q = pose.position, pose.orientation
        stamps.append(_stamp(msg))
        values.append((p.x, p.y, p.z, q.w, q.x, q.y, q.z))
    v = np.array(values, dtype=float).reshape(-1, 7)
    return BasePoses(source=topic, frame=frame, times=(np.array(stamps, dtype=np.int64) - t0_ns) * 1e-9,
                     positions=v[:, :3], quaternions=v[:, 3:], rows=np.arange(1, len(v) + 1))


def read_bag(path, *, topic: str = "/joint_states", wrench_topic: str | None = None,
             base_topic: str | None = None) -> RobotLog:
    """A ROS 2 bag's JointState topic (and WrenchStamped topic) as a log (module doc)."""
    folder = bag_folder(path)
    if folder is None:
        raise LogFormatError(f"{path}: not a rosbag2 folder (no metadata.yaml beside it); pass the bag's folder, "
                             "or run `ros2 bag reindex` on it", source=str(path))
    AnyReader, typestore = _rosbags()
    source = f"{folder} topic {topic}"
    with AnyReader([folder], default_typestore=typestore) as reader:
        conns = _connections(reader, str(folder), topic, JOINT_STATE)
        stamps, received, names, arrays = _joint_messages(reader, conns, str(folder), topic)
        notes = [f"read {len(stamps)} {JOINT_STATE} messages of topic {topic} from {folder}"]
        if not stamps.any():
            stamps = received
            notes.append(f"every header.stamp of {topic} is zero: the bag's receive times are used instead")
        t0 = int(stamps[0])
        notes.append(f"times in seconds after the first stamp {t0 // 10**9}.{t0 % 10**9:09d}")
        wrenches = None if wrench_topic is None else _wrenches(reader, str(folder), wrench_topic, t0)
        base = None if base_topic is None else _base_poses(reader, str(folder), base_topic, t0)
    if base is not None:
        notes.append(f"{len(base.times)} base poses of topic {base_topic} (frame {base.frame!r}; quaternions "
                     "reordered to w, x, y, z)")
    if wrenches is not None:
        notes.append(f"{len(wrenches.times)} {WRENCH_STAMPED} messages of topic {wrench_topic} "
                     f"(frame {wrenches.frame!r})")
    for q in QUANTITIES:
        if np.isnan(arrays[q]).all():
            notes.append(f"the messages carry no {q}: NaN")
    return RobotLog(times=(stamps - t0) * 1e-9, names=names, positions=arrays["position"],
                    velocities=arrays["velocity"], efforts=arrays["effort"], source=source, notes=tuple(notes),
                    columns={(q, j): f"{topic} {q}[{j}]" for q in QUANTITIES for j in names},
                    row_word="message", t0_ns=t0, topic=topic, wrenches=wrenches, base=base)
