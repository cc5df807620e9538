"""Reading robot descriptions: a file (URDF, xacro, MJCF) -> the parsed description -> the tree of links and its Model.

May import the base modules (errors, ranges, console, locations) and :mod:`urdf2links.dynamics`; never
scenes, integration, view or compare.
"""

from .description import RobotDescription
from .importer import AuditRecord, load_urdf, load_urdf_string, urdf_link_poses
from .mjcf import load_mjcf, load_mjcf_string
from .robot_file import load_robot
from .urdf import parse_urdf

__all__ = ["load_urdf", "load_urdf_string", "urdf_link_poses", "AuditRecord", "RobotDescription", "parse_urdf",
           "load_mjcf", "load_mjcf_string", "load_robot"]
