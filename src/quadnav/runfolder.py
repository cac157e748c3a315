"""Output folders replaced whole or not at all.

The commands that write a folder of files (``fly``, ``plan``, ``traj``, ``kino``, ``tello
fly``) write them into a hidden staging folder inside the output folder,
``DIR/.quadnav-partial-PID-XXXXXXXX``, and move them into place only when all are written
(:func:`replaced_folder`). The move — one rename per file, then the removal of the files of
an earlier run that this one does not write — runs with Ctrl-C, SIGTERM and SIGHUP held
back, so a run stopped by any of them leaves either the earlier run's files exactly as they
were or the new run's complete set, never a mix, and no staging folder. A signal held back
takes effect right after the move.

The folder itself is kept, not swapped for a new one: a shell or file browser inside it, its
permissions, a symbolic link to it, ``-o .`` and a mount point all keep working, and files in
it that the command does not write (yours, or another command's) are never touched. Only
SIGKILL or a power cut during the move itself (a few renames) could leave a mix; a staging
folder left by a killed run is removed by the next run into the same folder (only folders of
that exact name whose process is gone).
"""

from __future__ import annotations

import os
import re
import shutil
import tempfile
from collections.abc import Collection
from pathlib import Path
from types import CodeType, TracebackType

from quadnav.errors import DISK_FULL, QuadnavError, WriteError
from quadnav.signals import StopSignalHandler

#: Start of a staging folder's name; the process id and a random suffix follow.
STAGING_PREFIX = ".quadnav-partial-"
_STAGING_NAME = re.compile(re.escape(STAGING_PREFIX) + r"([1-9][0-9]*)-[a-z0-9_]{8}")


def _signal_gate(guard: CodeType | None = None) -> StopSignalHandler:
    """A handler, installed, that holds every stop signal back (``guard``: see
    :class:`~quadnav.signals.StopSignalHandler`) and passes them on, in order, to the
    handlers it replaced once it lets go (:meth:`~quadnav.signals.StopSignalHandler.let_go`)
    or is restored (the first held)."""
    gate = StopSignalHandler(True, guard=guard, pass_on=True)
    gate.install()
    return gate


def _nearest_existing(folder: Path) -> Path:
    """``folder`` or its nearest ancestor that exists; QuadnavError if that is not a
    folder (a file, or a symbolic link to nothing)."""
    existing = folder
    while not os.path.lexists(existing):
        existing = existing.parent
    if not existing.is_dir():
        if existing.is_symlink():
            raise QuadnavError(f"{existing}: a symbolic link to {os.readlink(existing)}, "
                               "which does not exist; expected a folder for the output")
        raise QuadnavError(f"{existing}: expected a folder for the output, found a file")
    return existing


def _make_staging(folder: Path) -> Path:
    """A new, empty staging folder in the existing ``folder``."""
    return Path(tempfile.mkdtemp(prefix=f"{STAGING_PREFIX}{os.getpid()}-", dir=folder))


def _cannot_write(folder: Path, existing: Path, error: OSError) -> QuadnavError:
    where = "into the output folder" if existing == folder else (
        f"the output folder in {existing}")
    verb = "write" if existing == folder else "create"
    return QuadnavError(f"{folder}: cannot {verb} {where}: {error.strerror}")


def check_output_folder(folder: str | Path) -> Path:
    """Check, before any work, that a run can write the folder ``folder``: it is a folder
    in which files can be made, or one that can be created. Returns it as a Path;
    QuadnavError (one line) if not. Leaves nothing behind."""
    folder = Path(folder)
    existing = _nearest_existing(folder)
    gate = _signal_gate()  # a stop between making the probe and removing it waits
    try:
        os.rmdir(_make_staging(existing))
    except OSError as error:
        raise _cannot_write(folder, existing, error) from None
    finally:
        gate.restore()
    return folder


def _create(folder: Path) -> list[Path]:
    """Create ``folder`` and its missing parents; returns those created, deepest first."""
    existing = _nearest_existing(folder)
    created = []
    path = folder
    while path != existing:
        created.append(path)
        path = path.parent
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        _remove_empty(created)
        raise _cannot_write(folder, existing, error) from None
    return created


def _remove_empty(folders: list[Path]) -> None:
    """Remove ``folders`` (deepest first) while they exist and are empty."""
    for path in folders:
        try:
            path.rmdir()
        except FileNotFoundError:
            continue
        except OSError:
            return


def _process_alive(pid: int) -> bool:
    """Whether a process ``pid`` exists (one of another user's too)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OverflowError):
        return True
    return True


def _sweep(folder: Path) -> None:
    """Remove the staging folders in ``folder`` whose process is gone (a run killed
    outright, by SIGKILL or a power cut)."""
    with os.scandir(folder) as entries:
        stale = [entry.path for entry in entries
                 if (match := _STAGING_NAME.fullmatch(entry.name))
                 and entry.is_dir(follow_symlinks=False)
                 and not _process_alive(int(match[1]))]
    for path in stale:
        shutil.rmtree(path, ignore_errors=True)


def _staged(staging: Path) -> list[str]:
    """The files a run wrote into ``staging`` (hidden names: temporary files)."""
    return sorted(name for name in os.listdir(staging) if not name.startswith("."))


def _move_in(staging: Path, folder: Path, names: Collection[str]) -> None:
    """Move the staged files into ``folder`` and remove the files in ``names`` that were
    not staged. QuadnavError, before anything moves, if a folder is in the way of a
    file."""
    staged = _staged(staging)
    for name in {*staged, *names}:
        target = folder / name
        if target.is_dir() and not target.is_symlink():
            raise QuadnavError(f"{target}: a folder is in the way of the output file {name}")
    try:
        for name in staged:
            os.replace(staging / name, folder / name)
        for name in names:
            if name not in staged:
                (folder / name).unlink(missing_ok=True)
    except OSError as error:
        raise QuadnavError(f"{folder}: cannot write: {error.strerror}") from None


def replaced_folder(folder: str | Path, names: Collection[str],
                    keep_partial: bool = False) -> FolderReplacement:
    """A context manager giving an empty staging folder for a run's files; when its block
    ends, the files move into ``folder`` (created if needed), all at once.

    Args:
        folder: the output folder.
        names: every file name the command writes: those of an earlier run that this one
            does not write are removed with the move, so the folder never mixes two runs.
            Other files in ``folder`` are left alone.
        keep_partial: when the block ends with an exception (an error, Ctrl-C, SIGTERM),
            move in what was written all the same, if anything was (a flight's log must
            outlive the failed flight). By default the folder is then left exactly as it
            was, and folders this call created are removed again.

    Raises:
        QuadnavError: (one line) the folder cannot be created or written.
    """
    return FolderReplacement(Path(folder), names, keep_partial)


class FolderReplacement:
    """The context manager of :func:`replaced_folder`: ``with`` gives the staging folder.

    Stop signals are held from the start of ``__enter__`` until the body begins, and
    from the start of ``__exit__`` (its very first instruction: a signal handled there
    is held too) until the files are in place or the staging folder is gone."""

    def __init__(self, folder: Path, names: Collection[str], keep_partial: bool) -> None:
        self.folder = folder
        self.names = names
        self.keep_partial = keep_partial
        self.staging: Path | None = None
        self._created: list[Path] = []
        self._gate: StopSignalHandler | None = None

    def __enter__(self) -> Path:
        self._gate = _signal_gate(guard=FolderReplacement.__exit__.__code__)
        try:
            self._created = _create(self.folder)
            _sweep(self.folder)
            try:
                self.staging = _make_staging(self.folder)
            except OSError as error:
                raise _cannot_write(self.folder, self.folder, error) from None
            self._gate.let_go()  # a stop held while setting up is raised here
        except BaseException:
            self._gate.holding = True
            self._finish(move=False)
            raise
        return self.staging

    def __exit__(self, kind: type[BaseException] | None, error: BaseException | None,
                 traceback: TracebackType | None) -> None:
        self._gate.holding = True
        full = ((isinstance(error, OSError) and error.errno in DISK_FULL)
                or (isinstance(error, WriteError) and error.full))
        self._finish(move=kind is None or (self.keep_partial and not full
                                           and bool(_staged(self.staging))))
        if full:  # no room for the files: none was moved in, and the folder is named
            reason = error.strerror if isinstance(error, OSError) else error.reason
            raise WriteError(self.folder, reason, full=True) from None

    def _finish(self, move: bool) -> None:
        """Move the staged files in (if ``move``), remove the staging folder and the
        folders made for it that stayed empty; then let stop signals through again."""
        try:
            if move:
                _move_in(self.staging, self.folder, self.names)
        finally:
            if self.staging is not None:
                shutil.rmtree(self.staging, ignore_errors=True)
            _remove_empty(self._created)
            self._gate.restore()
