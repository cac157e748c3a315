"""Jobs and warm-ups for the executor tests, in a module of their own: a spawned worker
imports the module of every function it is given, and a test module's imports (the batch's
modules, pyarrow) would add about half a second of CPU to each worker's start."""

from __future__ import annotations

import os
import signal


def kill_worker_for(shared: object, item: int) -> int:
    """A job: ``item`` times ``shared``, or for item 0 its worker killed (SIGKILL)."""
    if item == 0:
        os.kill(os.getpid(), signal.SIGKILL)
    return shared * item


def kill_worker(shared: object) -> None:
    """A warm-up that kills its worker (SIGKILL)."""
    os.kill(os.getpid(), signal.SIGKILL)
