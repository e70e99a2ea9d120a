"""navfuse.simulate, navfuse.evaluate and the readers against the CLI."""

import json

import numpy as np
import pandas as pd
import pytest

import navfuse
from conftest import DEMO, ROOT, SHORT_SCENARIO


def assert_stats_close(a, b, rel=1e-9):
    """Equal keys, numbers within rel or 10 nm (a DataFrame side goes through degrees, so its
    radians differ from a file's in the last bits)."""
    if isinstance(a, dict):
        assert a.keys() == b.keys()
        for k in a:
            assert_stats_close(a[k], b[k], rel)
    elif isinstance(a, list):
        assert len(a) == len(b)
        for x, y in zip(a, b):
            assert_stats_close(x, y, rel)
    elif isinstance(a, float):
        assert a == pytest.approx(b, rel=rel, abs=1e-8)
    else:
        assert a == b


def test_simulate_then_run_then_evaluate(cli, tmp_path):
    sim = navfuse.simulate(SHORT_SCENARIO, seed=7)
    assert sim.summary["seed"] == 7
    truth, imu, gnss = sim.truth, sim.imu, sim.gnss
    assert len(truth) > 1000 and {"t_s", "lat_deg", "yaw_deg"} <= set(truth.columns)
    assert len(imu) == sim.summary["imu_samples"]
    assert np.allclose(imu["dt_s"], 1 / sim.summary["imu_rate_hz"])
    assert len(gnss) == sim.summary["gnss_fixes"]
    # The same files as `navfuse sim` with that seed.
    cli("sim", SHORT_SCENARIO, "--out", tmp_path / "cli", "--seed", 7)
    for name in ("imu.txt", "gnss.txt", "truth.nav"):
        assert (sim.dir / name).read_bytes() == (tmp_path / "cli" / name).read_bytes(), name
    res = navfuse.run(sim.run_config)
    ev = navfuse.evaluate(res, sim)
    # The temporary folder lives as long as a path into it is used.
    assert navfuse.run(navfuse.simulate(SHORT_SCENARIO, seed=7).run_config).status == "completed"
    cli("run", tmp_path / "cli" / "run.toml", "--out", tmp_path / "cli" / "out", "-q")
    cli_ev = json.loads(cli("eval", tmp_path / "cli" / "out" / "solution.nav",
                            tmp_path / "cli" / "truth.nav", "--json").stdout)
    assert_stats_close(ev.stats, cli_ev)
    assert len(ev.errors) == cli_ev["epochs"]
    assert ev.rms("horizontal") < 5.0


def test_evaluate_files_equals_cli_eval(cli, cli_demo, tmp_path):
    errs = tmp_path / "errors.csv"
    cli_ev = json.loads(cli("eval", cli_demo / "solution.nav", DEMO.parent / "gnss.pos",
                            "--lever-arm", "0,-0.05,0", "--gaps", "20/60@243300", "--json",
                            "--errors", errs).stdout)
    ev = navfuse.evaluate(cli_demo / "solution.nav", DEMO.parent / "gnss.pos",
                          lever_arm=(0, -0.05, 0), gaps="20/60@243300")
    assert ev.stats == cli_ev
    # --errors rounds to 6 decimals; the frame keeps full precision.
    e = pd.read_csv(errs)
    assert list(e.columns) == list(ev.errors.columns)
    assert np.allclose(e.to_numpy(float), ev.errors.to_numpy(float), atol=5.1e-7, equal_nan=True)


def test_evaluate_a_dataframe(cli_demo):
    sol = navfuse.read_nav(cli_demo / "solution.nav")
    a = navfuse.evaluate(sol, DEMO.parent / "gnss.pos", lever_arm=(0, -0.05, 0))
    b = navfuse.evaluate(cli_demo / "solution.nav", DEMO.parent / "gnss.pos",
                         lever_arm=(0, -0.05, 0))
    assert_stats_close(a.stats, b.stats)


def test_read_nav_equals_the_run(cli_demo):
    res = navfuse.run(DEMO)
    nav = navfuse.read_nav(cli_demo / "solution.nav")
    cols = ["gps_week", "t_s", "lat_deg", "lon_deg", "h_m", "vn_mps", "ve_mps", "vd_mps",
            "roll_deg", "pitch_deg"]
    pd.testing.assert_frame_equal(nav[cols], res.solution[cols], check_exact=False, rtol=0,
                                  atol=1e-9)


def test_read_imu_and_gnss_of_the_demo():
    imu = navfuse.read_imu(DEMO)
    assert len(imu) == 17995
    assert list(imu.columns) == ["t_s", "dt_s", "dtheta_x_rad", "dtheta_y_rad", "dtheta_z_rad",
                                 "dvel_x_mps", "dvel_y_mps", "dvel_z_mps"]
    assert (np.diff(imu["t_s"]) > 0).all()
    gnss = navfuse.read_gnss(DEMO)
    assert len(gnss) > 100 and gnss["lat_deg"].between(-90, 90).all()


def test_read_rinex_obs():
    df = navfuse.read_rinex_obs(ROOT / "crates" / "io" / "tests" / "data" / "walk_0827_3ep_v304.obs")
    assert set(df.columns) == {"gps_week", "t_s", "flag", "sat", "code", "value", "lli", "ssi"}
    assert df["t_s"].nunique() == 3
    assert df["sat"].str.match(r"^[GRECJS]\d\d$").all()
    gps_c1c = df[(df["code"] == "C1C") & df["sat"].str.startswith("G")]["value"].dropna()
    assert len(gps_c1c) > 0 and gps_c1c.between(1.9e7, 2.7e7).all()


def test_reader_error_names_the_file(tmp_path):
    p = tmp_path / "bad.nav"
    p.write_text("2200 100.0 30.0 114.0 20.0 0 0 0 0 0 0\n2200 99.0 30.0 114.0 20.0 0 0 0 0 0 0\n")
    with pytest.raises(navfuse.InputError) as e:
        navfuse.read_nav(p)
    assert e.value.file == str(p) and e.value.line == 2


def test_evaluate_a_dataframe_across_a_week(cli_demo):
    sol = navfuse.read_nav(cli_demo / "solution.nav")
    ref = navfuse.read_trajectory(DEMO.parent / "gnss.pos")
    a = navfuse.evaluate(sol, ref, lever_arm=(0, -0.05, 0))
    # The same instants, written as the next week's seconds after the middle row.
    for df in (sol, ref):
        late = df["t_s"] > df["t_s"].iloc[len(df) // 2]
        df.loc[late, "t_s"] -= 604800.0
        df.loc[late, "gps_week"] += 1
    b = navfuse.evaluate(sol, ref, lever_arm=(0, -0.05, 0))
    assert_stats_close(b.stats, a.stats)


def test_unequal_columns_are_a_value_error():
    with pytest.raises(ValueError, match="differ in length"):
        navfuse._navfuse.evaluate({"t_s": np.arange(3.0), "lat_deg": np.zeros(2),
                                   "lon_deg": np.zeros(3), "h_m": np.zeros(3)},
                                  {"t_s": np.arange(3.0), "lat_deg": np.zeros(3),
                                   "lon_deg": np.zeros(3), "h_m": np.zeros(3)})


def test_read_a_data_file_with_its_section_keys():
    tomllib = pytest.importorskip("tomllib", reason="skipped: tomllib needs Python 3.11")
    cfg = tomllib.loads(DEMO.read_text())
    imu_keys = dict(cfg["imu"])
    imu_file = DEMO.parent / imu_keys.pop("file")
    a = navfuse.read_imu(imu_file, **imu_keys)
    pd.testing.assert_frame_equal(a, navfuse.read_imu(DEMO), check_exact=True)
    gnss_keys = dict(cfg["gnss"])
    gnss_file = DEMO.parent / gnss_keys.pop("file")
    b = navfuse.read_gnss(gnss_file, **gnss_keys)
    pd.testing.assert_frame_equal(b, navfuse.read_gnss(DEMO), check_exact=True)
    with pytest.raises(navfuse.InputError) as e:
        navfuse.read_imu(imu_file, fromat="csv")
    assert e.value.field == "fromat" and e.value.file is None and "format" in str(e.value)
