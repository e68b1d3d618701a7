"""Worker set-up for catalogue fits: one BLAS thread, kernels loaded once per worker process.

:class:`WorkerSetup` is a ``distributed`` worker plugin: when a worker joins (or the plugin is
registered), it limits BLAS to one thread for the whole process (``threadpoolctl``; each worker
runs one task at a time, the parallelism is across workers); on the workers of a
``LocalCluster`` of ours it ignores SIGINT (Ctrl-C in a terminal reaches the whole process
group; the client then cancels the tasks and closes the cluster); and it evaluates the model
once on a few directions, so that its compiled kernels are loaded from Numba's cache (or
compiled) once per worker process instead of in every task; the worker keeps them for every
later task. :data:`WORKER_ENV` is the environment given to the worker processes of a
``LocalCluster`` (thread pools of one thread: BLAS, OpenMP, Numba).

This module imports ``distributed``: it is loaded only when a catalogue runs.
"""

from __future__ import annotations

from typing import Any

from distributed import Nanny, Scheduler, Worker
from distributed.diagnostics.plugin import WorkerPlugin

__all__ = ["WorkerSetup", "WORKER_ENV", "warm", "QuietScheduler", "QuietWorker", "QuietNanny"]

#: environment of the LocalCluster's worker processes: one thread in every thread pool, the
#: workers' statistical profiler off (it keeps the call stacks of every task: with matplotlib's
#: deep stacks about 3.5 MB more per plotted file), distributed's log lines off (a task's
#: error comes back with its future; the rest is the shutdown noise of a Ctrl-C)
WORKER_ENV = {"OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1",
              "NUMBA_NUM_THREADS": "1", "DASK_LOGGING__DISTRIBUTED": "critical",
              "DASK_DISTRIBUTED__WORKER__PROFILE__ENABLED": "False",
              "ROUGHBRDF_CATALOGUE_WORKER": "1"}


def _ignore_sigint_if_worker() -> None:
    """In a worker process of our local cluster (marked by :data:`WORKER_ENV`, which the
    nannies set only while they spawn one), ignore SIGINT from now on: this module is loaded
    when the process unpickles its :class:`QuietWorker` class, before ``distributed`` installs
    the handler that turns Ctrl-C into a traceback; the parent closes the cluster on Ctrl-C."""
    import os

    if os.environ.get("ROUGHBRDF_CATALOGUE_WORKER") == "1":
        _ignore_sigint()


class QuietScheduler(Scheduler):
    """The scheduler of a local catalogue cluster: no HTTP server at all.

    ``distributed`` starts an HTTP server (port 8787, else a random one, with a warning when
    8787 is taken) even without a dashboard; it would serve the scheduler's state to anyone on
    this machine. The catalogue does not use it.
    """

    def start_http_server(self, routes: Any, dashboard_address: Any, default_port: int = 0,
                          ssl_options: Any = None) -> None:
        """Do not listen (see the class docstring)."""


class QuietWorker(Worker):
    """A worker of a local catalogue cluster: no HTTP server (as :class:`QuietScheduler`)."""

    def start_http_server(self, routes: Any, dashboard_address: Any, default_port: int = 0,
                          ssl_options: Any = None) -> None:
        """Do not listen (see :class:`QuietScheduler`)."""


class QuietNanny(Nanny):
    """A nanny whose worker process is a :class:`QuietWorker`, and never sees Ctrl-C.

    SIGINT, SIGTERM and SIGHUP (:data:`roughbrdf.interrupts.SIGNALS`) are blocked in the
    thread that makes the nanny (the cluster's event loop), and so in the threads it starts,
    which spawn the worker processes: a process inherits the signal mask of the thread that
    forks it and keeps it across ``exec``, so a worker process starts with them blocked, from
    its first instruction on. Without that, a Ctrl-C during the cluster's start-up (it reaches
    the whole process group) interrupts the workers while they import and each prints its
    traceback; a SIGTERM to the group (systemd, SLURM) kills them under their nannies, which
    log the failures. The client stops the workers instead (distributed stops a worker by a
    message, then SIGKILL; a worker whose client process is gone exits by itself). ``owner``
    (a list) receives the nanny once made.
    """

    def __init__(self, *args: Any, owner: list[Any] | None = None, **kwargs: Any) -> None:
        kwargs["worker_class"] = QuietWorker
        _block_signals_in_this_thread()
        super().__init__(*args, **kwargs)
        if owner is not None:  # the list of start_local's cluster: stopped if its start fails
            owner.append(self)


def _block_signals_in_this_thread() -> None:
    """Block :data:`roughbrdf.interrupts.SIGNALS` in the calling thread (and the threads and
    processes it starts), unless it is the main thread (there Python handles Ctrl-C: the
    program must stay interruptible)."""
    import signal
    import threading

    # the main thread (an asynchronous cluster on the caller's loop) keeps its Ctrl-C; a
    # platform without pthread_sigmask (Windows) has no process groups to send it to workers
    if threading.current_thread() is threading.main_thread() or not hasattr(
            signal, "pthread_sigmask"):
        return
    from multiprocessing import resource_tracker

    from ..interrupts import SIGNALS

    # multiprocessing starts its resource tracker when the nanny makes its first queue, and
    # then *unblocks* SIGINT and SIGTERM in the thread that started it: start it here, with
    # SIGHUP blocked too (it ignores the other two; a terminal's SIGHUP would kill it, and its
    # successor print a traceback per queue), then block again
    signal.pthread_sigmask(signal.SIG_BLOCK, set(SIGNALS))
    resource_tracker.ensure_running()
    signal.pthread_sigmask(signal.SIG_BLOCK, set(SIGNALS))


def warm(model: Any) -> None:
    """Load ``model``'s kernels (and the fitting code) into this process: one evaluation.

    Examples
    --------
    >>> import roughbrdf as rb
    >>> warm(rb.model("lambertian"))
    >>> warm("auto")  # a name: only the fitting code is imported
    """
    import numpy as np

    from .. import fitting  # noqa: F401  (SciPy and the fitting kernels, once)

    if hasattr(model, "brdf"):
        t = np.array([0.1, 0.5])
        model.brdf(t, t, np.array([0.0, 3.0]))


class WorkerSetup(WorkerPlugin):
    """Set a worker process up for catalogue fits (see the module docstring)."""

    name = "roughbrdf-catalogue-setup"

    def __init__(self, model: Any, *, local: bool = False) -> None:
        self.model = model
        self.local = local
        self._limits: Any = None

    def setup(self, worker: Any) -> None:
        from threadpoolctl import threadpool_limits

        if self.local:  # Ctrl-C reaches the whole process group: the client stops the cluster
            _ignore_sigint()
        self._limits = threadpool_limits(limits=1, user_api="blas")
        warm(self.model)


def _ignore_sigint() -> None:
    """Ignore SIGINT in this (worker) process, where that is possible."""
    import signal
    import threading

    if threading.current_thread() is threading.main_thread():
        try:
            signal.signal(signal.SIGINT, signal.SIG_IGN)
        except (ValueError, OSError):
            pass


_ignore_sigint_if_worker()
