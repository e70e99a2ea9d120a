//! The readers (`navfuse.read_*`) and the evaluator (`navfuse.evaluate`): navfuse's
//! own readers, with their checks and messages, returning columns.

use crate::errors::{to_py_err, to_py_err_any};
use crate::frame::Frame;
use crate::load_config;
use nalgebra::Vector3;
use navfuse_app::score::{epoch_errors, report_json, score, ScoreOptions, ERRORS_HEADER};
use navfuse_core::eval::TrajPoint;
use navfuse_core::outage::OutageSchedule;
use navfuse_core::GnssFix;
use navfuse_io::input::{Coupling, GnssFormat, UbxGnss};
use navfuse_io::trajectory::{detect_format, read_trajectory as read_traj, TrajFormat, Trajectory};
use numpy::PyReadonlyArray1;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyModule};
use std::path::{Path, PathBuf};

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(read_trajectory, m)?)?;
    m.add_function(wrap_pyfunction!(read_imu, m)?)?;
    m.add_function(wrap_pyfunction!(read_gnss, m)?)?;
    m.add_function(wrap_pyfunction!(read_rinex_obs, m)?)?;
    m.add_function(wrap_pyfunction!(evaluate, m)?)?;
    Ok(())
}

fn traj_format(py: Python<'_>, path: &Path, format: &str) -> PyResult<TrajFormat> {
    match TrajFormat::parse(format).map_err(PyValueError::new_err)? {
        Some(f) => Ok(f),
        None => detect_format(path).map_err(|e| to_py_err(py, &e.into(), None)),
    }
}

fn load_traj(py: Python<'_>, path: &Path, format: &str, quality: &[u8]) -> PyResult<Trajectory> {
    let f = traj_format(py, path, format)?;
    py.detach(|| read_traj(path, Some(f), quality))
        .map_err(|e| to_py_err(py, &e.into(), None))
}

/// Columns of a trajectory: gps_week, t_s, lat_deg, lon_deg, h_m, and velocity and
/// attitude when the file has them.
fn traj_frame(t: &Trajectory) -> Frame {
    let mut f = Frame::new();
    let week = f.i64("gps_week");
    let ts = f.f64("t_s");
    let (la, lo, h) = (f.f64("lat_deg"), f.f64("lon_deg"), f.f64("h_m"));
    let has_v = t.points.iter().any(|p| p.v_n.is_some());
    let has_a = t.points.iter().any(|p| p.rpy.is_some());
    let v0 = if has_v {
        f.f64("vn_mps");
        f.f64("ve_mps");
        f.f64("vd_mps") - 2
    } else {
        0
    };
    let a0 = if has_a {
        f.f64("roll_deg");
        f.f64("pitch_deg");
        f.f64("yaw_deg") - 2
    } else {
        0
    };
    for p in &t.points {
        f.push_i64(week, Some(i64::from(t.week)));
        f.push_f64(ts, p.t);
        f.push_f64(la, p.lla.x.to_degrees());
        f.push_f64(lo, p.lla.y.to_degrees());
        f.push_f64(h, p.lla.z);
        if has_v {
            for k in 0..3 {
                f.push_f64(v0 + k, p.v_n.map_or(f64::NAN, |v| v[k]));
            }
        }
        if has_a {
            for k in 0..3 {
                f.push_f64(a0 + k, p.rpy.map_or(f64::NAN, |a| a[k].to_degrees()));
            }
        }
    }
    f
}

/// `navfuse.read_trajectory` / `read_nav`: any trajectory `navfuse eval` reads.
#[pyfunction]
#[pyo3(signature = (path, format="auto", quality=vec![1]))]
fn read_trajectory(
    py: Python<'_>,
    path: PathBuf,
    format: &str,
    quality: Vec<u8>,
) -> PyResult<(Py<PyDict>, String, Vec<String>)> {
    let t = load_traj(py, &path, format, &quality)?;
    Ok((
        traj_frame(&t).into_py(py)?,
        t.format.describe().to_string(),
        t.warnings.clone(),
    ))
}

/// The `[imu]` / `[gnss]` sections alone (a file and its keys, no run configuration).
type InputSections = (
    Option<navfuse_io::input::ImuSource>,
    Option<(
        navfuse_io::input::GnssSource,
        navfuse_core::config::GnssOptions,
    )>,
);

fn input_sections(py: Python<'_>, text: &str, base_dir: &Path) -> PyResult<InputSections> {
    navfuse_io::config::parse_input_sections(text, &base_dir.join("<reader keys>"))
        .map_err(|e| to_py_err(py, &e.into(), None))
}

/// `navfuse.read_imu`: the `[imu]` of a configuration, read as `navfuse run` reads it
/// (units, axes, time offsets applied): t_s, dt_s, the angle and velocity increments.
#[pyfunction]
fn read_imu(
    py: Python<'_>,
    kind: &str,
    value: &str,
    base_dir: PathBuf,
) -> PyResult<(Py<PyDict>, Option<u32>)> {
    let imu_src = match kind {
        "inputs" => input_sections(py, value, &base_dir)?
            .0
            .ok_or_else(|| PyValueError::new_err("no [imu] keys given"))?,
        _ => {
            load_config(kind, value, &base_dir)
                .map_err(|e| to_py_err(py, &e, None))?
                .imu
        }
    };
    let r = py.detach(
        || -> Result<(Vec<navfuse_core::ImuSample>, Option<u32>), navfuse_app::Error> {
            let reader = navfuse_io::imu::open_imu(&imu_src)?;
            let week = reader.gps_week();
            let samples = reader.collect::<Result<Vec<_>, _>>()?;
            Ok((samples, week))
        },
    );
    let (samples, week) = r.map_err(|e| to_py_err(py, &e, None))?;
    let mut f = Frame::new();
    for n in [
        "t_s",
        "dt_s",
        "dtheta_x_rad",
        "dtheta_y_rad",
        "dtheta_z_rad",
        "dvel_x_mps",
        "dvel_y_mps",
        "dvel_z_mps",
    ] {
        f.f64(n);
    }
    for s in &samples {
        let v = [
            s.t, s.dt, s.dtheta.x, s.dtheta.y, s.dtheta.z, s.dvel.x, s.dvel.y, s.dvel.z,
        ];
        for (k, x) in v.iter().enumerate() {
            f.push_f64(k, *x);
        }
    }
    Ok((f.into_py(py)?, week))
}

/// `navfuse.read_gnss`: the `[gnss]` fixes of a configuration (RINEX / UBX raw: the
/// single point fixes the loose coupling uses): antenna position, 1-sigma, velocity.
#[pyfunction]
fn read_gnss(
    py: Python<'_>,
    kind: &str,
    value: &str,
    base_dir: PathBuf,
) -> PyResult<(Py<PyDict>, Option<u32>, Vec<String>)> {
    let (src, systems) = match kind {
        "inputs" => match input_sections(py, value, &base_dir)?.1 {
            Some((src, opts)) => (src, opts.systems),
            None => return Err(PyValueError::new_err("no [gnss] keys given")),
        },
        _ => {
            let cfg = load_config(kind, value, &base_dir).map_err(|e| to_py_err(py, &e, None))?;
            let Some(src) = cfg.gnss.clone() else {
                return Err(PyValueError::new_err(
                    "the configuration has no [gnss] section",
                ));
            };
            (src, cfg.nav.gnss.systems.clone())
        }
    };
    let r = py.detach(
        move || -> Result<(Vec<GnssFix>, Option<u32>, Vec<String>), navfuse_app::Error> {
            match &src.format {
                GnssFormat::Rinex(r) | GnssFormat::Ubx(UbxGnss::Raw(r)) => {
                    let mut r = r.clone();
                    r.coupling = Coupling::Loose;
                    let g = match src.format {
                        GnssFormat::Ubx(_) => navfuse_app::ubx_input::load_ubx(&src, &r, &systems)?,
                        _ => navfuse_app::gnss_input::load_rinex(&src, &r, &systems)?,
                    };
                    Ok((g.fixes, Some(g.gps_week), g.warnings))
                }
                _ => {
                    let g = navfuse_io::gnss::read_gnss(&src)?;
                    Ok((g.fixes, g.gps_week, g.warnings))
                }
            }
        },
    );
    let (fixes, week, warnings) = r.map_err(|e| to_py_err(py, &e, None))?;
    let mut f = Frame::new();
    for n in [
        "t_s",
        "lat_deg",
        "lon_deg",
        "h_m",
        "std_n_m",
        "std_e_m",
        "std_d_m",
        "vn_mps",
        "ve_mps",
        "vd_mps",
        "std_vn_mps",
        "std_ve_mps",
        "std_vd_mps",
    ] {
        f.f64(n);
    }
    let nan3 = Vector3::repeat(f64::NAN);
    for x in &fixes {
        let v = [
            x.t,
            x.lla.x.to_degrees(),
            x.lla.y.to_degrees(),
            x.lla.z,
            x.std_ned.x,
            x.std_ned.y,
            x.std_ned.z,
        ];
        for (k, y) in v.iter().enumerate() {
            f.push_f64(k, *y);
        }
        let vel = x.vel_ned.unwrap_or(nan3);
        let vs = x.vel_std_ned.unwrap_or(nan3);
        for k in 0..3 {
            f.push_f64(7 + k, vel[k]);
            f.push_f64(10 + k, vs[k]);
        }
    }
    Ok((f.into_py(py)?, week, warnings))
}

/// `navfuse.read_rinex_obs`: every observation of a RINEX 2/3/4 observation file
/// (plain, gzip, Hatanaka), one row per epoch, satellite and code.
#[pyfunction]
fn read_rinex_obs(py: Python<'_>, path: PathBuf) -> PyResult<(Py<PyDict>, Vec<String>)> {
    let all = py
        .detach(|| navfuse_io::rinex_obs::read_rinex_obs_all(&path))
        .map_err(|e| to_py_err(py, &e.into(), None))?;
    let mut f = Frame::new();
    let (week, sow, flag, sat, code, value, lli, ssi) = (
        f.i64("gps_week"),
        f.f64("t_s"),
        f.i64("flag"),
        f.text("sat"),
        f.text("code"),
        f.f64("value"),
        f.i64("lli"),
        f.i64("ssi"),
    );
    for ep in &all.epochs {
        for s in &ep.sats {
            let name = s.sat.to_string();
            for (c, v) in &s.signals {
                f.push_i64(week, Some(i64::from(ep.t.week)));
                f.push_f64(sow, ep.t.sow);
                f.push_i64(flag, Some(i64::from(ep.flag)));
                f.push_text(sat, name.clone());
                f.push_text(code, String::from_utf8_lossy(&c.0).into_owned());
                f.push_f64(value, v.value.unwrap_or(f64::NAN));
                f.push_i64(lli, v.lli.map(i64::from));
                f.push_i64(ssi, v.ssi.map(i64::from));
            }
        }
    }
    Ok((f.into_py(py)?, all.warnings.clone()))
}

/// A trajectory handed over as columns (t_s, lat_deg, lon_deg, h_m; optional
/// vn_mps ve_mps vd_mps, roll_deg pitch_deg yaw_deg, a gps_week number).
fn traj_of_columns(d: &Bound<'_, PyDict>, week: u32) -> PyResult<Trajectory> {
    let col = |name: &str| -> PyResult<Option<Vec<f64>>> {
        match d.get_item(name)? {
            Some(a) => Ok(Some(
                a.extract::<PyReadonlyArray1<f64>>()?.as_slice()?.to_vec(),
            )),
            None => Ok(None),
        }
    };
    let need = |name: &str| -> PyResult<Vec<f64>> {
        col(name)?
            .ok_or_else(|| PyValueError::new_err(format!("the trajectory has no column '{name}'")))
    };
    let (t, la, lo, h) = (
        need("t_s")?,
        need("lat_deg")?,
        need("lon_deg")?,
        need("h_m")?,
    );
    let v = [col("vn_mps")?, col("ve_mps")?, col("vd_mps")?];
    let a = [col("roll_deg")?, col("pitch_deg")?, col("yaw_deg")?];
    let lens = [&la, &lo, &h].map(Vec::len);
    let optional = v.iter().chain(&a).flatten().map(Vec::len);
    if lens.iter().copied().chain(optional).any(|n| n != t.len()) {
        return Err(PyValueError::new_err(format!(
            "the trajectory's columns differ in length (t_s has {} rows)",
            t.len()
        )));
    }
    let mut points = Vec::with_capacity(t.len());
    for k in 0..t.len() {
        let vals = [t[k], la[k], lo[k], h[k]];
        if vals.iter().any(|x| !x.is_finite()) {
            return Err(PyValueError::new_err(format!(
                "trajectory row {k}: t_s, lat_deg, lon_deg, h_m must be finite numbers, found {vals:?}"
            )));
        }
        if k > 0 && t[k] <= t[k - 1] {
            return Err(PyValueError::new_err(format!(
                "trajectory row {k}: t_s {} does not increase (previous {})",
                t[k],
                t[k - 1]
            )));
        }
        let v3 = |c: &[Option<Vec<f64>>; 3], scale: f64| match c {
            [Some(x), Some(y), Some(z)]
                if x[k].is_finite() && y[k].is_finite() && z[k].is_finite() =>
            {
                Some(Vector3::new(x[k], y[k], z[k]) * scale)
            }
            _ => None,
        };
        points.push(TrajPoint {
            t: t[k],
            lla: Vector3::new(la[k].to_radians(), lo[k].to_radians(), h[k]),
            v_n: v3(&v, 1.0),
            rpy: v3(&a, std::f64::consts::PI / 180.0),
        });
    }
    Ok(Trajectory {
        format: TrajFormat::Csv,
        week,
        points,
        warnings: Vec::new(),
    })
}

/// One side of `evaluate`: a path (format, quality) or columns (with its week).
fn side(
    py: Python<'_>,
    x: &Bound<'_, PyAny>,
    format: &str,
    quality: &[u8],
) -> PyResult<(Trajectory, String)> {
    if let Ok(d) = x.cast::<PyDict>() {
        let week: u32 = match d.get_item("__week__")? {
            Some(w) => w.extract()?,
            None => 0,
        };
        return Ok((traj_of_columns(d, week)?, "the DataFrame".into()));
    }
    let p: PathBuf = x.extract()?;
    Ok((load_traj(py, &p, format, quality)?, p.display().to_string()))
}

/// `navfuse.evaluate`: `navfuse eval` -> (the --json report as text, the --errors
/// columns at full precision).
#[pyfunction]
#[pyo3(signature = (solution, truth, gaps=None, lever_arm=None, window=None, solution_format="auto", truth_format="auto", quality=vec![1]))]
#[allow(clippy::too_many_arguments)]
fn evaluate(
    py: Python<'_>,
    solution: &Bound<'_, PyAny>,
    truth: &Bound<'_, PyAny>,
    gaps: Option<String>,
    lever_arm: Option<[f64; 3]>,
    window: Option<(f64, f64)>,
    solution_format: &str,
    truth_format: &str,
    quality: Vec<u8>,
) -> PyResult<(String, Py<PyDict>)> {
    let (sol, sol_name) = side(py, solution, solution_format, &[])?;
    let (reference, ref_name) = side(py, truth, truth_format, &quality)?;
    let gaps = gaps
        .as_deref()
        .map(OutageSchedule::parse)
        .transpose()
        .map_err(|e| PyValueError::new_err(format!("gaps: {e}")))?;
    let opts = ScoreOptions {
        gaps,
        lever_arm_b: lever_arm.map(|a| Vector3::new(a[0], a[1], a[2])),
        lever_arm_name: "lever_arm",
        window,
        keep_epochs: true,
    };
    let rep = py
        .detach(|| score(&sol, &sol_name, reference, &ref_name, &opts))
        .map_err(|e| to_py_err(py, &e, None))?;
    let json =
        serde_json::to_string(&report_json(&rep)).map_err(|e| to_py_err_any(py, &e.into()))?;
    let mut f = Frame::new();
    for n in ERRORS_HEADER.split(',') {
        f.f64(n);
    }
    for e in &rep.per_epoch {
        for (k, v) in epoch_errors(e).iter().enumerate() {
            f.push_f64(k, v.unwrap_or(f64::NAN));
        }
    }
    Ok((json, f.into_py(py)?))
}
