"""Errors raised by urdf2links.

Every error that comes from a robot description is a :class:`DescriptionError` (a
``ValueError``, so ``except ValueError`` still catches them): a :class:`URDFError` for URDF and
xacro files, an :class:`MJCFError` for MuJoCo's MJCF files. Messages name
the file, the element (link, joint, attribute) and the value, and say what would
fix the input.
"""

from __future__ import annotations

__all__ = [
    "DescriptionError",
    "URDFError",
    "MJCFError",
    "URDFSyntaxError",
    "URDFStructureError",
    "URDFValueError",
    "InertiaError",
    "MeshError",
    "DynamicsError",
    "SceneError",
    "IntegrationError",
]


class DescriptionError(ValueError):
    """Base class of every error raised while importing a robot description (URDF, xacro, MJCF).

    ``problem`` is the defect alone (without file, line and fix), for a note when the reader
    tolerates it; the whole message when not given."""

    def __init__(self, message: str = "", *, problem: str | None = None):
        super().__init__(message)
        self.problem = problem if problem is not None else message


class URDFError(DescriptionError):
    """An error raised while importing a URDF (or xacro) description."""


class MJCFError(DescriptionError):
    """An MJCF file that cannot become a tree of links: MuJoCo's compiler refused it (its own words
    quoted, with the file), or it holds what a tree of links cannot be (the element, the body or
    joint, and what would fix it)."""


class URDFSyntaxError(URDFError):
    """The file is not well-formed XML, or not a URDF ``<robot>`` document."""


class URDFStructureError(URDFError):
    """The links and joints do not form a tree (unknown names, cycles, two roots, duplicates)."""


class URDFValueError(URDFError):
    """An attribute holds a value that cannot be used (NaN, negative mass, unknown joint type, ...)."""


class InertiaError(URDFError):
    """An inertia is not physically consistent and the policy is ``inertia="strict"``."""


class MeshError(URDFError):
    """A mesh named by the description cannot be found or read."""


class DynamicsError(ArithmeticError):
    """The equations of motion cannot be solved at a state (mass matrix not positive definite).

    Attributes ``q`` (the configuration), ``coordinates`` (names of the coordinates involved) and
    ``row`` (the row of a batch, or None) say where.
    """

    def __init__(self, message: str, *, q=None, coordinates: tuple[str, ...] = (), row: int | None = None):
        super().__init__(message)
        self.q = q
        self.coordinates = tuple(coordinates)
        self.row = row


class SceneError(ValueError):
    """A scene file cannot be used: unknown key, link or coordinate, wrong type or unit.

    Messages name the file, the key and the valid choices.
    """


class IntegrationError(RuntimeError):
    """An integration cannot continue: a Newton iteration that does not converge, a state or a
    right-hand side that is no longer finite. The message says where (time, step) and why."""
