"""What the commands show a person: progress on stderr, messages, and paths as a user typed them."""

from __future__ import annotations

import sys
from pathlib import Path

from .compilation import clock     # the elapsed seconds shown leave numba's compilation out (one clock)

__all__ = ["Progress", "TaskBar", "err", "shown_path"]


def err(message: str) -> None:
    """A line on stderr, flushed (progress and diagnostics; stdout keeps the results)."""
    print(message, file=sys.stderr, flush=True)


def shown_path(path) -> str | None:
    """``path`` relative to the working folder when it lies inside it, else absolute (reports show
    paths the way a user in that folder would type them)."""
    if path is None:
        return None
    p, here = Path(path).resolve(), Path.cwd().resolve()
    return str(p.relative_to(here)) if p.is_relative_to(here) else str(p)


class Progress:
    """A one-line progress bar on stderr, redrawn at most 10 times a second; silent when stderr is
    not a terminal or ``enabled`` is False."""

    def __init__(self, t_end: float, *, label: str = "", enabled: bool | None = None, stream=None):
        self.stream = stream or sys.stderr
        self.enabled = (self.stream.isatty() if enabled is None else enabled)
        self.t_end, self.label = t_end, label
        self.start = clock()
        self.last = 0.0

    def __call__(self, t, y=None):
        if not self.enabled:
            return
        now = clock()
        if now - self.last < 0.1 and t < self.t_end:
            return
        self.last = now
        frac = min(max(t / self.t_end, 0.0), 1.0) if self.t_end > 0 else 1.0
        bar = "#" * int(30 * frac)
        self.stream.write(f"\r{self.label} [{bar:<30}] {100 * frac:5.1f}%  t = {t:.4g} s  {now - self.start:.1f} s wall")
        self.stream.flush()

    def close(self):
        if self.enabled:
            self(self.t_end)
            self.stream.write("\n")
            self.stream.flush()


class TaskBar:
    """Progress of a set of tasks on stderr: one line per finished task (:meth:`line`), printed above
    an overall bar ``[####    ] k/total`` that is redrawn after each line. The lines are printed
    whenever ``enabled``; the bar only when the stream is a terminal (a log keeps the lines alone)."""

    def __init__(self, total: int, *, label: str = "", enabled: bool = True, stream=None):
        self.stream = stream or sys.stderr
        self.enabled = bool(enabled)
        self.bar = self.enabled and self.stream.isatty()
        self.total, self.label, self.done = int(total), label, 0
        self.start = clock()
        self._draw()

    def _draw(self) -> None:
        if not self.bar:
            return
        frac = self.done / self.total if self.total else 1.0
        self.stream.write(f"\r{self.label} [{'#' * int(30 * frac):<30}] {self.done}/{self.total}  "
                          f"{clock() - self.start:.0f} s")
        self.stream.flush()

    def line(self, text: str, *, advance: bool = True) -> None:
        """Print ``text`` on its own line (above the bar) and, with ``advance``, count one task done."""
        if advance:
            self.done += 1
        if not self.enabled:
            return
        if self.bar:
            self.stream.write("\r\033[K")
        self.stream.write(text + "\n")
        self._draw()

    def close(self) -> None:
        if self.bar:
            self.stream.write("\n")
            self.stream.flush()
