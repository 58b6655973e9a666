"""Parameter sweeps: every combination of a grid through one study cell, serially or on Dask;
records to CSV."""

from __future__ import annotations

import csv
import itertools
from pathlib import Path

from .cluster import local_client

__all__ = ["sweep", "write_csv", "seed_list"]


def seed_list(seeds) -> list:
    """``seeds`` as a non-empty list of integers ≥ 0 (a study's codes and noise), or a
    ``ValueError`` naming what was wrong."""
    from ..validate import integer

    if isinstance(seeds, (str, bytes)) or not hasattr(seeds, "__iter__"):
        raise ValueError(f"seeds must be a sequence of integers ≥ 0, got {seeds!r}")
    out = [integer("seed", q, low=0) for q in seeds]
    if not out:
        raise ValueError("seeds must hold at least one integer")
    return out


def _call(run, params):
    out = run(**params)
    if not isinstance(out, dict):
        raise TypeError(f"run(**{params}) must return a dict of results, got {type(out).__name__}")
    clash = sorted(set(out) & set(params))
    if clash:
        raise ValueError(f"run's results {clash} would overwrite the parameters of the same name")
    return {**params, **out}


def sweep(grid: dict, run, *, client=None, progress: bool = True) -> list[dict]:
    """Run ``run(**params)`` for every combination of ``grid``; one record per combination.

    Parameters
    ----------
    grid : dict of name → sequence
        The parameter grid (e.g. systems × scenes × SNR × methods × design
        parameters); the records come back in ``itertools.product`` order.
    run : callable
        ``run(**params) -> dict`` of results (PSNR, seconds, …); picklable
        (a module-level function) when a Dask cluster runs it.
        :func:`reconstruction_run` is one for the usual study.
    client : None, ``"local"``, a scheduler address or a ``dask.distributed.Client``
        ``None`` runs serially here; ``"local"`` starts a local cluster for the
        sweep (:func:`local_client`, closed after it); an address
        (``"tcp://host:8786"``) connects to a running scheduler; a client is used
        as is.  Needs the ``.[dask]`` extra.
    progress : bool
        A tqdm bar (serial) or Dask's progress bar.

    Returns
    -------
    list of dict — the parameters and the results of each combination, ready
    for :func:`write_csv` (or ``pandas.DataFrame``).
    """
    from ..validate import flag

    if not isinstance(grid, dict) or not grid:
        raise ValueError("grid must be a non-empty dict of name → sequence of values")
    values = {}
    for k, v in grid.items():
        if not isinstance(k, str) or not k.isidentifier():
            raise ValueError(f"grid keys must be parameter names (identifiers), got {k!r}")
        if isinstance(v, (str, bytes, dict, set, frozenset)) or not hasattr(v, "__iter__"):
            # a dict would sweep its keys, a set in no fixed order
            raise ValueError(f"grid[{k!r}] must be a sequence of values, got {v!r}")
        values[k] = list(v)  # once: an iterator's values are read a single time
        if not values[k]:
            raise ValueError(f"grid[{k!r}] holds no values: the sweep would run nothing")
    if not callable(run):
        raise ValueError(f"run must be callable, got {run!r}")
    progress = flag("progress", progress)
    keys = list(values)
    combos = [dict(zip(keys, vals)) for vals in itertools.product(*(values[k] for k in keys))]
    if client is not None and not isinstance(client, str):
        if not all(callable(getattr(client, a, None)) for a in ("map", "gather")):
            raise ValueError(
                'client must be None, "local", a scheduler address ("tcp://host:8786") or a '
                f"dask.distributed.Client, got {client!r}"
            )
    if client is None:
        from tqdm import tqdm

        return [_call(run, c) for c in tqdm(combos, desc="sweep", disable=not progress)]
    try:
        from dask.distributed import Client
        from dask.distributed import progress as dask_progress
    except ImportError:
        raise ImportError(
            "a Dask sweep needs the dask extra: pip install 'tensor_cosdi[dask]'"
        ) from None

    def gather(client):
        futures = client.map(_call, [run] * len(combos), combos, pure=False)
        if progress:
            dask_progress(futures)
        return client.gather(futures)

    if client == "local":
        with local_client() as own:
            return gather(own)
    if isinstance(client, str):
        with Client(client) as own:
            return gather(own)
    return gather(client)


def write_csv(records, path, *, overwrite: bool = False) -> Path:
    """Write :func:`sweep` records as CSV (columns: the union of keys, in first-seen order),
    atomically; an existing file only with ``overwrite=True``."""
    from ..io import atomic_write

    records = list(records)
    if not records:
        raise ValueError("no records to write")
    cols = list(dict.fromkeys(k for r in records for k in r))

    def write(tmp):
        with open(tmp, "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=cols)
            w.writeheader()
            for r in records:
                w.writerow({k: r.get(k, "") for k in cols})

    return atomic_write(path, write, overwrite=overwrite)
