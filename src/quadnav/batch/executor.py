"""Run one module-level function over many items on local worker processes or on Ray.

Generic: nothing here knows about missions. A job is ``function(shared, item)``, where
``function`` is a module-level function (picklable by reference), ``shared`` is data every
job needs (maps, settings; sent once to each worker process, not once per job) and ``item``
is the job's own small value. Results come back as ``(index of the item, result)`` as they
finish, in any order::

    with open_executor(shared, warm_up=load_kernels, workers=4) as executor:
        for index, result in executor.map_unordered(evaluate, items):
            ...

Local (:class:`LocalExecutor`): ``workers`` processes, spawned (not forked: numba's
compiled state and ``fork`` do not mix), each made once with ``shared`` and
``warm_up(shared)`` run as it starts (import, load the compiled kernels), then given one
job at a time through a pipe of its own, so the parent knows which job each runs. Workers
ignore Ctrl-C, SIGTERM and SIGHUP: the parent handles them and
:meth:`~LocalExecutor.close` with ``cancel`` ends the workers at once.

A worker process that dies (killed by a signal or the OOM killer, a crash in compiled
code, ``os._exit`` in a plug-in) loses only the job it ran: a new worker takes its place
(started when a job needs it) and the job runs again, at most :data:`RETRIES` times; a job
whose worker dies every time is then given up, its result ``lost(item, reason)``
(:meth:`Executor.map_unordered`). A job of several parts (``split(item)``: a batch's
missions that share a plan) runs again as its parts, one job each, so that a part that
kills its worker every time is the only one given up. A worker that dies before it has
started (in its warm-up) is an error at once (:class:`WorkerDiedError`): another would die
the same way.

A job may be given a time limit (``time_limit`` of :meth:`LocalExecutor.map_unordered`,
wall-clock seconds on its worker, its warm-up not counted): a job that runs longer (an
endless loop in a plug-in) has its worker killed (SIGKILL) and replaced, and its result is
``lost(item, reason)`` at once, not run again (it would run as long again). Each executor
counts the jobs run again (:attr:`~_Base.retried`). A job's result depends only on its
``shared`` and ``item``, so a job run again gives the same result.

Each worker runs its numba kernels on the threads :func:`~quadnav.batch.threads.numba_threads`
gives (one per worker unless a single local worker has the machine), set in the worker
before its first job (``threads`` of :func:`open_executor` sets another count).

Ray (:class:`RayExecutor`, the optional ``quadnav[ray]``; imported only here, only when
asked for): ``ray.init(address=...)``, or a local Ray started for the run without an
address; ``shared`` goes to the object store once (``ray.put``) and each worker process
reads it once; one remote task per item, results taken with ``ray.wait`` as they finish.
A task whose worker process or node dies is submitted again, as a local job is run
again (Ray's own retries are off, so that each is counted). Both give the same results.
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
import traceback
from collections import Counter, deque
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager, suppress
from multiprocessing import resource_tracker
from multiprocessing.connection import Connection
from multiprocessing.connection import wait as wait_for
from multiprocessing.process import BaseProcess
from types import TracebackType
from typing import Any, Protocol

from quadnav.batch.threads import numba_threads, use_numba_threads
from quadnav.errors import QuadnavError
from quadnav.signals import STOP_SIGNALS

#: ``function(shared, item) -> result``, defined at a module's top level.
Job = Callable[[Any, Any], Any]
#: ``warm_up(shared)``: run once in each worker before its first job.
WarmUp = Callable[[Any], None]
#: ``lost(item, reason) -> result``: the result of a job given up because its worker
#: process died each time it ran, ``reason`` saying so in words.
Lost = Callable[[Any, str], Any]
#: ``split(item) -> parts``: the items a job runs again as after its worker died (one, or
#: none to run it again whole: a job of one part).
Split = Callable[[Any], list[Any]]


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
    #: jobs run again because the worker process running them died (so far)
    retried: int
    #: the items of those jobs
    retried_jobs: list[Any]

    def map_unordered(self, function: Job, items: Sequence[Any], lost: Lost | None = None,
                      split: Split | None = None, time_limit: float | None = None
                      ) -> Iterator[tuple[int, Any]]:
        """``(index, function(shared, items[index]))`` for every item, as each finishes.
        A job whose worker process dies is run again, at most :data:`RETRIES` times; then
        its result is ``lost(item, reason)`` (WorkerDiedError without ``lost``). With
        ``split``, a job of several parts runs again as one job per part instead, each
        part's index counting on from ``len(items)`` (in :attr:`retried_jobs`' order).
        With ``time_limit`` (s, local workers only), a job that runs longer is stopped and
        its result is ``lost(item, reason)`` (TimeLimitError without ``lost``)."""

    def close(self, cancel: bool = False) -> None:
        """Release the workers; with ``cancel``, at once, dropping unfinished jobs."""

    def __enter__(self) -> Executor: ...

    def __exit__(self, kind: type[BaseException] | None, error: BaseException | None,
                 traceback: TracebackType | None) -> None: ...


class _Base:
    """What both executors share: the context manager protocol (leaving the block closes
    the executor, cancelling the unfinished jobs when it ends with an exception: an error,
    Ctrl-C) and the count of jobs run again (:attr:`retried`)."""

    def __init__(self) -> None:
        self._calls: list[_Deaths] = []

    def _deaths(self, items: Sequence[Any], lost: Lost | None, split: Split | None
                ) -> _Deaths:
        """The worker deaths of a new :meth:`map_unordered` call's jobs."""
        self._calls.append(_Deaths(items, lost, split))
        return self._calls[-1]

    @property
    def retried(self) -> int:
        """The jobs run again because the worker process running them died, so far."""
        return len(self.retried_jobs)

    @property
    def retried_jobs(self) -> list[Any]:
        """The items of the jobs counted in :attr:`retried`."""
        return [deaths.items[index] for deaths in self._calls for index in deaths.counts]

    def close(self, cancel: bool = False) -> None:
        raise NotImplementedError

    def __enter__(self):
        return self

    def __exit__(self, kind: type[BaseException] | None, error: BaseException | None,
                 traceback: TracebackType | None) -> None:
        self.close(cancel=kind is not None)


# ------------------------------------------------------------------------- worker deaths
#: How many times a job is run again after the worker process running it died (killed by
#: a signal, the OOM killer, a crash in compiled code, ``os._exit``) before it is given up.
RETRIES = 2


class WorkerDiedError(QuadnavError):
    """A job whose worker process died each of the :data:`RETRIES` + 1 times it ran, when
    the caller gave no ``lost`` result for it (exit code 1: a failed run, not bad input)."""

    exit_code = 1


class TimeLimitError(QuadnavError):
    """A job that ran longer than its time limit, when the caller gave no ``lost``
    result for it (exit code 1: a failed run, not bad input)."""

    exit_code = 1


def time_limit_reason(limit: float) -> str:
    """Why a job stopped at the time limit of ``limit`` s was given up, in words."""
    return f"ran longer than the {limit:g} s limit; stopped"


class _Deaths:
    """The worker deaths of the jobs of one :meth:`Executor.map_unordered` call: its
    ``items``, the parts of jobs split after a death appended."""

    def __init__(self, items: Sequence[Any], lost: Lost | None, split: Split | None
                 ) -> None:
        self.items = list(items)
        self.lost = lost
        self.split = split
        self.counts: Counter[int] = Counter()

    def run_again(self, index: int) -> list[int]:
        """Count a death of job ``index``'s worker; the jobs to run in its place: itself,
        its parts (new items, each counting the death instead of it), or none when it has
        run :data:`RETRIES` times again already."""
        self.counts[index] += 1
        if self.counts[index] > RETRIES:
            return []
        parts = [] if self.split is None else self.split(self.items[index])
        if len(parts) <= 1:
            return [index]
        deaths = self.counts.pop(index)
        first = len(self.items)
        self.items += parts
        self.counts.update(dict.fromkeys(range(first, len(self.items)), deaths))
        return list(range(first, len(self.items)))

    def given_up(self, index: int, cause: str) -> Any:
        """The result of job ``index``, given up after its worker's last death of
        ``cause``: ``lost(item, reason)``, or WorkerDiedError without ``lost``."""
        reason = f"its worker process died {RETRIES + 1} times ({cause}); given up"
        if self.lost is None:
            raise WorkerDiedError(f"a job's worker process died {RETRIES + 1} times ({cause}); "
                             "given up")
        return self.lost(self.items[index], reason)

    def timed_out(self, index: int, limit: float) -> Any:
        """The result of job ``index``, stopped at the time limit of ``limit`` s:
        ``lost(item, reason)``, or TimeLimitError without ``lost``."""
        reason = time_limit_reason(limit)
        if self.lost is None:
            raise TimeLimitError(f"a job {reason}")
        return self.lost(self.items[index], reason)


# ------------------------------------------------------------------------------- local
_shared: Any = None


#: How often a local worker looks whether the process that started it is still there, s.
PARENT_CHECK_PERIOD = 0.5


def _start_worker(shared: Any, warm_up: WarmUp | None, threads: int, parent: int) -> None:
    """Start a local worker: ignore stop signals, leave when ``parent`` (the batch's
    process id) is gone, set numba's ``threads``, keep ``shared``, warm up."""
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
    """Start multiprocessing's resource tracker (which spawning a process starts) ignoring
    every stop signal, as the workers do: it ignores SIGINT and SIGTERM itself, but a SIGHUP
    to the whole process group (a closed terminal) ended it, and multiprocessing then
    printed a traceback and "process died unexpectedly ... resources might leak". An
    ignored signal stays ignored in the process started now."""
    if not hasattr(signal, "SIGHUP"):
        return
    held = signal.signal(signal.SIGHUP, signal.SIG_IGN)
    try:
        resource_tracker.ensure_running()
    finally:
        signal.signal(signal.SIGHUP, held)


#: What a local worker sends once it has started; and what :meth:`_Worker.receive` returns
#: for a worker that died without answering.
STARTED, DIED = "started", "died"


def _serve(connection: Connection, shared: Any, warm_up: WarmUp | None, threads: int,
           parent: int) -> None:
    """A local worker's process: start (:func:`_start_worker`) and say so (:data:`STARTED`),
    then answer each ``(function, item)`` received on ``connection`` with ``(True, result)``
    or, when the job raised, ``(False, (error, traceback))``, until None or the parent's end
    is closed. A warm-up that raised answers every job with its error."""
    failed = None
    try:
        _start_worker(shared, warm_up, threads, parent)
        connection.send(STARTED)
    except Exception as error:
        failed = _failure(error)
    while True:
        try:
            task = connection.recv()
        except EOFError:
            return
        if task is None:
            return
        if failed is not None:
            reply = failed
        else:
            function, item = task
            try:
                reply = (True, function(_shared, item))
            except Exception as error:
                reply = _failure(error)
        try:
            connection.send(reply)
        except Exception as error:  # a result that cannot be pickled
            connection.send(_failure(error))


def _failure(error: Exception) -> tuple[bool, tuple[Exception, str]]:
    """A worker's answer for a job that raised ``error`` (in its ``except`` block)."""
    return False, (error, traceback.format_exc())


def _result(answer: tuple[bool, Any]) -> Any:
    """The result in a worker's ``answer``; the job's exception raised again, with the
    worker's traceback as its cause, when it raised one."""
    done, value = answer
    if not done:
        error, trace = value
        raise error from _RemoteTracebackError(trace)
    return value


class _RemoteTracebackError(Exception):
    """The traceback of a job's exception in its worker, as the cause of the exception
    raised again in the parent."""

    def __str__(self) -> str:
        return f"\n\"\"\"\n{self.args[0]}\"\"\""


def _end_of(process: BaseProcess) -> str:
    """How a worker process that is gone ended, in words."""
    process.join()
    code = process.exitcode
    if code is not None and code < 0:
        try:
            return f"killed by {signal.Signals(-code).name}"
        except ValueError:
            return f"killed by signal {-code}"
    return f"exit code {code}"


class _Worker:
    """A local worker process (:func:`_serve`), the parent's end of its connection and the
    index of the job it runs (None when idle)."""

    def __init__(self, arguments: tuple) -> None:
        spawn = multiprocessing.get_context("spawn")
        self.connection, theirs = spawn.Pipe()
        self.process = spawn.Process(target=_serve, args=(theirs, *arguments),
                                     name="quadnav-worker")
        self.process.start()
        theirs.close()
        self.job: int | None = None
        self.started = False
        #: when the worker began its job (time.monotonic(), s); None while it warms up
        self.began: float | None = None

    def run(self, index: int, function: Job, item: Any) -> None:
        """Send job ``index``: ``function(shared, item)``. A worker that died meanwhile is
        found by :meth:`receive`."""
        self.job = index
        self.began = time.monotonic() if self.started else None
        with suppress(OSError):  # BrokenPipeError: it died
            self.connection.send((function, item))

    def overran(self, limit: float | None, now: float) -> bool:
        """Whether its job has run longer than ``limit`` s (None: no limit) at ``now``."""
        return limit is not None and self.began is not None and now - self.began > limit

    def receive(self) -> tuple[bool, Any] | str | None:
        """The worker's answer to its job; None while it has not answered (noting that it
        started, :attr:`started`, when it says so); :data:`DIED` when it died without an
        answer."""
        try:
            while self.connection.poll():
                message = self.connection.recv()
                if message != STARTED:
                    return message
                self.started = True
                self.began = time.monotonic()  # the job's time counts from here
        except (EOFError, OSError):
            return DIED
        return None if self.process.is_alive() else DIED

    def end(self, cancel: bool) -> None:
        """End the worker: at once with ``cancel`` (it ignores stop signals: SIGKILL),
        else once it has finished its job."""
        if cancel:
            self.process.kill()
        else:
            with suppress(OSError):
                self.connection.send(None)
        self.process.join()
        self.connection.close()


class LocalExecutor(_Base):
    """Jobs on ``workers`` local processes (see the module docstring)."""

    def __init__(self, shared: Any, warm_up: WarmUp | None = None,
                 workers: int | None = None, threads: int | None = None) -> None:
        self.workers = workers or cpu_count()
        self.numba_threads = threads or numba_threads(self.workers)
        super().__init__()
        _start_resource_tracker()
        self._arguments = (shared, warm_up, self.numba_threads, os.getpid())
        #: the workers; None in the place of one that died, until a job needs it again
        self._pool: list[_Worker | None] = [_Worker(self._arguments)
                                            for _ in range(self.workers)]

    def map_unordered(self, function: Job, items: Sequence[Any], lost: Lost | None = None,
                      split: Split | None = None, time_limit: float | None = None
                      ) -> Iterator[tuple[int, Any]]:
        todo = deque(range(len(items)))
        deaths = self._deaths(items, lost, split)
        items = deaths.items
        while todo or self._busy():
            for place, worker in enumerate(self._pool):
                if todo and (worker is None or worker.job is None):
                    if worker is None:  # one that died: started again when needed only
                        worker = self._pool[place] = _Worker(self._arguments)
                    index = todo.popleft()
                    worker.run(index, function, items[index])
            busy = self._busy()
            wait_for([*(w.connection for w in busy), *(w.process.sentinel for w in busy)],
                     _time_left(busy, time_limit))
            for worker in busy:
                answer = worker.receive()
                if answer is None:
                    if worker.overran(time_limit, time.monotonic()):
                        index, worker.job = worker.job, None
                        worker.process.kill()
                        self._drop(worker)
                        yield index, deaths.timed_out(index, time_limit)
                    continue
                index, worker.job = worker.job, None
                if answer != DIED:
                    yield index, _result(answer)
                    continue
                if not worker.started:  # not the job's doing: starting again would not help
                    raise WorkerDiedError("a worker process died as it started "
                                          f"({_end_of(worker.process)})")
                cause = self._drop(worker)
                again = deaths.run_again(index)
                if again:
                    todo.extendleft(reversed(again))
                else:
                    yield index, deaths.given_up(index, cause)

    def _busy(self) -> list[_Worker]:
        """The workers running a job."""
        return [worker for worker in self._pool if worker is not None and worker.job is not None]

    def _drop(self, worker: _Worker) -> str:
        """Take ``worker``, which died (or was killed), out of the pool, its place empty
        until a job needs a worker there; returns how it ended."""
        cause = _end_of(worker.process)
        worker.connection.close()
        self._pool[self._pool.index(worker)] = None
        return cause

    def close(self, cancel: bool = False) -> None:
        for worker in self._pool:
            if worker is not None:
                worker.end(cancel)
        self._pool = []


def _time_left(busy: list[_Worker], limit: float | None) -> float | None:
    """Seconds until the first of the ``busy`` workers' jobs reaches ``limit`` s (at
    least 0); None when none can (no limit, or none has begun its job)."""
    begun = [worker.began for worker in busy if worker.began is not None]
    if limit is None or not begun:
        return None
    return max(0.0, min(begun) + limit - time.monotonic())


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


class RayExecutor(_Base):
    """Jobs as Ray tasks on the cluster at ``address``, or on a local Ray of ``workers``
    CPUs started for the run when ``address`` is None (see the module docstring)."""

    def __init__(self, shared: Any, warm_up: WarmUp | None = None,
                 address: str | None = None, workers: int | None = None,
                 threads: int | None = None) -> None:
        super().__init__()
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
        # max_retries=0: a task whose worker died is submitted again here, and counted
        self._task = ray.remote(num_cpus=1, max_retries=0)(_ray_job)
        self._pending: dict[Any, int] = {}

    def map_unordered(self, function: Job, items: Sequence[Any], lost: Lost | None = None,
                      split: Split | None = None, time_limit: float | None = None
                      ) -> Iterator[tuple[int, Any]]:
        """As :meth:`Executor.map_unordered`, but with no time limit: a ``time_limit`` is
        refused (QuadnavError), Ray's tasks being stopped only by cancelling them."""
        if time_limit is not None:
            raise QuadnavError("a time limit on each job is for local workers only, not Ray")
        ray = self._ray
        died = (ray.exceptions.WorkerCrashedError, ray.exceptions.NodeDiedError,
                ray.exceptions.LocalRayletDiedError)
        deaths = self._deaths(items, lost, split)
        items = deaths.items

        def submit(index: int) -> None:
            self._pending[self._task.remote(function, self._shared, self._warm_up,
                                            self.numba_threads, items[index])] = index

        self._pending = {}
        for index in range(len(items)):
            submit(index)
        while self._pending:
            done, _ = ray.wait(list(self._pending), num_returns=1)
            for ref in done:
                index = self._pending.pop(ref)
                try:
                    result = ray.get(ref)
                except died as error:
                    again = deaths.run_again(index)
                    for part in again:
                        submit(part)
                    if again:
                        continue
                    result = deaths.given_up(index, type(error).__name__)
                yield index, result

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
