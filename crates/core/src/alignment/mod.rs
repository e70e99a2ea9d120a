//! Initial attitude without a surveyed attitude: coarse levelling from the mean
//! specific force while static, and yaw from the GNSS course over ground once the
//! vehicle moves. SYSTEM.md §1 "Initial alignment" (seed 002: analytic coarse, then
//! fine alignment in the filter).

use crate::attitude::c_bn_from_euler;
use crate::types::{GnssFix, ImuSample};
use nalgebra::Vector3;

#[cfg(test)]
pub(crate) mod synth;
pub(crate) mod velocity_match;

/// Roll and pitch \[rad\] from the mean specific force in the body frame while static:
/// f^b = C_n^b (0, 0, -g), so roll = atan2(-f_y, -f_z), pitch = atan2(f_x, |f_yz|).
pub fn level(mean_f_b: &Vector3<f64>) -> (f64, f64) {
    let roll = (-mean_f_b.y).atan2(-mean_f_b.z);
    let pitch = mean_f_b
        .x
        .atan2((mean_f_b.y.powi(2) + mean_f_b.z.powi(2)).sqrt());
    (roll, pitch)
}

/// Mean specific force \[m/s²\] and mean angular rate \[rad/s\] of a sample window.
pub fn mean_motion(samples: &[ImuSample]) -> Option<(Vector3<f64>, Vector3<f64>)> {
    let t: f64 = samples.iter().map(|s| s.dt).sum();
    if t <= 0.0 {
        return None;
    }
    let dv: Vector3<f64> = samples.iter().map(|s| s.dvel).sum();
    let dth: Vector3<f64> = samples.iter().map(|s| s.dtheta).sum();
    Some((dv / t, dth / t))
}

/// Course over ground \[rad, from north\] of the first fix at or after `t_from` whose
/// horizontal speed is at least `min_speed` m/s: from the fix velocity when present,
/// otherwise from the displacement to the next fix (seed 001 eq. 11).
pub fn first_course(fixes: &[GnssFix], t_from: f64, min_speed: f64) -> Option<(f64, f64)> {
    for (i, f) in fixes.iter().enumerate().filter(|(_, f)| f.t >= t_from) {
        if let Some(v) = f.vel_ned {
            if v.x.hypot(v.y) >= min_speed {
                return Some((f.t, v.y.atan2(v.x)));
            }
        } else if let Some(g) = fixes.get(i + 1) {
            let d = crate::earth::lla_diff_ned(&g.lla, &f.lla);
            let dt = g.t - f.t;
            if dt > 0.0 && d.x.hypot(d.y) / dt >= min_speed {
                return Some((f.t, d.y.atan2(d.x)));
            }
        }
    }
    None
}

/// Gyrocompassing (static): yaw \[rad\] from the mean angular rate \[rad/s\] and the
/// levelled roll and pitch. In the local level frame Earth rate is
/// (W cos(lat) cos(yaw), -W cos(lat) sin(yaw), .), so yaw = atan2(-w_l,y, w_l,x).
pub fn gyrocompass_yaw(mean_w_b: &Vector3<f64>, roll: f64, pitch: f64) -> f64 {
    let c_bl = c_bn_from_euler(&Vector3::new(roll, pitch, 0.0));
    let w_l = c_bl * mean_w_b;
    (-w_l.y).atan2(w_l.x)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::earth::omega_ie_n;

    #[test]
    fn levelling_recovers_tilt() {
        let rpy = Vector3::new(0.05, -0.12, 2.0);
        let f_b = c_bn_from_euler(&rpy).transpose() * Vector3::new(0.0, 0.0, -9.8);
        let (r, p) = level(&f_b);
        assert!((r - rpy.x).abs() < 1e-12 && (p - rpy.y).abs() < 1e-12);
    }

    #[test]
    fn course_from_velocity_or_positions() {
        let base = Vector3::new(0.7, -1.8, 1600.0);
        let fix = |t: f64, n: f64, e: f64, v: Option<Vector3<f64>>| GnssFix {
            t,
            lla: crate::earth::lla_add_ned(&base, &Vector3::new(n, e, 0.0)),
            std_ned: Vector3::repeat(0.01),
            vel_ned: v,
            vel_std_ned: None,
        };
        let with_v = [
            fix(0.0, 0.0, 0.0, Some(Vector3::new(0.1, 0.0, 0.0))),
            fix(1.0, 0.0, 0.0, Some(Vector3::new(3.0, -3.0, 0.0))),
        ];
        let (t, c) = first_course(&with_v, 0.0, 2.0).unwrap();
        assert_eq!(t, 1.0);
        assert!((c + std::f64::consts::FRAC_PI_4).abs() < 1e-12);
        let no_v = [
            fix(0.0, 0.0, 0.0, None),
            fix(1.0, 0.0, 0.5, None),
            fix(2.0, 0.0, 4.0, None),
        ];
        let (t, c) = first_course(&no_v, 0.0, 2.0).unwrap();
        assert_eq!(t, 1.0);
        assert!((c - std::f64::consts::FRAC_PI_2).abs() < 1e-6);
    }

    #[test]
    fn gyrocompass_finds_yaw_from_earth_rate() {
        let lat = 0.7;
        for yaw in [-2.5, -0.3, 0.0, 1.0, 3.0] {
            let rpy = Vector3::new(0.02, -0.04, yaw);
            let w_b = c_bn_from_euler(&rpy).transpose() * omega_ie_n(lat);
            let y = gyrocompass_yaw(&w_b, rpy.x, rpy.y);
            assert!((y - yaw).abs() < 1e-9, "{y} {yaw}");
        }
    }
}
