"""A real robot's log as the input of identification: read (CSV, NPZ, ROS 2 bags), checked, differentiated.

The layer reads files and checks data; it builds no regressor and fits nothing (that is
``urdf2links.identification``). What ``identify --data`` calls, in order (docs/logs.md):

    log = read_log(path, topic=..., wrench_topic=..., base_topic=..., t_from=..., t_to=...)
    print(log.describe())
    log = check_log(log, joints=model.coordinate_names, limits=angular_limits(model))
    d = derivatives(log, method="savgol", cutoff_hz=...)   # d.describe() printed, d.plot(png)
    check_samples(log, n_base=..., equations_per_sample=...)   # once the base parameters are known
"""

from .base import BASE_SLOTS, BasePoses
from .checks import angular_limits, check_log, check_samples, check_times
from .derivatives import DEFAULT_CUTOFF_HZ, Derivatives, derivatives, noise_level
from .errors import (DegreesError, JumpError, LogError, LogFormatError, NonFiniteError, NonUniformError,
                     TimeOrderError, TooFewSamplesError, UnknownJointError)
from .filters import Filter
from .log import QUANTITIES, RobotLog, Wrenches, segment
from .readers import read_log
from .tables import write_csv, write_npz

__all__ = [
    "read_log", "check_log", "angular_limits", "check_samples", "check_times", "derivatives", "Derivatives",
    "Filter", "noise_level", "DEFAULT_CUTOFF_HZ", "RobotLog", "Wrenches", "BasePoses", "BASE_SLOTS", "QUANTITIES",
    "segment", "write_csv", "write_npz",
    "LogError", "LogFormatError", "NonFiniteError", "TimeOrderError", "JumpError", "UnknownJointError",
    "DegreesError", "TooFewSamplesError", "NonUniformError",
]
