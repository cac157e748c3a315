"""Benchmark: what a plain-Python controller costs — control steps per second of the closed
loop with a Python controller (and a Python wind) against the compiled one, in one run.

Run: ``python bench/python_controller.py [--repeats 5]``, or ``--quick`` for a smoke run
(1 repeat, a 3 s hover instead of the helix).

The flight: the built-in ``helix:radius=1,speed=1`` (13.7 s, plus 2 s settling) from a hover
at its start, on the Tello without drag (rotorpy's SE3Control knows none), physics at 1 kHz.
Each row times whole calls of :func:`quadnav.sim.simulate.simulate` (sampling the
reference, loading the loop, the flight) in CPU seconds of this process, after a warm-up
flight (numba's compiling or loading from its cache), on one numba thread; CPU time, not
wall time, so that other work on a shared machine does not count:

* compiled: quadnav's SE(3) controller with rotorpy's gains (kp_att 310, kd_att 57), the
  whole flight in one call of the compiled loop;
* compiled, one call per control step: the same, with a Python wind of still air, so the
  loop runs one control step per call (the cost of going through Python at each step);
* Python, fixed commands: a Python controller whose ``update`` returns the same dict every
  time (hover motor speeds; it does not track the helix): quadnav's own cost per Python
  step, the least a Python controller can cost;
* rotorpy's ``SE3Control``, unchanged (needs ``pip install rotorpy``; skipped without it),
  by motor speeds at 1 kHz and at 200 Hz (``--control-rate``), the same law as the
  compiled row: their flights agree (the RMS tracking errors are printed).

Printed per row: control steps per CPU second (median over the repeats), the real-time
factor (simulated s / CPU s) and the compiled row's steps per second over this row's.
Nothing is asserted.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import numba
import numpy as np
from planning import table

from quadnav.control.contract import Controller
from quadnav.control.registry import make_controller
from quadnav.control.se3 import SE3Gains, se3_controller
from quadnav.sim.flight import Flight
from quadnav.sim.settings import SimSettings
from quadnav.sim.simulate import simulate
from quadnav.trajectory.references.builtin import load_reference
from quadnav.vehicle.params import load_params

VEHICLE = load_params("tello").replace(name="tello without drag", drag=np.zeros(3))
ROTORPY_SE3 = "rotorpy.controllers.quadrotor_control:SE3Control"
PLUGINS = '''
import numpy as np


class StillAir:
    def update(self, t, position):
        return np.zeros(3)


class Fixed:
    def __init__(self, quad_params):
        speed = np.sqrt(quad_params["mass"] * 9.81 / 4 / quad_params["k_eta"])
        self.commands = {"cmd_motor_speeds": np.full(4, speed)}

    def update(self, t, state, flat_output):
        return self.commands
'''


def flights(reference, controller: Callable[[], Controller], settings: SimSettings,
            repeats: int) -> list[tuple[Flight, float]]:
    """``repeats`` flights of ``reference`` after a warm-up one, each with a new controller,
    with the CPU seconds of each whole :func:`simulate` call."""
    simulate(reference, VEHICLE, settings=settings, controller=controller())
    flown = []
    for _ in range(repeats):
        flying = controller()
        began = time.process_time()
        flight = simulate(reference, VEHICLE, settings=settings, controller=flying)
        flown.append((flight, time.process_time() - began))
    return flown


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=None, help="timed flights (5; quick 1)")
    parser.add_argument("--quick", action="store_true",
                        help="smoke run: 1 flight per row, a 3 s hover")
    args = parser.parse_args()
    repeats = args.repeats or (1 if args.quick else 5)
    spec = "hover:duration=3" if args.quick else "helix:radius=1,speed=1"
    reference = load_reference(spec)
    numba.set_num_threads(1)
    folder = Path(tempfile.mkdtemp(prefix="quadnav-bench-"))
    plugins = folder / "plugins.py"
    plugins.write_text(PLUGINS)
    try:
        import rotorpy  # noqa: F401
        rotorpy_here = True
    except ImportError:
        rotorpy_here = False

    fast = SimSettings()
    stepped = fast.replace(wind_model=f"{plugins}:StillAir")
    slow = SimSettings(control_rate=200.0, record_rate=100.0)
    compiled = se3_controller(SE3Gains(kr=(310.0,) * 3, kw=(57.0,) * 3))

    def python(text: str) -> Callable[[], Controller]:
        return lambda: make_controller(text, VEHICLE)

    rows = [("compiled SE(3), rotorpy's gains", "one call", lambda: compiled, fast),
            ("compiled SE(3), rotorpy's gains", "one call per step (a Python wind)",
             lambda: compiled, stepped),
            ("Python, fixed commands", "one call per step", python(f"{plugins}:Fixed"), fast)]
    if rotorpy_here:
        rows += [("rotorpy's SE3Control, unchanged", "one call per step", python(ROTORPY_SE3),
                  fast),
                 ("rotorpy's SE3Control, unchanged", "one call per step", python(ROTORPY_SE3),
                  slow)]
    else:
        print("  rotorpy is not installed: its rows are skipped", file=sys.stderr)
    measured = []
    for name, calls, controller, settings in rows:
        print(f"  {name}, {settings.control_rate:g} Hz", file=sys.stderr, flush=True)
        flown = flights(reference, controller, settings, repeats)
        steps = statistics.median(f.duration * settings.control_rate / cpu for f, cpu in flown)
        measured.append((name, calls, settings.control_rate, steps,
                         steps / settings.control_rate, flown[-1][0].rms_tracking_error))
    best = measured[0][3]
    print(f"flight: {spec} ({reference.duration:.1f} s + {fast.settle_time:g} s settling), "
          f"{VEHICLE.name}, physics 1 kHz; median of {repeats} flights after a warm-up; "
          f"numba threads {numba.get_num_threads()}\n")
    print(table(["controller", "calls of the compiled loop", "control rate Hz",
                 "control steps / CPU s", "real-time factor", "compiled one call / this",
                 "RMS error mm"],
                [[name, calls, f"{rate:g}", f"{steps:,.0f}", f"{factor:.1f}x",
                  f"{best / steps:.0f}x", f"{rms * 1e3:.2f}"]
                 for name, calls, rate, steps, factor, rms in measured]))


if __name__ == "__main__":
    main()
