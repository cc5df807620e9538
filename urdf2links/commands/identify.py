"""``urdf2links identify DESCRIPTION --against OTHER``: the options; the handler
(:func:`urdf2links.compare.identify.command.identify_command`) is imported only when it runs (it imports MuJoCo)."""

from __future__ import annotations

__all__ = ["add_identify", "run_identify"]


def add_identify(p) -> None:
    """The ``identify`` command's options."""
    p.add_argument("file", help="the description whose parameters to fit (URDF, xacro or MJCF)")
    p.add_argument("--against", metavar="OTHER", help="the description whose motion (in MuJoCo) to fit to")
    p.add_argument("--map", action="append", default=[], metavar="JOINT=OTHER_JOINT",
                   help="a joint of the first file and its name in OTHER (repeat for more)")
    p.add_argument("--runs", type=int, default=3, help="excitation runs (seeds SEED.. SEED+RUNS-1; default 3)")
    p.add_argument("--seed", type=int, default=1, help="first seed of the excitation trajectories (default 1; the "
                   "held-out run uses SEED+100)")
    p.add_argument("--t-end", type=float, default=6.0, help="length of each run in s (default 6)")
    p.add_argument("--band", type=float, default=0.05, help="rows with |q'| below this (rad/s) are left out of the "
                   "fit: MuJoCo's frictionloss is a soft constraint there (default 0.05)")
    p.add_argument("--out", help="folder of the report (default out/reports/identify/<description>/)")
    p.add_argument("--write-urdf", metavar="OUT", help="write the corrected URDF, every change listed")
    p.add_argument("--write-mjcf", metavar="OUT", help="write the corrected MJCF (an MJCF description), every change listed")
    p.add_argument("--design", metavar="OUT.toml", help="instead: write an excitation scene, a periodic Fourier "
                   "series within the joint limits (position, velocity, effort) that lowers the condition number of "
                   "the base regressor, run by both engines (urdf2links compare OUT.toml)")
    from .identify_data import add_data_options     # issue 47: --data FILE (a robot's log)

    add_data_options(p)


def run_identify(args) -> int:
    if getattr(args, "data", None):                 # issue 47: a robot's log, no MuJoCo
        from .identify_data import run_identify_data

        return run_identify_data(args)
    from ..compare.identify.command import identify_command

    return identify_command(args)
