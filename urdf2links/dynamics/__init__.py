"""Dynamics: the tree of links (frames, coordinates, H) and Lagrange's equations in trace form, compiled -> Model.

May import only the base modules (errors, ranges); nothing that reads files, scenes, integration, view or compare.
"""

from .loads import Wrench
from .model import Model
from .transforms import BaseState, base_transforms
from .tree import LinkSpec, LinkTree, build_tree, pseudo_inertia_from

__all__ = ["Model", "LinkSpec", "LinkTree", "build_tree", "pseudo_inertia_from", "Wrench", "BaseState",
           "base_transforms"]
