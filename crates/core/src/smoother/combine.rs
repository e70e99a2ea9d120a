//! Two estimates of one epoch: their difference in error-state terms and their
//! combination weighted by their variances, state by state (Inertial Explorer's
//! combined forward/reverse solution; REFERENCES \[FP69\], the
//! two-filter smoother with the cross-covariances of each state dropped).

use super::nominal::{is_source_block, Nominal};
use crate::earth::lla_diff_ned;
use crate::state::{Block, StateLayout, ATT, BA, BG, POS, SA, SG, VEL};
use nalgebra::{DVector, Rotation3};

/// The error-state vector d with `b == a.corrected(layout, d)` to first order: a
/// minus b in the conventions of state.rs (position, velocity, attitude and the
/// vehicle and source states a - b; the IMU errors b - a).
pub fn difference(layout: &StateLayout, a: &Nominal, b: &Nominal) -> DVector<f64> {
    let n = layout.len();
    let mut d = DVector::zeros(n);
    let dp = lla_diff_ned(&a.nav.lla, &b.nav.lla);
    let dv = a.nav.v_n - b.nav.v_n;
    // C_b = (I + phi x) C_a.
    let rot = (b.nav.q_bn * a.nav.q_bn.inverse()).scaled_axis();
    for k in 0..3 {
        d[POS + k] = dp[k];
        d[VEL + k] = dv[k];
        d[ATT + k] = rot[k];
        d[BG + k] = b.imu_errors.gyro_bias[k] - a.imu_errors.gyro_bias[k];
        d[BA + k] = b.imu_errors.accel_bias[k] - a.imu_errors.accel_bias[k];
        d[SG + k] = b.imu_errors.gyro_scale[k] - a.imu_errors.gyro_scale[k];
        d[SA + k] = b.imu_errors.accel_scale[k] - a.imu_errors.accel_scale[k];
    }
    for (blk, i) in layout.blocks() {
        match blk {
            Block::TimeOffset => d[i] = a.time_offset_s - b.time_offset_s,
            Block::TimeOffsetRate => d[i] = a.time_offset_rate - b.time_offset_rate,
            Block::OdometerScale => d[i] = a.odometer_scale - b.odometer_scale,
            Block::Mounting => {
                let r = Rotation3::from_matrix_unchecked(b.c_bm * a.c_bm.transpose()).scaled_axis();
                d[i] = r.y;
                d[i + 1] = r.z;
            }
            blk if is_source_block(blk) => {
                for k in i..i + blk.len() {
                    d[k] = a.extra[k] - b.extra[k];
                }
            }
            _ => {}
        }
    }
    d
}

/// `a` and `b` (variances `var_a`, `var_b` per state) combined state by state with
/// inverse-variance weights; returns the combination and its variances. A state
/// neither estimates (both variances zero) keeps `a`'s value.
pub fn combine(
    layout: &StateLayout,
    a: &Nominal,
    var_a: &DVector<f64>,
    b: &Nominal,
    var_b: &DVector<f64>,
) -> (Nominal, DVector<f64>) {
    let d = difference(layout, a, b);
    let n = layout.len();
    let mut step = DVector::zeros(n);
    let mut var = DVector::zeros(n);
    for i in 0..n {
        let (va, vb) = (var_a[i].max(0.0), var_b[i].max(0.0));
        let s = va + vb;
        if s > 0.0 {
            step[i] = d[i] * va / s;
            var[i] = va * vb / s;
        }
    }
    (a.corrected(layout, &step), var)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::types::{ImuErrors, NavState};
    use nalgebra::{Matrix3, UnitQuaternion, Vector3};

    fn nominal(lat: f64, yaw: f64, v: f64) -> Nominal {
        Nominal {
            nav: NavState {
                t: 0.0,
                lla: Vector3::new(lat, 0.2, 50.0),
                v_n: Vector3::new(v, 0.0, 0.0),
                q_bn: UnitQuaternion::from_euler_angles(0.01, 0.02, yaw),
            },
            imu_errors: ImuErrors::default(),
            time_offset_s: 0.0,
            time_offset_rate: 0.0,
            odometer_scale: 0.0,
            c_bm: Matrix3::identity(),
            extra: DVector::zeros(21),
        }
    }

    #[test]
    fn equal_weights_give_the_midpoint() {
        let layout = StateLayout::ins21();
        let a = nominal(0.5, 0.10, 10.0);
        let b = nominal(0.5 + 1e-6, 0.12, 12.0);
        let var = DVector::from_element(21, 1.0);
        let (c, v) = combine(&layout, &a, &var, &b, &var);
        assert!((c.nav.v_n.x - 11.0).abs() < 1e-9);
        let mid = lla_diff_ned(&c.nav.lla, &a.nav.lla).x;
        let full = lla_diff_ned(&b.nav.lla, &a.nav.lla).x;
        assert!((mid - 0.5 * full).abs() < 1e-6, "{mid} {full}");
        let yaw = crate::attitude::euler_from_q_bn(&c.nav.q_bn).z;
        assert!((yaw - 0.11).abs() < 1e-6, "{yaw}");
        assert!((v[0] - 0.5).abs() < 1e-12);
        // difference() inverts corrected().
        let d = difference(&layout, &a, &b);
        let back = a.corrected(&layout, &d);
        assert!(lla_diff_ned(&back.nav.lla, &b.nav.lla).norm() < 1e-6);
        assert!((back.nav.v_n - b.nav.v_n).norm() < 1e-12);
    }
}
