"""Run folders are replaced whole or not at all, and the output folder is checked first.

``quadnav fly`` is killed (SIGTERM and SIGINT) at many points while it writes over an
earlier run: each time the folder holds either the earlier run, exactly, or the new one,
complete, never a mix and never a temporary file. The kills are timed from events seen in
the folder (the run beginning to write, the new files arriving), so they land in the
same phases on a busy machine as on an idle one.
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
import pytest
from clitools import QUADNAV, run_here

from quadnav.cli.launch import stop_again
from quadnav.cli.main import main
from quadnav.errors import QuadnavError
from quadnav.runfolder import STAGING_PREFIX, _signal_gate, check_output_folder, replaced_folder
from quadnav.runs import FIGURES, REPORT
from quadnav.signals import Stopped

SMALL = "forest:size=12x12x4,seed=2"
#: The earlier run (with figures and report) and the new one (without), different seeds.
OLD_FLAGS = ("--seed", "1")
NEW_FLAGS = ("--seed", "2", "--no-figures")
NOTES = "notes.txt"  # a file of the user's in the run folder: never touched
NOTES_TEXT = "my notes on the run\n"
POLL = 0.002  # s between looks at a folder
EXIT_KILLED = {signal.SIGINT: 130, signal.SIGTERM: 143}


def fly_args(folder: Path, *flags: str) -> list[str]:
    return ["fly", SMALL, "--iterations", "300", *flags, "--quiet", "-o", str(folder)]


def start_fly(folder: Path, *flags: str) -> subprocess.Popen:
    return subprocess.Popen([*QUADNAV, *fly_args(folder, *flags)], stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE, text=True)


def wait_for(condition, process: subprocess.Popen) -> float | None:
    """When ``condition()`` first held (monotonic s), or None if the process ended first."""
    while process.poll() is None:
        if condition():
            return time.monotonic()
        time.sleep(POLL)
    return None


def writing_in(folder: Path):
    """A condition: something in ``folder`` has changed (the run began writing)."""
    before = sorted(os.listdir(folder))
    return lambda: sorted(os.listdir(folder)) != before


def timed_fly(folder: Path, *flags: str) -> tuple[int, float]:
    """``quadnav fly`` into the empty ``folder``, run in this process: its exit code, and
    how long it took from beginning to write (the folder changes, as the staging folder
    appears) to its files reaching the folder (its metrics.json is in place), s, timed
    from the folder as the killed runs are, by a thread that looks every :data:`POLL` s."""
    events = [writing_in(folder), lambda: (folder / "metrics.json").exists()]
    seen: list[float] = []
    done = threading.Event()

    def watch() -> None:
        for event in events:
            while not event():
                if done.is_set():
                    return
                time.sleep(POLL)
            seen.append(time.monotonic())

    watcher = threading.Thread(target=watch)
    watcher.start()
    try:
        code = run_here(*fly_args(folder, *flags)).returncode
    finally:
        done.set()
        watcher.join()
    assert len(seen) == 2, "the run's writing was not seen"
    return code, seen[1] - seen[0]


def files_of(folder: Path) -> dict[str, bytes]:
    """The files in ``folder`` (not its subfolders) by name, with their contents."""
    return {path.name: path.read_bytes() for path in folder.iterdir() if path.is_file()}


@pytest.fixture(scope="module")
def references(tmp_path_factory):
    """The earlier run's files (with the user's notes), the new run's files, and how long
    the new run took from beginning to write to its files reaching the folder (s)."""
    root = tmp_path_factory.mktemp("references")
    old, new = root / "old", root / "new"
    new.mkdir()
    assert run_here(*fly_args(old, *OLD_FLAGS)).returncode == 0
    code, writing = timed_fly(new, *NEW_FLAGS)
    assert code == 0
    (old / NOTES).write_text(NOTES_TEXT)
    old_files, new_files = files_of(old), files_of(new)
    assert {*FIGURES, REPORT} <= old_files.keys() and not {*FIGURES, REPORT} & new_files.keys()
    assert f"folder {old};".encode() in old_files[REPORT]  # the folder, not the staging one
    assert old_files["path.csv"] != new_files["path.csv"]
    for folder in (old, new):  # each run is consistent in itself
        metrics = json.loads((folder / "metrics.json").read_text())
        path = np.loadtxt(folder / "path.csv", delimiter=",", skiprows=1)
        flight = np.loadtxt(folder / "flight.csv", delimiter=",", skiprows=1)
        assert metrics["path_vertices"] == len(path)
        assert flight[-1, 0] == pytest.approx(metrics["flight_time_s"], abs=1e-9)
    return old, old_files, new_files, writing


def which_run(folder: Path, old_files: dict[str, bytes], new_files: dict[str, bytes]) -> str:
    """"old" if ``folder`` holds exactly the earlier run, "new" if it holds the whole new
    run (and the notes); fails on anything else (a mix, a missing file, a temporary file)."""
    found = files_of(folder)
    assert sorted(os.listdir(folder)) == sorted(found)  # no staging folder
    assert not [name for name in found if name.startswith(".")], sorted(found)
    if found == old_files:
        return "old"
    assert found.keys() == {*new_files, NOTES}, sorted(found)
    assert found[NOTES] == NOTES_TEXT.encode()
    metrics = json.loads(found["metrics.json"])
    expected = json.loads(new_files["metrics.json"])
    for key in ("seed", "path_vertices", "path_length_m", "flight_time_s", "success"):
        assert metrics[key] == expected[key], key
    for name, data in new_files.items():
        if name != "metrics.json":  # it holds wall-clock times
            assert found[name] == data, name
    return "new"


def killed_run(folder: Path, old: Path, signum: int, trigger: str, delay: float
               ) -> tuple[int, str]:
    """Write the new run over a copy of the earlier one in ``folder``; send ``signum``
    ``delay`` s after the ``trigger`` ("start"; "writing": the folder changes, as the
    staging folder appears; "moved": the new metrics.json is in place). Returns the exit
    code and stderr."""
    shutil.copytree(old, folder)
    old_inode = (folder / "metrics.json").stat().st_ino
    conditions = {"start": lambda: True, "writing": writing_in(folder),
                  "moved": lambda: (folder / "metrics.json").stat().st_ino != old_inode}
    began = time.monotonic()
    process = start_fly(folder, *NEW_FLAGS)
    seen = wait_for(conditions[trigger], process)
    if seen is not None:
        time.sleep(max(0.0, (began if trigger == "start" else seen) + delay - time.monotonic()))
        process.send_signal(signum)
    _, err = process.communicate(timeout=120)
    return process.returncode, err


def test_fly_killed_while_writing_over_an_earlier_run_leaves_one_of_them_whole(
        references, tmp_path):
    old, old_files, new_files, writing = references
    plan = [("start", 0.5, "old")]  # starting up: far from done
    plan += [("writing", 0.0, "old"), ("writing", 0.0, "old")]  # as the writing begins
    plan += [("writing", k / 8 * writing, None) for k in (1, 3, 5, 7, 9)]  # some after it
    plan += [("moved", delay, "new") for delay in (0.0, 0.01)]
    signals = [(signal.SIGTERM, signal.SIGINT)[k % 2] for k in range(len(plan))]
    with ThreadPoolExecutor(max_workers=2) as pool:  # two at a time, in their own folders
        ends = list(pool.map(lambda k: killed_run(tmp_path / f"run{k}", old, signals[k],
                                                  *plan[k][:2]), range(len(plan))))
    outcomes = []
    for k, ((trigger, delay, expected), (code, err)) in enumerate(zip(plan, ends, strict=True)):
        where = f"{signals[k].name} {delay:.3f} s after {trigger}: exit {code}, {err!r}"
        print(where)  # shown with a failure below
        assert "Traceback" not in err, where
        outcome = which_run(tmp_path / f"run{k}", old_files, new_files)
        assert expected in (None, outcome), where
        # Stopped, or done before the signal. A signal that comes before Python has started
        # up, or during its shutdown after the command returned, ends the process as the
        # signal's default action does.
        default_action = trigger == "start" or outcome == "new"
        assert code in (0, EXIT_KILLED[signals[k]], *[-signals[k]] * default_action), where
        outcomes.append(outcome)
    assert [code for code, _ in ends[1:3]] == [130, 143]  # both stop a run that writes
    assert outcomes[1:3] == ["old", "old"]
    assert sorted(os.listdir(tmp_path)) == sorted(f"run{k}" for k in range(len(plan)))


# --- the output folder is checked before any work ----------------------------------------

COMMANDS = {
    "fly": ["fly"],
    "plan": ["plan"],
    "traj": ["traj", "--path", "nosuch.csv"],
    "kino diffdrive": ["kino", "diffdrive", "--start", "0", "0", "0", "--goal", "1", "1"],
    "kino quadrotor": ["kino", "quadrotor"],
    "tello fly": ["tello", "fly", "--dry-run"],
}


@pytest.mark.parametrize("command", COMMANDS)
def test_an_unwritable_output_folder_is_one_line_before_any_work(command, tmp_path, capsys):
    """With a map that does not exist either, the error names the output: it is checked
    first."""
    args = [*COMMANDS[command], str(tmp_path / "nosuchmap.txt")]
    (tmp_path / "file").write_text("")
    (tmp_path / "dangling").symlink_to(tmp_path / "gone")
    for output, fragment in (("/proc/x", "/proc/x: cannot create the output folder in /proc"),
                             (str(tmp_path / "file" / "out"), "expected a folder"),
                             (str(tmp_path / "dangling"), "which does not exist")):
        assert main([*args, "-o", output]) == 2
        (line,) = capsys.readouterr().err.strip().splitlines()
        assert line.startswith("quadnav: error: ") and fragment in line, line
    assert sorted(os.listdir(tmp_path)) == ["dangling", "file"]


def test_check_output_folder_leaves_nothing_behind(tmp_path):
    assert check_output_folder(tmp_path / "a" / "b") == tmp_path / "a" / "b"
    assert check_output_folder(str(tmp_path)) == tmp_path
    assert list(tmp_path.iterdir()) == []
    with pytest.raises(QuadnavError, match="cannot write into the output folder"):
        check_output_folder("/proc/self")


# --- replaced_folder itself --------------------------------------------------------------

NAMES = ("a.csv", "b.csv", "figure.png")


def earlier_run(folder: Path) -> dict[str, bytes]:
    folder.mkdir(parents=True, exist_ok=True)
    for name in (*NAMES, NOTES):
        (folder / name).write_text(f"earlier {name}\n")
    (folder / "mine").mkdir()
    (folder / "mine" / "data.txt").write_text("kept\n")
    return files_of(folder)


def test_the_new_files_replace_the_earlier_run_and_leave_the_rest(tmp_path):
    folder = tmp_path / "run"
    earlier_run(folder)
    inode = folder.stat().st_ino
    with replaced_folder(folder, NAMES) as staging:
        assert staging.parent == folder and staging.name.startswith(STAGING_PREFIX)
        (staging / "a.csv").write_text("new a\n")
        assert (folder / "a.csv").read_text() == "earlier a.csv\n"  # not yet
    assert sorted(os.listdir(folder)) == ["a.csv", "mine", NOTES]  # b and the figure: stale
    assert (folder / "a.csv").read_text() == "new a\n"
    assert (folder / NOTES).read_text() == f"earlier {NOTES}\n"
    assert (folder / "mine" / "data.txt").read_text() == "kept\n"
    assert folder.stat().st_ino == inode  # the same folder: a shell inside it stays there


@pytest.mark.parametrize("error", [KeyboardInterrupt, QuadnavError])
def test_a_failed_or_interrupted_run_leaves_the_folder_as_it_was(tmp_path, error):
    folder = tmp_path / "run"
    before = earlier_run(folder)
    with pytest.raises(error), replaced_folder(folder, NAMES) as staging:
        (staging / "a.csv").write_text("new a\n")
        raise error("stopped")
    assert files_of(folder) == before
    new = tmp_path / "new" / "deeper"
    with pytest.raises(error), replaced_folder(new, NAMES):
        raise error("stopped")
    assert os.listdir(tmp_path) == ["run"]  # the folders it made are gone again


def test_keep_partial_moves_in_what_an_interrupted_run_wrote(tmp_path):
    """As for ``tello fly``: the log of a flight that was stopped is kept, the earlier
    run's figure goes; a run stopped before it wrote anything leaves the folder alone."""
    folder = tmp_path / "run"
    earlier_run(folder)
    with pytest.raises(KeyboardInterrupt), replaced_folder(folder, NAMES, True):
        raise KeyboardInterrupt
    assert (folder / "figure.png").read_text() == "earlier figure.png\n"
    with pytest.raises(KeyboardInterrupt), replaced_folder(folder, NAMES, True) as staging:
        (staging / "a.csv").write_text("the log so far\n")
        (staging / ".figure.png.tmp").write_text("half a figure")
        raise KeyboardInterrupt
    assert sorted(os.listdir(folder)) == ["a.csv", "mine", NOTES]
    assert (folder / "a.csv").read_text() == "the log so far\n"


def test_a_symlinked_folder_and_the_current_folder(tmp_path, monkeypatch):
    target = tmp_path / "target"
    earlier_run(target)
    (tmp_path / "link").symlink_to(target)
    with replaced_folder(tmp_path / "link", NAMES) as staging:
        (staging / "b.csv").write_text("new b\n")
    assert (tmp_path / "link").is_symlink()
    assert sorted(os.listdir(target)) == ["b.csv", "mine", NOTES]
    monkeypatch.chdir(target)
    with replaced_folder(".", NAMES) as staging:
        (staging / "a.csv").write_text("new a\n")
    assert sorted(os.listdir(".")) == ["a.csv", "mine", NOTES]


def test_a_folder_in_the_way_of_a_file_is_refused_before_anything_moves(tmp_path):
    folder = tmp_path / "run"
    before = earlier_run(folder)
    (folder / "b.csv").unlink()
    (folder / "b.csv").mkdir()
    with pytest.raises(QuadnavError, match=r"b\.csv: a folder is in the way"), \
            replaced_folder(folder, NAMES) as staging:
        (staging / "a.csv").write_text("new a\n")
    assert (folder / "a.csv").read_bytes() == before["a.csv"]
    assert not [name for name in os.listdir(folder) if name.startswith(".")]


def test_staging_folders_of_killed_runs_are_swept_and_only_those(tmp_path):
    dead = _dead_pid()
    folder = tmp_path / "run"
    earlier_run(folder)
    swept = folder / f"{STAGING_PREFIX}{dead}-abcd_123"
    alive = folder / f"{STAGING_PREFIX}{os.getppid()}-abcd_123"  # a live process's
    lookalikes = [folder / f"{STAGING_PREFIX}{dead}-notes", folder / f"{STAGING_PREFIX}x",
                  folder / f"{STAGING_PREFIX}{9 ** 40}-abcd_123"]  # no process id
    for path in (swept, alive, *lookalikes):
        path.mkdir()
        (path / "a.csv").write_text("partial")
    with replaced_folder(folder, NAMES) as staging:
        (staging / "a.csv").write_text("new a\n")
    assert not swept.exists() and alive.exists() and all(p.exists() for p in lookalikes)


def _dead_pid() -> int:
    """The id of a process that has ended."""
    process = subprocess.Popen(["true"])
    process.wait()
    return process.pid


@pytest.fixture
def python_handles_ctrl_c():
    """Ctrl-C handled as a Python process does by default, whatever this one inherited (a
    background job of a shell starts with Ctrl-C ignored, and the gate leaves it so)."""
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, previous)


def test_stop_signals_while_the_files_move_in_take_effect_after_it(python_handles_ctrl_c):
    """Ctrl-C and SIGTERM that arrive while the files move in (the gate holding), or as
    the context manager's exit begins (its code guarded), are held back until the files
    are in place, then raised as usual; in the body, they pass straight through."""
    def stop(signum, frame):
        raise Stopped(signum)

    def guarded():
        return sys._getframe()

    previous = signal.signal(signal.SIGTERM, stop)  # as the console script sets it
    try:
        gate = _signal_gate(guard=guarded.__code__)
        signal.raise_signal(signal.SIGTERM)
        signal.raise_signal(signal.SIGINT)  # delivered and held: nothing raised
        assert gate.held == [signal.SIGTERM, signal.SIGINT]
        with pytest.raises(Stopped):
            gate.let_go()  # the body begins: the held signals go through
        with pytest.raises(KeyboardInterrupt):
            signal.raise_signal(signal.SIGINT)
        gate.handle(signal.SIGINT, guarded())  # handled in the guarded code: held
        assert gate.held == [signal.SIGINT]
        with pytest.raises(KeyboardInterrupt):
            gate.restore()
        assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
        assert signal.getsignal(signal.SIGTERM) is stop
    finally:
        signal.signal(signal.SIGTERM, previous)


def test_a_stop_raised_inside_a_finalizer_still_stops(monkeypatch, python_handles_ctrl_c):
    """A signal handled while the garbage collector runs a ``__del__`` (numba's compiled
    code has many) raises there, where Python would only print it and carry on; the
    console script sends it again, so the run still stops."""
    monkeypatch.setattr(sys, "unraisablehook", stop_again)

    class Finalized:
        def __del__(self):
            signal.raise_signal(signal.SIGINT)
            for _ in range(1000):  # the handler runs in here
                pass

    with pytest.raises(KeyboardInterrupt):
        Finalized()
        deadline = time.monotonic() + 10
        while time.monotonic() < deadline:
            time.sleep(0.001)
