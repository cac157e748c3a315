"""A small Monte-Carlo study from Python: two built-in worlds x 4 seeds x two speeds, flown
on local worker processes, with the success rate and its Wilson 95 % interval per group.

Run: python examples/batch_study.py [OUT]   (default: batch_study; a re-run resumes)
"""

import json
import sys
from pathlib import Path

from quadnav.batch.grid import spec_from_table
from quadnav.batch.run import BatchRun

if __name__ == "__main__":  # the workers are spawned processes: they import this file
    out = Path(sys.argv[1] if len(sys.argv) > 1 else "batch_study")
    spec = spec_from_table({"maps": ["forest:size=10x10x4", "window:size=4x6x3,walls=1"],
                            "seeds": 4, "speeds": [1.0, 2.0], "improve": 5000}, folder=".")
    BatchRun(spec, out).run(workers=2)
    for group in json.loads((out / "summary.json").read_text())["groups"]:
        print(f"{group['map']} at {group['speed']:g} m/s: {group['successes']} of "
              f"{group['n']}, interval {100 * group['ci_low']:.0f} to "
              f"{100 * group['ci_high']:.0f} %")
