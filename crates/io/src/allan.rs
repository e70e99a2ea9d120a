//! `navfuse allan`'s outputs (docs/FORMATS.md "Allan deviation"): the curves as CSV,
//! the read-offs as CSV, and the read-offs as a text table. Datasheet units
//! ([`Sensor::units`]): gyro deg/h and deg/sqrt(h), accelerometer mGal and
//! m/s/sqrt(h).
//!
//! Not here yet: the plot, `write_allan_svg(path, &ImuAllan)` (with the project's
//! plotting crate). Everything it draws is in [`ImuAllan`]: per axis the curve with its
//! error bars `adev (1 +- rel_error)`, the fitted -1/2 line over its tau range and the
//! bias-instability floor `0.664 B` at its tau, in [`Sensor::units`].

use std::fmt::Write as _;
use std::path::Path;

use navfuse_core::allan::imu::{AxisAllan, ImuAllan, Sensor};
use navfuse_core::allan::FLICKER_FLOOR_FACTOR;

use crate::table::TextTable;
use crate::InputError;

/// Column of an axis's deviation in the curve CSV: `gyro_x_deg_h`, `accel_z_mgal`.
fn curve_column(a: &AxisAllan) -> String {
    let unit = match a.sensor {
        Sensor::Gyro => "deg_h",
        Sensor::Accel => "mgal",
    };
    format!("{}_{unit}", a.name())
}

/// The curves: one row per tau, `tau_s,m,clusters,rel_error` and the six axes'
/// deviations. Every axis has the same taus (one record).
pub fn curves_csv(a: &ImuAllan) -> String {
    let mut s = String::from("tau_s,m,clusters,rel_error");
    for ax in &a.axes {
        s.push(',');
        s.push_str(&curve_column(ax));
    }
    s.push('\n');
    let rows = a.axes.iter().map(|x| x.curve.len()).min().unwrap_or(0);
    for k in 0..rows {
        let p = &a.axes[0].curve[k];
        let _ = write!(
            s,
            "{:.6e},{},{},{:.6}",
            p.tau_s, p.m, p.clusters, p.rel_error
        );
        for ax in &a.axes {
            let _ = write!(
                s,
                ",{:.9e}",
                ax.curve[k].adev * ax.sensor.units().adev_factor
            );
        }
        s.push('\n');
    }
    s
}

fn opt(x: Option<f64>) -> String {
    x.map_or(String::new(), |v| format!("{v:.6e}"))
}

/// The read-offs: one row per axis, `axis,random_walk,random_walk_unit,fit_tau_lo_s,
/// fit_tau_hi_s,bias_instability,bias_instability_unit,bias_tau_s,bias_upper_bound`;
/// empty cells where a figure could not be read.
pub fn readoffs_csv(a: &ImuAllan) -> String {
    let mut s = String::from(
        "axis,random_walk,random_walk_unit,fit_tau_lo_s,fit_tau_hi_s,bias_instability,\
         bias_instability_unit,bias_tau_s,bias_upper_bound\n",
    );
    for ax in &a.axes {
        let u = ax.sensor.units();
        let rw = ax.random_walk;
        let bi = ax.bias_instability;
        let _ = writeln!(
            s,
            "{},{},{},{},{},{},{},{},{}",
            ax.name(),
            opt(rw.map(|r| r.coefficient * u.random_walk_factor)),
            u.random_walk,
            opt(rw.map(|r| r.tau_lo_s)),
            opt(rw.map(|r| r.tau_hi_s)),
            opt(bi.map(|b| b.value * u.adev_factor)),
            u.adev,
            opt(bi.map(|b| b.tau_s)),
            bi.map_or(String::new(), |b| b.still_falling.to_string()),
        );
    }
    s
}

/// The curves' CSV ([`curves_csv`]) at `path` and the read-offs ([`readoffs_csv`])
/// beside it, `STEM_readoffs.csv`; returns the read-offs' path.
pub fn write_allan_csv(path: &Path, a: &ImuAllan) -> Result<std::path::PathBuf, InputError> {
    std::fs::write(path, curves_csv(a)).map_err(|e| InputError::write(path, &e))?;
    let stem = path
        .file_stem()
        .map_or("allan".into(), |s| s.to_string_lossy());
    let ro = path.with_file_name(format!("{stem}_readoffs.csv"));
    std::fs::write(&ro, readoffs_csv(a)).map_err(|e| InputError::write(&ro, &e))?;
    Ok(ro)
}

/// The read-offs as two tables (gyros, accelerometers), units in the headers, and a
/// legend.
pub fn readoffs_text(a: &ImuAllan) -> String {
    let mut s = String::new();
    for sensor in [Sensor::Gyro, Sensor::Accel] {
        let u = sensor.units();
        let mut t = TextTable::new([
            "axis".to_string(),
            format!("{} [{}]", sensor.random_walk_name(), u.random_walk),
            "fit tau [s]".into(),
            format!("bias inst. [{}]", u.adev),
            "at tau [s]".into(),
            format!("min adev [{}]", u.adev),
        ]);
        for ax in a.axes.iter().filter(|x| x.sensor == sensor) {
            let rw = ax.random_walk;
            let bi = ax.bias_instability;
            t.row([
                ax.name(),
                rw.map_or("-".into(), |r| {
                    format!("{:.4}", r.coefficient * u.random_walk_factor)
                }),
                rw.map_or("-".into(), |r| {
                    format!("{:.3}-{:.3}", r.tau_lo_s, r.tau_hi_s)
                }),
                bi.map_or("-".into(), |b| {
                    let bound = if b.still_falling { "<= " } else { "" };
                    format!("{bound}{:.4}", b.value * u.adev_factor)
                }),
                bi.map_or("-".into(), |b| format!("{:.3}", b.tau_s)),
                bi.map_or("-".into(), |b| {
                    format!("{:.4}", b.value * FLICKER_FLOOR_FACTOR * u.adev_factor)
                }),
            ]);
        }
        s.push_str(&t.render_wrapped(crate::table::MAX_WIDTH));
        s.push('\n');
    }
    s.push_str(
        "  ARW / VRW: the -1/2 slope line fitted over 'fit tau', read at tau = 1 s\n  \
         bias inst.: the curve's minimum / 0.664, at tau 'at tau' (<=: the curve still falls \
         at\n    the longest tau with 10 independent clusters: an upper bound)\n",
    );
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn record() -> ImuAllan {
        // A deterministic pseudo-random sequence: enough for the formats.
        let mut state = 1u64;
        let ch: [Vec<f64>; 6] = std::array::from_fn(|k| {
            (0..5000)
                .map(|_| {
                    state = state
                        .wrapping_mul(6364136223846793005)
                        .wrapping_add(1442695040888963407);
                    ((state >> 11) as f64 / (1u64 << 53) as f64 - 0.5)
                        * if k < 3 { 1e-5 } else { 1e-3 }
                })
                .collect()
        });
        ImuAllan::from_increments(&ch, 0.01)
    }

    #[test]
    fn curves_and_readoffs_have_their_documented_columns() {
        let a = record();
        let c = curves_csv(&a);
        let mut lines = c.lines();
        assert_eq!(
            lines.next().unwrap(),
            "tau_s,m,clusters,rel_error,gyro_x_deg_h,gyro_y_deg_h,gyro_z_deg_h,accel_x_mgal,\
             accel_y_mgal,accel_z_mgal"
        );
        let first: Vec<&str> = lines.next().unwrap().split(',').collect();
        assert_eq!(first.len(), 10);
        assert_eq!(first[0].parse::<f64>().unwrap(), 0.01);
        let r = readoffs_csv(&a);
        assert_eq!(r.lines().count(), 7);
        assert!(r.lines().nth(1).unwrap().starts_with("gyro_x,"));
        assert!(r.contains(",deg/sqrt(h),") && r.contains(",mGal,"));
        let t = readoffs_text(&a);
        assert!(crate::table::max_line_width(&t) <= 100, "{t}");
        assert!(t.contains("ARW [deg/sqrt(h)]") && t.contains("VRW [m/s/sqrt(h)]"));
    }
}
