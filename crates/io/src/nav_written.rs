//! A solution record as a `.nav` file holds it, without the file: every field rounded
//! to the 9 decimals [`NavWriter`](crate::nav::NavWriter) prints and parsed back as
//! [`read_nav`](crate::nav::read_nav) parses it (same digits, same parser, same
//! conversion to a [`NavState`]), so that scoring records in memory gives, bit for bit,
//! what scoring the written file gives. 9 decimals of a degree are 0.1 mm of latitude;
//! of a metre, a nanometre.

use crate::fmt::{parse_f64, push_fixed9};
use crate::nav::{nav_fields, SolutionRecord};
use nalgebra::Vector3;
use navfuse_core::attitude::q_bn_from_euler;
use navfuse_core::NavState;

/// `r` as `read_nav` gives it back from a `.nav` line that `NavWriter` wrote: (GPS
/// week, state). A value the writer would not print as a number (NaN) stays NaN; the
/// reader would refuse the line.
pub fn nav_as_written(r: &SolutionRecord) -> (u32, NavState) {
    let mut digits = Vec::with_capacity(32);
    let [week, t, lat, lon, h, vn, ve, vd, roll, pitch, yaw] = nav_fields(r).map(|v| {
        digits.clear();
        push_fixed9(&mut digits, v);
        parse_f64(&digits).unwrap_or(f64::NAN)
    });
    let rpy = Vector3::new(roll.to_radians(), pitch.to_radians(), yaw.to_radians());
    (
        week as u32,
        NavState {
            t,
            lla: Vector3::new(lat.to_radians(), lon.to_radians(), h),
            v_n: Vector3::new(vn, ve, vd),
            q_bn: q_bn_from_euler(&rpy),
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::nav::{read_nav, NavWriter};
    use navfuse_core::attitude::euler_from_q_bn;
    use navfuse_core::ImuErrors;

    fn record(k: u32) -> SolutionRecord {
        let x = f64::from(k);
        let rpy = Vector3::new(
            (0.854208367 + 0.37 * x).to_radians(),
            (-2.034815106 - 0.011 * x).to_radians(),
            // Through north: yaw near 360 deg and near 0 (the writer's wrap).
            (359.9999999999 + 0.3e-9 * x - 0.5 * x * (x - 1.0)).to_radians(),
        );
        SolutionRecord {
            gps_week: 2381 + k / 3,
            nav: NavState {
                t: 345_600.123_456_789_1 + 0.1 * x,
                lla: Vector3::new(
                    (21.028_512_345_678_9 + 1e-7 * x).to_radians(),
                    (-105.854_212_345_678 - 3e-7 * x).to_radians(),
                    15.123_456_789_987 - 0.7 * x,
                ),
                v_n: Vector3::new(9.876_543_210_123 * x, -1e-10 * x, 0.333_333_333_333),
                q_bn: q_bn_from_euler(&rpy),
            },
            imu_errors: ImuErrors::default(),
            std: None,
            gnss_integrity: None,
            state: None,
        }
    }

    #[test]
    fn same_bits_as_writing_and_reading_the_file() {
        let dir = std::env::temp_dir().join(format!("navfuse-nav-written-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("s.nav");
        let records: Vec<_> = (0..8).map(record).collect();
        let mut w = NavWriter::create(&p).unwrap();
        for r in &records {
            w.write(r).unwrap();
        }
        w.finish().unwrap();
        let back = read_nav(&p).unwrap();
        let _ = std::fs::remove_dir_all(&dir);
        assert_eq!(back.len(), records.len());
        for (r, (week, s)) in records.iter().zip(&back) {
            let (w2, m) = nav_as_written(r);
            assert_eq!(w2, *week);
            assert_eq!(m.t.to_bits(), s.t.to_bits());
            for k in 0..3 {
                assert_eq!(m.lla[k].to_bits(), s.lla[k].to_bits());
                assert_eq!(m.v_n[k].to_bits(), s.v_n[k].to_bits());
            }
            let (a, b) = (euler_from_q_bn(&m.q_bn), euler_from_q_bn(&s.q_bn));
            for k in 0..3 {
                assert_eq!(a[k].to_bits(), b[k].to_bits());
            }
            // Rounded, not the record itself.
            assert!(m.t != r.nav.t && (m.t - r.nav.t).abs() <= 5e-10);
        }
    }
}
