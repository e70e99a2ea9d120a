//! A run's IMU and GNSS inputs written in KF-GINS's formats (docs/FORMATS.md,
//! "KF-GINS files"), with a KF-GINS YAML, so that `navfuse run --kf-gins` (and
//! KF-GINS itself) can be run on data recorded in other formats: the real drive of
//! ../shared/data/rtklibexplorer/drive_0708 (issue 30, RESULTS.md §20).
//!
//! KF-GINS has no GNSS-IMU time offset: the converter puts the IMU time tags on the
//! GNSS time scale with a given offset line, t_gnss = t_imu - (offset_s + rate *
//! (t_imu - t0_s)) (the sign of `[filter] time_offset`: a fix tagged t is due at IMU
//! time t + offset).

use anyhow::{anyhow, Context, Result};
use navfuse_io::config::RunConfig;
use navfuse_io::gnss::read_gnss;
use navfuse_io::imu::open_imu;
use std::fmt::Write as _;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// GNSS-IMU time offset as a line in IMU time \[s, s/s, s\].
#[derive(Clone, Copy, Debug, Default)]
pub struct OffsetLine {
    pub offset_s: f64,
    pub rate: f64,
    pub t0_s: f64,
}

impl OffsetLine {
    /// The GNSS time of IMU time `t_imu` \[s\].
    pub fn gnss_time(&self, t_imu: f64) -> f64 {
        t_imu - (self.offset_s + self.rate * (t_imu - self.t0_s))
    }
}

/// The start state KF-GINS needs (`starttime`, `initpos`, `initvel`, `initatt`):
/// one row of a `.nav` solution on the GNSS time scale.
#[derive(Clone, Copy, Debug)]
pub struct NavRow {
    pub t: f64,
    /// Latitude, longitude \[deg\], height \[m\].
    pub lla_deg_m: [f64; 3],
    pub vel_ned_mps: [f64; 3],
    pub rpy_deg: [f64; 3],
}

/// The first row at or after `t` of a KF-GINS `.nav` file (11 columns).
pub fn nav_row_at(path: &Path, t: f64) -> Result<NavRow> {
    let text = std::fs::read_to_string(path).with_context(|| format!("{}", path.display()))?;
    for (n, line) in text.lines().enumerate() {
        let v: Vec<f64> = line
            .split_whitespace()
            .map(str::parse)
            .collect::<Result<_, _>>()
            .with_context(|| format!("{}:{}: not a number", path.display(), n + 1))?;
        if v.len() != 11 {
            return Err(anyhow!(
                "{}:{}: expected 11 columns, found {}",
                path.display(),
                n + 1,
                v.len()
            ));
        }
        if v[1] >= t {
            return Ok(NavRow {
                t: v[1],
                lla_deg_m: [v[2], v[3], v[4]],
                vel_ned_mps: [v[5], v[6], v[7]],
                rpy_deg: [v[8], v[9], v[10]],
            });
        }
    }
    Err(anyhow!("{}: no row at or after t = {t}", path.display()))
}

/// What [`write_kfgins_inputs`] wrote.
#[derive(Clone, Debug)]
pub struct KfGinsFiles {
    pub imu: PathBuf,
    pub gnss: PathBuf,
    pub yaml: PathBuf,
    /// IMU samples and GNSS fixes written.
    pub imu_samples: usize,
    pub fixes: usize,
}

/// Write `cfg`'s IMU (increments in the body frame, as navfuse reads them) and GNSS
/// fixes (those the run keeps: quality filter, decimation) as `IMU.txt` and
/// `GNSS.txt` in `dir`, the IMU times moved to GNSS time by `offset`, and
/// `kf-gins.yaml` with `cfg`'s noise model, lever arm and initial uncertainties,
/// starting at `start` (its velocity and attitude; IMU errors zero).
pub fn write_kfgins_inputs(
    cfg: &RunConfig,
    offset: OffsetLine,
    start: &NavRow,
    dir: &Path,
) -> Result<KfGinsFiles> {
    std::fs::create_dir_all(dir)?;
    let imu = dir.join("IMU.txt");
    let gnss = dir.join("GNSS.txt");
    let yaml = dir.join("kf-gins.yaml");
    let mut w = BufWriter::new(std::fs::File::create(&imu)?);
    let mut imu_samples = 0;
    for s in open_imu(&cfg.imu)? {
        let s = s?;
        let (a, v) = (s.dtheta, s.dvel);
        writeln!(
            w,
            "{:.9} {:.15e} {:.15e} {:.15e} {:.15e} {:.15e} {:.15e}",
            offset.gnss_time(s.t),
            a.x,
            a.y,
            a.z,
            v.x,
            v.y,
            v.z
        )?;
        imu_samples += 1;
    }
    w.flush()?;
    let src = cfg
        .gnss
        .as_ref()
        .ok_or_else(|| anyhow!("the configuration has no [gnss] input"))?;
    let g = read_gnss(src)?;
    let mut text = String::new();
    for f in &g.fixes {
        let (lat, lon) = (f.lla.x.to_degrees(), f.lla.y.to_degrees());
        let s = f.std_ned;
        writeln!(
            text,
            "{:.9} {lat:.11} {lon:.11} {:.4} {:.4} {:.4} {:.4}",
            f.t, f.lla.z, s.x, s.y, s.z
        )?;
    }
    std::fs::write(&gnss, text)?;
    let nav = &cfg.nav;
    let n = &nav.imu_noise;
    let i = &nav.initial;
    let deg = f64::to_degrees;
    // 12 significant digits: unit conversions leave 0.9999999999999999 for 1
    let num = |x: f64| format!("{}", format!("{x:.11e}").parse::<f64>().unwrap_or(x));
    let l3 = |v: [f64; 3]| format!("[{}, {}, {}]", num(v[0]), num(v[1]), num(v[2]));
    let v3 = |v: nalgebra::Vector3<f64>, k: f64| l3([v.x * k, v.y * k, v.z * k]);
    let degph = 180.0 / std::f64::consts::PI * 3600.0;
    let e = &i.imu_errors_std;
    let y = format!(
        "# Written by navfuse_experiments::kfgins_convert from {}\n\
         imupath: \"IMU.txt\"\ngnsspath: \"GNSS.txt\"\noutputpath: \"out\"\n\
         imudatalen: 7\nimudatarate: {}\nstarttime: {}\nendtime: -1\n\
         initpos: {}\ninitvel: {}\ninitatt: {}\n\
         initgyrbias: [0, 0, 0]\ninitaccbias: [0, 0, 0]\ninitgyrscale: [0, 0, 0]\ninitaccscale: [0, 0, 0]\n\
         initposstd: {}\ninitvelstd: {}\ninitattstd: {}\n\
         initbgstd: {}\ninitbastd: {}\ninitsgstd: {}\ninitsastd: {}\n\
         imunoise:\n  arw: {}\n  vrw: {}\n  gbstd: {}\n  abstd: {}\n  gsstd: {}\n  asstd: {}\n  corrtime: {}\n\
         antlever: {}\n",
        cfg.source_path.display(),
        cfg.imu.rate_hz,
        start.t,
        l3(start.lla_deg_m),
        l3(start.vel_ned_mps),
        l3(start.rpy_deg),
        v3(i.pos_std, 1.0),
        v3(i.vel_std, 1.0),
        v3(i.att_std.map(deg), 1.0),
        v3(e.gyro_bias, degph),
        v3(e.accel_bias, 1e5),
        v3(e.gyro_scale, 1e6),
        v3(e.accel_scale, 1e6),
        v3(n.arw, 180.0 / std::f64::consts::PI * 60.0),
        v3(n.vrw, 60.0),
        v3(n.gyro_bias_std, degph),
        v3(n.accel_bias_std, 1e5),
        v3(n.gyro_scale_std, 1e6),
        v3(n.accel_scale_std, 1e6),
        num(n.corr_time_s / 3600.0),
        v3(nav.gnss.lever_arm_b, 1.0),
    );
    std::fs::write(&yaml, y)?;
    Ok(KfGinsFiles {
        imu,
        gnss,
        yaml,
        imu_samples,
        fixes: g.fixes.len(),
    })
}

/// Run navfuse on the configuration at `cfg_path` (its own time-offset estimation)
/// into `dir/ref`, then write its inputs in KF-GINS's formats into `dir/kfgins`
/// ([`write_kfgins_inputs`]) with the offset line it found and its solution's first
/// epoch at or after `start_s` (GNSS time; None: its first epoch) as the start state.
pub fn convert_run(cfg_path: &Path, dir: &Path, start_s: Option<f64>) -> Result<KfGinsFiles> {
    let cfg = navfuse_app::config::load(cfg_path)?;
    let ref_dir = dir.join("ref");
    let mut sink = navfuse_app::FileSink::create(&ref_dir)?;
    let job = navfuse_app::run(cfg.clone(), &mut sink, &navfuse_app::RunOptions::default())?;
    let offset = job.time_offset.as_ref().map_or(
        OffsetLine {
            offset_s: cfg.imu.time_offset_s,
            ..Default::default()
        },
        |f| OffsetLine {
            offset_s: f.tau0,
            rate: f.rate,
            t0_s: f.t0,
        },
    );
    let start = nav_row_at(&ref_dir.join("solution.nav"), start_s.unwrap_or(f64::MIN))?;
    write_kfgins_inputs(&cfg, offset, &start, &dir.join("kfgins"))
}
