"""Figures of the reports: matplotlib figures without a display, as compact PNG (base64 or file)."""

from __future__ import annotations

import base64
import io
from pathlib import Path

__all__ = ["figure", "png_base64", "save_png"]


def figure(w, h, *, dpi: int = 90):
    from matplotlib.figure import Figure

    return Figure(figsize=(w, h), dpi=dpi, layout="constrained")


def png_base64(fig) -> str:
    """The figure as base64 PNG, reduced to a 256-colour palette (a third of the size; the plots
    are line art on white)."""
    from PIL import Image  # a declared dependency: a failure here is a bug, not a reason to fall back

    buf = io.BytesIO()
    fig.savefig(buf, format="png", metadata={"Software": None})
    img = Image.open(io.BytesIO(buf.getvalue())).convert("RGB").quantize(colors=256, method=Image.Quantize.MEDIANCUT)
    small = io.BytesIO()
    img.save(small, format="PNG", optimize=True)
    if small.tell() < buf.tell():
        buf = small
    return base64.b64encode(buf.getvalue()).decode("ascii")


def save_png(fig, path) -> Path:
    """The figure as a PNG file, palette-reduced like :func:`png_base64`."""
    path = Path(path)
    path.write_bytes(base64.b64decode(png_base64(fig)))
    return path
