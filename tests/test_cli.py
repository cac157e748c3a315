"""The ``quadnav`` command line, run as a user runs it: a real process."""

from __future__ import annotations

import fcntl
import json
import os
import pty
import signal
import struct
import subprocess
import sys
import termios
import time

import numpy as np
import pytest
from clitools import QUADNAV, assert_user_error, run, run_here

from quadnav import __version__
from quadnav.cli.commands import COMMANDS
from quadnav.cli.main import build_parser
from quadnav.signals import Stopped, StopSignalHandler, report_stop
from quadnav.world import read_map


def test_version_and_help():
    result = run("--version")
    assert result.returncode == 0 and result.stdout.strip() == f"quadnav {__version__}"
    result = run("--help")
    assert result.returncode == 0 and "usage: quadnav" in result.stdout
    for command in (["map"], ["map", "info"], ["map", "check"], ["map", "show"],
                    ["map", "convert"], ["worlds"]):
        result = run_here(*command, "--help")
        assert result.returncode == 0 and "usage: quadnav" in result.stdout, command


LOADED = """
import sys
from quadnav.cli.launch import main
try:
    main(sys.argv[1:])
except SystemExit:
    pass
heavy = ("numba", "numpy", "scipy", "matplotlib", "quadnav.cli.fly_command",
         "quadnav.cli.worlds_command")
print("loaded:", *(name for name in heavy if name in sys.modules))
"""


@pytest.mark.parametrize(("args", "loaded"), [
    (["--version"], ""), (["--help"], ""), (["nosuch"], ""),
    (["worlds"], "numba numpy scipy quadnav.cli.worlds_command"),
    (["fly", "--help"], "numba numpy scipy quadnav.cli.fly_command")])  # no plotting
def test_a_command_line_loads_only_the_command_it_runs(args, loaded):
    """--version, --help and a typo load no command and none of the numeric stack; a
    command loads its own module and not the others'."""
    result = subprocess.run([sys.executable, "-c", LOADED, *args], capture_output=True,
                            text=True, timeout=60)
    assert result.stdout.splitlines()[-1] == f"loaded: {loaded}".strip(), result
    listing = run_here("--help").stdout
    assert all(name in listing for name in COMMANDS)


def test_map_info_on_a_real_map(shared_maps):
    result = run_here("map", "info", shared_maps / "meam620/test_window.json")
    assert result.returncode == 0, result.stderr
    out = result.stdout
    assert "bounds:      x 0 .. 10, y -5 .. 20, z 0 .. 6 m" in out
    assert "blocks:      8" in out
    assert "free volume: 92.12 %" in out
    assert "start:       (0.1, -4.9, 0.2)" in out
    assert "margin:      0.3 m" in out


def test_map_info_on_a_built_in_world():
    result = run_here("map", "info", "forest:size=30x20x5,seed=2")
    assert result.returncode == 0, result.stderr
    assert "size:        30 x 20 x 5 m" in result.stdout
    assert "start:" in result.stdout and "goal:" in result.stdout


def test_map_check_reports_margin_block_and_outside(shared_maps):
    window = shared_maps / "meam620/test_window.json"
    result = run_here("map", "check", window)
    assert result.returncode == 0, result.stderr
    assert "start (0.1, -4.9, 0.2): inside the 0.3 m safety margin (near the boundary)" in result.stdout
    assert "goal (8, 18, 3): free" in result.stdout

    result = run_here("map", "check", window, "--start", "1", "2.2", "1", "--goal", "5", "5", "9")
    assert_user_error(result, "test_window.json", "start (1, 2.2, 1) is in a block",
                      "goal (5, 5, 9) is outside the boundary")
    assert "start (1, 2.2, 1): inside block 0 [0, 10] x [2, 2.5] x [0, 1.5]" in result.stdout

    result = run_here("map", "check", shared_maps / "rbe595/map1.txt", "--margin", "0.2",
                 "--start", "0", "-4.5", "0.5", "--goal", "8", "18", "3")
    assert result.returncode == 0
    assert "(on the boundary)" in result.stdout


def test_map_check_with_a_start_goal_file(shared_maps):
    result = run_here("map", "check", shared_maps / "rbe595/p2b_map1.txt",
                 "--start-goal", shared_maps / "rbe595/p2b_startandgoal_map1.txt")
    assert result.returncode == 0, result.stderr
    assert "start (0, 0, 0): inside the 0.2 m safety margin (on the boundary)" in result.stdout


def test_map_check_without_points_is_a_user_error(shared_maps):
    assert_user_error(run_here("map", "check", shared_maps / "rbe595/map1.txt"), "has no start or goal")


def test_map_show_writes_a_picture(tmp_path, shared_maps):
    out = tmp_path / "map.png"
    result = run_here("map", "show", shared_maps / "rbe595/map1.txt", "--start", "0.5", "-4.5", "0.5",
                 "--goal", "8", "18", "3", "-o", out)
    assert result.returncode == 0, result.stderr
    from matplotlib.image import imread

    image = imread(out)
    assert image.shape[0] > 500 and image.shape[1] > 500
    # Not blank: the red blocks and the start sphere put plenty of strongly red pixels in it.
    red = (image[..., 0] > 0.6) & (image[..., 1] < 0.3) & (image[..., 2] < 0.3)
    assert red.mean() > 0.01


def test_map_show_defaults_to_the_built_in_world(tmp_path):
    result = run_here("map", "show", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert (tmp_path / "map.png").stat().st_size > 10_000


def test_map_convert_text_json_text(tmp_path, shared_maps):
    source = shared_maps / "meam620/map_2017_boundary9fields.txt"
    assert run_here("map", "convert", source, tmp_path / "m.json").returncode == 0
    assert run_here("map", "convert", tmp_path / "m.json", tmp_path / "m.txt").returncode == 0
    original, again = read_map(source), read_map(tmp_path / "m.txt")
    np.testing.assert_array_equal(original.blocks, again.blocks)
    np.testing.assert_array_equal(original.boundary, again.boundary)
    data = json.loads((tmp_path / "m.json").read_text())
    assert data["bounds"]["extents"] == [0, 20, 0, 5, 0, 6]


def test_map_convert_a_built_in_world(tmp_path):
    result = run_here("map", "convert", "window:seed=4", tmp_path / "w.json")
    assert result.returncode == 0, result.stderr
    assert read_map(tmp_path / "w.json").start is not None


def test_worlds_lists_every_built_in_world_and_its_parameters():
    result = run_here("worlds")
    assert result.returncode == 0
    for name in ("forest", "window", "maze", "empty"):
        assert f"\n{name}" in "\n" + result.stdout
    assert "density=" in result.stdout and "seed=" in result.stdout
    # Every parameter's range, e.g. the forest's size and branches:
    assert "WxDxH of the map, metres; each from 2 to 10,000 m" in result.stdout
    assert "mean number of branches per trunk; from 0 to 5" in result.stdout


def test_clip_warning_is_one_line(tmp_path):
    path = tmp_path / "m.txt"
    path.write_text("boundary 0 0 0 5 5 5\nblock 4 4 4 6 6 6\n")
    result = run_here("map", "info", path)
    assert result.returncode == 0
    assert result.stderr.strip() == f"quadnav: warning: {path}:2: block extends past the boundary; clipped to it"


@pytest.mark.parametrize(("args", "fragments"), [
    (["map", "info", "nowhere.txt"], ["nowhere.txt: no such map file, and not a built-in world"]),
    (["map", "info", "forest:densty=3"], ["forest:densty=3", "densty"]),
    (["map", "info", "{bad}"], ["{bad}"]),
    (["map", "check", "empty", "--margin", "-1"], ["--margin", "expected from 0 to 100 m"]),
    (["map", "check", "empty", "--start", "1", "2"], ["--start", "expected 3 argument"]),
    (["map", "check", "empty", "--start", "1", "2", "nan"],
     ["--start", "expected from -10,000 to 10,000 m, got 'nan'"]),
    (["map", "check", "empty", "--margin", "100"], ["margin 100 m leaves no free space"]),
    (["map", "show", "empty", "-o", "map.xyz"], ["map.xyz: expected an image file name"]),
    (["map", "show", "empty", "-o", "no/such/dir/map.png"], ["does not exist"]),
    (["map", "convert", "empty", "no/such/dir/m.json"], ["no/such/dir/m.json: cannot write"]),
    (["map", "convert", "empty", "m.map"], ["m.map: expected a file name ending in .json"]),
    (["map", "frobnicate"], ["invalid choice: 'frobnicate'"]),
    (["worlds", "--bogus"], ["unrecognized arguments: --bogus"]),
    ([], ["required"]),
])
def test_bad_input_is_one_line_and_exit_2(tmp_path, args, fragments):
    result = run_here(*args, cwd=tmp_path)
    assert_user_error(result, *fragments)
    assert list(tmp_path.iterdir()) == []  # nothing half-written


@pytest.mark.parametrize(("command", "args", "flag"), [
    ("fly", ["forest", "--spede"], "--spede"),
    ("map info", ["--zzz", "forest"], "--zzz"),
    ("tello fly", ["forest", "--bogus"], "--bogus"),
    ("batch", ["forest", "--sedes", "3"], "--sedes 3"),
    ("worlds", ["--bogus"], "--bogus"),
])
def test_a_misspelt_flag_points_to_its_commands_own_help(command, args, flag, tmp_path):
    """The command (and subcommand) that did not know the flag names its own --help, where
    the right spelling is listed, not the top level's."""
    result = run_here(*command.split(), *args, cwd=tmp_path)
    assert_user_error(result)
    assert result.stderr == (f"quadnav {command}: error: unrecognized arguments: {flag} "
                             f"(see quadnav {command} --help)\n")


@pytest.mark.parametrize(("args", "values"), [
    (["batch", "a.txt", "--start-goal", "sg.txt", "b.txt", "--seeds", "2", "c.txt"],
     {"inputs": ["a.txt", "b.txt", "c.txt"], "start_goal": "sg.txt", "seeds": 2}),
    (["batch", "--seeds", "2", "a.txt", "b.txt"], {"inputs": ["a.txt", "b.txt"], "seeds": 2}),
    (["report", "runs/a", "-o", "both.html", "runs/b"],
     {"folders": ["runs/a", "runs/b"], "output": "both.html"}),
    (["refly", "batch", "-o", "again", "3"], {"folder": "batch", "mission": "3", "output": "again"}),
    (["map", "check", "--margin", "0.3", "forest"], {"map": "forest", "margin": 0.3}),
])
def test_positional_arguments_may_come_anywhere_among_the_flags(args, values):
    parsed = vars(build_parser(args).parse_args(args))
    assert {name: parsed[name] for name in values} == values


#: A command whose simulation reports its progress a few times: a 6 s step reference.
SHORT_FLIGHT = ("track", "step:axis=z,size=0.5", "--no-figures")


def _stderr_on_a_terminal(args: list[str], cwd) -> str:
    """What ``quadnav args`` writes to stderr when stderr is a pseudo-terminal of 80 x 24
    characters (stdout a pipe), read from the terminal's other end until the process
    ends."""
    controller, terminal = pty.openpty()
    fcntl.ioctl(terminal, termios.TIOCSWINSZ, struct.pack("HHHH", 24, 80, 0, 0))
    process = subprocess.Popen([*QUADNAV, *args], cwd=cwd, stdout=subprocess.PIPE,
                               stderr=terminal)
    os.close(terminal)
    written = bytearray()
    while True:
        try:
            chunk = os.read(controller, 4096)
        except OSError:  # EIO: the process ended and closed the terminal
            break
        if not chunk:
            break
        written += chunk
    os.close(controller)
    process.communicate(timeout=120)
    assert process.returncode == 0, written
    return written.decode()


def test_progress_bars_are_drawn_on_a_terminal_and_not_into_a_pipe(tmp_path):
    """A bar's carriage returns and cursor moves belong on a terminal; piped or redirected,
    stderr stays empty of them (here: empty, as the flight warns of nothing)."""
    piped = run(*SHORT_FLIGHT, "-o", "piped", cwd=tmp_path)
    assert piped.returncode == 0, piped.stderr
    assert piped.stderr == ""
    assert "success" in piped.stdout and "\r" not in piped.stdout
    shown = _stderr_on_a_terminal([*SHORT_FLIGHT, "-o", "shown"], tmp_path)
    assert "\r" in shown and "fly: " in shown
    quiet = _stderr_on_a_terminal([*SHORT_FLIGHT, "-o", "quiet", "--quiet"], tmp_path)
    assert quiet == ""


def test_malformed_map_file_names_file_and_line(tmp_path):
    path = tmp_path / "m.txt"
    path.write_text("boundary 0 0 0 5 5 5\n\nblock 1 1 1 2 2\n")
    assert_user_error(run_here("map", "info", path), f"{path}:3: block: expected 6 numbers")


@pytest.mark.parametrize(("signum", "code", "words"), [
    (signal.SIGINT, 130, "quadnav: interrupted"),
    (signal.SIGTERM, 143, "quadnav: stopped by SIGTERM"),
    (signal.SIGHUP, 129, "quadnav: stopped by SIGHUP"),
])
def test_a_stop_signal_while_starting_up_is_one_line(signum, code, words):
    """Stopped at any point of start-up (the imports take most of a second) or of the
    work: one line and 128 + the signal number, never a traceback."""
    for delay in (0.15, 0.3, 0.6):
        process = subprocess.Popen([*QUADNAV, "map", "info", "forest"], text=True,
                                   stdout=subprocess.PIPE, stderr=subprocess.PIPE)
        time.sleep(delay)
        process.send_signal(signum)
        _, stderr = process.communicate(timeout=60)
        if process.returncode == 0:  # finished before the signal came: nothing to check
            continue
        if process.returncode == -signum and not stderr:
            continue  # came before Python ran any of quadnav (a loaded machine): killed as is
        assert process.returncode == code, stderr
        assert stderr.strip().splitlines() == [words], stderr


def test_an_import_cut_short_by_a_stop_signal_is_a_stop(capsys):
    """An extension module whose loading a signal interrupts reports an ImportError
    caused by the signal's exception: that is a stop, one line, not a traceback."""
    try:
        try:
            raise Stopped(signal.SIGTERM)
        except Stopped as stop:
            raise ImportError("initialization failed") from stop
    except ImportError as error:
        assert report_stop(error) == 143
    assert capsys.readouterr().err == "quadnav: stopped by SIGTERM\n"
    with pytest.raises(ImportError, match="no module"):
        report_stop(ImportError("no module"))


def test_an_import_that_lost_the_stop_behind_it_is_still_a_stop(capsys):
    """numpy's C-level imports (PyCapsule_Import) turn a stop raised while they run into an
    ImportError that no longer names it as its cause: the stop the handlers raised is."""
    handler = StopSignalHandler()
    with pytest.raises(Stopped):
        handler.handle(signal.SIGTERM, None)
    lost = ImportError("numpy.core.multiarray failed to import")
    assert lost.__cause__ is None and lost.__context__ is None
    assert report_stop(lost, handler.raised) == 143
    assert capsys.readouterr().err == "quadnav: stopped by SIGTERM\n"
    with pytest.raises(ImportError, match="failed to import"):
        report_stop(lost, StopSignalHandler().raised)  # no stop was raised: a real ImportError


def test_stop_signals_wait_while_numba_holds_its_compiler_lock():
    """A stop while a compiled kernel loads or compiles would leave llvmlite's objects
    half built (the process then crashes as Python frees them): it waits for the lock."""
    script = """
import os, signal
from numba.core.compiler_lock import global_compiler_lock
from quadnav.cli.launch import install_stop_handlers, watch_kernel_loads
install_stop_handlers()
watch_kernel_loads()
try:
    with global_compiler_lock:
        signal.raise_signal(signal.SIGINT)
        sum(range(100_000))
        print("held", flush=True)
    sum(range(100_000))
    print("not delivered")
except KeyboardInterrupt:
    print("delivered")
"""
    result = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                            timeout=60)
    assert result.stdout.split() == ["held", "delivered"], result


def test_output_piped_into_a_reader_that_stops_ends_quietly():
    # As `quadnav references | head -0`: the reader is gone before the first line.
    read_end, write_end = os.pipe()
    os.close(read_end)
    try:
        result = subprocess.run([*QUADNAV, "references"], stdout=write_end,
                                stderr=subprocess.PIPE, text=True, timeout=120)
    finally:
        os.close(write_end)
    assert result.returncode == 141 and result.stderr == ""
