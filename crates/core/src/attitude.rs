//! Attitude representations: quaternion, DCM, Euler angles, rotation vector.
//!
//! Convention: `c_bn` is C_b^n, the rotation that takes body-frame (FRD) vectors to
//! NED. Euler angles are ZYX: C_b^n = Rz(yaw) Ry(pitch) Rx(roll), angles in radians.

use nalgebra::{Matrix3, Quaternion, UnitQuaternion, Vector3};
use std::f64::consts::PI;

/// Skew-symmetric (cross-product) matrix: `skew(a) * b == a.cross(b)`.
#[inline]
pub fn skew(v: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -v.z, v.y, v.z, 0.0, -v.x, -v.y, v.x, 0.0)
}

/// Quaternion of a rotation vector (axis times angle, rad). Below 0.01 rad (every
/// IMU interval) the Taylor series of cos(x/2) and sin(x/2)/x are exact to double
/// precision (first omitted terms < 1e-19), and avoid a sincos call.
#[inline]
pub fn quat_from_rotvec(rv: &Vector3<f64>) -> UnitQuaternion<f64> {
    let a2 = rv.norm_squared();
    if a2 < 1e-4 {
        let w = 1.0 - a2 / 8.0 + a2 * a2 / 384.0 - a2 * a2 * a2 / 46080.0;
        let k = 0.5 - a2 / 48.0 + a2 * a2 / 3840.0 - a2 * a2 * a2 / 645_120.0;
        UnitQuaternion::new_unchecked(Quaternion::new(w, k * rv.x, k * rv.y, k * rv.z))
    } else {
        UnitQuaternion::from_scaled_axis(*rv)
    }
}

/// C_b^n from (roll, pitch, yaw) \[rad\], ZYX convention.
pub fn c_bn_from_euler(rpy: &Vector3<f64>) -> Matrix3<f64> {
    let (sr, cr) = rpy.x.sin_cos();
    let (sp, cp) = rpy.y.sin_cos();
    let (sy, cy) = rpy.z.sin_cos();
    Matrix3::new(
        cp * cy,
        -cr * sy + sr * sp * cy,
        sr * sy + cr * sp * cy,
        cp * sy,
        cr * cy + sr * sp * sy,
        -sr * cy + cr * sp * sy,
        -sp,
        sr * cp,
        cr * cp,
    )
}

/// (roll, pitch, yaw) \[rad\] from C_b^n; yaw in (-pi, pi].
pub fn euler_from_c_bn(c: &Matrix3<f64>) -> Vector3<f64> {
    let pitch = (-c[(2, 0)]).clamp(-1.0, 1.0).asin();
    let roll = c[(2, 1)].atan2(c[(2, 2)]);
    let yaw = c[(1, 0)].atan2(c[(0, 0)]);
    Vector3::new(roll, pitch, yaw)
}

/// Quaternion q_bn from (roll, pitch, yaw) \[rad\].
pub fn q_bn_from_euler(rpy: &Vector3<f64>) -> UnitQuaternion<f64> {
    UnitQuaternion::from_euler_angles(rpy.x, rpy.y, rpy.z)
}

/// (roll, pitch, yaw) \[rad\] of quaternion q_bn.
pub fn euler_from_q_bn(q: &UnitQuaternion<f64>) -> Vector3<f64> {
    euler_from_c_bn(q.to_rotation_matrix().matrix())
}

/// Wrap an angle to (-pi, pi].
#[inline]
pub fn wrap_pi(a: f64) -> f64 {
    let mut x = (a + PI) % (2.0 * PI);
    if x < 0.0 {
        x += 2.0 * PI;
    }
    let r = x - PI;
    if r <= -PI {
        r + 2.0 * PI
    } else {
        r
    }
}

/// Wrap an angle to [0, 2pi).
#[inline]
pub fn wrap_2pi(a: f64) -> f64 {
    let x = a % (2.0 * PI);
    if x < 0.0 {
        x + 2.0 * PI
    } else {
        x
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn euler_round_trip_and_quat_agree() {
        let rpy = Vector3::new(0.1, -0.4, 2.9);
        let c = c_bn_from_euler(&rpy);
        assert!((euler_from_c_bn(&c) - rpy).norm() < 1e-12);
        let q = q_bn_from_euler(&rpy);
        assert!((q.to_rotation_matrix().matrix() - c).norm() < 1e-12);
        assert!((euler_from_q_bn(&q) - rpy).norm() < 1e-12);
    }

    #[test]
    fn rotvec_is_small_angle_consistent() {
        let rv = Vector3::new(1e-3, -2e-3, 5e-4);
        let q = quat_from_rotvec(&rv);
        let c = q.to_rotation_matrix().into_inner();
        let approx = Matrix3::identity() + skew(&rv);
        assert!((c - approx).norm() < 1e-5);
    }

    #[test]
    fn rotvec_series_matches_exact() {
        for rv in [
            Vector3::new(3e-3, -4e-3, 5e-3),
            Vector3::new(1e-9, 0.0, 0.0),
            Vector3::new(0.0, 0.0, 0.0099),
        ] {
            let a = quat_from_rotvec(&rv);
            let b = UnitQuaternion::from_scaled_axis(rv);
            let d = (a.coords - b.coords).norm();
            assert!(d < 5e-16, "{rv:?}: {d:e}");
        }
    }

    #[test]
    fn wrapping() {
        assert!((wrap_pi(3.0 * PI / 2.0) + PI / 2.0).abs() < 1e-12);
        assert!((wrap_pi(-3.0 * PI / 2.0) - PI / 2.0).abs() < 1e-12);
        assert!((wrap_2pi(-0.1) - (2.0 * PI - 0.1)).abs() < 1e-12);
        assert_eq!(wrap_pi(PI), PI);
    }
}
