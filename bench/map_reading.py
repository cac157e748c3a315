"""Benchmark: reading a large map, per block, in both formats, against the floor of reading
the same bytes with no checks at all (Python's ``json.loads`` for JSON, splitting the lines
and ``float`` of every field for text), measured in the same run.

Run: ``python bench/map_reading.py [--blocks 100000] [--repeats 3]``, or ``--quick``.

The map is ``--blocks`` random 1 x 1 m columns in a 1,000 x 1,000 x 50 m boundary, each with
a colour, written once as text and as JSON (indented as rotorpy's files are). Printed: per
format the median wall time of :func:`quadnav.world.parse_map` over the repeats, microseconds
per block, the ratio to the floor, and the peak memory of one read in a fresh process (Linux),
whole and per block beyond the import's. A map over the 128 MiB limit of map files (JSON of
about 900,000 blocks or more, as written here) is not read. Nothing is asserted.
"""

from __future__ import annotations

import argparse
import json
import random
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from quadnav.limits import MAX_FILE_BYTES
from quadnav.world import parse_map


def write_maps(folder: Path, blocks: int) -> dict[str, Path]:
    """The same random map as text and as JSON in ``folder``."""
    rng = random.Random(1)
    boxes = []
    for _ in range(blocks):
        x, y, top = rng.uniform(0, 990), rng.uniform(0, 990), rng.uniform(1, 40)
        boxes.append((round(x, 3), round(y, 3), round(top, 3)))
    text = ["boundary 0 0 0 1000 1000 50"] + [
        f"block {x} {y} 0 {x + 1:.3f} {y + 1:.3f} {top} 128 128 128" for x, y, top in boxes]
    data = {"bounds": {"extents": [0, 1000, 0, 1000, 0, 50]},
            "blocks": [{"extents": [x, round(x + 1, 3), y, round(y + 1, 3), 0, top],
                        "color": [0.5, 0.5, 0.5]} for x, y, top in boxes]}
    paths = {"text": folder / "map.txt", "json": folder / "map.json"}
    paths["text"].write_text("\n".join(text) + "\n")
    paths["json"].write_text(json.dumps(data, indent=1))
    return paths


def floor(kind: str, data: bytes) -> None:
    """The bytes read with no checks: what any reader must at least do."""
    text = data.decode()
    if kind == "json":
        json.loads(text)
    else:
        for line in text.split("\n"):
            [float(field) for field in line.split()[1:]]


def median_seconds(read, repeats: int) -> float:
    times = []
    for _ in range(repeats):
        began = time.perf_counter()
        read()
        times.append(time.perf_counter() - began)
    return statistics.median(times)


def peak_megabytes(path: Path | None) -> float:
    """The peak resident memory of a fresh process that imports quadnav's map readers and
    reads ``path`` (``None``: reads nothing), MB. Linux's VmHWM of the process's own memory:
    ``ru_maxrss`` would start at the resident size of this process, which forked it."""
    script = ("import sys; from quadnav.world import parse_map\n"
              "if len(sys.argv) > 1: parse_map(open(sys.argv[1], 'rb').read(), sys.argv[1])\n"
              "print(next(line.split()[1] for line in open('/proc/self/status')\n"
              "           if line.startswith('VmHWM:')))")
    done = subprocess.run([sys.executable, "-c", script, *([str(path)] if path else [])],
                          check=True, capture_output=True, text=True)
    return int(done.stdout) / 1024


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--blocks", type=int, default=100_000)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--quick", action="store_true", help="10,000 blocks, one repeat")
    args = parser.parse_args()
    blocks, repeats = (10_000, 1) if args.quick else (args.blocks, args.repeats)
    with tempfile.TemporaryDirectory() as folder:
        paths = write_maps(Path(folder), blocks)
        print(f"{blocks:,} blocks, median of {repeats}")
        imported = peak_megabytes(None)
        print(f"peak memory of the import alone: {imported:.0f} MB")
        print(f"{'format':6s} {'parse_map s':>12s} {'us/block':>9s} {'floor s':>8s} "
              f"{'ratio':>6s} {'peak MB':>8s} {'B/block':>8s}")
        for kind, path in paths.items():
            data = path.read_bytes()
            if len(data) > MAX_FILE_BYTES:
                print(f"{kind:6s} {len(data) / 2**20:.0f} MiB: over the limit of map files")
                continue
            ours = median_seconds(lambda p=path, d=data: parse_map(d, str(p)), repeats)
            base = median_seconds(lambda k=kind, d=data: floor(k, d), repeats)
            peak = peak_megabytes(path)
            print(f"{kind:6s} {ours:12.2f} {1e6 * ours / blocks:9.1f} {base:8.2f} "
                  f"{ours / base:6.1f} {peak:8.0f} {(peak - imported) * 2**20 / blocks:8.0f}")


if __name__ == "__main__":
    main()
