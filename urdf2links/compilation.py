"""numba's compilation, kept out of every reported time and shown while it runs.

numba compiles a function at its first call in a process (or loads it from the disk cache,
:mod:`urdf2links.numba_cache`). A cold first run of a scene spends seconds there, in the middle of the
code it times. This module watches numba's ``numba:compile`` events (numba's public event API) and:

- :func:`clock` is ``time.perf_counter()`` standing still while numba compiles: a duration taken
  with it (``clock() - start``) leaves compilation out, wherever in the timed code it happened (the
  integration loops at their first call, Radau5 when a run of ``auto`` turns stiff, a batch kernel);
- :func:`ensure` compiles, or loads from the cache, a compiled function for the arguments it is about
  to get, before a timed region (loading a large function takes tens of milliseconds, and raises no
  event), and adds that time to the compilation too;
- :func:`seconds` and :func:`functions` say how much was compiled in this process; :func:`elsewhere`
  adds what worker processes compiled (``check --jobs``, a sweep on a Dask cluster: their durations
  leave it out with their own clock); :func:`summary` is the one line the command prints, once
  ("compiling the solver for this machine, first run only: 14 s"), and :func:`show_progress` turns on
  a line on stderr that counts the seconds while numba compiles (the command line turns it on; the
  library stays silent); :func:`per_function` the
  seconds of each function (``URDF2LINKS_COMPILE_LOG=FILE`` writes them at exit);
- :func:`one_signature` compiles a kernel once whatever constants its callers pass;
- :func:`kernel` compiles a function that allocates nothing without numba's reference counting.

Nothing here imports numba until a compiled function is about to be used (:func:`watch`, called by
:mod:`urdf2links.numba_cache` when it installs the cache): ``import urdf2links`` stays fast.

**numba's private hooks.** :func:`one_signature` replaces a dispatcher's ``get_call_template`` and
:func:`kernel` / :func:`c_function` pass the ``_nrt`` option: neither is numba's public API (explicit
signatures given to ``njit`` would compile every kernel eagerly at import, for every type of array it
may get, which is what the cold start avoids). numba is therefore pinned to the tested minor release
(pyproject.toml), and ``tests/test_numba_hooks.py`` fails if either hook stops doing what it does here
(docs/speed.md, "numba's private hooks").
"""

from __future__ import annotations

import sys
import threading
import time

__all__ = ["clock", "ensure", "seconds", "functions", "per_function", "summary", "show_progress", "watch", "WHAT",
           "one_signature", "c_function", "kernel", "elsewhere", "Snapshot", "snapshot"]

#: How the command line names what is compiled.
WHAT = "compiling the solver for this machine, first run only"


class _Tracker:
    """Top-level compilations (numba compiles callees inside their caller: only the outermost event
    counts), their total seconds and the functions compiled; the progress line's state."""

    def __init__(self):
        self.lock = threading.Lock()
        self.depth = 0
        self.since = 0.0            # perf_counter() when the outermost compilation (or ensure) started
        self.total = 0.0            # seconds of finished compilations
        self.names: list[str] = []
        self.stack: list = []       # [name, start, seconds of nested compilations] per open compilation
        self.per_function: dict = {}    # name -> [seconds of its own, seconds with its callees, compilations]
        self.progress = None        # the stream of the progress line, or None
        self.ticker = None
        self.shown = False          # a progress line is on the screen
        self.other = [0.0, []]      # compilation in worker processes: seconds, names (elsewhere)

    def begin(self, name: str | None = None):
        with self.lock:
            if self.depth == 0:
                self.since = time.perf_counter()
            self.depth += 1
            if name:
                self.names.append(name)
            self.stack.append([name, time.perf_counter(), 0.0])
            if self.progress is not None and self.ticker is None:
                self.ticker = threading.Thread(target=self._tick, name="urdf2links-compiling", daemon=True)
                self.ticker.start()

    def end(self, compiled: str | None = None):
        """Close the innermost compilation; ``compiled`` names an unnamed one (:func:`c_function`) when
        it compiled something rather than loading it from the cache."""
        with self.lock:
            self.depth -= 1
            if self.stack:
                name, start, nested = self.stack.pop()
                if name is None and compiled:
                    name = compiled
                    self.names.append(name)
                took = time.perf_counter() - start
                if self.stack:
                    self.stack[-1][2] += took
                if name:
                    rec = self.per_function.setdefault(name, [0.0, 0.0, 0])
                    rec[0] += took - nested
                    rec[1] += took
                    rec[2] += 1
            if self.depth == 0:
                self.total += time.perf_counter() - self.since
                self._clear()

    def ongoing(self) -> float:
        with self.lock:
            return self.total + (time.perf_counter() - self.since if self.depth > 0 else 0.0)

    def _clear(self):
        if self.shown and self.progress is not None:
            if self.progress.isatty():
                self.progress.write("\r\033[K")
                self.progress.flush()
            self.shown = False

    def _tick(self):
        """The progress line: after 1 s of compilation, the seconds so far (redrawn each second on a
        terminal; a log gets one line saying that it compiles)."""
        told = False
        while True:
            time.sleep(0.25)
            with self.lock:
                stream = self.progress
                if stream is None:
                    self.ticker = None
                    return
                busy = time.perf_counter() - self.since if self.depth > 0 else 0.0
                if busy < 1.0:
                    continue
                if stream.isatty():
                    stream.write(f"\r{WHAT}: {self.total + busy:.0f} s ...")
                    stream.flush()
                    self.shown = True
                elif not told:
                    stream.write(f"{WHAT} ...\n")
                    stream.flush()
                    told = True


_T = _Tracker()
_WATCHING: list = []


def watch() -> None:
    """Listen to numba's ``numba:compile`` events (once per process; imports numba)."""
    if _WATCHING:
        return
    from numba.core import event

    class Listener(event.Listener):
        def on_start(self, ev):
            fn = getattr(ev.data.get("dispatcher"), "py_func", None)
            _T.begin(f"{getattr(fn, '__module__', '?')}.{getattr(fn, '__qualname__', fn)}")

        def on_end(self, ev):
            _T.end()

    listener = Listener()
    event.register("numba:compile", listener)
    import atexit

    atexit.register(_write_log)
    _WATCHING.append(listener)


def clock() -> float:
    """``time.perf_counter()`` minus every second numba has spent compiling in this process (and
    :func:`ensure` loading): the difference of two readings leaves compilation out."""
    return time.perf_counter() - _T.ongoing()


def seconds() -> float:
    """Seconds spent compiling (and in :func:`ensure`) in this process so far."""
    return _T.ongoing()


def functions() -> list[str]:
    """The functions numba compiled in this process (``module.qualname``), in order, each once."""
    return list(dict.fromkeys(_T.names))


class Snapshot:
    """What this process had compiled at one moment (:func:`snapshot`); ``since()`` what it compiled after:
    ``(seconds, functions)``, for a worker process to send back with its result (:func:`elsewhere`)."""

    def __init__(self):
        self.seconds, self.count = seconds(), len(_T.names)

    def since(self) -> tuple[float, list[str]]:
        return seconds() - self.seconds, list(dict.fromkeys(_T.names[self.count:]))


def snapshot() -> Snapshot:
    """:class:`Snapshot` of this process's compilation now."""
    return Snapshot()


def elsewhere(seconds_: float, names=()) -> None:
    """Count compilation done in other processes (a ``check --jobs`` worker, a Dask worker): ``seconds_``
    and the ``names`` of the functions compiled there. It never touches :func:`clock` (that compilation
    did not happen here); :func:`summary` shows it, once, with this process's own."""
    with _T.lock:
        _T.other[0] += float(seconds_)
        _T.other[1].extend(names)


def ensure(dispatcher, args) -> None:
    """Compile, or load from the disk cache, ``dispatcher`` for the types of ``args`` (a tuple of the
    arguments of its next call) unless it has that variant already; the time counts as compilation
    (:func:`clock`), so that the timed call that follows runs the compiled code at once."""
    watch()
    sig = tuple(dispatcher.typeof_pyval(a) for a in args)
    if sig in dispatcher.overloads:
        return
    _T.begin()
    try:
        dispatcher.compile(sig)
    finally:
        _T.end()


def c_function(pyfunc, signature, *, refcounts: bool = True):
    """``pyfunc`` compiled (or loaded from the disk cache) as a C function of ``signature`` (numba's
    ``cfunc``): a first-class function whose type is its signature alone, so that a compiled function
    it is passed to is compiled once for every such function (the scene's right-hand side of each
    combination of effects, :func:`urdf2links.scenes.scene_kernels.rhs_function`). numba raises no
    compile event for a ``cfunc``: its time counts as compilation here, and it is named among the
    compiled functions when it was not in the cache. ``refcounts=False`` compiles it without numba's
    reference counting, as :func:`kernel`, for a function that allocates nothing and makes no array of
    a pointer (the scene's right-hand side; MuJoCo's callback makes arrays of MuJoCo's pointers)."""
    from numba import cfunc

    watch()
    name = f"{pyfunc.__module__}.{pyfunc.__qualname__}"
    _T.begin()
    compiled = None
    try:
        compiled = cfunc(signature, cache=True, _nrt=refcounts)(pyfunc)
    finally:
        _T.end(compiled=name if compiled is not None and not compiled.cache_hits else None)
    return compiled


def per_function() -> dict:
    """``{name: {"own_s", "with_callees_s", "compilations"}}`` of every function numba compiled in this
    process: its own seconds (its callees' compilations, nested in it, left out), with them, and how
    many variants (docs/speed.md's table of compile times per kernel)."""
    with _T.lock:
        return {k: {"own_s": v[0], "with_callees_s": v[1], "compilations": v[2]} for k, v in _T.per_function.items()}


def _write_log() -> None:
    """At exit, when ``URDF2LINKS_COMPILE_LOG`` names a file: :func:`per_function` as JSON there."""
    import json
    import os

    path = os.environ.get("URDF2LINKS_COMPILE_LOG")
    if path and _T.per_function:
        with open(path, "w", encoding="utf-8") as fh:
            json.dump({"seconds": seconds(), "functions": per_function()}, fh, indent=1)


def summary(cache_folder=None) -> str | None:
    """The command's one line about compilation: None when nothing was compiled, here or in a worker
    process (:func:`elsewhere`)."""
    with _T.lock:
        other_s, other_names = _T.other[0], list(_T.other[1])
    names = list(dict.fromkeys(functions() + other_names))
    if not names:
        return None
    where = f"; cached in {cache_folder}: `urdf2links cache --list`" if cache_folder else ""
    workers = f", {other_s:.1f} s of it in worker processes" if other_names else ""
    return (f"{WHAT}: {seconds() + other_s:.1f} s ({len(names)} compiled functions{workers}{where}; "
            "no reported time includes it)")


def show_progress(on: bool = True, *, stream=None) -> None:
    """Show compilation on ``stream`` (default stderr) while it runs (:class:`_Tracker`), or not (``on`` False)."""
    with _T.lock:
        _T.progress = (stream or sys.stderr) if on else None


def one_signature(dispatcher):
    """``dispatcher`` (a compiled function) compiled once for the types of its arguments, whatever
    constants its callers pass: numba types a constant argument by its value (``0`` is
    ``Literal[int](0)``, ``True`` is ``Literal[bool](True)``) and compiles a callee anew for every
    pattern of constants it is called with (the recursive pass was compiled five times for a
    pendulum). Callers' constants are widened to their plain types (``int64``, ``bool``) here;
    ``None`` stays ``none`` (the effects' markers, :mod:`urdf2links.scenes.scene_kernels`).
    ``get_call_template`` is numba's private method through which a compiled caller types (and
    compiles) a call to a dispatcher; the instance's own replaces it (module doc: pinned, tested)."""
    from numba.core import types

    resolve = getattr(dispatcher, "get_call_template", None)
    if resolve is None:         # numba's private hook is gone: say so rather than compile a variant per constant
        import numba

        raise RuntimeError(f"urdf2links.compilation.one_signature: numba {numba.__version__}'s dispatcher has no "
                           "get_call_template (a private hook); install the numba release pyproject.toml pins "
                           "(docs/speed.md, \"numba's private hooks\")")

    def get_call_template(args, kws):
        return resolve(tuple(types.unliteral(a) for a in args), {k: types.unliteral(v) for k, v in kws.items()})

    dispatcher.get_call_template = get_call_template
    return dispatcher


def kernel(fn, *, error_model: str = "python"):
    """``fn`` compiled like ``njit(cache=True)``, without numba's reference counting (its ``_nrt=False``
    option), for a function that allocates nothing and only reads and writes the arrays it is given
    (the passes over the tree, the factorizations, the scene's terms). numba otherwise adds an atomic
    increment and decrement of each array argument's count to a function that loops, and the
    optimizer removes only some of them: they took about a fifth of the time of one forward-dynamics
    evaluation of UR5 (0.13 of 0.77 us, ``perf`` on the compiled loop), more in a batch, where the
    threads share the counts. A function that allocates is refused at compilation ("NRT required but
    not enabled", or a typing error for ``np.zeros``), so the option cannot hide a leak.
    ``tests/test_cold_start.py`` checks that the compiled kernels carry no reference counting;
    ``tests/test_numba_hooks.py`` that the private option still works (module doc). ``error_model="numpy"``:
    a division by zero gives inf or nan (IEEE) instead of raising, for loops that must stay vectorizable
    and may divide by a lane's zero pivot (:mod:`urdf2links.dynamics.lane_factor`)."""
    from numba import njit

    return njit(cache=True, _nrt=False, error_model=error_model)(fn)
