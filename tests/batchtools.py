"""A small batch for the batch tests: 2 maps (a built-in world with its own start and goal,
and a map file without, whose start and goal each seed draws) x 3 seeds at 2 m/s, with a
short search budget; and its rows flown one by one in this process."""

from __future__ import annotations

import functools
from pathlib import Path

import numba

from quadnav.batch.fly_one import fly_row, load_context
from quadnav.batch.grid import read_spec

SPEC = """\
seeds = 3
speeds = [2.0]
improve = 2000
maps = ["window:size=4x6x3,walls=1", "pillar.txt"]
"""
PILLAR_MAP = "boundary 0 0 0 6 6 3\nblock 2.5 2.5 0 3.5 3.5 3\n"
MISSIONS = 6


def write_spec(folder: Path, text: str = SPEC) -> Path:
    """The test spec (and its map file) in ``folder``; returns the spec's path."""
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "pillar.txt").write_text(PILLAR_MAP)
    path = folder / "spec.toml"
    path.write_text(text)
    return path


@functools.cache
def _rows_one_by_one(spec_path: str) -> tuple[dict, ...]:
    spec = read_spec(spec_path)
    context = load_context(spec)
    return tuple(fly_row(context, mission) for mission in spec.missions())


def rows_one_by_one(spec_path: Path) -> list[dict]:
    """The rows of the spec's missions flown in this process, one after the other."""
    return list(_rows_one_by_one(str(spec_path)))



def numba_threads_in_worker(shared: object, item: object) -> int:
    """A job for an executor: the numba threads its worker's kernels run on."""
    return numba.get_num_threads()
