//! Atmospheric delays for single-frequency GPS.
//!
//! - Ionosphere: the broadcast Klobuchar model, IS-GPS-200 20.3.3.5.2.5 (Figure 20-4),
//!   L1 group delay in metres.
//! - Troposphere: Saastamoinen zenith delays with a standard atmosphere (pressure
//!   1013.25 hPa and 15 C at sea level, lapse rate 6.5 K/km, relative humidity 0.7 by
//!   default: the conventions RTKLIB's `tropmodel` documents), mapped to the slant by
//!   the simple 1/sin(el) mapping function.

use crate::ephemeris::{GPS_PI, SPEED_OF_LIGHT_MPS};

/// Klobuchar L1 ionospheric delay \[m\] (IS-GPS-200 20.3.3.5.2.5).
///
/// `alpha` [s, s/sc, s/sc^2, s/sc^3] and `beta` [s, s/sc, s/sc^2, s/sc^3] as broadcast
/// (RINEX `ION ALPHA`/`ION BETA`); receiver latitude/longitude, satellite azimuth and
/// elevation in radians; `gps_sow` the GPS seconds of week of reception.
pub fn klobuchar_l1_delay_m(
    alpha: &[f64; 4],
    beta: &[f64; 4],
    rx_lat_rad: f64,
    rx_lon_rad: f64,
    az_rad: f64,
    el_rad: f64,
    gps_sow: f64,
) -> f64 {
    // The model works in semicircles (sc).
    let e_sc = el_rad / GPS_PI;
    let phi_u = rx_lat_rad / GPS_PI;
    let lam_u = rx_lon_rad / GPS_PI;
    // Earth-centred angle and ionospheric pierce point latitude, clamped to +-0.416 sc.
    let psi = 0.0137 / (e_sc + 0.11) - 0.022;
    let phi_i = (phi_u + psi * az_rad.cos()).clamp(-0.416, 0.416);
    let lam_i = lam_u + psi * az_rad.sin() / (phi_i * GPS_PI).cos();
    // Geomagnetic latitude of the pierce point.
    let phi_m = phi_i + 0.064 * ((lam_i - 1.617) * GPS_PI).cos();
    // Local time at the pierce point [s], in [0, 86400).
    let t = (4.32e4 * lam_i + gps_sow).rem_euclid(86_400.0);
    // Obliquity factor.
    let f = 1.0 + 16.0 * (0.53 - e_sc).powi(3);
    let poly = |c: &[f64; 4]| c[0] + phi_m * (c[1] + phi_m * (c[2] + phi_m * c[3]));
    let amp = poly(alpha).max(0.0);
    let per = poly(beta).max(72_000.0);
    let x = 2.0 * std::f64::consts::PI * (t - 50_400.0) / per;
    let delay_s = if x.abs() < 1.57 {
        f * (5e-9 + amp * (1.0 - x * x / 2.0 + x.powi(4) / 24.0))
    } else {
        f * 5e-9
    };
    delay_s * SPEED_OF_LIGHT_MPS
}

/// Standard-atmosphere relative humidity used by default (RTKLIB `tropmodel`).
pub const STD_REL_HUMIDITY: f64 = 0.7;

/// Saastamoinen zenith delays (hydrostatic, wet) \[m\] with a standard atmosphere at
/// ellipsoidal height `h_m` (clamped at 0) and latitude `lat_rad`; `rel_humidity` in
/// [0, 1]. Returns (0, 0) outside -100 m..10 km, where the model is not meant to work.
pub fn saastamoinen_zenith_m(lat_rad: f64, h_m: f64, rel_humidity: f64) -> (f64, f64) {
    if !(-100.0..=1e4).contains(&h_m) {
        return (0.0, 0.0);
    }
    let h = h_m.max(0.0);
    // Standard atmosphere: pressure [hPa], temperature [K], water vapour pressure [hPa].
    let p_hpa = 1013.25 * (1.0 - 2.2557e-5 * h).powf(5.2568);
    let t_k = 15.0 - 6.5e-3 * h + 273.16;
    let e_hpa = 6.108 * rel_humidity * ((17.15 * t_k - 4684.0) / (t_k - 38.45)).exp();
    // Saastamoinen (1972) zenith terms with the gravity correction of latitude/height.
    let zhd = 0.002_276_8 * p_hpa / (1.0 - 0.002_66 * (2.0 * lat_rad).cos() - 0.000_28 * h / 1e3);
    let zwd = 0.002_277 * (1_255.0 / t_k + 0.05) * e_hpa;
    (zhd, zwd)
}

/// Simple tropospheric mapping function 1/sin(el), elevation floored at 3 deg so the
/// value stays finite (19.1) near the horizon.
pub fn tropo_mapping(el_rad: f64) -> f64 {
    1.0 / el_rad.max(3f64.to_radians()).sin()
}

/// Slant tropospheric delay \[m\]: Saastamoinen zenith delays (humidity 0.7) times
/// [`tropo_mapping`]; 0 for el <= 0.
pub fn saastamoinen_slant_m(lat_rad: f64, h_m: f64, el_rad: f64) -> f64 {
    if el_rad <= 0.0 {
        return 0.0;
    }
    let (zhd, zwd) = saastamoinen_zenith_m(lat_rad, h_m, STD_REL_HUMIDITY);
    (zhd + zwd) * tropo_mapping(el_rad)
}

#[cfg(test)]
mod tests {
    use super::*;

    // Broadcast coefficients of a real day (walk_0827-era values are similar in size).
    const ALPHA: [f64; 4] = [1.1176e-8, 1.4901e-8, -5.9605e-8, -1.1921e-7];
    const BETA: [f64; 4] = [1.1469e5, 8.1920e4, -1.3107e5, -5.2429e5];

    const ZENITH_RAD: f64 = std::f64::consts::FRAC_PI_2;

    #[test]
    fn klobuchar_night_value_is_the_constant_5ns() {
        // Local time at the pierce point 02:00: |x| >= 1.57, so T = F * 5 ns exactly.
        let el = std::f64::consts::FRAC_PI_2;
        let d = klobuchar_l1_delay_m(&ALPHA, &BETA, 0.7, 0.0, 0.0, el, 2.0 * 3_600.0);
        let e_sc = el / GPS_PI;
        let f = 1.0 + 16.0 * (0.53 - e_sc).powi(3);
        assert!((d - f * 5e-9 * SPEED_OF_LIGHT_MPS).abs() < 1e-9);
        assert!((d - 1.4989).abs() < 1e-3);
    }

    #[test]
    fn klobuchar_daytime_peak_and_slant() {
        // 14:00 local at the pierce point: the cosine peak, AMP + 5 ns at zenith.
        let lat = 0.3f64; // ~17 deg
        let zen = klobuchar_l1_delay_m(&ALPHA, &BETA, lat, 0.0, 0.0, ZENITH_RAD, 50_400.0);
        assert!(zen > 1.5 && zen < 30.0, "{zen}");
        let low = klobuchar_l1_delay_m(&ALPHA, &BETA, lat, 0.0, 0.0, 10f64.to_radians(), 50_400.0);
        // Obliquity at 10 deg elevation is ~2.5-3: slant larger than zenith.
        assert!(low > 2.0 * zen && low < 3.5 * zen, "{low} vs {zen}");
        // Day larger than night.
        let night = klobuchar_l1_delay_m(&ALPHA, &BETA, lat, 0.0, 0.0, ZENITH_RAD, 0.0);
        assert!(zen > night);
    }

    #[test]
    fn klobuchar_negative_amplitude_clamped() {
        let a = [-1e-7, 0.0, 0.0, 0.0];
        let d = klobuchar_l1_delay_m(&a, &BETA, 0.3, 0.0, 0.0, ZENITH_RAD, 50_400.0);
        let night = klobuchar_l1_delay_m(&a, &BETA, 0.3, 0.0, 0.0, ZENITH_RAD, 0.0);
        assert!((d - night).abs() < 1e-9);
    }

    #[test]
    fn saastamoinen_sea_level_zenith() {
        // ZHD = 0.0022768 * 1013.25 / (1 - 0.00266 cos 90 deg) = 2.3070 m at 45 deg.
        let (zhd, zwd) = saastamoinen_zenith_m(45f64.to_radians(), 0.0, 0.7);
        assert!((zhd - 2.3070).abs() < 1e-3, "{zhd}");
        assert!(zwd > 0.05 && zwd < 0.3, "{zwd}");
        let (zhd_hi, _) = saastamoinen_zenith_m(45f64.to_radians(), 2_000.0, 0.7);
        assert!(zhd_hi < 0.8 * zhd);
        assert_eq!(saastamoinen_zenith_m(0.0, 2e4, 0.7), (0.0, 0.0));
        let s = saastamoinen_slant_m(45f64.to_radians(), 0.0, 30f64.to_radians());
        assert!((s - 2.0 * (zhd + zwd)).abs() < 1e-9);
        assert_eq!(saastamoinen_slant_m(0.0, 0.0, -0.1), 0.0);
    }
}
