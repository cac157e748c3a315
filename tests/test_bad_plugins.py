"""A plain-Python controller or wind that is wrong gets one line naming its file and what is
wrong: exit 2 when it cannot be used (a bad name, no ``update``, a constructor that raises),
exit 1 when the flight fails because of it (an ``update`` that raises, returns the wrong
keys or sizes, or commands that are not numbers), with its own traceback shown once above
the line when its code raised; nothing is written."""

from __future__ import annotations

import pytest
from clitools import run_here

PLUGINS = '''
import numpy as np


class Hover:
    def __init__(self, quad_params):
        self.speed = np.sqrt(quad_params["mass"] * 9.81 / 4 / quad_params["k_eta"])

    def speeds(self, t):
        return {"cmd_motor_speeds": np.full(4, self.speed)}


class NoUpdate:
    def __init__(self, quad_params):
        pass


class WrongKeys(Hover):
    def update(self, t, state, flat_output):
        return {"thrust": 1.0, "moment": [0, 0, 0]}


class NotADict(Hover):
    def update(self, t, state, flat_output):
        return [self.speed] * 4


class ThreeRotors(Hover):
    def update(self, t, state, flat_output):
        return {"cmd_motor_speeds": np.full(3, self.speed)}


class KeysVanish(Hover):
    def update(self, t, state, flat_output):
        return self.speeds(t) if t < 0.25 else {"cmd_motor_thrusts": np.zeros(4)}


class GoesNaN(Hover):
    def update(self, t, state, flat_output):
        return self.speeds(t) if t < 0.5 else {"cmd_motor_speeds": np.full(4, np.nan)}


class Raises(Hover):
    def update(self, t, state, flat_output):
        if t >= 0.3:
            return self.divide(t)
        return self.speeds(t)

    def divide(self, t):
        return 1 / 0


class BadInit(Hover):
    def __init__(self, quad_params):
        self.mass = quad_params["weight"]

    def update(self, t, state, flat_output):
        return self.speeds(t)


class WindNoUpdate:
    pass


class WindNaN:
    def update(self, t, position):
        return np.array([np.nan, 0.0, 0.0]) if t >= 0.2 else np.zeros(3)


class WindTwo:
    def update(self, t, position):
        return np.zeros(2)


class WindBadInit:
    def __init__(self, speed=-1.0):
        if speed < 0:
            raise ValueError(f"a wind speed is at least 0 m/s, got {speed}")

    def update(self, t, position):
        return np.zeros(3)


class WindRaises:
    def update(self, t, position):
        raise RuntimeError(f"no wind at {position[2]:.1f} m")
'''


@pytest.fixture
def plugins(tmp_path):
    path = tmp_path / "bad.py"
    path.write_text(PLUGINS)
    return path


def track(folder, *flags):
    """``quadnav track hover:duration=1`` at 100 Hz with ``flags``, in this process."""
    return run_here("track", "hover:duration=1", "--settle", "0", "--control-rate", "100",
                    "--no-figures", "--quiet", "-o", folder / "out", *flags)


def error_lines(stderr: str) -> list[str]:
    return [line for line in stderr.splitlines() if line.startswith("quadnav: error: ")]


@pytest.mark.parametrize(("flag", "name", "code", "words"), [
    ("--controller", "NoUpdate", 2, "NoUpdate has no method update(t, state, flat_output)"),
    ("--controller", "WrongKeys", 1, "update(0, state, flat_output) returned thrust, moment: "
     "expected the commands of a control abstraction: cmd_motor_speeds, cmd_motor_thrusts, "
     "cmd_thrust with cmd_moment, cmd_q or cmd_w, or cmd_v"),
    ("--controller", "NotADict", 1, "update(0, state, flat_output) returned list: expected a "
     "dict of commands: cmd_motor_speeds, cmd_motor_thrusts, cmd_thrust with cmd_moment, "
     "cmd_q or cmd_w, or cmd_v"),
    ("--controller", "ThreeRotors", 1, "update(0, state, flat_output) returned "
     "cmd_motor_speeds of 3 number(s): expected 4"),
    ("--controller", "KeysVanish", 1, "update(0.25, state, flat_output) returned no "
     "cmd_motor_speeds (it gave cmd_motor_thrusts): flying by cmd_motor_speeds, expected "
     "cmd_motor_speeds"),
    ("--controller", "GoesNaN", 1, "update(0.5, state, flat_output) returned a non-finite "
     "cmd_motor_speeds: [nan nan nan nan]"),
    ("--wind", "WindNoUpdate", 2, "WindNoUpdate has no method update(t, position)"),
    ("--wind", "WindNaN", 1, "update(0.2, position) returned '[nan  0.  0.]': expected the "
     "wind's velocity, 3 finite numbers, m/s"),
    ("--wind", "WindTwo", 1, "update(0, position) returned '[0. 0.]': expected the wind's "
     "velocity, 3 finite numbers, m/s"),
])
def test_a_plugin_that_is_wrong_is_one_line_naming_its_file(plugins, tmp_path, flag, name,
                                                            code, words):
    result = track(tmp_path, flag, f"{plugins}:{name}")
    kind = "controller" if flag == "--controller" else "wind"
    assert result.returncode == code
    assert result.stderr.splitlines() == [f"quadnav: error: {kind} {plugins}:{name}: {words}"]
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize(("flag", "name", "code", "words", "line"), [
    ("--controller", "Raises", 1, "update(0.3, state, flat_output) raised ZeroDivisionError: "
     "division by zero", "return 1 / 0"),
    ("--controller", "BadInit", 2, "building it raised KeyError: 'weight'",
     'self.mass = quad_params["weight"]'),
    ("--wind", "WindBadInit", 2, "building it raised ValueError: a wind speed is at least "
     "0 m/s, got -1.0", 'raise ValueError(f"a wind speed is at least 0 m/s, got {speed}")'),
    ("--wind", "WindRaises", 1, "update(0, position) raised RuntimeError: no wind at 1.0 m",
     'raise RuntimeError(f"no wind at {position[2]:.1f} m")'),
])
def test_a_plugin_that_raises_shows_its_own_traceback_once_above_the_line(
        plugins, tmp_path, flag, name, code, words, line):
    result = track(tmp_path, flag, f"{plugins}:{name}")
    kind = "controller" if flag == "--controller" else "wind"
    assert result.returncode == code
    lines = result.stderr.splitlines()
    assert lines[0] == "Traceback (most recent call last):"
    assert lines[-1] == f"quadnav: error: {kind} {plugins}:{name}: {words}"
    assert result.stderr.count("Traceback") == 1 and line in result.stderr
    assert str(plugins) in result.stderr and "quadnav/" not in result.stderr.replace(
        str(tmp_path), "")  # the plug-in's frames only
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize(("flags", "line"), [
    (["--controller", "pid"], "unknown controller 'pid'; expected one of cascade, se3, or "
     "module:NAME or file.py:NAME"),
    (["--controller", "no_such_file.py:Ctl"], "controller no_such_file.py: no such file"),
    (["--controller", "no_such_module:Ctl"], "controller no_such_module: no module named "
     "'no_such_module' (is it installed, or did you mean path/to/file.py?)"),
    (["--wind", "gale"], "unknown wind 'gale'; expected module:NAME or file.py:NAME"),
    (["--wind", "1", "2"], "--wind: expected three forces FX FY FZ (N) or one wind model's "
     "spec, got 1 2"),
    (["--wind", "0.1", "0", "north"], "--wind: expected three forces FX FY FZ (N) or one "
     "wind model's spec, got 0.1 0 north"),
])
def test_a_bad_name_is_bad_input(tmp_path, flags, line):
    result = track(tmp_path, *flags)
    assert result.returncode == 2 and error_lines(result.stderr) == [f"quadnav: error: {line}"]
    assert len(result.stderr.splitlines()) == 1 and not (tmp_path / "out").exists()


def test_fly_refuses_a_bad_controller_before_it_plans(plugins, tmp_path):
    result = run_here("fly", "--controller", f"{plugins}:NoUpdate", "--no-figures", "--quiet",
                      "-o", tmp_path / "out")
    assert result.returncode == 2 and result.stdout == ""
    assert error_lines(result.stderr) == [f"quadnav: error: --controller: controller "
                                          f"{plugins}:NoUpdate: "
                                          "NoUpdate has no method update(t, state, "
                                          "flat_output)"]
