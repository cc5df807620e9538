"""View: robots and trajectories drawn (offline HTML animations, PNG thumbnails and plots, the web player).

May import every stage below it (base, dynamics, parsers, scenes, integration); never compare.
"""

from .animation import write_trajectory_page
from .plots import plot_trajectory
from .thumbnail import render_thumbnail

__all__ = ["write_trajectory_page", "render_thumbnail", "plot_trajectory"]
