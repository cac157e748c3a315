"""Progress bars on stderr for the long stages (planning, simulation, batches), drawn
only on a terminal."""

from __future__ import annotations

import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import TYPE_CHECKING, Any

from tqdm import tqdm

if TYPE_CHECKING:  # the planning stage is imported only by the commands that plan
    from quadnav.planning.result import Progress


def terminal_bar(quiet: bool, **options: Any) -> tqdm:
    """A tqdm bar on stderr (``options``: tqdm's), drawn only when stderr is a terminal and
    not ``quiet``: piped or redirected to a file, stderr keeps only warnings and errors,
    with no carriage returns or cursor moves to litter a log."""
    return tqdm(file=sys.stderr, disable=quiet or not sys.stderr.isatty(), **options)


@contextmanager
def percent_bar(name: str, quiet: bool) -> Iterator[Callable[[float, str | None], None]]:
    """A :func:`terminal_bar` of the percent of a job done; yields ``progress(fraction
    done, postfix)``, ``postfix`` a few words shown after the percent (None: those shown
    last). The bar appears at the first report, so input refused before the job starts
    leaves stderr to the one-line error, and it can be set up before earlier stages."""
    bars: list[tqdm] = []

    def progress(fraction: float, postfix: str | None) -> None:
        if not bars:
            bars.append(terminal_bar(quiet, total=100, desc=name, unit="%", leave=False,
                                     bar_format="{desc}: {bar} {n:.0f}%{postfix}"))
        if postfix is not None:
            bars[0].set_postfix_str(postfix, refresh=False)
        bars[0].update(100 * fraction - bars[0].n)

    try:
        yield progress
    finally:
        for bar in bars:
            bar.close()


@contextmanager
def planning_bar(name: str, quiet: bool) -> Iterator[Progress]:
    """A :func:`percent_bar` for a search; yields ``progress(fraction of the budget, best
    length m)``."""
    with percent_bar(name, quiet) as progress:
        yield lambda fraction, best: progress(
            fraction, f"best {best:.2f} m" if best < float("inf") else "no path yet")


@contextmanager
def fraction_bar(name: str, quiet: bool) -> Iterator[Callable[[float], None]]:
    """A :func:`percent_bar` for a job that reports the fraction done alone; yields
    ``progress(fraction)``."""
    with percent_bar(name, quiet) as progress:
        yield lambda fraction: progress(fraction, None)
