"""Where the command line runs its tasks: this process, a local Dask cluster, or any running
Dask cluster (the only module of the toolkit that starts or connects to one).

* no option: in this process (no Dask at all; the numba kernels use this machine's cores);
* ``--workers N``: a :class:`distributed.LocalCluster` of N worker processes on this machine
  (:func:`local_cluster`: one thread each, numba and BLAS limited to one thread per worker so
  the workers do not fight over the cores, and Dask's own housekeeping slowed down so that it
  does not take CPU from them), over TCP on localhost;
* ``--scheduler ADDRESS``: a running cluster (``tcp://host:8786``; started e.g. with
  ``dask scheduler`` and ``dask worker tcp://host:8786`` on each machine, or by dask-jobqueue /
  dask-kubernetes). The workers must be able to import this package (same version) and, for
  the fleet diagnosis and the blind benchmark, see the same file system paths.

The core takes any ``concurrent.futures``-style executor (:func:`zrp.tasks.map_tasks`); this
module hands it ``Client.get_executor()``.
"""

from __future__ import annotations

import argparse
import contextlib
import logging
import os
import signal
from collections.abc import Iterator
from concurrent.futures import Executor
from typing import Any

from zrp.cli.options import whole
from zrp.cli.signals import handling
from zrp.errors import InputError

__all__ = ["LOCAL_CONFIG", "WORKER_ENV", "add_cluster_options", "check_cluster_options",
           "executor", "executor_from_args", "local_cluster"]

#: Environment of local workers: one numba thread per worker process. numba and OpenBLAS read
#: it once, when they are first imported, and a spawned worker imports them before Dask applies
#: a Nanny's ``env=`` (it re-imports the ``__main__`` module, e.g. the ``zrp`` script, which
#: imports numba): so it is passed as ``distributed.nanny.pre-spawn-environ``, set before the
#: process starts. A variable already set in this process's environment wins (Dask's rule).
WORKER_ENV = {"NUMBA_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1",
              "MKL_NUM_THREADS": "1"}

#: Dask settings of a local cluster whose workers fill every core with compiled, GIL-free
#: kernels. Each periodic callback below wakes a process that then competes with a worker for
#: a core; at the defaults they cost ~5-8 % of a 2-core machine (Monte Carlo 1e5 x 360 on 2
#: workers vs 1: 1.71-1.79x at the defaults, 1.83-1.88x with these; tests/benchmarks/
#: bench_speed.py). What is given up: the dashboard's CPU/memory plots refresh every 5 s, a
#: worker near its memory limit reacts within 1 s instead of 0.1 s, blocked event loops are
#: detected within 1 s, no statistical profile of the tasks (10 ms samples), and no work
#: stealing (the scheduler's queue already hands a task to whichever worker frees up first).
#: Log level below which a local cluster's Dask processes print nothing. A task's error reaches
#: the command through its future (with the task's input); what Dask itself logs at ERROR on a
#: local cluster is shutdown noise (a worker's heartbeat finding the closing scheduler gone,
#: with a traceback, after Ctrl-C). Set ZRP_DASK_LOGS=1 to see Dask's warnings and errors.
SILENCE_LOGS = logging.WARNING if os.environ.get("ZRP_DASK_LOGS") == "1" else logging.CRITICAL

LOCAL_CONFIG = {
    "distributed.admin.tick.interval": "1s",
    "distributed.admin.system-monitor.interval": "5s",
    "distributed.worker.memory.monitor-interval": "1s",
    "distributed.worker.profile.enabled": False,
    "distributed.scheduler.work-stealing": False,
}


def add_cluster_options(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group("where it runs (zrp/cli/README.md)")
    x = g.add_mutually_exclusive_group()
    x.add_argument("--workers", type=whole(1, 1024), default=None, metavar="N",
                   help="run on a local Dask cluster of N worker processes (default: in this "
                        "process); results are the same for any N")
    x.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="run on a running Dask cluster, e.g. tcp://10.0.0.5:8786")


def check_cluster_options(args: argparse.Namespace) -> None:
    """Refuse bad values before any work."""
    if args.workers is not None and args.workers < 1:
        raise InputError(f"--workers: expected at least 1 worker, got {args.workers}")


#: how to install the optional Dask dependency (the ``cluster`` extra)
INSTALL_CLUSTER = 'pip install "zrp-accuracy[cluster]"'


def _dask(field: str) -> Any:
    """The ``dask`` module, imported now (~1 s: only when a cluster is asked for).

    Raises:
        InputError: Dask (dask.distributed) is not installed: names ``field`` and the extra.
    """
    try:
        import dask
        import distributed  # noqa: F401
    except ImportError as exc:
        raise InputError(f"{field}: runs on a Dask cluster, and dask.distributed is not "
                         f"installed ({exc}); install it with {INSTALL_CLUSTER}") from None
    return dask


@contextlib.contextmanager
def local_cluster(workers: int) -> Iterator[Any]:
    """A :class:`distributed.Client` of a new LocalCluster of ``workers`` processes (one
    thread each, :data:`WORKER_ENV`, :data:`LOCAL_CONFIG`, TCP on 127.0.0.1); both are closed
    on exit."""
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise InputError(f"workers: expected an integer >= 1, got {workers!r}")
    dask = _dask("--workers")
    from distributed import Client, LocalCluster

    environ = dict(dask.config.get("distributed.nanny.pre-spawn-environ", {}))
    environ.update(WORKER_ENV)
    saved = os.environ.copy()
    with contextlib.ExitStack() as stack:
        try:
            # the Nannies read the settings as they start (inside LocalCluster()) and pass
            # them on to their workers; the environment is put in os.environ while spawning
            with dask.config.set({**LOCAL_CONFIG,
                                  "distributed.nanny.pre-spawn-environ": environ}), \
                    handling(signal.SIGINT, signal.SIG_IGN):
                # Ctrl-C in a terminal signals every process of the group, and each worker
                # would print a KeyboardInterrupt traceback. A process started while SIGINT is
                # ignored keeps ignoring it (Python installs its handler only over the
                # default one): only this process sees Ctrl-C and closes the cluster.
                cluster = stack.enter_context(LocalCluster(
                    n_workers=workers, threads_per_worker=1, processes=True, protocol="tcp",
                    host="127.0.0.1", dashboard_address=":0", silence_logs=SILENCE_LOGS))
        finally:  # the Nanny leaves WORKER_ENV in this process's environment: undo it
            os.environ.clear()
            os.environ.update(saved)
        yield stack.enter_context(Client(cluster))


@contextlib.contextmanager
def executor(workers: int | None = None, scheduler: str | None = None, *,
             field: str = "--scheduler") -> Iterator[Executor | None]:
    """None (in this process), or a Dask executor on a local cluster of ``workers``
    processes or on the cluster at ``scheduler``; the cluster is closed on exit."""
    if workers is None and scheduler is None:
        yield None
        return
    if workers is not None and scheduler is not None:
        raise InputError("--workers, --scheduler: give one of them, not both")
    with contextlib.ExitStack() as stack:
        if scheduler is not None:
            _dask(field)
            from distributed import Client

            try:
                client = stack.enter_context(Client(scheduler, timeout="10s"))
            except (OSError, TimeoutError, ValueError) as exc:  # ValueError: not an address
                raise InputError(f"{field}: cannot reach a Dask scheduler at {scheduler!r} "
                                 f"({exc}); expected e.g. tcp://host:8786") from exc
        else:
            assert workers is not None
            client = stack.enter_context(local_cluster(workers))
        # pure=False: every submit runs (concurrent.futures semantics), never a result Dask
        # still holds from an identical earlier submission
        yield client.get_executor(pure=False)


def executor_from_args(args: argparse.Namespace) -> contextlib.AbstractContextManager:
    """:func:`executor` from ``--workers`` / ``--scheduler``."""
    check_cluster_options(args)
    return executor(args.workers, args.scheduler)
