"""Running catalogue tasks on ``dask.distributed``: the cluster, the loop, progress and limits.

:func:`run_tasks` connects to the cluster (a ``Client`` given, a scheduler address, or a new
local cluster of single-threaded worker processes, :func:`start_local`: TLS with temporary
credentials, no HTTP server, the workers' profiler off), registers
:class:`~roughbrdf.catalogue.worker.WorkerSetup`, and keeps at most one task per worker thread
in flight, so that a task's start is known (its per-task time limit counts from there). A task
whose worker died is run again up to ``retries`` times; a task over the time limit is reported
failed and its worker restarted. Ctrl-C (SIGTERM, SIGHUP: :mod:`roughbrdf.interrupts`)
cancels what is running and closes a cluster this module started, also one interrupted in the
middle of its start (its workers are stopped; they never see Ctrl-C themselves:
:class:`~roughbrdf.catalogue.worker.QuietNanny`); the fit folders of finished tasks are
complete (each one is committed as a set on its worker), and unfinished ones keep no temporary
files.
"""

from __future__ import annotations

import contextlib
import os
import time
from collections import deque
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

from .rows import failed_row
from .tasks import Task, run_task

__all__ = ["run_tasks", "connect", "start_local", "close_local", "abandon", "STARTED_HOOKS",
           "CONNECTED_HOOKS"]

#: seconds between two looks at the running tasks (time limits, progress)
POLL = 0.2


#: called with the cluster object once a local cluster is up, before the client connects
#: (test and tool hooks: a fault injected at the start)
STARTED_HOOKS: list[Callable[[Any], None]] = []
#: called with the client once it is connected, before any task is submitted
CONNECTED_HOOKS: list[Callable[[Any], None]] = []


@contextlib.contextmanager
def connect(client: Any = None, scheduler: str | None = None,
            n_workers: int | None = None, n_tasks: int = 1) -> Iterator[tuple[Any, bool]]:
    """A ``distributed.Client``: ``client`` itself, one to ``scheduler``, or one to a new local
    cluster (:func:`start_local`, closed on exit); yields ``(client, local)`` (local: a cluster
    of ours)."""
    if client is not None:
        yield client, False
        return
    from distributed import Client

    if scheduler is not None:  # that cluster's own security applies (its config or loader)
        with Client(scheduler, timeout="20s") as c:
            _call(CONNECTED_HOOKS, c)
            yield c, False
        return
    if n_workers is not None and (not isinstance(n_workers, int) or n_workers < 1):
        from ..errors import ArgumentError

        raise ArgumentError("n_workers", "must be a whole number >= 1", value=n_workers)
    n = n_workers or max(1, min(os.cpu_count() or 1, n_tasks))
    import dask

    from .worker import WORKER_ENV

    spawn = {**dask.config.get("distributed.nanny.pre-spawn-environ", {}), **WORKER_ENV}
    # distributed's nannies apply pre-spawn-environ to *this* process's os.environ before they
    # spawn a worker and leave it there: NUMBA_NUM_THREADS=1 would stay set for the caller
    # (and a later Numba parallel loop raise "Cannot set NUMBA_NUM_THREADS to a different
    # value"); the caller's environment is put back once the workers are up and at the end
    saved = {k: os.environ.get(k) for k in spawn}
    muted: dict[str, bool] = {}
    try:
        cluster = start_local(n, spawn)
        try:
            _restore_environ(saved)
            _call(STARTED_HOOKS, cluster)
            with Client(cluster, security=cluster.security) as c, sync_cancel_quiet():
                _call(CONNECTED_HOOKS, c)
                try:
                    yield c, True
                except BaseException:
                    # an interrupted run's teardown: distributed's own loop callbacks can fail
                    # as the loop is cut (a NameError in distributed.utils.sync's cancel, which
                    # tornado logs with its traceback); not the user's, who is told "interrupted"
                    muted = _mute(TEARDOWN_LOGGERS)
                    raise
        finally:
            from ..interrupts import cleaning_up

            with cleaning_up():  # a second Ctrl-C must not leave the workers running
                close_local(cluster)
    finally:
        _restore_environ(saved)
        _unmute(muted)


class SyncCancelFilter:
    """A logging filter that drops tornado's record of ``distributed.utils.sync``'s ``cancel``
    callback failing with a NameError (``future`` not yet bound: ``sync`` was interrupted
    before it had its future, a race in distributed). It runs on the event loop's thread the
    moment Ctrl-C reaches ``sync`` in the main thread, before the run's own teardown can mute
    anything: ``fit-batch`` printed its traceback before "interrupted" once in 20 CI runs.
    Every other record passes.

    Examples
    --------
    >>> import logging
    >>> rec = logging.LogRecord("tornado.application", logging.ERROR, "", 0, "boom", (), None)
    >>> SyncCancelFilter().filter(rec)
    True
    """

    def filter(self, record: Any) -> bool:
        exc = record.exc_info[1] if record.exc_info else None
        if not isinstance(exc, NameError):
            return True
        tb = exc.__traceback__
        while tb is not None and tb.tb_next is not None:
            tb = tb.tb_next
        code = tb.tb_frame.f_code if tb is not None else None
        return not (code is not None and code.co_name == "cancel"
                    and "distributed" in code.co_filename)


@contextlib.contextmanager
def sync_cancel_quiet() -> Iterator[None]:
    """:class:`SyncCancelFilter` on tornado's application logger for the duration."""
    import logging

    log, quiet = logging.getLogger("tornado.application"), SyncCancelFilter()
    log.addFilter(quiet)
    try:
        yield
    finally:
        log.removeFilter(quiet)


#: the loggers of the event loop under distributed, muted while an interrupted run is torn down
TEARDOWN_LOGGERS = ("tornado.application", "tornado.general", "asyncio", "distributed")


def _mute(names: tuple[str, ...]) -> dict[str, bool]:
    """Disable the loggers ``names``; returns their previous ``disabled`` flags."""
    import logging

    before = {nm: logging.getLogger(nm).disabled for nm in names}
    for nm in names:
        logging.getLogger(nm).disabled = True
    return before


def _unmute(before: dict[str, bool]) -> None:
    """Put back the ``disabled`` flags :func:`_mute` returned."""
    import logging

    for nm, flag in before.items():
        logging.getLogger(nm).disabled = flag


#: seconds a local cluster has to close before its worker processes are killed
CLOSE_TIMEOUT = 60.0


def close_local(cluster: Any, timeout: float = CLOSE_TIMEOUT) -> None:
    """Close a local cluster of ours within ``timeout`` seconds, whatever its workers do.

    ``LocalCluster.close()`` without a timeout can wait for ever when a nanny does not answer
    (a loaded machine after a worker was killed and restarted): the results are written by
    then, so the call must end. After ``timeout`` the cluster's worker processes still alive
    are killed (only those: the nannies' processes, never another child of the caller's).
    """
    import signal

    pids = {pid for pid in (_worker_pid(w) for w in dict(cluster.workers).values()) if pid}
    try:
        cluster.close(timeout=timeout)
    except Exception:  # a timeout or a comm error: the processes still alive are ended below
        for pid in pids:
            with contextlib.suppress(OSError):  # already gone
                os.kill(pid, signal.SIGKILL)


def _worker_pid(nanny: Any) -> int | None:
    """The pid of a nanny's worker process (None when it has none)."""
    try:
        return int(nanny.pid) if nanny.pid else None
    except (AttributeError, TypeError, ValueError):  # a worker without a nanny, or not started
        return None


def start_local(n: int, spawn: dict[str, str]) -> Any:
    """A local cluster of ``n`` single-threaded worker processes, for this user only.

    * TLS with temporary credentials (``Security.temporary()``: a certificate made for this
      cluster and held in memory): without them no other process, another user's included,
      can connect to the scheduler or the workers and run code as this user; everything
      listens on 127.0.0.1 only;
    * no HTTP server (:class:`~roughbrdf.catalogue.worker.QuietScheduler`), so no port 8787
      and no warning when it is taken;
    * the workers' statistical profiler off (its call stacks grow the workers' memory);
    * SIGINT blocked in the worker processes from their start
      (:class:`~roughbrdf.catalogue.worker.QuietNanny`) and ignored once they load their worker
      class (:data:`~roughbrdf.catalogue.worker.WORKER_ENV` marks them): Ctrl-C in a terminal
      reaches the whole process group, and a worker would print its traceback; the client
      cancels the tasks and closes the cluster instead;
    * a start interrupted (Ctrl-C, SIGTERM) or failed half-way stops what was started (the
      scheduler, the workers up or starting: :func:`abandon`) before the exception goes on.
    """
    import logging

    import dask
    from distributed import SpecCluster
    from distributed.security import Security
    from distributed.worker_memory import parse_memory_limit

    from .worker import WORKER_ENV, QuietNanny, QuietScheduler

    security = Security.temporary()
    common = {"host": "127.0.0.1", "protocol": "tls://", "security": security}
    scheduler = {"cls": QuietScheduler,
                 "options": {**common, "port": 0, "dashboard": False, "dashboard_address": None}}
    nannies: list[Any] = []  # every nanny made, up or not (QuietNanny's owner)
    worker = {"cls": QuietNanny,
              "options": {**common, "nthreads": 1, "env": WORKER_ENV, "dashboard": False,
                          "owner": nannies,
                          "memory_limit": parse_memory_limit(
                              "auto", 1, n, logger=logging.getLogger("distributed")),
                          "silence_logs": logging.ERROR}}
    config = {"distributed.nanny.pre-spawn-environ": spawn,
              "distributed.worker.profile.enabled": False,
              "logging.distributed": "error"}  # the workers' own log lines are not the user's
    # made in two steps, so that a start interrupted inside SpecCluster's __init__ (nearly all
    # of the start happens there) leaves an object to stop
    cluster = SpecCluster.__new__(SpecCluster)
    with dask.config.set(config):
        try:
            SpecCluster.__init__(cluster, scheduler=scheduler,
                                 workers={i: worker for i in range(n)}, worker=worker,
                                 security=security, silence_logs=logging.ERROR)
        except BaseException:
            from ..interrupts import cleaning_up

            with cleaning_up():  # a second Ctrl-C must not leave the workers running
                abandon(cluster, nannies)
            raise
    return cluster


def abandon(cluster: Any, nannies: list[Any], timeout: float = CLOSE_TIMEOUT) -> None:
    """Stop a local cluster whose start was interrupted: its scheduler and every nanny made
    (``nannies``), each worker process once it is up; those still alive after ``timeout``
    seconds are killed.

    ``SpecCluster.close()`` alone cannot: the start it was in is cancelled, the workers still
    starting are not yet the cluster's (it would close none, and fail on them), a cluster
    whose own start was cancelled stays "starting" (its close would skip the scheduler), and
    the worker processes would live on until this one exits. distributed's warnings stay
    silenced meanwhile (a connection cut in its TLS handshake is one).
    """
    import asyncio
    import logging
    import signal

    from distributed.core import Status
    from distributed.utils import silence_logging_cmgr

    async def stop() -> None:
        await asyncio.sleep(0.05)  # the start's cancellation (queued before this) goes first
        # a nanny can only stop its worker once that one is up: let the starts end first
        await asyncio.gather(*nannies, return_exceptions=True)
        await asyncio.gather(*(nanny.close(timeout=timeout / 2) for nanny in nannies),
                             return_exceptions=True)
        # a start cancelled half-way leaves "starting": as "failed", close stops everything
        if getattr(cluster, "status", None) == Status.starting:
            cluster.status = Status.failed

    with silence_logging_cmgr(logging.ERROR):
        try:
            cluster.sync(stop, callback_timeout=timeout)
            cluster.close(timeout=timeout)
        except Exception:  # a timeout, or a start interrupted before its loop ran: kill below
            with contextlib.suppress(Exception):  # no loop to stop (never started)
                cluster._loop_runner.stop()
    for pid in {pid for pid in map(_worker_pid, nannies) if pid}:
        with contextlib.suppress(OSError):  # already gone (the usual case)
            os.kill(pid, signal.SIGKILL)


def _call(hooks: list[Callable[[Any], None]], arg: Any) -> None:
    for hook in list(hooks):
        hook(arg)


def _restore_environ(saved: dict[str, str | None]) -> None:
    """Put the environment variables ``saved`` back as they were (None: unset)."""
    for key, value in saved.items():
        if value is None:
            os.environ.pop(key, None)
        else:
            os.environ[key] = value


def run_tasks(tasks: list[tuple[int, Task]], model: Any, *, client: Any = None,
              scheduler: str | None = None, n_workers: int | None = None,
              time_limit: float | None = None, retries: int = 1, progress: bool | None = None,
              skipped: int = 0) -> dict[int, list[dict[str, Any]]]:
    """Run ``tasks`` (``(index, Task)``); returns ``{index: rows}``."""
    if not tasks:
        return {}
    if time_limit is not None and not time_limit > 0:
        from ..errors import ArgumentError

        raise ArgumentError("time_limit", "must be a number of seconds > 0", value=time_limit)
    from .worker import WorkerSetup

    loop = _Loop(tasks, time_limit, retries, _bar(progress, len(tasks), skipped))
    try:
        with connect(client, scheduler, n_workers, len(tasks)) as (c, local):
            loop.local = local
            c.register_plugin(WorkerSetup(model, local=local))
            loop.run(c)
    finally:
        loop.close()
    return loop.done


class _Loop:
    """The scheduling loop of :func:`run_tasks` (state: queued, running, done)."""

    def __init__(self, tasks: list[tuple[int, Task]], time_limit: float | None, retries: int,
                 bar: Any) -> None:
        self.queue = deque(tasks)
        self.tries = {i: 0 for i, _ in tasks}
        self.running: dict[Any, tuple[int, Task, float]] = {}
        self.done: dict[int, list[dict[str, Any]]] = {}
        self.time_limit, self.retries, self.bar = time_limit, retries, bar
        self.channels = self.failures = 0
        self.local = False
        self.unfinished: list[Task] = []
        #: fit folders of tasks whose worker was killed under them (time limit, a death):
        #: tidied at the end, when those processes are gone
        self.killed: list[str] = []

    def run(self, client: Any) -> None:
        from distributed import wait

        slots = max(1, sum(client.nthreads().values()))
        try:
            while self.queue or self.running:
                while self.queue and len(self.running) < slots:
                    i, task = self.queue.popleft()
                    fut = client.submit(run_task, task, key=f"roughbrdf-fit-{i}-"
                                        f"{self.tries[i]}-{task.fingerprint[:8]}", pure=False)
                    self.running[fut] = (i, task, time.monotonic())
                with contextlib.suppress(TimeoutError):
                    wait(list(self.running), timeout=POLL, return_when="FIRST_COMPLETED")
                for fut in [f for f in self.running if f.done()]:
                    self._finished(fut)
                self._over_time(client)
        except BaseException:
            self._cancel(client)
            raise

    def _finished(self, fut: Any) -> None:
        i, task, _ = self.running.pop(fut)
        if fut.status == "finished":
            self._record(i, fut.result())
            return
        exc = fut.exception()
        self.tries[i] += 1
        self.killed.append(task.folder)  # a retry's own ResultFolder also recovers it
        if self.tries[i] <= self.retries:  # the worker died under it (or the task broke)
            self.queue.appendleft((i, task))
            return
        self._record(i, [failed_row(task.file, task.label, f"{type(exc).__name__}: {exc}",
                                    sha256=None)])

    def _over_time(self, client: Any) -> None:
        if self.time_limit is None:
            return
        now = time.monotonic()
        late = [f for f, (_, _, t0) in self.running.items() if now - t0 > self.time_limit]
        if not late:
            return
        where = _workers_of(client, late)
        for fut in late:
            i, task, t0 = self.running.pop(fut)
            fut.cancel()
            self.killed.append(task.folder)  # its worker is restarted mid-write below
            self._record(i, [failed_row(task.file, task.label,
                                        f"time limit of {self.time_limit:g} s exceeded",
                                        sha256=None, elapsed_s=now - t0)])
        if where:
            with contextlib.suppress(Exception):  # a worker without a nanny cannot restart
                client.restart_workers(sorted(where), timeout=30, raise_for_error=False)

    def _record(self, i: int, rows: list[dict[str, Any]]) -> None:
        self.done[i] = rows
        self.channels += sum(1 for r in rows if r["channel"] is not None)
        self.failures += any(r["status"] == "failed" for r in rows)
        if self.bar is not None:
            self.bar.set_postfix_str(f"channels {self.channels}, failed {self.failures}")
            self.bar.update(1)

    def _cancel(self, client: Any) -> None:
        """Stop the running tasks (Ctrl-C or an error); their folders keep no stray files."""
        futs = list(self.running)
        with contextlib.suppress(Exception):
            client.cancel(futs, force=True)
        self.unfinished = [task for _, task, _ in self.running.values()]
        self.running.clear()

    def close(self) -> None:
        from ..interrupts import cleaning_up

        if self.bar is not None:
            self.bar.close()
        # every folder, also after Ctrl-C or SIGTERM (the interrupt would otherwise be raised
        # again by the first tidy's first held block, and end the others)
        with cleaning_up():
            if self.local:  # the tasks of a cluster of ours are cancelled, its workers gone
                for task in self.unfinished:
                    tidy(task.folder)
            # the workers restarted or dead under a task: their locks and temporary files (a
            # live process's are never touched: tidy judges each by its process id)
            for folder in dict.fromkeys(self.killed):
                tidy(folder)


def _workers_of(client: Any, futures: list[Any]) -> set[str]:
    keys = {f.key for f in futures}
    with contextlib.suppress(Exception):
        return {w for w, ks in client.processing().items() if keys & set(ks)}
    return set()


def tidy(folder: str | os.PathLike) -> None:
    """Repair what a killed task left in its fit folder (a worker killed by ``--time-limit``
    or by the operating system): :func:`roughbrdf.output.recover` rolls a half-done commit
    forward or back and removes the temporary files and the lock of processes that no longer
    exist (never a live process's); an empty folder the task had just created goes too."""
    from ..output import recover

    path = Path(folder)
    with contextlib.suppress(OSError):  # a crafted manifest (ManifestRefused) is left as it is
        recover(path)
    with contextlib.suppress(OSError):
        path.rmdir()  # only if empty: a folder the task had just created


def _bar(progress: bool | None, total: int, skipped: int) -> Any:
    """A tqdm bar over files (postfix: channels done, failures; tqdm shows the ETA)."""
    import sys

    show = sys.stderr.isatty() if progress is None else progress
    if not show:
        return None
    from tqdm.auto import tqdm

    desc = "fit-batch" + (f" ({skipped} channels kept)" if skipped else "")
    return tqdm(total=total, desc=desc, unit="file", file=sys.stderr)
