//! `navfuse allan IMU_FILE | --config RUN.toml`: the Allan deviation of an IMU file
//! (`navfuse_app::allan`), printed as a table and written as CSV (`navfuse_io::allan`).

use std::path::PathBuf;

use anyhow::{Context, Result};
use navfuse_app::allan::{allan_of_imu, measured_rate_hz};
use navfuse_app::config;
use navfuse_io::input::{
    AccelUnit, CsvImuOptions, GapPolicy, GyroUnit, ImuFormat, ImuQuantity, ImuSource,
};

/// The command line's description of the IMU input (docs in `navfuse allan --help`).
#[derive(clap::Args)]
pub struct AllanArgs {
    /// The IMU file (KF-GINS text unless --format csv).
    #[arg(required_unless_present = "config", conflicts_with = "config")]
    pub imu_file: Option<PathBuf>,
    /// Read the IMU input of this run configuration (navfuse TOML; a .yaml file is
    /// read as KF-GINS) with all its [imu] settings, instead of IMU_FILE.
    #[arg(long, value_name = "RUN.toml")]
    pub config: Option<PathBuf>,
    /// Nominal sample rate [Hz] (default: measured from the time tags). The
    /// analysis uses the record's mean interval.
    #[arg(long, value_name = "HZ", conflicts_with = "config")]
    pub rate: Option<f64>,
    /// IMU_FILE's format.
    #[arg(long, value_parser = ["kf-gins", "csv"], default_value = "kf-gins", conflicts_with = "config")]
    pub format: String,
    /// --format csv: header lines to skip.
    #[arg(long, value_name = "N", default_value_t = 0)]
    pub skip_lines: usize,
    /// --format csv: rates (rad/s or deg/s, m/s² or g) or increments (rad or deg,
    /// m/s or g*s).
    #[arg(long, value_parser = ["rate", "increment"], default_value = "rate")]
    pub quantity: String,
    /// --format csv: gyro unit.
    #[arg(long, value_parser = ["rad", "deg"], default_value = "rad")]
    pub gyro_unit: String,
    /// --format csv: accelerometer unit (m: m/s² or m/s; g: 9.80665 m/s²).
    #[arg(long, value_parser = ["m", "g"], default_value = "m")]
    pub accel_unit: String,
    /// Write the curves as CSV (tau_s, m, clusters, rel_error, six axes in deg/h
    /// and mGal) and the read-offs beside it as STEM_readoffs.csv.
    #[arg(long, value_name = "FILE.csv")]
    pub out: Option<PathBuf>,
    /// Plot the curves into DIR/allan_gyro.svg and DIR/allan_accel.svg (log-log,
    /// with error bands, the fitted random-walk line and the bias-instability point).
    #[arg(long, value_name = "DIR")]
    pub svg: Option<PathBuf>,
}

/// The IMU source: the configuration's `[imu]`, or the file with the options given.
fn source(a: &AllanArgs) -> Result<ImuSource> {
    if let Some(p) = &a.config {
        let is_yaml = p.extension().is_some_and(|e| e == "yaml" || e == "yml");
        let cfg = if is_yaml {
            config::load_kfgins_yaml(p)
        } else {
            config::load(p)
        }?;
        return Ok(cfg.imu);
    }
    let path = a.imu_file.clone().context("no IMU file given")?;
    let format = match a.format.as_str() {
        "csv" => ImuFormat::Csv(CsvImuOptions {
            skip_lines: a.skip_lines,
            quantity: if a.quantity == "increment" {
                ImuQuantity::Increment
            } else {
                ImuQuantity::Rate
            },
            gyro_unit: if a.gyro_unit == "deg" {
                GyroUnit::Deg
            } else {
                GyroUnit::Rad
            },
            accel_unit: if a.accel_unit == "g" {
                AccelUnit::G
            } else {
                AccelUnit::Metre
            },
            ..CsvImuOptions::default()
        }),
        _ => ImuFormat::KfGins,
    };
    Ok(ImuSource {
        path,
        format,
        rate_hz: a.rate.unwrap_or(100.0),
        sensor_to_body_rpy_deg: [0.0; 3],
        time_offset_s: 0.0,
        gap_policy: GapPolicy::default(),
    })
}

pub fn main(a: &AllanArgs) -> Result<()> {
    let mut src = source(a)?;
    if a.config.is_none() && a.rate.is_none() {
        src.rate_hz = measured_rate_hz(&src)?;
    }
    let run = allan_of_imu(&src)?;
    for w in &run.warnings {
        eprintln!("navfuse: warning: {w}");
    }
    let al = &run.allan;
    println!(
        "Allan deviation of {}: {} samples, {:.1} s at {:.3} Hz (mean interval {:.6} s)\n",
        src.path.display(),
        al.samples,
        al.duration_s(),
        1.0 / al.dt_s,
        al.dt_s
    );
    print!("{}", navfuse_io::allan::readoffs_text(al));
    if let Some(out) = &a.out {
        let ro = navfuse_io::allan::write_allan_csv(out, al)?;
        eprintln!("navfuse: wrote {} and {}", out.display(), ro.display());
    }
    if let Some(dir) = &a.svg {
        std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
        for f in navfuse_report::allan::allan_figures(al)? {
            let p = dir.join(format!("{}.svg", f.name));
            std::fs::write(&p, &f.svg).with_context(|| format!("cannot write {}", p.display()))?;
            eprintln!("navfuse: wrote {}", p.display());
        }
    }
    Ok(())
}
