"""``urdf2links simulate`` (one scene, its trajectory saved), ``urdf2links sweep`` (many initial states of one
scene at once) and ``urdf2links cache`` (numba's cache of the code these runs compile): the commands that run
scenes with the project alone, without MuJoCo."""

from __future__ import annotations

import sys
import warnings

from ..errors import SceneError
from .options import INPUT, add_animation_option, add_max_wall, add_scene_input

__all__ = ["add_simulate", "run_simulate", "add_sweep", "run_sweep", "add_cache", "run_cache"]


def add_simulate(p) -> None:
    """The ``simulate`` command's options."""
    add_scene_input(p, scene_help=INPUT + "; a robot runs in its default scene: gravity, fixed base, at rest, URDF "
                                          "damping, 1 s")
    p.add_argument("--t-end", type=float, help="override [run] t_end (s)")
    p.add_argument("--method", help="auto (the default: DOP853, Radau5 while stiff), RK45, DOP853, Radau5, Radau, "
                                    "BDF, LSODA, RK4 or midpoint")
    p.add_argument("--rtol", type=float)
    p.add_argument("--dt", type=float, help="step for RK4 and midpoint (s)")
    p.add_argument("--out", default="out", help="folder for .npz, .csv and .png (default: out)")
    p.add_argument("--plot", action="store_true", help="also plot coordinates and energy against time (PNG)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.add_argument("--animate", action="store_true", help="also write <out>/<scene>.html: the robot moving, with "
                   "play/pause and a time slider (self-contained, works offline)")
    add_animation_option(p)
    add_max_wall(p)


def _scene_and_model(args):
    """The command's scene (a scene file, or a robot's default scene, written out with ``--write-scene``) and its
    loaded robot: ``(scene, model)``. A default scene's inertia audit is not warned about (``inspect`` shows it)."""
    from ..scenes.scene_toml import scene_from_args, write_scene_option

    scene = scene_from_args(args)
    write_scene_option(args, scene)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore" if scene.path is None else "default")  # default scene: audit in inspect
        model = scene.model()
    return scene, model


def _output(args, scene, model):
    """``(folder, stem)`` of the command's files: ``--out``, made; the scene's name (a default scene's prefixed
    with its robot's label)."""
    from pathlib import Path

    from ..scenes.scene import robot_label

    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    return out, scene.name if scene.path is not None else f"{robot_label(scene, model)}_{scene.name}"  # default scene


def run_simulate(args) -> int:
    """``urdf2links simulate``: the scene integrated (:func:`urdf2links.integration.simulate.simulate`), the
    trajectory saved as .npz and .csv, a line of figures, the notes; a plot and an animation when asked."""
    from ..integration.simulate import describe_stretches, simulate
    from ..scenes.limits import LimitExcursion

    scene, model = _scene_and_model(args)
    traj = simulate(scene, model=model, t_end=args.t_end, method=args.method, rtol=args.rtol, dt=args.dt,
                    progress=False if args.quiet else None, max_wall=args.max_wall)
    out, stem = _output(args, scene, model)
    npz = traj.save_npz(out / f"{stem}.npz")
    csv_path = traj.save_csv(out / f"{stem}.csv")
    s = traj.stats
    print(f"{scene.name}: {model.name}, {model.n} coordinates, t = 0..{traj.t[-1]:g} s, {s['method']}"
          f" (rtol {s['rtol']:g}" + (f", dt {s['dt']:g}" if s["dt"] else "") + f"): {s['nsteps']} steps, "
          f"{s['nfev']} evaluations, {s['wall_time']:.3f} s wall")
    print(f"  terms: {', '.join(s['terms'])}; energy balance error {traj.energy_error:.2e} (relative)")
    if s["stretches"]:
        print(f"  methods: {s['methods_used']}")
        for line in describe_stretches(s["stretches"]):
            print(f"    {line}")
    for note in [*model.info.get("missing_files", ()), *s["spring_notes"]]:     # issue 42: a missing mesh named
        print(f"  note: {note}")
    for e in s["limit_excursions"]:
        print(f"  note: {LimitExcursion(**e).text()}")
    c = s.get("constraints")       # issue 45: the loop's residual and the change points passed
    if c is not None and c["rows"]:
        print(f"  constraints: max |Phi| {c['max_residual']:.2e}; {c['method']}")
        for ev in c.get("events", ()):
            print(f"  note: {ev['what']}")
    print(f"  wrote {npz} and {csv_path}")
    if args.plot:
        from ..view.plots import plot_trajectory

        png = plot_trajectory(traj, out / f"{stem}.png")
        print(f"  plot {png}")
    if args.animate:
        from ..view.animation import write_trajectory_page
        from ..view.visuals import scene_shapes

        page = write_trajectory_page(out / f"{stem}.html", traj, model, fps=args.animation_fps or 30.0,
                                     base=scene.base_state if scene.base is not None else None,
                                     shapes=scene_shapes(scene, model))
        print(f"  animation {page} ({page.stat().st_size / 1e6:.1f} MB)")
    return 0


def add_sweep(p) -> None:
    """The ``sweep`` command's options."""
    add_scene_input(p, seed=False)
    p.add_argument("--count", type=int, default=100, help="number of initial states (default 100)")
    p.add_argument("--seed", type=int, default=0, help="seed of the states' draw (and of --q0 random; default 0)")
    p.add_argument("--spread", type=float, default=0.1, help="half-width of the uniform draw around q0, rad or m "
                   "(default 0.1)")
    p.add_argument("--t-end", type=float, help="override [run] t_end (s)")
    p.add_argument("--samples", type=int, help="sample times on [0, t_end] (default: the scene's)")
    p.add_argument("--method", choices=("DOP853", "RK45"), help="default DOP853 (or the scene's, if one of these)")
    p.add_argument("--rtol", type=float)
    p.add_argument("--scheduler", metavar="ADDRESS", help="split the states across the Dask cluster whose scheduler "
                   "is at ADDRESS (pip install 'urdf2links[distributed]')")
    p.add_argument("--chunks", type=int, help="with --scheduler: number of chunks (default: one per worker)")
    p.add_argument("--out", default="out", help="folder of the .npz (default: out)")


def run_sweep(args) -> int:
    """``urdf2links sweep``: seeded initial states around the scene's, integrated by the compiled batch
    loop here or split across a Dask cluster (``--scheduler``); an .npz of the trajectories."""
    import numpy as np

    from ..integration.batch import simulate_batch, sweep_states

    scene, model = _scene_and_model(args)
    try:
        q0, qd0 = sweep_states(scene, model, args.count, seed=args.seed, spread=args.spread)
    except ValueError as exc:
        raise SceneError(f"urdf2links sweep: {exc}") from None
    client = None
    if args.scheduler:
        from ..integration.distributed import connect

        try:
            client = connect(args.scheduler)
        except (ImportError, OSError) as exc:
            print(f"urdf2links sweep: error: {exc}", file=sys.stderr)
            return 2
    try:
        res = simulate_batch(scene, q0, qd0, t_end=args.t_end, samples=args.samples, method=args.method,
                             rtol=args.rtol, model=model, client=client, chunks=args.chunks)
    finally:
        if client is not None:
            client.close()
    out, stem = _output(args, scene, model)
    npz = out / f"{stem}_sweep.npz"
    np.savez_compressed(npz, t=res.t, q=res.q, qd=res.qd, work=res.work, nfev=res.nfev, status=res.status, q0=q0,
                        qd0=qd0, coordinate_names=np.array(res.coordinate_names))
    where = f"on {len(res.chunks)} chunks at {args.scheduler}" if client is not None else "on this machine"
    for note in res.notes:
        print(f"note: {note}")
    print(f"{scene.name}: {model.name}, {args.count} initial states (seed {args.seed}, spread {args.spread:g}), "
          f"t = 0..{res.t[-1]:g} s, {res.method}, {where}: {int(np.sum(res.status == 1))} reached the end, "
          f"{res.wall_time:.2f} s wall, {int(res.nfev.sum())} evaluations")
    spread = res.q[:, -1, :].std(axis=0) if len(res.q) > 1 else np.zeros(model.n)
    print(f"  final spread of q (std over the sweep): largest {float(spread.max(initial=0.0)):.3g} "
          f"({model.coordinate_names[int(np.argmax(spread))] if model.n else '-'})")
    print(f"  wrote {npz}")
    return 0 if np.all(res.status == 1) else 1


def add_cache(p) -> None:
    """The ``cache`` command's options: ``--list`` (the default) or ``--clear [--all]``."""
    g = p.add_mutually_exclusive_group()
    g.add_argument("--list", action="store_true", help="the cache's folders: size, and the install each serves (default)")
    g.add_argument("--clear", action="store_true", help="remove the folders of other and removed installs")
    p.add_argument("--all", action="store_true", help="with --clear: this install's too (the next run compiles again)")


def run_cache(args) -> int:
    """``urdf2links cache``: numba's cache folder, each of its folders with its size and the install it serves;
    ``--clear`` removes the stale ones first (``--all``: every one)."""
    from ..numba_cache import cache_dir, cache_folders, clear_cache

    folder = cache_dir()
    if args.clear:
        gone = clear_cache(folder, which="all" if args.all else "stale")
        print(f"{folder}: removed {len(gone)} folder(s), {sum(f.size for f in gone) / 1e6:.1f} MB"
              + ("" if args.all else " (other installs' and removed installs'; --all removes this install's too)"))
    rows = cache_folders(folder)
    if not rows:
        print(f"{folder}: empty (nothing compiled yet; the first run compiles and fills it)")
        return 0
    words = {"current": "this install", "other": "another install", "gone": "sources removed (stale)",
             "unknown": "no origin recorded: an older version's, or being written (stale)"}
    print(f"{folder}: {len(rows)} folder(s), {sum(f.size for f in rows) / 1e6:.1f} MB")
    for f in rows:
        print(f"  {f.path.name:<32} {f.size / 1e6:7.1f} MB {f.files:5d} files  {words[f.status]}"
              + (f": {f.source}" if f.source is not None else ""))
    return 0
