"""navfuse.batch, batch_case and navfuse.dask against `navfuse batch`: the same rows,
bit for bit, whatever runs them (threads, Dask worker processes)."""

import numpy as np
import pandas as pd
import pytest

import navfuse
from conftest import ROOT, SHORT_SCENARIO

SEEDS = 6


@pytest.fixture(scope="module")
def manifest(tmp_path_factory):
    d = tmp_path_factory.mktemp("mc")
    p = d / "mc.toml"
    p.write_text(f"""[monte_carlo]
scenario = "{SHORT_SCENARIO.as_posix()}"
seeds = {SEEDS}
first_seed = 11
name = "car"
outages = "20/60@345640"
gaps = "20/60@345640"
""")
    return p


@pytest.fixture(scope="module")
def serial_csv(cli, manifest, tmp_path_factory):
    out = tmp_path_factory.mktemp("serial")
    cli("batch", manifest, "--out", out, "--jobs", 1, "--tables-only", "-q")
    return pd.read_csv(out / "batch.csv")


def assert_same_rows(table, csv):
    """Every column of batch.csv, equal to the last bit (NaN where both have none)."""
    assert len(table) == len(csv)
    for c in csv.columns:
        a, b = table[c].to_numpy(), csv[c].to_numpy()
        if c in ("name", "status"):
            assert list(a) == list(b), c
        elif c == "error":
            assert all(pd.isna(x) for x in a) and all(pd.isna(x) for x in b)
        else:
            a, b = a.astype(np.float64), b.astype(np.float64)
            assert np.array_equal(a, b, equal_nan=True), (c, a, b)


def test_names(manifest):
    assert navfuse.batch_cases(manifest) == [f"car_seed{s:04d}" for s in range(11, 11 + SEEDS)]


def test_batch_threads_equal_the_cli(manifest, serial_csv):
    r = navfuse.batch(manifest, jobs=2)
    assert r.failed == 0 and len(r.wall_s) == SEEDS
    assert_same_rows(r.table, serial_csv)
    assert (r.table["h_rms_m"] > 0).all() and (r.table["gap_h_max_rms_m"] > 0).all()


def test_batch_writes_the_cli_tables(cli, manifest, tmp_path):
    navfuse.batch(manifest, out=tmp_path / "py", jobs=2)
    cli("batch", manifest, "--out", tmp_path / "cli", "--jobs", 1, "-q")
    for name in ("batch.csv", "batch.json"):
        assert (tmp_path / "py" / name).read_bytes() == (tmp_path / "cli" / name).read_bytes()
    case = "car_seed0011"
    assert ((tmp_path / "py" / case / "solution.nav").read_bytes()
            == (tmp_path / "cli" / case / "solution.nav").read_bytes())


def test_one_case_equals_its_row(manifest, serial_csv):
    row = navfuse.batch_case(manifest, 3)
    assert row["name"] == "car_seed0014" and row["seed"] == 14
    assert_same_rows(navfuse.batch_table([row]), serial_csv.iloc[[3]].reset_index(drop=True))
    with pytest.raises(IndexError):
        navfuse.batch_case(manifest, SEEDS)


def test_bad_manifest_names_file_line_and_key(tmp_path):
    p = tmp_path / "bad.toml"
    p.write_text('[monte_carlo]\nscenario = "x.toml"\nseedz = 3\n')
    with pytest.raises(navfuse.InputError) as e:
        navfuse.batch_cases(p)
    assert "seedz" in str(e.value)
    assert e.value.file == str(p) and e.value.line == 3 and e.value.field == "monte_carlo.seedz"


def test_dask_local_cluster_equals_serial(manifest, serial_csv):
    distributed = pytest.importorskip("distributed", reason="skipped: dask.distributed not installed")
    import navfuse.dask
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  host="127.0.0.1", dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        table = navfuse.dask.run_manifest(manifest, client)
        # The tasks ran in the two worker processes (not here).
        done = client.run(lambda dask_worker: dask_worker.state.executed_count)
    assert len(done) == 2 and sum(done.values()) == SEEDS
    assert_same_rows(table, serial_csv)


def test_ctrl_c_stops_a_batch_with_its_rows(tmp_path):
    import _thread
    import threading
    p = tmp_path / "long.toml"
    p.write_text(f'[monte_carlo]\nscenario = "{SHORT_SCENARIO.as_posix()}"\nseeds = 200\n')
    threading.Timer(0.5, _thread.interrupt_main).start()
    with pytest.raises(KeyboardInterrupt) as e:
        navfuse.batch(p, jobs=1, out=tmp_path / "out")
    r = e.value.result
    assert len(r.table) == 200
    not_run = r.table["error"].fillna("").str.startswith("not run").sum()
    done = (r.table["status"] == "completed").sum()
    assert done >= 1 and not_run >= 100 and done + not_run == 200
    # The tables were written before the interrupt was raised.
    assert len(pd.read_csv(tmp_path / "out" / "batch.csv")) == 200


def test_dask_on_a_scheduler_and_workers_started_as_on_a_cluster(manifest, serial_csv, tmp_path):
    """The `dask scheduler` and two `dask worker` processes a cluster runs, here on
    loopback, the client connected through the scheduler file."""
    distributed = pytest.importorskip("distributed", reason="skipped: dask.distributed not installed")
    import subprocess
    import sys
    import time
    from pathlib import Path
    import navfuse.dask
    dask_cli = Path(sys.executable).parent / "dask"
    if not dask_cli.exists():
        pytest.skip(f"skipped: no dask command beside {sys.executable}")
    sched = tmp_path / "scheduler.json"
    log = open(tmp_path / "cluster.log", "w")
    procs = [subprocess.Popen([str(dask_cli), "scheduler", "--host", "127.0.0.1", "--port", "0",
                               "--no-dashboard", "--scheduler-file", str(sched)],
                              stdout=log, stderr=log)]
    try:
        t0 = time.time()
        while not sched.exists() and time.time() - t0 < 60:
            time.sleep(0.1)
        assert sched.exists(), (tmp_path / "cluster.log").read_text()
        for _ in range(2):
            procs.append(subprocess.Popen([str(dask_cli), "worker", "--scheduler-file", str(sched),
                                           "--nthreads", "1", "--no-dashboard", "--host", "127.0.0.1"],
                                          stdout=log, stderr=log))
        with distributed.Client(scheduler_file=str(sched)) as client:
            client.wait_for_workers(2, timeout=60)
            table = navfuse.dask.run_manifest(manifest, client)
            done = client.run(lambda dask_worker: dask_worker.state.executed_count)
    finally:
        for p in reversed(procs):
            p.terminate()
        for p in procs:
            p.wait(timeout=30)
        log.close()
    assert len(done) == 2 and sum(done.values()) == SEEDS
    assert_same_rows(table, serial_csv)
