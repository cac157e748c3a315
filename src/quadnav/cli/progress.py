"""Progress bars on stderr for the long stages (planning, simulation)."""

from __future__ import annotations

import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager

from tqdm import tqdm


@contextmanager
def planning_bar(name: str, quiet: bool) -> Iterator[Callable[[float, float], None]]:
    """A bar for a search; yields ``progress(fraction of the budget, best length m)``.
    The bar appears at the first report, so input refused before the search leaves
    stderr to the one-line error."""
    bars: list[tqdm] = []

    def progress(fraction: float, best: float) -> None:
        if not bars:
            bars.append(tqdm(total=100, desc=name, unit="%", leave=False, disable=quiet,
                             file=sys.stderr, bar_format="{desc}: {bar} {n:.0f}%{postfix}"))
        bars[0].set_postfix_str(f"best {best:.2f} m" if best < float("inf") else "no path yet",
                                refresh=False)
        bars[0].update(100 * fraction - bars[0].n)

    try:
        yield progress
    finally:
        for bar in bars:
            bar.close()


@contextmanager
def fraction_bar(name: str, quiet: bool) -> Iterator[Callable[[float], None]]:
    """A bar for a job that reports the fraction done; yields ``progress(fraction)``.
    The bar appears at the first report, so it can be set up before earlier stages."""
    bars: list[tqdm] = []

    def progress(fraction: float) -> None:
        if not bars:
            bars.append(tqdm(total=100, desc=name, unit="%", leave=False, disable=quiet,
                             file=sys.stderr, bar_format="{desc}: {bar} {n:.0f}%"))
        bars[0].update(100 * fraction - bars[0].n)

    try:
        yield progress
    finally:
        for bar in bars:
            bar.close()
