"""Making and saving figures: each figure has an Agg canvas of its own (no pyplot, which
keeps every figure open until it is closed, and costs its import); files are of checked
types, written whole or not at all."""

from __future__ import annotations

import gc
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import BinaryIO

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from PIL import Image

from quadnav.errors import QuadnavError
from quadnav.files import atomic_output

#: Resolution of the figures, dots per inch: they are drawn to be shown about 1100 pixels
#: wide (the report's width).
DPI = 120
#: zlib level of a PNG file: at 3 the four figures of ``quadnav fly`` encode in 0.11 s of
#: CPU instead of 0.14 s at 6 (PIL's and matplotlib's default), in files under 1 % larger.
PNG_COMPRESSION = 3


def new_figure(size: tuple[float, float]) -> Figure:
    """An empty figure ``size`` (width, height) inches at :data:`DPI`, with a constrained
    layout, drawn by its own Agg canvas."""
    fig = Figure(figsize=size, dpi=DPI, layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def check_figure_path(path: str | Path) -> str:
    """The image format named by ``path``'s extension; QuadnavError if unsupported."""
    suffix = Path(path).suffix.lower().lstrip(".")
    supported = Figure().canvas.get_supported_filetypes()
    if suffix not in supported:
        raise QuadnavError(f"{path}: expected an image file name ending in one of "
                           f"{', '.join('.' + s for s in sorted(supported))}")
    if not Path(path).parent.is_dir():
        raise QuadnavError(f"{path}: folder {str(Path(path).parent)!r} does not exist")
    return suffix


def write_png(fig: Figure, target: str | Path | BinaryIO) -> None:
    """Draw ``fig`` once and write it to ``target`` (a file name or a binary file) as a
    PNG image of its pixels at its dpi: RGB when it is opaque (as every figure with
    matplotlib's default white face is: a quarter fewer bytes to compress than the RGBA
    that ``savefig`` writes), else RGBA, at :data:`PNG_COMPRESSION`. A figure made
    without an Agg canvas (not by :func:`new_figure`) is given one."""
    canvas = fig.canvas if isinstance(fig.canvas, FigureCanvasAgg) else FigureCanvasAgg(fig)
    canvas.draw()
    image = Image.fromarray(np.asarray(canvas.buffer_rgba()))
    if image.getextrema()[3][0] == 255:
        image = image.convert("RGB")
    image.save(target, format="png", compress_level=PNG_COMPRESSION, dpi=(fig.dpi, fig.dpi))


def save_figure(fig: Figure, path: str | Path) -> None:
    """Save ``fig`` (a PNG with :func:`write_png`); the file at ``path`` is either
    complete or untouched."""
    fmt = check_figure_path(path)
    with atomic_output(path) as tmp:
        if fmt == "png":
            write_png(fig, tmp)
        else:
            fig.savefig(tmp, format=fmt)


@contextmanager
def collector_spared() -> Iterator[None]:
    """Keep the objects alive now (a command's imports and its run: hundreds of thousands)
    out of the garbage collector's full collections while figures are made and saved,
    which make so many short-lived objects that it collects again and again; they are
    handed back to it afterwards, so nothing is kept that would have been freed."""
    gc.freeze()
    try:
        yield
    finally:
        gc.unfreeze()
