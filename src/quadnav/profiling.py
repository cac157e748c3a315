"""Where a process spends its CPU time, stage by stage (``bench/batch.py --stages``).

A stage of a mission marks itself with ``with stage("name"):`` or the decorator
``@staged("name")``. Nothing is recorded (and a marked stage costs under a microsecond
more) unless a profile is open in this process: ``with profiled() as profile:``, on the
thread that flies. Then each run of a stage adds to ``profile.seconds[name]`` the CPU
seconds of the process (:func:`time.process_time`, all its threads: profile with one numba
thread) spent inside it, less those of the stages run inside it, and counts itself in
``profile.runs[name]``: the seconds of all stages add up to the time spent in any of them.

Work a map needs once (its inflated worlds, their block grids, the labels of the
connectivity proof) is a stage of its own, marked where it is made rather than where it
is found, so its runs count how often it was made.
"""

from __future__ import annotations

import functools
import time
from collections import Counter, defaultdict
from collections.abc import Callable, Iterator
from contextlib import AbstractContextManager, contextmanager, nullcontext
from dataclasses import dataclass, field
from typing import ParamSpec, TypeVar

Params = ParamSpec("Params")
Result = TypeVar("Result")


@dataclass
class StageProfile:
    """What the stages run while a profile was open spent.

    Attributes:
        seconds: CPU seconds of each stage by its name, its nested stages' excluded.
        runs: how many times each stage ran.
    """

    seconds: defaultdict[str, float] = field(default_factory=lambda: defaultdict(float))
    runs: Counter[str] = field(default_factory=Counter)
    _inner: _Run | None = field(default=None, repr=False)  # the innermost stage running


class _Run:
    """One run of a stage while ``profile`` is open (a context manager)."""

    def __init__(self, profile: StageProfile, name: str) -> None:
        self.profile, self.name = profile, name
        self.nested = 0.0  # CPU seconds of the stages run inside this one
        self.outer: _Run | None = None
        self.began = 0.0

    def __enter__(self) -> None:
        self.outer, self.profile._inner = self.profile._inner, self
        self.began = time.process_time()

    def __exit__(self, *raised: object) -> None:
        spent = time.process_time() - self.began
        self.profile._inner = self.outer
        self.profile.seconds[self.name] += spent - self.nested
        self.profile.runs[self.name] += 1
        if self.outer is not None:
            self.outer.nested += spent


#: The profile open in this process, if any.
_OPEN: StageProfile | None = None
_OFF = nullcontext()


def stage(name: str) -> AbstractContextManager[None]:
    """Run the block inside as the stage ``name`` (recorded while a profile is open)."""
    return _OFF if _OPEN is None else _Run(_OPEN, name)


def staged(name: str) -> Callable[[Callable[Params, Result]], Callable[Params, Result]]:
    """A decorator: each call of the function is a run of the stage ``name``."""
    def decorate(function: Callable[Params, Result]) -> Callable[Params, Result]:
        @functools.wraps(function)
        def run(*args: Params.args, **kwargs: Params.kwargs) -> Result:
            with stage(name):
                return function(*args, **kwargs)
        return run
    return decorate


@contextmanager
def profiled() -> Iterator[StageProfile]:
    """Record the stages run inside in a new :class:`StageProfile` (the one open before,
    if any, records nothing meanwhile)."""
    global _OPEN
    profile = StageProfile()
    before, _OPEN = _OPEN, profile
    try:
        yield profile
    finally:
        _OPEN = before
