"""A Monte Carlo of one experiment four ways, and whether they agree to the last bit:
`navfuse batch --jobs 1` (the serial reference), `navfuse batch --jobs 2`, and
`navfuse.dask.run_manifest` on a LocalCluster with 1 and with 2 worker processes.
Throughput: cases per second of wall time, 2 workers against 1 (asked: >= 1.8x).

    python python/bench/monte_carlo.py [--seeds 100] [--scenario scenarios/seed001_car.toml]
        [--navfuse target/release/navfuse] [--json FILE]

The runs keep no case folders (`--tables-only`; Dask: out=None): with folders each
seed001 case writes about 80 MB, and the page cache, not the CPU, sets the pace.
"""

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd

import navfuse
import navfuse.dask

ROOT = Path(__file__).resolve().parents[2]


def same_rows(a: pd.DataFrame, b: pd.DataFrame) -> bool:
    if list(a.columns) != list(b.columns) or len(a) != len(b):
        return False
    for c in b.columns:
        x, y = a[c].to_numpy(), b[c].to_numpy()
        if c in ("name", "status"):
            ok = list(x) == list(y)
        elif c == "error":
            ok = all(pd.isna(v) for v in x) and all(pd.isna(v) for v in y)
        else:
            ok = np.array_equal(x.astype(np.float64), y.astype(np.float64), equal_nan=True)
        if not ok:
            print(f"  column {c} differs", file=sys.stderr)
            return False
    return True


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--seeds", type=int, default=100)
    ap.add_argument("--scenario", default=str(ROOT / "scenarios" / "seed001_car.toml"))
    ap.add_argument("--navfuse", default=str(ROOT / "target" / "release" / "navfuse"))
    ap.add_argument("--json")
    a = ap.parse_args()
    from distributed import Client, LocalCluster

    with tempfile.TemporaryDirectory(prefix="navfuse-mc-") as tmp:
        tmp = Path(tmp)
        manifest = tmp / "mc.toml"
        manifest.write_text(f'[monte_carlo]\nscenario = "{Path(a.scenario).resolve().as_posix()}"\n'
                            f'seeds = {a.seeds}\nname = "mc"\n')
        res = {}

        def cli(jobs):
            out = tmp / f"cli{jobs}"
            t0 = time.perf_counter()
            subprocess.run([a.navfuse, "batch", str(manifest), "--out", str(out), "--jobs",
                            str(jobs), "--tables-only", "-q"], check=True)
            wall = time.perf_counter() - t0
            return pd.read_csv(out / "batch.csv"), wall

        def dask(workers):
            with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                              host="127.0.0.1", dashboard_address=None) as cluster, \
                    Client(cluster) as client:
                client.run(lambda: __import__("navfuse"))  # imported before the clock starts
                t0 = time.perf_counter()
                table = navfuse.dask.run_manifest(manifest, client)
                wall = time.perf_counter() - t0
            # As batch.csv reads back (the same dtypes), for the comparison.
            p = tmp / f"dask{workers}.csv"
            table.to_csv(p, index=False)
            return pd.read_csv(p), wall

        serial, res["batch_jobs1_s"] = cli(1)
        t2, res["batch_jobs2_s"] = cli(2)
        d1, res["dask_1worker_s"] = dask(1)
        d2, res["dask_2workers_s"] = dask(2)
        res["seeds"] = a.seeds
        res["identical"] = {"batch_jobs2": same_rows(t2, serial), "dask_1worker": same_rows(d1, serial),
                            "dask_2workers": same_rows(d2, serial)}
        res["speedup_batch"] = res["batch_jobs1_s"] / res["batch_jobs2_s"]
        res["speedup_dask"] = res["dask_1worker_s"] / res["dask_2workers_s"]
        res["h_rms_m_mean"] = float(serial["h_rms_m"].mean())
    print(f"{a.seeds} seeds of {Path(a.scenario).name}")
    print(f"  navfuse batch --jobs 1   {res['batch_jobs1_s']:8.2f} s  {a.seeds / res['batch_jobs1_s']:6.2f} cases/s  (reference)")
    print(f"  navfuse batch --jobs 2   {res['batch_jobs2_s']:8.2f} s  {a.seeds / res['batch_jobs2_s']:6.2f} cases/s  x{res['speedup_batch']:.2f}  identical: {res['identical']['batch_jobs2']}")
    print(f"  Dask, 1 worker           {res['dask_1worker_s']:8.2f} s  {a.seeds / res['dask_1worker_s']:6.2f} cases/s         identical: {res['identical']['dask_1worker']}")
    print(f"  Dask, 2 workers          {res['dask_2workers_s']:8.2f} s  {a.seeds / res['dask_2workers_s']:6.2f} cases/s  x{res['speedup_dask']:.2f}  identical: {res['identical']['dask_2workers']}")
    ok = all(res["identical"].values())
    fast = res["speedup_batch"] >= 1.8 and res["speedup_dask"] >= 1.8
    print(f"  figures identical to the serial run: {'PASS' if ok else 'FAIL'}; throughput x1.8: {'PASS' if fast else 'FAIL'}")
    if a.json:
        Path(a.json).write_text(json.dumps(res, indent=2) + "\n")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
