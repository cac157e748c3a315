"""No room for the output: one line naming the folder, exit 2, and nothing written: a small
tmpfs where this machine lets us mount one, and everywhere a file-size limit (RLIMIT_FSIZE),
which fails a write the same way (EFBIG) as a full disk does (ENOSPC)."""

from __future__ import annotations

import resource
import signal
import subprocess

import pytest
from clitools import QUADNAV, run_here

#: One worker for the module, so that its module-scoped fixtures are built once under
#: --dist loadgroup (each test apart would build them on each worker).
pytestmark = pytest.mark.xdist_group("full-disk")


@pytest.fixture(scope="module")
def saved(tmp_path_factory):
    """A saved path and a fly run folder, written where there is room."""
    folder = tmp_path_factory.mktemp("saved")
    assert run_here("plan", "forest", "--improve", "2000", "--no-figures", "--quiet",
                    "-o", folder / "plan").returncode == 0
    assert run_here("fly", "forest", "--improve", "2000", "--no-figures", "--quiet",
                    "-o", folder / "fly").returncode == 0
    return folder


def commands(saved) -> list[list[str]]:
    """The commands that write a run's files (the issue's list)."""
    return [["fly", "forest", "--improve", "2000", "--quiet"],
            ["fly", "forest", "--improve", "2000", "--no-figures", "--quiet"],
            ["traj", "forest", "--path", str(saved / "plan" / "path.csv")],
            ["refly", str(saved / "fly"), "--no-figures"],
            ["tello", "fly", "forest", "--improve", "2000", "--dry-run"]]


def _small_files() -> None:
    """In the child: no file may grow past 16 KiB, and going past it is an error (EFBIG),
    not the signal that would kill the process."""
    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
    resource.setrlimit(resource.RLIMIT_FSIZE, (16 * 1024, 16 * 1024))


@pytest.mark.parametrize("index", range(5))
def test_no_room_for_a_file_is_one_line_and_leaves_nothing(saved, tmp_path, index):
    args = commands(saved)[index]
    out = tmp_path / "out"
    done = subprocess.run([*QUADNAV, *args, "-o", str(out)], capture_output=True, text=True,
                          preexec_fn=_small_files, timeout=300, check=False)
    assert done.returncode == 2, done.stderr[-3000:]
    assert done.stderr.strip().splitlines() == [f"quadnav: error: {out}: cannot write: File "
                                                "too large"]
    assert not out.exists()


@pytest.fixture
def tiny_tmpfs(tmp_path):
    """A 64 KiB tmpfs, where this machine lets us mount one (root in a container that
    allows it); skipped otherwise."""
    mount = tmp_path / "tiny"
    mount.mkdir()
    done = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=64k", "tmpfs", str(mount)],
                          capture_output=True, text=True, check=False)
    if done.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here: {done.stderr.strip()[:100]}")
    yield mount
    subprocess.run(["umount", str(mount)], check=False)


def test_a_full_tmpfs_is_one_line_and_leaves_nothing(saved, tiny_tmpfs):
    # A full disk (ENOSPC) reaches the same handler as a file-size limit (EFBIG), which the
    # test above checks for each command: the fly with figures, the most files, shows it.
    out = tiny_tmpfs / "out"
    done = subprocess.run([*QUADNAV, *commands(saved)[0], "-o", str(out)], capture_output=True,
                          text=True, timeout=300, check=False)
    assert done.returncode == 2, done.stderr[-3000:]
    assert done.stderr.strip().splitlines() == [f"quadnav: error: {out}: cannot write: "
                                                "No space left on device"]
    assert list(tiny_tmpfs.iterdir()) == []
