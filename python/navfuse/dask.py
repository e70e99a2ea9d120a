"""Many runs on a Dask cluster: each task one case of a batch manifest (one
configuration, or one seed of a Monte Carlo), the rows gathered into one DataFrame in
manifest order. The same function computes a case here as in ``navfuse batch`` and
``navfuse.batch``, so the figures equal theirs bit for bit, on a LocalCluster or a
real cluster (workers must see the manifest and its files at the same paths).

    from dask.distributed import Client, LocalCluster
    import navfuse.dask
    with LocalCluster(n_workers=2, threads_per_worker=1) as cluster, Client(cluster) as client:
        table = navfuse.dask.run_manifest("mc.toml", client)

Ray and Slurm arrays: see docs/PYTHON.md "Scale-out".
"""

from __future__ import annotations

import os
from typing import Any, Dict, List, Optional, Sequence, Union

import pandas as pd

import navfuse


def _case(manifest: str, index: int, out: Optional[str]) -> Dict[str, Any]:
    # Imported on the worker.
    import navfuse as nf
    return nf.batch_case(manifest, index, out=out)


def run_manifest(manifest: Union[str, "os.PathLike[str]"], client: Any = None, *,
                 out: Union[str, "os.PathLike[str]", None] = None,
                 cases: Optional[Sequence[int]] = None) -> pd.DataFrame:
    """Run the cases of a batch manifest as Dask tasks (``client``: a
    ``dask.distributed.Client``; default the current one). ``out``: the batch folder
    each case writes its run into (on the workers' file system; None: nothing written).
    ``cases``: indices to run (default all). Returns the combined table, one row per
    case in manifest order, as ``navfuse batch`` writes it to batch.csv."""
    if client is None:
        from dask.distributed import get_client
        client = get_client()
    path = os.path.abspath(os.fspath(manifest))
    out_s = os.path.abspath(os.fspath(out)) if out is not None else None
    indices: List[int] = list(range(len(navfuse.batch_cases(path)))) if cases is None else list(cases)
    futures = client.map(_case, [path] * len(indices), indices, [out_s] * len(indices), pure=False)
    rows = client.gather(futures)
    return navfuse.batch_table(rows)
