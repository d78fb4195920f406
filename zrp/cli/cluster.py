"""Where the command line runs its tasks: this process, a local Dask cluster, or any running
Dask cluster (the only module of the toolkit that starts or connects to one).

* no option: in this process (no Dask at all; the numba kernels use this machine's cores);
* ``--workers N``: a :class:`distributed.LocalCluster` of N worker processes on this machine
  (one thread each, numba limited to one thread per worker so the workers do not fight over
  the cores), over TCP on localhost;
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
from collections.abc import Iterator
from concurrent.futures import Executor

from zrp.cli.options import whole
from zrp.errors import InputError

__all__ = ["add_cluster_options", "check_cluster_options", "executor", "executor_from_args"]

#: Environment of local workers: one numba thread per worker process.
WORKER_ENV = {"NUMBA_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1",
              "MKL_NUM_THREADS": "1"}


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
    # dask.distributed costs ~1 s to import: only when a cluster is asked for
    from distributed import Client, LocalCluster

    with contextlib.ExitStack() as stack:
        if scheduler is not None:
            try:
                client = stack.enter_context(Client(scheduler, timeout="10s"))
            except (OSError, TimeoutError) as exc:
                raise InputError(f"{field}: cannot reach a Dask scheduler at {scheduler!r} "
                                 f"({exc}); expected e.g. tcp://host:8786") from exc
        else:
            cluster = stack.enter_context(LocalCluster(
                n_workers=workers, threads_per_worker=1, processes=True, protocol="tcp",
                host="127.0.0.1", dashboard_address=":0", env=WORKER_ENV))
            client = stack.enter_context(Client(cluster))
        # pure=False: every submit runs (concurrent.futures semantics), never a result Dask
        # still holds from an identical earlier submission
        yield client.get_executor(pure=False)


def executor_from_args(args: argparse.Namespace) -> contextlib.AbstractContextManager:
    """:func:`executor` from ``--workers`` / ``--scheduler``."""
    check_cluster_options(args)
    return executor(args.workers, args.scheduler)
