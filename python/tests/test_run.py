"""navfuse.run against `navfuse run` on the same configuration."""

import threading
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import navfuse
from conftest import DEMO, ROOT


def test_solution_equals_cli_csv(cli_demo):
    res = navfuse.run(DEMO)
    assert res.status == "completed"
    csv = pd.read_csv(cli_demo / "solution.csv")
    # Same columns, dtypes and values, to the last bit.
    pd.testing.assert_frame_equal(res.solution, csv, check_exact=True)
    assert list(res.solution.columns[:11]) == [
        "gps_week", "t_s", "lat_deg", "lon_deg", "h_m", "vn_mps", "ve_mps", "vd_mps",
        "roll_deg", "pitch_deg", "yaw_deg"]
    assert "std_yaw_deg" in res.solution.columns and res.solution.columns[-1] == "state"
    # events.log and summary.json as the CLI wrote them (but wall times, file list).
    assert res.events == (cli_demo / "events.log").read_text().splitlines()
    assert res.summary["outputs"] == len(csv)


def test_out_writes_the_cli_files(cli_demo, tmp_path):
    res = navfuse.run(DEMO, out=tmp_path / "py")
    assert res.out == tmp_path / "py"
    for name in ("solution.nav", "solution.csv", "imu_err.txt", "std.txt", "events.log"):
        assert (tmp_path / "py" / name).read_bytes() == (cli_demo / name).read_bytes(), name


def test_smoothed_equals_cli(cli, tmp_path):
    cli("run", DEMO, "--out", tmp_path / "cli", "--smooth", "-q")
    res = navfuse.run(DEMO, smooth=True)
    assert res.smoothed is not None
    pd.testing.assert_frame_equal(res.smoothed, pd.read_csv(tmp_path / "cli" / "smoothed.csv"),
                                  check_exact=True)
    sm_states = tmp_path / "cli" / "smoothed_states.csv"
    if sm_states.exists():
        pd.testing.assert_frame_equal(res.smoothed_states, pd.read_csv(sm_states), check_exact=True)


def test_text_and_dict_configs_give_the_same_run():
    text = DEMO.read_text()
    a = navfuse.run(DEMO)
    b = navfuse.run(text, base_dir=DEMO.parent)
    pd.testing.assert_frame_equal(a.solution, b.solution, check_exact=True)
    tomllib = pytest.importorskip("tomllib", reason="skipped: tomllib needs Python 3.11")
    c = navfuse.run(tomllib.loads(text), base_dir=DEMO.parent)
    pd.testing.assert_frame_equal(a.solution, c.solution, check_exact=True)


def test_outages_option_as_cli(cli, tmp_path):
    cli("run", DEMO, "--out", tmp_path, "--outages", "20/60@243300", "-q")
    res = navfuse.run(DEMO, outages="20/60@243300")
    pd.testing.assert_frame_equal(res.solution, pd.read_csv(tmp_path / "solution.csv"),
                                  check_exact=True)
    assert (res.solution["state"] != "gnss").sum() > 0


def test_bad_key_is_an_input_error_with_line_and_key(tmp_path):
    cfg = DEMO.read_text().replace("[imu]", "[imu]\nrate_hzz = 100", 1)
    p = tmp_path / "bad.toml"
    p.write_text(cfg)
    with pytest.raises(navfuse.InputError) as e:
        navfuse.run(p)
    assert e.value.file == str(p)
    assert e.value.line is not None and "rate_hzz" in cfg.splitlines()[e.value.line - 1]
    assert "rate_hzz" in (e.value.field or "") and "rate_hzz" in str(e.value)
    assert isinstance(e.value, ValueError)


def test_damaged_input_names_file_line_and_field(tmp_path):
    imu = (DEMO.parent / "imu.csv").read_text().splitlines()
    imu[100] = imu[100].replace(",", ",x", 1)
    (tmp_path / "imu.csv").write_text("\n".join(imu) + "\n")
    (tmp_path / "gnss.pos").write_bytes((DEMO.parent / "gnss.pos").read_bytes())
    (tmp_path / "run.toml").write_text(DEMO.read_text())
    with pytest.raises(navfuse.InputError) as e:
        navfuse.run(tmp_path / "run.toml")
    assert Path(e.value.file).name == "imu.csv"
    assert e.value.line == 101
    assert e.value.field


def test_missing_file_is_an_input_error(tmp_path):
    (tmp_path / "run.toml").write_text(DEMO.read_text())
    with pytest.raises(navfuse.InputError) as e:
        navfuse.run(tmp_path / "run.toml")
    assert e.value.file and Path(e.value.file).name in ("imu.csv", "gnss.pos")


def test_the_gil_is_released_during_a_run():
    ticks = []
    stop = threading.Event()

    def count():
        while not stop.is_set():
            ticks.append(time.perf_counter())
            time.sleep(0.002)

    t = threading.Thread(target=count)
    t.start()
    t0 = time.perf_counter()
    navfuse.run(DEMO, smooth=True)
    t1 = time.perf_counter()
    stop.set()
    t.join()
    during = [x for x in ticks if t0 < x < t1]
    # The other thread kept running through the run (it would get nothing while a
    # run held the GIL).
    assert (t1 - t0) > 0.05
    assert len(during) >= 0.25 * (t1 - t0) / 0.002 * 0.2


def test_ctrl_c_stops_the_run_cleanly(tmp_path):
    """Ctrl-C during a run: KeyboardInterrupt once the run has stopped, with what was
    computed, and the files complete up to that epoch (the KF-GINS stand-in: long
    enough to be interrupted)."""
    import _thread
    cfg = ROOT / "examples" / "kfgins-synthetic.toml"
    if not (ROOT.parent / "shared" / "data" / "kf-gins" / "synthetic").is_dir():
        pytest.skip("skipped: ../shared/data/kf-gins/synthetic is not here")
    # On a busy machine 0.1 s may not reach the first output epoch (the run is then
    # interrupted before it, with an empty solution): later delays land mid-run.
    for delay in (0.1, 0.3, 0.6):
        out = tmp_path / f"after_{delay}"
        timer = threading.Timer(delay, _thread.interrupt_main)
        timer.start()
        with pytest.raises(KeyboardInterrupt) as e:
            navfuse.run(cfg, out=out)
            time.sleep(5)  # the run ended first: let the interrupt land (fails below)
        r = e.value.result
        assert r is not None and r.status == "interrupted"
        lines = (out / "solution.nav").read_text().splitlines() if (out / "solution.nav").exists() else []
        assert len(lines) == len(r.solution)
        assert "interrupted" in (out / "events.log").read_text().splitlines()[-1]
        if len(r.solution) > 0:
            break
    assert 0 < len(r.solution) < 680_000


def test_dict_config_with_numpy_values_and_its_errors():
    import numpy as np
    tomllib = pytest.importorskip("tomllib", reason="skipped: tomllib needs Python 3.11")
    cfg = tomllib.loads(DEMO.read_text())
    cfg["imu"]["rate_hz"] = np.float64(cfg["imu"].get("rate_hz", 100.0))
    a = navfuse.run(cfg, base_dir=DEMO.parent)
    assert a.status == "completed"
    cfg["imu"]["rate_hzz"] = 100
    with pytest.raises(navfuse.InputError) as e:
        navfuse.run(cfg, base_dir=DEMO.parent)
    assert e.value.file == "<config dict>" and e.value.line is None
    assert "rate_hzz" in e.value.field and "rate_hzz = 100" in str(e.value)


@pytest.mark.parametrize("kw, field", [({"outages": "60/x"}, "outages"),
                                       ({"smooth_mode": "backward"}, "smooth_mode"),
                                       ({"formats": "pos,shp"}, "formats")])
def test_bad_option_values_are_input_errors(kw, field):
    with pytest.raises(navfuse.InputError) as e:
        navfuse.run(DEMO, **kw)
    assert e.value.field == field and e.value.file is None


def test_a_missing_path_is_not_read_as_text(tmp_path):
    with pytest.raises(navfuse.InputError) as e:
        navfuse.run(str(tmp_path / "a=b.toml"))
    assert "a=b.toml" in str(e.value) and "cannot read" in str(e.value)


def test_plausibility_findings_are_python_warnings():
    # The everyday mistake: the sensor-to-body rotation left out.
    text = DEMO.read_text().replace("sensor_to_body_rpy_deg = [180.0, 0.0, 180.0]",
                                    "sensor_to_body_rpy_deg = [0.0, 0.0, 0.0]")
    with pytest.warns(navfuse.NavfuseWarning) as caught:
        res = navfuse.run(text, base_dir=DEMO.parent)
    msgs = [str(w.message) for w in caught]
    assert any("sensor_to_body_rpy_deg" in m for m in msgs), msgs
    assert len(msgs) >= len(res.summary["warnings"])


def test_relative_paths_of_text_configs_get_a_hint(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(navfuse.InputError) as e:
        navfuse.run(DEMO.read_text())
    assert "base_dir" in str(e.value) and str(tmp_path) in str(e.value)


def test_innovations_as_the_cli_file(cli_demo):
    res = navfuse.run(DEMO)
    csv = pd.read_csv(cli_demo / "innovations.csv")
    inn = res.innovations
    assert list(inn.columns) == list(csv.columns) and len(inn) == len(csv)
    assert (inn["source"].tolist() == csv["source"].tolist()
            and inn["outcome"].tolist() == csv["outcome"].tolist())
    # The file rounds t to 4 decimals, y to 6, nis and gate to 4.
    for c, tol in (("t_s", 5e-5), ("y1", 5e-7), ("nis", 5e-5), ("gate", 5e-5)):
        a, b = inn[c].to_numpy(float), csv[c].to_numpy(float)
        assert ((abs(a - b) <= tol) | (np.isnan(a) & np.isnan(b))).all(), c
