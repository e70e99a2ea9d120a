//! WGS-84 earth model: radii, normal gravity, earth and transport rates, and
//! geodetic / ECEF / local NED conversions. SYSTEM.md §1.
//!
//! Geodetic positions are `Vector3(lat_rad, lon_rad, h_m)` (ellipsoidal height).
//! NED vectors are metres or metres per second along (north, east, down).

use nalgebra::{Matrix3, Vector3};

/// WGS-84 semi-major axis \[m\].
pub const WGS84_A: f64 = 6_378_137.0;
/// WGS-84 flattening.
pub const WGS84_F: f64 = 1.0 / 298.257_223_563;
/// WGS-84 first eccentricity squared.
pub const WGS84_E2: f64 = WGS84_F * (2.0 - WGS84_F);
/// Earth rotation rate \[rad/s\] (WGS-84, IS-GPS-200 value).
pub const OMEGA_IE: f64 = 7.292_115_146_7e-5;

/// Meridian radius M and prime-vertical radius N \[m\] at geodetic latitude `lat_rad`.
/// SYSTEM.md §1: N = a / sqrt(1 - e² sin²φ), M = a (1 - e²) / (1 - e² sin²φ)^(3/2).
#[inline]
pub fn radii(lat_rad: f64) -> (f64, f64) {
    let s = lat_rad.sin();
    let w2 = 1.0 - WGS84_E2 * s * s;
    let w = w2.sqrt();
    let n = WGS84_A / w;
    let m = WGS84_A * (1.0 - WGS84_E2) / (w2 * w);
    (m, n)
}

/// Normal gravity magnitude \[m/s²\] at latitude and ellipsoidal height.
/// SYSTEM.md §1; seed 000 eq. 9-10 (a1 with the standard value 9.7803267715).
#[inline]
pub fn gravity_normal(lat_rad: f64, h_m: f64) -> f64 {
    gravity_normal_sc(lat_rad.sin(), h_m)
}

/// [`gravity_normal`] from sin(latitude), for callers that already have it.
#[inline]
pub fn gravity_normal_sc(sin_lat: f64, h_m: f64) -> f64 {
    const A1: f64 = 9.780_326_771_5;
    const A2: f64 = 0.005_279_041_4;
    const A3: f64 = 0.000_023_271_8;
    const A4: f64 = -0.000_003_087_691_089_1;
    const A5: f64 = 0.000_000_004_397_731_1;
    const A6: f64 = 0.000_000_000_000_721_1;
    let s2 = sin_lat * sin_lat;
    A1 * (1.0 + A2 * s2 + A3 * s2 * s2) + (A4 + A5 * s2) * h_m + A6 * h_m * h_m
}

/// Earth rotation rate resolved in NED, omega_ie^n \[rad/s\].
#[inline]
pub fn omega_ie_n(lat_rad: f64) -> Vector3<f64> {
    Vector3::new(OMEGA_IE * lat_rad.cos(), 0.0, -OMEGA_IE * lat_rad.sin())
}

/// Transport rate omega_en^n \[rad/s\] for NED velocity `v_n`. SYSTEM.md §1.
#[inline]
pub fn omega_en_n(lat_rad: f64, h_m: f64, v_n: &Vector3<f64>) -> Vector3<f64> {
    let (m, n) = radii(lat_rad);
    Vector3::new(
        v_n.y / (n + h_m),
        -v_n.x / (m + h_m),
        -v_n.y * lat_rad.tan() / (n + h_m),
    )
}

/// Matrix D^-1 mapping NED metres to (dlat, dlon, dh): SYSTEM.md §1, p_dot = D^-1 v^n.
#[inline]
pub fn ned_to_dlla_scale(lat_rad: f64, h_m: f64) -> Vector3<f64> {
    let (m, n) = radii(lat_rad);
    Vector3::new(1.0 / (m + h_m), 1.0 / ((n + h_m) * lat_rad.cos()), -1.0)
}

/// Small NED displacement \[m\] of `lla` relative to `lla_ref` (first order; exact
/// enough for the metre-scale differences of filter innovations and evaluation).
#[inline]
pub fn lla_diff_ned(lla: &Vector3<f64>, lla_ref: &Vector3<f64>) -> Vector3<f64> {
    let (m, n) = radii(lla_ref.x);
    let h = lla_ref.z;
    let mut dlon = lla.y - lla_ref.y;
    if dlon > std::f64::consts::PI {
        dlon -= 2.0 * std::f64::consts::PI;
    } else if dlon < -std::f64::consts::PI {
        dlon += 2.0 * std::f64::consts::PI;
    }
    Vector3::new(
        (lla.x - lla_ref.x) * (m + h),
        dlon * (n + h) * lla_ref.x.cos(),
        -(lla.z - lla_ref.z),
    )
}

/// Move geodetic position `lla` by a small NED displacement \[m\].
#[inline]
pub fn lla_add_ned(lla: &Vector3<f64>, d_ned: &Vector3<f64>) -> Vector3<f64> {
    let s = ned_to_dlla_scale(lla.x, lla.z);
    lla + d_ned.component_mul(&s)
}

/// Geodetic (lat, lon, h) to ECEF \[m\].
pub fn lla_to_ecef(lla: &Vector3<f64>) -> Vector3<f64> {
    let (_, n) = radii(lla.x);
    let (sl, cl) = lla.x.sin_cos();
    let (so, co) = lla.y.sin_cos();
    Vector3::new(
        (n + lla.z) * cl * co,
        (n + lla.z) * cl * so,
        (n * (1.0 - WGS84_E2) + lla.z) * sl,
    )
}

/// ECEF \[m\] to geodetic (lat, lon, h); iterative, converges to < 1e-9 m.
pub fn ecef_to_lla(r_e: &Vector3<f64>) -> Vector3<f64> {
    let p = (r_e.x * r_e.x + r_e.y * r_e.y).sqrt();
    let lon = r_e.y.atan2(r_e.x);
    let mut lat = r_e.z.atan2(p * (1.0 - WGS84_E2));
    let mut h = 0.0;
    for _ in 0..10 {
        let (_, n) = radii(lat);
        let (sl, cl) = lat.sin_cos();
        let h_new = if cl.abs() > 1e-10 {
            p / cl - n
        } else {
            r_e.z.abs() - n * (1.0 - WGS84_E2)
        };
        let lat_new = r_e.z.atan2(p * (1.0 - WGS84_E2 * n / (n + h_new)));
        let done = (lat_new - lat).abs() < 1e-13 && (h_new - h).abs() < 1e-6;
        lat = lat_new;
        h = h_new;
        let _ = sl;
        if done {
            break;
        }
    }
    Vector3::new(lat, lon, h)
}

/// Rotation from NED to ECEF, C_n^e, at (lat, lon).
pub fn c_ne(lat_rad: f64, lon_rad: f64) -> Matrix3<f64> {
    let (sl, cl) = lat_rad.sin_cos();
    let (so, co) = lon_rad.sin_cos();
    Matrix3::new(
        -sl * co,
        -so,
        -cl * co, //
        -sl * so,
        co,
        -cl * so, //
        cl,
        0.0,
        -sl,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ecef_round_trip() {
        for &(lat, lon, h) in &[
            (30.444_787, 114.471_863, 20.9),
            (-89.9, -179.0, 8000.0),
            (0.0, 0.0, -50.0),
            (40.0966, -105.1474, 1601.47),
        ] {
            let lla = Vector3::new(f64::to_radians(lat), f64::to_radians(lon), h);
            let back = ecef_to_lla(&lla_to_ecef(&lla));
            assert!((back.x - lla.x).abs() < 1e-11, "lat {lat}");
            assert!((back.y - lla.y).abs() < 1e-11);
            assert!((back.z - lla.z).abs() < 1e-5);
        }
    }

    #[test]
    fn gravity_values() {
        // Equator and pole at h = 0 match the WGS-84 normal gravity to 1e-6 m/s².
        assert!((gravity_normal(0.0, 0.0) - 9.780_326_771_5).abs() < 1e-9);
        assert!((gravity_normal(std::f64::consts::FRAC_PI_2, 0.0) - 9.832_184_937_8).abs() < 2e-5);
        // Free-air gradient about -3.086e-6 /s².
        let d = gravity_normal(0.5, 1000.0) - gravity_normal(0.5, 0.0);
        assert!((d + 3.086e-3).abs() < 2e-5, "{d}");
    }

    #[test]
    fn ned_diff_matches_ecef() {
        let a = Vector3::new(0.7, -1.8, 1600.0);
        let d = Vector3::new(30.0, -40.0, 2.0);
        let b = lla_add_ned(&a, &d);
        let de = lla_to_ecef(&b) - lla_to_ecef(&a);
        let dn = c_ne(a.x, a.y).transpose() * de;
        assert!((dn - d).norm() < 1e-3, "{dn:?}");
        assert!((lla_diff_ned(&b, &a) - d).norm() < 1e-9);
    }
}
