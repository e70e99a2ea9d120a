//! Synthetic GPS constellations: the nominal 24-slot constellation and the six
//! satellites of seed 000's Table 3.

use crate::ephemeris::{GpsEphemeris, GPS_PI};
use crate::time::GpsTime;

/// Baseline 24-slot constellation (GPS SPS Performance Standard, 4th ed. 2008
/// Table 3.2-1 / 2001 ed. Table 3-1): plane RAAN and argument of latitude [deg] at
/// the standard's epoch (0000Z 1 July 1993), slots A1-A4, B1-B4, ..., F1-F4.
const SLOTS_DEG: [(f64, f64); 24] = [
    (272.847, 268.126),
    (272.847, 161.786),
    (272.847, 11.676),
    (272.847, 41.806),
    (332.847, 80.956),
    (332.847, 173.336),
    (332.847, 309.976),
    (332.847, 204.376),
    (32.847, 111.876),
    (32.847, 11.796),
    (32.847, 339.666),
    (32.847, 241.556),
    (92.847, 135.226),
    (92.847, 265.446),
    (92.847, 35.156),
    (92.847, 167.356),
    (152.847, 197.046),
    (152.847, 302.596),
    (152.847, 66.066),
    (152.847, 333.686),
    (212.847, 238.886),
    (212.847, 345.226),
    (212.847, 105.206),
    (212.847, 135.346),
];

/// Nominal sqrt(A) of a GPS orbit [sqrt(m)] (A = 26 559.7 km).
pub(crate) const NOMINAL_SQRT_A: f64 = 5_153.6;
/// Nominal inclination \[deg\].
pub(crate) const NOMINAL_INCLINATION_DEG: f64 = 55.0;
/// Nominal node rate of the SPS PS almanac tables, -4.4874e-7 deg/s [rad/s].
pub(crate) const NOMINAL_OMEGA_DOT_RAD_PER_S: f64 = -4.4874e-7 * std::f64::consts::PI / 180.0;

/// The baseline 24-slot constellation as circular ephemerides at `toe`, PRN 1-24 in
/// slot order A1..F4; clocks zero, healthy, 4 h fit interval.
///
/// The slot table's RAAN values (inertial, 1993 epoch) are used directly as Omega0
/// (longitude of the node at the week start) and the arguments of latitude as M0 at
/// toe (e = 0, omega = 0). This keeps the standard's relative geometry (plane spacing
/// 60 deg, in-plane phasing) exactly; the orientation relative to the Earth is not
/// propagated from 1993.
pub fn nominal_gps24(toe: GpsTime) -> Vec<GpsEphemeris> {
    SLOTS_DEG
        .iter()
        .enumerate()
        .map(|(k, &(raan_deg, u_deg))| {
            let mut eph = GpsEphemeris::zeroed(k as u8 + 1, toe);
            eph.sqrt_a_sqrt_m = NOMINAL_SQRT_A;
            eph.i0_rad = NOMINAL_INCLINATION_DEG.to_radians();
            eph.omega0_rad = raan_deg.to_radians();
            eph.m0_rad = u_deg.to_radians();
            eph.omega_dot_rad_per_s = NOMINAL_OMEGA_DOT_RAD_PER_S;
            eph.iode = 1;
            eph.iodc = 1;
            eph.sv_accuracy_m = 2.0;
            eph
        })
        .collect()
}

/// Seed 000 Table 3 as printed: columns satellites 1-6, rows in physical order.
/// Row 13 is Crc (see [`seed000_table3`]); row 5 sat 3 and row 4 sat 5 repaired there.
const SEED000_ROWS: [[f64; 6]; 15] = [
    // 1 Crs [m]
    [-5.9875e1, 6.5281e1, -8.5656e1, 4.6969e1, 6.200e2, 5.4563e1],
    // 2 Delta n [sc/s]
    [
        1.5294e-9, 1.6692e-9, 1.4644e-9, 1.4919e-9, 1.1192e-9, 1.6494e-9,
    ],
    // 3 M0 [sc]
    [
        -4.8401e-1, -8.7179e-1, -8.8417e-1, -8.8899e-1, -9.7589e-1, 1.1990e-1,
    ],
    // 4 Cuc [rad]; sat 5 printed "1,3784-007"
    [
        -2.9840e-6, 3.3509e-6, -4.5337e-6, 2.4196e-6, 1.3784e-7, 2.8610e-6,
    ],
    // 5 e [-]; sat 3 printed "68008e-006"
    [
        3.7472e-3, 1.1916e-3, 6.8008e-6, 6.7628e-3, 7.8766e-3, 5.0219e-3,
    ],
    // 6 Cus [rad]; sat 6 printed 3.4180e-003
    [
        7.8715e-6, 3.3546e-6, 6.5677e-6, 1.1941e-5, 1.1863e-5, 3.4180e-6,
    ],
    // 7 sqrt(A) [sqrt(m)]
    [5.1536e3, 5.1535e3, 5.1537e3, 5.1537e3, 5.1538e3, 5.1537e3],
    // 8 toe [s]
    [2.5198e5, 2.5200e5, 2.5200e5, 2.5200e5, 2.5200e5, 2.5200e5],
    // 9 Cic [rad]
    [
        -2.2352e-8, -5.0291e-8, -4.4703e-8, -1.2852e-7, 7.2643e-8, -1.6764e-8,
    ],
    // 10 Omega0 [sc]
    [
        6.408e-1, -7.0909e-1, -3.5952e-1, 9.6454e-1, -2.7200e-1, -7.0123e-1,
    ],
    // 11 Cis [rad]
    [
        1.3039e-7, 4.0978e-7, -1.2480e-7, -9.1270e-8, -6.8918e-8, 6.8918e-8,
    ],
    // 12 i0 [sc] (labelled Crc by Table 2's order)
    [
        3.0394e-1, 3.0031e-1, 3.0513e-1, 3.0066e-1, 3.1381e-1, 3.0266e-1,
    ],
    // 13 Crc [m as printed] (labelled omega)
    [
        2.2494e-2, 3.0363e-2, 2.5019e-2, 1.4213e-2, 1.6128e-2, 3.0716e-2,
    ],
    // 14 omega [sc] (labelled Omega_dot)
    [
        -5.1669e-1, -2.8071e-1, -8.2533e-1, 8.2234e-1, -6.0022e-1, 5.1312e-1,
    ],
    // 15 Omega_dot [sc/s] (labelled IDOT)
    [
        -2.5994e-9, -2.7268e-9, -2.5919e-9, -2.5278e-9, -2.3444e-9, -2.7663e-9,
    ],
];

/// The six satellites of seed 000 Table 3 (PRN 1-6 = "Vệ tinh" 1-6), in week `week`.
///
/// Reading (docs/GNSS.md has the full discussion). Table 2 lists 15 parameters
/// without i0, ending Crc, omega, Omega_dot, IDOT; Table 3 has 15 rows whose last
/// four are, by physical range: row 12 ~0.30 sc = i0 (54-56 deg); row 13 ~0.014-0.031
/// = Crc (the only remaining parameter that fits; taken as printed, in metres,
/// although real Crc values are ~1e2 m); row 14 in [-0.83, 0.82] sc = omega; row 15
/// ~-2.6e-9 sc/s = Omega_dot. IDOT is absent and set to 0; af0/af1/af2 and TGD are
/// absent and set to 0 (toc = toe). Rows 1-11 follow Table 2: Crs, Delta n, M0, Cuc,
/// e, Cus, sqrt(A), toe, Cic, Omega0, Cis.
///
/// Misprints repaired: sat 3 e "68008e-006" read 6.8008e-6 (missing decimal comma);
/// sat 5 Cuc "1,3784-007" read 1.3784e-7 (missing "e"); sat 6 Cus 3.4180e-3 read
/// 3.4180e-6 (a 3.4e-3 rad correction, 90 km along track, is physically impossible;
/// all other Cus are ~1e-5). Sat 1 toe 2.5198e5 = 251980 s kept as printed (not a
/// multiple of 16 s, so probably 251984 s rounded). Semicircles and semicircles/s
/// are multiplied by the IS-GPS-200 value of pi.
pub fn seed000_table3(week: i32) -> Vec<GpsEphemeris> {
    (0..6)
        .map(|s| {
            let row = |r: usize| SEED000_ROWS[r][s];
            let toe = GpsTime::new(week, row(7));
            let mut eph = GpsEphemeris::zeroed(s as u8 + 1, toe);
            eph.crs_m = row(0);
            eph.delta_n_rad_per_s = row(1) * GPS_PI;
            eph.m0_rad = row(2) * GPS_PI;
            eph.cuc_rad = row(3);
            eph.e = row(4);
            eph.cus_rad = row(5);
            eph.sqrt_a_sqrt_m = row(6);
            eph.cic_rad = row(8);
            eph.omega0_rad = row(9) * GPS_PI;
            eph.cis_rad = row(10);
            eph.i0_rad = row(11) * GPS_PI;
            eph.crc_m = row(12);
            eph.omega_rad = row(13) * GPS_PI;
            eph.omega_dot_rad_per_s = row(14) * GPS_PI;
            eph.idot_rad_per_s = 0.0;
            eph.sv_accuracy_m = 2.0;
            eph
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{az_el, signal_path};
    use nalgebra::Vector3;
    use navfuse_core::earth::lla_to_ecef;

    #[test]
    fn nominal_constellation_shape() {
        let toe = GpsTime::new(2381, 345_600.0);
        let c = nominal_gps24(toe);
        assert_eq!(c.len(), 24);
        for (k, e) in c.iter().enumerate() {
            assert_eq!(e.prn as usize, k + 1);
            assert_eq!(e.health, 0);
            let s = e.sat_state(toe.add_s(1_000.0));
            assert!((s.pos_ecef_m.norm() - 26_559.7e3).abs() < 1e3);
            assert_eq!(s.clock_bias_s, 0.0);
        }
        // Planes 60 deg apart.
        assert!((c[4].omega0_rad - c[0].omega0_rad - 60f64.to_radians()).abs() < 1e-12);
    }

    #[test]
    fn nominal_constellation_always_gives_four_above_10_deg() {
        let toe = GpsTime::new(2381, 345_600.0);
        let c = nominal_gps24(toe);
        for (lat, lon) in [
            (45.0f64, 7.0f64),
            (35.0, 139.0),
            (-33.9, 151.2),
            (40.0, -105.0),
        ] {
            let lla = Vector3::new(lat.to_radians(), lon.to_radians(), 100.0);
            let rx = lla_to_ecef(&lla);
            let mut min_visible = usize::MAX;
            for step in 0..=(24 * 12) {
                let t = toe.add_s(-43_200.0 + f64::from(step) * 300.0);
                let n = c
                    .iter()
                    .filter(|e| {
                        let sp = signal_path(e, &rx, &Vector3::zeros(), t);
                        az_el(&lla, &sp.los_unit).1 > 10f64.to_radians()
                    })
                    .count();
                min_visible = min_visible.min(n);
            }
            assert!(
                min_visible >= 4,
                "site ({lat}, {lon}): min {min_visible} satellites"
            );
        }
    }

    #[test]
    fn seed000_satellites() {
        let sats = seed000_table3(2381);
        assert_eq!(sats.len(), 6);
        for e in &sats {
            assert!((e.i0_rad.to_degrees() - 55.0).abs() < 2.0);
            assert!(e.omega_dot_rad_per_s < -7e-9 && e.omega_dot_rad_per_s > -9e-9);
            for k in -4..=4 {
                let s = e.sat_state(e.toe.add_s(f64::from(k) * 1_800.0));
                let alt = s.pos_ecef_m.norm() - 6_371e3;
                assert!(
                    (19_900e3..20_500e3).contains(&alt),
                    "prn {} alt {alt}",
                    e.prn
                );
            }
        }
        assert_eq!(sats[0].toe.sow, 251_980.0);
        assert_eq!(sats[2].e, 6.8008e-6);
        assert_eq!(sats[5].cus_rad, 3.4180e-6);
    }
}

/// Broadcast updates: each ephemeris of `ephs` re-issued every `step_s` from its
/// toe while a re-issue would be the nearest record at some time up to `until`
/// (and not before `from` minus half a fit interval), so that they cover
/// `[from, until]` (the control segment uploads GPS
/// ephemerides every 2 h, each fit for 4 h; IS-GPS-200 20.3.4.4). Each copy is the
/// same orbit and clock at a later reference time, so the satellites move on
/// seamlessly from one record to the next: toe' = toc' = toe + dt, M0' = M0 + n dt
/// with n = sqrt(mu / A^3) + Delta n, i0' = i0 + IDOT dt, Omega0' = Omega0 +
/// Omega_dot dt (Omega_k = Omega0 + Omega_dot t_k - Omega_e t, Table 20-IV; minus
/// Omega_e 604800 s per week rolled over), af0' = af0 + af1 dt + af2 dt^2, af1' = af1
/// + 2 af2 dt, IODE and IODC + 1 per issue (mod 256 / 1024). The input records come
/// first, then the copies in time order.
pub fn reissued(
    ephs: &[GpsEphemeris],
    from: GpsTime,
    until: GpsTime,
    step_s: f64,
) -> Vec<GpsEphemeris> {
    use crate::ephemeris::{GPS_MU_M3_PER_S2, GPS_OMEGA_E_RAD_PER_S};
    let mut out = ephs.to_vec();
    if step_s <= 0.0 {
        return out;
    }
    for e in ephs {
        let a = e.sqrt_a_sqrt_m.powi(2);
        let n = (GPS_MU_M3_PER_S2 / (a * a * a)).sqrt() + e.delta_n_rad_per_s;
        let mut k = 1;
        loop {
            let dt = step_s * f64::from(k);
            let toe = e.toe.add_s(dt);
            // Only records that are the nearest one at some time up to `until`.
            if toe.diff_s(&until) >= step_s / 2.0 {
                break;
            }
            k += 1;
            if toe.diff_s(&from) < -e.fit_interval_s() / 2.0 {
                continue;
            }
            let weeks = f64::from(toe.week - e.toe.week);
            let mut c = e.clone();
            c.toe = toe;
            c.toc = e.toc.add_s(dt);
            let dtc = c.toc.diff_s(&e.toc);
            c.af0_s = e.af0_s + e.af1_s_per_s * dtc + e.af2_s_per_s2 * dtc * dtc;
            c.af1_s_per_s = e.af1_s_per_s + 2.0 * e.af2_s_per_s2 * dtc;
            c.m0_rad = wrap_2pi(e.m0_rad + n * dt);
            c.i0_rad = e.i0_rad + e.idot_rad_per_s * dt;
            c.omega0_rad = wrap_2pi(
                e.omega0_rad + e.omega_dot_rad_per_s * dt
                    - GPS_OMEGA_E_RAD_PER_S * 604_800.0 * weeks,
            );
            c.iode = ((u32::from(e.iode) + k as u32 - 1) % 256) as u16;
            c.iodc = ((u32::from(e.iodc) + k as u32 - 1) % 1024) as u16;
            c.transmission_time = Some(toe.add_s(-7_200.0));
            out.push(c);
        }
    }
    out.sort_by(|a, b| a.toe.diff_s(&b.toe).total_cmp(&0.0).then(a.prn.cmp(&b.prn)));
    out
}

fn wrap_2pi(x: f64) -> f64 {
    x.rem_euclid(2.0 * std::f64::consts::PI)
}

#[cfg(test)]
mod reissue_tests {
    use super::*;

    #[test]
    fn reissued_records_continue_the_same_orbit_and_clock_over_a_day_and_a_week_end() {
        // Start 10 h before the end of a week: the day crosses the week rollover.
        let t0 = GpsTime::new(2111, 604_800.0 - 36_000.0);
        let mut ephs = seed000_table3(2111);
        for e in ephs.iter_mut() {
            e.toe = t0;
            e.toc = t0;
            e.af0_s = 2e-4;
            e.af1_s_per_s = 1e-11;
            e.af2_s_per_s2 = 1e-19;
            e.e = 0.01;
            e.idot_rad_per_s = 1e-10;
        }
        let until = t0.add_s(86_400.0);
        let all = reissued(&ephs, t0, until, 7_200.0);
        // The first record and one every 2 h to the end.
        assert_eq!(all.len(), ephs.len() * 13);
        let mut worst = (0.0f64, 0.0f64);
        for c in &all {
            let orig = ephs.iter().find(|e| e.prn == c.prn).unwrap();
            for dt in [-3_600.0, 0.0, 1_800.0, 3_599.0] {
                let t = c.toe.add_s(dt);
                let (a, b) = (orig.sat_state(t), c.sat_state(t));
                worst.0 = worst.0.max((a.pos_ecef_m - b.pos_ecef_m).norm());
                worst.1 = worst.1.max((a.clock_bias_s - b.clock_bias_s).abs());
            }
        }
        assert!(worst.0 < 1e-4 && worst.1 < 1e-15, "{worst:?}");
        assert!(
            all.iter().any(|e| e.toe.week == 2112),
            "records in the next week"
        );
        let iodes: Vec<u16> = all
            .iter()
            .filter(|e| e.prn == ephs[0].prn)
            .map(|e| e.iode)
            .collect();
        let mut distinct = iodes.clone();
        distinct.dedup();
        assert_eq!(distinct.len(), iodes.len(), "a new IODE per issue");
    }
}
