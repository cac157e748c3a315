"""Saving figures: checked file types, written whole or not at all."""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
from matplotlib.figure import Figure

from quadnav.errors import QuadnavError
from quadnav.files import atomic_output


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


def save_figure(fig: Figure, path: str | Path) -> None:
    """Save and close ``fig``; the file at ``path`` is either complete or untouched."""
    fmt = check_figure_path(path)
    try:
        with atomic_output(path) as tmp:
            fig.savefig(tmp, format=fmt)
    finally:
        plt.close(fig)
