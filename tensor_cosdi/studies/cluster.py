"""The local Dask cluster of :func:`tensor_cosdi.studies.sweep` (``client="local"``)."""

from __future__ import annotations

import numbers
import os
from contextlib import contextmanager


@contextmanager
def local_client(n_workers: int | None = None):
    """A Dask client on a local cluster of single-threaded worker processes, closed on exit —
    what ``sweep(client="local")`` uses.

    Each worker's BLAS / OpenMP runs one thread.  Dask's nanny would also set
    ``MALLOC_TRIM_THRESHOLD_`` in its workers; that fixes glibc's mmap threshold, so every
    array over 128 kB is mapped and unmapped afresh, and the page faults cost as much system
    time as the reconstructions themselves (``benchmarks/thesis_findings.py --quick`` on
    2 cores: 1 min 48 s with it, 1 min 7 s without; system time 82 s → 6 s).  It is left out.
    Needs the ``.[dask]`` extra.

    Parameters
    ----------
    n_workers : int, optional
        Worker processes (default: one per CPU).

    Yields
    ------
    dask.distributed.Client
        For the ``client=`` of :func:`~tensor_cosdi.studies.sweep`, the design
        studies or :func:`tensor_cosdi.reconstruct_tiled`.
    """
    try:
        import dask
        from dask.distributed import Client, LocalCluster
    except ImportError:
        raise ImportError(
            "a Dask cluster needs the dask extra: pip install 'tensor_cosdi[dask]'"
        ) from None
    n = (os.cpu_count() or 1) if n_workers is None else n_workers
    if isinstance(n, bool) or not isinstance(n, numbers.Integral) or n < 1:
        raise ValueError(f"n_workers must be a positive integer, got {n_workers!r}")
    environ = {k: 1 for k in ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS")}
    with dask.config.set({"distributed.nanny.pre-spawn-environ": environ}):
        with LocalCluster(n_workers=int(n), threads_per_worker=1, processes=True) as cluster:
            with Client(cluster) as client:
                yield client
