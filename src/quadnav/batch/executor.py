"""Run one module-level function over many items on local worker processes or on Ray.

Generic: nothing here knows about missions. A job is ``function(shared, item)``, where
``function`` is a module-level function (picklable by reference), ``shared`` is data every
job needs (maps, settings; sent once to each worker process, not once per job) and ``item``
is the job's own small value. Results come back as ``(index of the item, result)`` as they
finish, in any order::

    with open_executor(shared, warm_up=load_kernels, workers=4) as executor:
        for index, result in executor.map_unordered(evaluate, items):
            ...

Local (:class:`LocalExecutor`): a :class:`~concurrent.futures.ProcessPoolExecutor` whose
workers are spawned (not forked: numba's compiled state and ``fork`` do not mix), each
made once with ``shared`` and ``warm_up(shared)`` run in its initializer (import, load the
compiled kernels). Workers ignore Ctrl-C, SIGTERM and SIGHUP: the parent handles them and
:meth:`~LocalExecutor.close` with ``cancel`` ends the workers at once.

Each worker runs its numba kernels on the threads :func:`~quadnav.batch.threads.numba_threads`
gives (one per worker unless a single local worker has the machine), set in the worker
before its first job (``threads`` of :func:`open_executor` sets another count).

Ray (:class:`RayExecutor`, the optional ``quadnav[ray]``; imported only here, only when
asked for): ``ray.init(address=...)``, or a local Ray started for the run without an
address; ``shared`` goes to the object store once (``ray.put``) and each worker process
reads it once; one remote task per item, results taken with ``ray.wait`` as they finish.
A job's result depends only on its ``shared`` and ``item``, so both give the same results.
"""

from __future__ import annotations

import logging
import multiprocessing
import os
import signal
import socket
import sys
import threading
import time
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from contextlib import contextmanager
from multiprocessing import resource_tracker
from types import TracebackType
from typing import Any, Protocol

from quadnav.batch.threads import numba_threads, use_numba_threads
from quadnav.errors import QuadnavError
from quadnav.signals import STOP_SIGNALS

#: ``function(shared, item) -> result``, defined at a module's top level.
Job = Callable[[Any, Any], Any]
#: ``warm_up(shared)``: run once in each worker before its first job.
WarmUp = Callable[[Any], None]


def cpu_count() -> int:
    """CPUs this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


class Executor(Protocol):
    """What :func:`open_executor` returns."""

    workers: int
    #: numba threads of each worker process
    numba_threads: int

    def map_unordered(self, function: Job, items: Sequence[Any]
                      ) -> Iterator[tuple[int, Any]]:
        """``(index, function(shared, items[index]))`` for every item, as each finishes."""

    def close(self, cancel: bool = False) -> None:
        """Release the workers; with ``cancel``, at once, dropping unfinished jobs."""

    def __enter__(self) -> Executor: ...

    def __exit__(self, kind: type[BaseException] | None, error: BaseException | None,
                 traceback: TracebackType | None) -> None: ...


class _Closing:
    """Context manager protocol: leaving the block closes the executor, cancelling the
    unfinished jobs when it ends with an exception (an error, Ctrl-C)."""

    def __enter__(self):
        return self

    def __exit__(self, kind: type[BaseException] | None, error: BaseException | None,
                 traceback: TracebackType | None) -> None:
        self.close(cancel=kind is not None)


# ------------------------------------------------------------------------------- local
_shared: Any = None


#: How often a local worker looks whether the process that started it is still there, s.
PARENT_CHECK_PERIOD = 0.5


def _start_worker(shared: Any, warm_up: WarmUp | None, threads: int, parent: int) -> None:
    """Initializer of a local worker: ignore stop signals, leave when ``parent`` (the
    batch's process id) is gone, set numba's ``threads``, keep ``shared``, warm up."""
    global _shared
    for signum in STOP_SIGNALS:
        signal.signal(signum, signal.SIG_IGN)
    threading.Thread(target=_leave_with, args=(parent,), daemon=True,
                     name="quadnav-parent-watch").start()
    use_numba_threads(threads)
    _shared = shared
    if warm_up is not None:
        warm_up(shared)


def _leave_with(parent: int) -> None:
    """In a worker: end the process once ``parent`` is gone (the worker is then someone
    else's child). A worker ignores stop signals, so a batch killed with SIGKILL (the OOM
    killer, a CI time-out) left its workers, about 220 MB each, running for good."""
    while os.getppid() == parent:
        time.sleep(PARENT_CHECK_PERIOD)
    os._exit(1)


def _start_resource_tracker() -> None:
    """Start multiprocessing's resource tracker (which the pool's queues and locks use)
    ignoring every stop signal, as the workers do: it ignores SIGINT and SIGTERM itself,
    but a SIGHUP to the whole process group (a closed terminal) ended it, and multiprocessing
    then printed a traceback and "process died unexpectedly ... resources might leak". An
    ignored signal stays ignored in the process started now."""
    if not hasattr(signal, "SIGHUP"):
        return
    held = signal.signal(signal.SIGHUP, signal.SIG_IGN)
    try:
        resource_tracker.ensure_running()
    finally:
        signal.signal(signal.SIGHUP, held)


def _call(function: Job, item: Any) -> Any:
    return function(_shared, item)


class LocalExecutor(_Closing):
    """Jobs on ``workers`` local processes (see the module docstring)."""

    def __init__(self, shared: Any, warm_up: WarmUp | None = None,
                 workers: int | None = None, threads: int | None = None) -> None:
        self.workers = workers or cpu_count()
        self.numba_threads = threads or numba_threads(self.workers)
        _start_resource_tracker()
        self._pool = ProcessPoolExecutor(
            self.workers, mp_context=multiprocessing.get_context("spawn"),
            initializer=_start_worker,
            initargs=(shared, warm_up, self.numba_threads, os.getpid()))

    def map_unordered(self, function: Job, items: Sequence[Any]
                      ) -> Iterator[tuple[int, Any]]:
        pending: dict[Future, int] = {self._pool.submit(_call, function, item): index
                                      for index, item in enumerate(items)}
        while pending:
            done, _ = wait(pending, return_when=FIRST_COMPLETED)
            for future in done:
                yield pending.pop(future), future.result()

    def close(self, cancel: bool = False) -> None:
        if cancel:
            # The workers ignore stop signals: end them at once. (Python 3.14 has
            # ProcessPoolExecutor.kill_workers for this.)
            processes = list(getattr(self._pool, "_processes", {}).values())
            self._pool.shutdown(wait=False, cancel_futures=True)
            for process in processes:
                process.kill()
            for process in processes:
                process.join()
        else:
            self._pool.shutdown(wait=True)


# --------------------------------------------------------------------------------- Ray
_ray_shared: dict[str, Any] = {}


def _ray_job(function: Job, shared_ref: list, warm_up: WarmUp | None, threads: int,
             item: Any) -> Any:
    """A Ray task: ``function(shared, item)`` on numba's ``threads``, with ``shared`` read
    from the object store (and ``warm_up`` run) once per worker process."""
    import ray

    use_numba_threads(threads)  # on the thread that runs the task, before the job
    ref = shared_ref[0]  # in a list, so that Ray passes the reference, not the value
    if ref.hex() not in _ray_shared:
        _ray_shared.clear()
        shared = ray.get(ref)
        if warm_up is not None:
            warm_up(shared)
        _ray_shared[ref.hex()] = shared
    return function(_ray_shared[ref.hex()], item)


def _import_ray():
    try:
        import ray
    except ImportError:
        raise QuadnavError("--ray needs the optional Ray package: "
                           "python -m pip install 'quadnav[ray]'") from None
    return ray


#: Seconds to wait for a Ray cluster's head to answer (``ray.init`` itself waits forever).
CONNECT_TIMEOUT = 10.0


def _host_and_port(address: str) -> tuple[str, int] | None:
    """The host and port of a ``[ray://]HOST:PORT`` address; None for another (``auto``)."""
    host, _, port = address.removeprefix("ray://").rpartition(":")
    return (host.strip("[]"), int(port)) if host and port.isdigit() else None


def check_reachable(address: str) -> None:
    """QuadnavError unless something answers at the ``HOST:PORT`` of ``address`` (a
    ``ray://`` prefix allowed; ``auto`` and addresses without a port are left to Ray)."""
    host_and_port = _host_and_port(address)
    if host_and_port is None:
        return
    try:
        socket.create_connection(host_and_port, CONNECT_TIMEOUT).close()
    except OSError as error:
        reason = error.strerror or str(error) or type(error).__name__
        raise QuadnavError(f"--ray {address}: cannot reach the Ray cluster's head: {reason}; "
                           "start it with ray start --head") from None


#: Where a client finds a Ray cluster's token (Ray's token authentication).
TOKEN_PLACES = ("the cluster's token (ray get-auth-token on the head prints it) in "
                "RAY_AUTH_TOKEN, ~/.ray/auth_token or a file that RAY_AUTH_TOKEN_PATH names")


@contextmanager
def _stderr_dropped() -> Iterator[None]:
    """Drop what is written on file descriptor 2 in the block (Ray's C++ warnings)."""
    sys.stderr.flush()
    saved = os.dup(2)
    with open(os.devnull, "wb") as null:
        os.dup2(null.fileno(), 2)
        try:
            yield
        finally:
            os.dup2(saved, 2)
            os.close(saved)


def check_authenticated(address: str) -> None:
    """QuadnavError at once unless the Ray cluster's head at ``address`` (``HOST:PORT``,
    reachable) takes this client's authentication token, or asks for none (other
    addresses, ``auto`` or ``ray://...``, are left to Ray).

    A head started by ``ray start --head`` where a token is found (Ray's token
    authentication) refuses a client without it; ``ray.init`` would then retry for about
    20 s and say only that it failed to connect, the cause left in Ray's warnings. Also
    QuadnavError when what answers is no Ray head. Nothing is checked with a Ray without
    token authentication.
    """
    try:
        from ray._private.authentication.authentication_token_setup import (
            ensure_token_if_auth_enabled,
        )
        from ray._raylet import GcsClient
        from ray.exceptions import AuthenticationError, RayError
    except ImportError:  # a Ray before token authentication
        return
    if address.startswith("ray://") or _host_and_port(address) is None:
        return
    token_mode = os.environ.get("RAY_AUTH_MODE", "").lower() == "token"
    try:
        ensure_token_if_auth_enabled(None, create_token_if_missing=False)
    except AuthenticationError:
        raise QuadnavError(f"--ray {address}: RAY_AUTH_MODE is token but no authentication "
                           f"token was found: put {TOKEN_PLACES}") from None
    try:
        with _stderr_dropped():  # Ray warns of the refusal in a line of its own
            GcsClient(address=address)  # asks the head for the cluster's id
    except AuthenticationError:
        problem = ("the Ray cluster refused this client's authentication token (not the "
                   "cluster's): put " if token_mode else "the Ray cluster asks for an "
                   "authentication token and RAY_AUTH_MODE is not token here: set "
                   "RAY_AUTH_MODE=token and put ")
        raise QuadnavError(f"--ray {address}: {problem}{TOKEN_PLACES}") from None
    except RayError as error:  # something else answers there (after about 40 s)
        raise QuadnavError(f"--ray {address}: no Ray cluster's head answers there: "
                           f"{str(error).strip().splitlines()[0]}") from None


class RayExecutor(_Closing):
    """Jobs as Ray tasks on the cluster at ``address``, or on a local Ray of ``workers``
    CPUs started for the run when ``address`` is None (see the module docstring)."""

    def __init__(self, shared: Any, warm_up: WarmUp | None = None,
                 address: str | None = None, workers: int | None = None,
                 threads: int | None = None) -> None:
        ray = self._ray = _import_ray()
        options: dict[str, Any] = {"logging_level": logging.WARNING, "log_to_driver": False,
                                   "configure_logging": True}
        if address is None:
            options |= {"num_cpus": workers or cpu_count(), "include_dashboard": False}
        else:
            check_reachable(address)
            check_authenticated(address)
        try:
            ray.init(address=address, **options)
        except (ConnectionError, RuntimeError, ValueError, ray.exceptions.RayError) as error:
            first_line = str(error).strip().splitlines()[0] if str(error).strip() else ""
            raise QuadnavError(f"cannot connect to the Ray cluster at {address}: "
                               f"{first_line}") from None
        self.workers = int(ray.cluster_resources().get("CPU", 1))
        self.numba_threads = threads or numba_threads(self.workers, ray=True)
        self._shared = [ray.put(shared)]
        self._warm_up = warm_up
        self._task = ray.remote(num_cpus=1)(_ray_job)
        self._pending: dict[Any, int] = {}

    def map_unordered(self, function: Job, items: Sequence[Any]
                      ) -> Iterator[tuple[int, Any]]:
        ray = self._ray
        self._pending = {self._task.remote(function, self._shared, self._warm_up,
                                           self.numba_threads, item): index
                         for index, item in enumerate(items)}
        while self._pending:
            done, _ = ray.wait(list(self._pending), num_returns=1)
            for ref in done:
                index = self._pending.pop(ref)
                yield index, ray.get(ref)

    def close(self, cancel: bool = False) -> None:
        if cancel:
            for ref in self._pending:
                self._ray.cancel(ref, force=True)
        self._pending = {}
        self._ray.shutdown()


def open_executor(shared: Any, warm_up: WarmUp | None = None, workers: int | None = None,
                  ray: bool = False, address: str | None = None,
                  threads: int | None = None) -> Executor:
    """Local worker processes (``workers``, default: one per CPU), or with ``ray`` a Ray
    cluster at ``address`` (None: a local Ray of ``workers`` CPUs), each worker running
    numba on ``threads`` (default: :func:`~quadnav.batch.threads.numba_threads`). QuadnavError
    when Ray is asked for but not installed or the cluster cannot be reached."""
    if ray:
        return RayExecutor(shared, warm_up, address, workers, threads)
    return LocalExecutor(shared, warm_up, workers, threads)
