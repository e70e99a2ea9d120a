//! Synthetic constellations: the nominal 24-slot GPS constellation, the six
//! satellites of seed 000's Table 3, and the bundled Galileo (Walker 24/3/1) and
//! BeiDou (MEO Walker 24/3/1 + 3 IGSO) constellations of the simulator, with their
//! broadcast updates ([`reissued`], [`reissued_galileo`], [`reissued_beidou`]), and
//! GLONASS (24 slots, state vectors every 30 min: [`glonass_records`]).

use crate::ephemeris::beidou::gpst_to_bdt;
use crate::ephemeris::kepler::{KeplerConstants, KeplerOrbit, BEIDOU_CONSTANTS, GALILEO_CONSTANTS};
use crate::ephemeris::{BeiDouEphemeris, GalileoEphemeris, GlonassEphemeris, GpsEphemeris, GPS_PI};
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

    /// The mid-latitude sites (lat, lon deg) of the visibility tests.
    pub(super) const SITES: [(f64, f64); 4] =
        [(45.0, 7.0), (35.0, 139.0), (-33.9, 151.2), (40.0, -105.0)];

    /// How many of `recs` are above 10 deg at `lla` at t.
    pub(super) fn above_10_deg<E: crate::geometry::SatOrbit>(
        recs: impl Iterator<Item = E>,
        lla: &Vector3<f64>,
        t: GpsTime,
    ) -> usize {
        let rx = lla_to_ecef(lla);
        recs.filter(|e| {
            let sp = signal_path(e, &rx, &Vector3::zeros(), t);
            az_el(lla, &sp.los_unit).1 > 10f64.to_radians()
        })
        .count()
    }

    #[test]
    fn nominal_constellation_always_gives_four_above_10_deg() {
        let toe = GpsTime::new(2381, 345_600.0);
        let c = nominal_gps24(toe);
        for (lat, lon) in SITES {
            let lla = Vector3::new(lat.to_radians(), lon.to_radians(), 100.0);
            let mut min_visible = usize::MAX;
            for step in 0..=(24 * 12) {
                let t = toe.add_s(-43_200.0 + f64::from(step) * 300.0);
                min_visible = min_visible.min(above_10_deg(c.iter(), &lla, t));
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
/// Omega_e 604800 s per week rolled over), af0' = af0 + af1 dt + af2 dt^2,
/// af1' = af1 + 2 af2 dt, IODE and IODC + 1 per issue (mod 256 / 1024). The input records come
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
        for (k, dt) in issue_steps(e.toe, from, until, step_s, e.fit_interval_s() / 2.0) {
            let toe = e.toe.add_s(dt);
            let weeks = f64::from(toe.week - e.toe.week);
            let mut c = e.clone();
            c.toe = toe;
            c.toc = e.toc.add_s(dt);
            let dtc = c.toc.diff_s(&e.toc);
            [c.af0_s, c.af1_s_per_s] = advance_clock([e.af0_s, e.af1_s_per_s, e.af2_s_per_s2], dtc);
            let o = advance_orbit(&e.orbit(), n, GPS_OMEGA_E_RAD_PER_S, dt, weeks, toe.sow);
            c = c.with_orbit(&o);
            c.iode = ((u32::from(e.iode) + k) % 256) as u16;
            c.iodc = ((u32::from(e.iodc) + k) % 1024) as u16;
            c.transmission_time = Some(toe.add_s(-7_200.0));
            out.push(c);
        }
    }
    out.sort_by(|a, b| a.toe.diff_s(&b.toe).total_cmp(&0.0).then(a.prn.cmp(&b.prn)));
    out
}

/// The re-issues of a record with reference time `toe`: (k, k step_s) for k = 1, 2,
/// ... while the new toe would be the nearest record at some time up to `until`, and
/// not more than `max_age_s` before `from` ([`reissued`]).
fn issue_steps(
    toe: GpsTime,
    from: GpsTime,
    until: GpsTime,
    step_s: f64,
    max_age_s: f64,
) -> Vec<(u32, f64)> {
    let mut out = Vec::new();
    if step_s <= 0.0 {
        return out;
    }
    let mut k = 1u32;
    loop {
        let dt = step_s * f64::from(k);
        let t = toe.add_s(dt);
        if t.diff_s(&until) >= step_s / 2.0 {
            break;
        }
        if t.diff_s(&from) >= -max_age_s {
            out.push((k, dt));
        }
        k += 1;
    }
    out
}

fn wrap_2pi(x: f64) -> f64 {
    x.rem_euclid(2.0 * std::f64::consts::PI)
}

/// af0, af1 of a clock polynomial moved `dtc` later (af2 unchanged).
fn advance_clock(af: [f64; 3], dtc: f64) -> [f64; 2] {
    [
        af[0] + af[1] * dtc + af[2] * dtc * dtc,
        af[1] + 2.0 * af[2] * dtc,
    ]
}

/// The same orbit referred to a toe `dt` later (`weeks` week rollovers between the
/// two toes, `toe_sow` the new toe's seconds of week): M0 + n dt, i0 + IDOT dt,
/// Omega0 + Omega_dot dt - Omega_e 604800 weeks ([`reissued`]).
fn advance_orbit(
    o: &KeplerOrbit,
    n: f64,
    omega_e: f64,
    dt: f64,
    weeks: f64,
    toe_sow: f64,
) -> KeplerOrbit {
    KeplerOrbit {
        m0_rad: wrap_2pi(o.m0_rad + n * dt),
        i0_rad: o.i0_rad + o.idot_rad_per_s * dt,
        omega0_rad: wrap_2pi(
            o.omega0_rad + o.omega_dot_rad_per_s * dt - omega_e * 604_800.0 * weeks,
        ),
        toe_sow_s: toe_sow,
        ..*o
    }
}

/// Mean motion sqrt(mu / A^3) + Delta n [rad/s].
fn mean_motion(o: &KeplerOrbit, k: &KeplerConstants) -> f64 {
    let a = o.sqrt_a_sqrt_m.powi(2);
    (k.mu_m3_per_s2 / (a * a * a)).sqrt() + o.delta_n_rad_per_s
}

// ---------------------------------------------------------------------------------
// Galileo and BeiDou

/// Equatorial radius [m] and J2 of the Earth (WGS-84 / EGM), for the nominal node
/// rates of the bundled constellations.
const EARTH_RE_M: f64 = 6_378_137.0;
const EARTH_J2: f64 = 1.082_63e-3;

/// Galileo nominal semi-major axis \[m\] (29 600 km; OS SDD §2.1, Walker 24/3/1).
pub const GALILEO_NOMINAL_A_M: f64 = 29_600.318e3;
/// Galileo nominal inclination \[deg\].
pub const GALILEO_NOMINAL_INCLINATION_DEG: f64 = 56.0;
/// BeiDou-3 MEO nominal semi-major axis \[m\] (27 906 km, Walker 24/3/1, i = 55 deg).
pub const BEIDOU_MEO_A_M: f64 = 27_906.1e3;
/// BeiDou IGSO / GEO semi-major axis \[m\] (geosynchronous, 42 164 km).
pub const BEIDOU_IGSO_A_M: f64 = 42_164.17e3;
/// BeiDou MEO and IGSO inclination \[deg\].
pub const BEIDOU_INCLINATION_DEG: f64 = 55.0;
/// Longitude of the ascending node of the bundled BeiDou IGSO ground track \[deg\]
/// (118 deg E, as C38-C40).
pub const BEIDOU_IGSO_NODE_LON_DEG: f64 = 118.0;
/// PRN of the first bundled BeiDou MEO satellite (C19-C42) and IGSO (C46-C48).
pub const BEIDOU_FIRST_MEO_PRN: u8 = 19;
pub const BEIDOU_FIRST_IGSO_PRN: u8 = 46;

/// Secular node rate of a circular orbit by J2: -3/2 n J2 (Re/a)^2 cos i [rad/s].
fn j2_node_rate(a_m: f64, i_rad: f64, mu: f64) -> f64 {
    let n = (mu / (a_m * a_m * a_m)).sqrt();
    -1.5 * n * EARTH_J2 * (EARTH_RE_M / a_m).powi(2) * i_rad.cos()
}

/// Walker T/P/F: (RAAN, argument of latitude) \[rad\] of the T satellites, plane by
/// plane: RAAN = 360 j / P, u = 360 k / (T/P) + 360 F j / T.
fn walker(t: usize, p: usize, f: usize) -> Vec<(f64, f64)> {
    let s = t / p;
    (0..p)
        .flat_map(|j| {
            (0..s).map(move |k| {
                let raan = 360.0 * j as f64 / p as f64;
                let u = 360.0 * k as f64 / s as f64 + 360.0 * (f * j) as f64 / t as f64;
                (raan.to_radians(), (u % 360.0).to_radians())
            })
        })
        .collect()
}

/// A circular orbit at toe (seconds of week `toe_sow`): A, i, Omega0, M0 (omega = 0)
/// and the J2 node rate.
fn circular(a_m: f64, i_deg: f64, omega0: f64, m0: f64, mu: f64, toe_sow: f64) -> KeplerOrbit {
    let i = i_deg.to_radians();
    KeplerOrbit {
        sqrt_a_sqrt_m: a_m.sqrt(),
        i0_rad: i,
        omega0_rad: wrap_2pi(omega0),
        m0_rad: wrap_2pi(m0),
        omega_dot_rad_per_s: j2_node_rate(a_m, i, mu),
        toe_sow_s: toe_sow,
        ..KeplerOrbit::ZERO
    }
}

/// A deterministic satellite clock offset af0 [s] (within +-2e-4 s), drift af1 [s/s]
/// (within +-4e-12) and a group delay [s] (within +-`gd_max_s`) for `prn` and a
/// system salt, so that the bundled records exercise the clock and group-delay terms.
fn synthetic_clock(prn: u8, salt: u32, gd_max_s: f64) -> (f64, f64, f64) {
    let p = u32::from(prn) + 100 * salt;
    let af0 = (f64::from((p * 37) % 41) - 20.0) * 1e-5;
    let af1 = (f64::from((p * 13) % 9) - 4.0) * 1e-12;
    let gd = (f64::from((p * 7) % 11) - 5.0) / 5.0 * gd_max_s;
    (af0, af1, gd)
}

/// Galileo I/NAV data sources: E1-B and E5b-I, clock for E5b,E1 (RINEX 3.05 Table A8).
pub const GALILEO_INAV_DATA_SOURCES: u32 = 0b10_0000_0101;

/// The bundled Galileo constellation: Walker 24/3/1 (a = 29 600 km, i = 56 deg; Galileo
/// OS SDD §2.1), E01-E24 plane by plane, circular, as I/NAV records at `toe` (GST =
/// GPST): IODnav 1, healthy, SISA 3.12 m, af0/af1 and BGD(E1,E5b) (within +-2 ns;
/// BGD(E1,E5a) 0.2 ns more) from `synthetic_clock`. Omega0 is the plane's RAAN
/// (longitude of the node at the week start, as [`nominal_gps24`]).
pub fn nominal_galileo24(toe: GpsTime) -> Vec<GalileoEphemeris> {
    let mu = GALILEO_CONSTANTS.mu_m3_per_s2;
    walker(24, 3, 1)
        .into_iter()
        .enumerate()
        .map(|(k, (raan, u))| {
            let prn = k as u8 + 1;
            let (af0, af1, bgd) = synthetic_clock(prn, 1, 2e-9);
            GalileoEphemeris {
                prn,
                toc: toe,
                af0_s: af0,
                af1_s_per_s: af1,
                af2_s_per_s2: 0.0,
                iodnav: 1,
                orbit: circular(
                    GALILEO_NOMINAL_A_M,
                    GALILEO_NOMINAL_INCLINATION_DEG,
                    raan,
                    u,
                    mu,
                    toe.sow,
                ),
                toe,
                data_sources: GALILEO_INAV_DATA_SOURCES,
                sisa_m: 3.12,
                health: 0,
                bgd_e1_e5a_s: bgd + 0.2e-9,
                bgd_e1_e5b_s: bgd,
                transmission_time: None,
            }
        })
        .collect()
}

/// The bundled BeiDou constellation at `toe_bdt` (BDT): 24 MEO in Walker 24/3/1
/// (a = 27 906 km, i = 55 deg), C19-C42 plane by plane, and 3 IGSO (a = 42 164 km,
/// i = 55 deg, C46-C48) on one figure-of-eight ground track crossing the equator
/// northwards at 118 deg E: planes 120 deg apart, mean anomalies -120 deg apart. All
/// circular, D1 records with AODE = AODC = 1, healthy, URA 2 m; af0/af1 and TGD1 (within
/// +-6 ns; TGD2 = TGD1 / 2) from `synthetic_clock`. No GEO (C01-C05 use the GEO
/// rotation; none bundled).
pub fn nominal_beidou27(toe_bdt: GpsTime) -> Vec<BeiDouEphemeris> {
    let k = &BEIDOU_CONSTANTS;
    let mu = k.mu_m3_per_s2;
    let meo = walker(24, 3, 1)
        .into_iter()
        .enumerate()
        .map(|(j, (raan, u))| {
            let o = circular(
                BEIDOU_MEO_A_M,
                BEIDOU_INCLINATION_DEG,
                raan,
                u,
                mu,
                toe_bdt.sow,
            );
            (BEIDOU_FIRST_MEO_PRN + j as u8, o)
        });
    let igso = (0..3).map(|j| {
        let dj = (120.0 * f64::from(j)).to_radians();
        // Longitude of the node at toe = Omega0 - Omega_e toe.
        let omega0 = BEIDOU_IGSO_NODE_LON_DEG.to_radians() + k.omega_e_rad_per_s * toe_bdt.sow + dj;
        let o = circular(
            BEIDOU_IGSO_A_M,
            BEIDOU_INCLINATION_DEG,
            omega0,
            -dj,
            mu,
            toe_bdt.sow,
        );
        (BEIDOU_FIRST_IGSO_PRN + j as u8, o)
    });
    meo.chain(igso)
        .map(|(prn, orbit)| {
            let (af0, af1, tgd) = synthetic_clock(prn, 2, 6e-9);
            BeiDouEphemeris {
                prn,
                toc: toe_bdt,
                af0_s: af0,
                af1_s_per_s: af1,
                af2_s_per_s2: 0.0,
                aode: 1,
                aodc: 1,
                orbit,
                toe: toe_bdt,
                sv_accuracy_m: 2.0,
                sat_h1: 0,
                tgd1_s: tgd,
                tgd2_s: 0.5 * tgd,
                transmission_time: None,
            }
        })
        .collect()
}

/// Reference time of the bundled Galileo records for a scenario starting at `start`
/// (GPST): the nearest whole hour of GST (= GPST).
pub fn galileo_toe_near(start: GpsTime) -> GpsTime {
    GpsTime::new(start.week, (start.sow / 3_600.0).round() * 3_600.0)
}

/// Reference time (BDT) of the bundled BeiDou records for a scenario starting at
/// `start` (GPST): the nearest whole hour of BDT.
pub fn beidou_toe_near(start: GpsTime) -> GpsTime {
    let b = gpst_to_bdt(start);
    GpsTime::new(b.week, (b.sow / 3_600.0).round() * 3_600.0)
}

/// A Keplerian broadcast record that [`reissue_records`] can re-issue.
trait KeplerRecord: Clone {
    fn prn(&self) -> u8;
    /// toe and toc in the record's time scale.
    fn toe_toc(&self) -> (GpsTime, GpsTime);
    fn orbit(&self) -> &KeplerOrbit;
    fn af(&self) -> [f64; 3];
    /// Set the re-issue `k` (1, 2, ...) at `toe` / `toc` with its orbit and af0, af1.
    fn set_issue(&mut self, k: u32, o: KeplerOrbit, toe: GpsTime, toc: GpsTime, af01: [f64; 2]);
}

/// The accessors of [`KeplerRecord`] for a record with `prn`, `toe`, `toc`, `orbit`
/// and `af0_s`, `af1_s_per_s`, `af2_s_per_s2` fields.
macro_rules! kepler_record_fields {
    () => {
        fn prn(&self) -> u8 {
            self.prn
        }
        fn toe_toc(&self) -> (GpsTime, GpsTime) {
            (self.toe, self.toc)
        }
        fn orbit(&self) -> &KeplerOrbit {
            &self.orbit
        }
        fn af(&self) -> [f64; 3] {
            [self.af0_s, self.af1_s_per_s, self.af2_s_per_s2]
        }
    };
}

impl KeplerRecord for GalileoEphemeris {
    kepler_record_fields!();
    fn set_issue(&mut self, k: u32, o: KeplerOrbit, toe: GpsTime, toc: GpsTime, af01: [f64; 2]) {
        (self.orbit, self.toe, self.toc) = (o, toe, toc);
        [self.af0_s, self.af1_s_per_s] = af01;
        self.iodnav = ((u32::from(self.iodnav) + k) % 1024) as u16;
        self.transmission_time = Some(toe.add_s(-600.0));
    }
}

impl KeplerRecord for BeiDouEphemeris {
    kepler_record_fields!();
    fn set_issue(&mut self, k: u32, o: KeplerOrbit, toe: GpsTime, toc: GpsTime, af01: [f64; 2]) {
        (self.orbit, self.toe, self.toc) = (o, toe, toc);
        [self.af0_s, self.af1_s_per_s] = af01;
        self.aode = ((u32::from(self.aode) + k) % 256) as u16;
        self.aodc = ((u32::from(self.aodc) + k) % 256) as u16;
        self.transmission_time = Some(toe.add_s(-600.0));
    }
}

/// [`reissued`] for Keplerian records of another system: `from` / `until` in the
/// records' time scale, `max_age_s` the system's validity.
fn reissue_records<E: KeplerRecord>(
    ephs: &[E],
    from: GpsTime,
    until: GpsTime,
    step_s: f64,
    max_age_s: f64,
    k: &KeplerConstants,
) -> Vec<E> {
    let mut out = ephs.to_vec();
    for e in ephs {
        let n = mean_motion(e.orbit(), k);
        let (toe0, toc0) = e.toe_toc();
        for (i, dt) in issue_steps(toe0, from, until, step_s, max_age_s) {
            let toe = toe0.add_s(dt);
            let toc = toc0.add_s(dt);
            let weeks = f64::from(toe.week - toe0.week);
            let o = advance_orbit(e.orbit(), n, k.omega_e_rad_per_s, dt, weeks, toe.sow);
            let mut c = e.clone();
            c.set_issue(i, o, toe, toc, advance_clock(e.af(), toc.diff_s(&toc0)));
            out.push(c);
        }
    }
    out.sort_by(|a, b| {
        let (ta, tb) = (a.toe_toc().0, b.toe_toc().0);
        ta.diff_s(&tb).total_cmp(&0.0).then(a.prn().cmp(&b.prn()))
    });
    out
}

/// Galileo records re-issued every `step_s` to cover `[from, until]` (GPST), as
/// [`reissued`] does for GPS: the same orbit and clock at a later toe = toc, IODnav
/// plus 1 per issue (mod 1024), transmitted 10 min before toe. (Galileo refreshes
/// its batches every 10 min, each valid 4 h: `GALILEO_MAX_AGE_S`.)
pub fn reissued_galileo(
    ephs: &[GalileoEphemeris],
    from: GpsTime,
    until: GpsTime,
    step_s: f64,
) -> Vec<GalileoEphemeris> {
    let max_age = crate::ephemeris::GALILEO_MAX_AGE_S;
    reissue_records(ephs, from, until, step_s, max_age, &GALILEO_CONSTANTS)
}

/// BeiDou records re-issued every `step_s` (BeiDou updates hourly) to cover
/// `[from, until]` (GPST): the same orbit and clock at a later toe = toc (BDT),
/// AODE and AODC + 1 per issue (mod 256), transmitted 10 min before toe.
pub fn reissued_beidou(
    ephs: &[BeiDouEphemeris],
    from: GpsTime,
    until: GpsTime,
    step_s: f64,
) -> Vec<BeiDouEphemeris> {
    let (from, until) = (gpst_to_bdt(from), gpst_to_bdt(until));
    let max_age = crate::ephemeris::BEIDOU_MAX_AGE_S;
    reissue_records(ephs, from, until, step_s, max_age, &BEIDOU_CONSTANTS)
}

/// GLONASS nominal semi-major axis \[m\] (19 100 km altitude, period 11 h 15 min 44 s;
/// ICD 5.1 §3.1.1) and inclination \[deg\].
pub const GLONASS_A_M: f64 = 25_508.2e3;
pub const GLONASS_INCLINATION_DEG: f64 = 64.8;
/// FDMA channel of slots R01-R24 (antipodal slots share one; the assignment in force
/// since 2005, ICD 5.1 §3.3.1.4: k in -7..6).
pub const GLONASS_CHANNELS: [i8; 24] = [
    1, -4, 5, 6, 1, -4, 5, 6, -2, -7, 0, -1, -2, -7, 0, -1, 4, -3, 3, 2, 4, -3, 3, 2,
];
/// Interval of the GLONASS immediate data \[s\] (tb every 30 min).
pub const GLONASS_TB_STEP_S: f64 = 1_800.0;

/// The bundled GLONASS constellation as broadcast records covering `[from, until]`
/// (GPST; `leap_s` = GPS - UTC): 24 slots in 3 planes (RAAN 0, 120, 240 deg), 8 per
/// plane 45 deg apart, phased 15 deg from plane to plane (Walker 24/3/1), a = 25 508.2
/// km, i = 64.8 deg, channels [`GLONASS_CHANNELS`]. tb falls on hh:15 and hh:45 UTC,
/// every 30 min. The first record of each slot is the circular Keplerian orbit at its
/// tb (position and ECEF velocity, PZ-90 = WGS-84 here); each next one is the state of
/// the previous record integrated by the broadcast model (`GlonassEphemeris::sat_state`:
/// central field + J2) to its tb, so consecutive records continue one orbit; the
/// luni-solar accelerations are 0. Clock: -tau_n = af0 and gamma_n = af1 of
/// `synthetic_clock`, tau_n carried on from record to record; healthy, age 0.
pub fn glonass_records(from: GpsTime, until: GpsTime, leap_s: f64) -> Vec<GlonassEphemeris> {
    let k = &GALILEO_CONSTANTS; // PZ-90.11 GM = 3.986004418e14 as Galileo's
                                // First tb: the hh:15 / hh:45 UTC at or before `from` minus 15 min.
    let utc0 = from.add_s(-leap_s - 900.0);
    let sow0 = ((utc0.sow - 900.0) / GLONASS_TB_STEP_S).floor() * GLONASS_TB_STEP_S + 900.0;
    let tb0 = GpsTime::new(utc0.week, sow0).add_s(leap_s);
    let n = (until.diff_s(&tb0) / GLONASS_TB_STEP_S).ceil().max(0.0) as usize + 1;
    let mut out = Vec::new();
    for (j, (raan, u)) in walker(24, 3, 1).into_iter().enumerate() {
        let slot = j as u8 + 1;
        let (af0, af1, _) = synthetic_clock(slot, 3, 0.0);
        let o = circular(
            GLONASS_A_M,
            GLONASS_INCLINATION_DEG,
            raan,
            u,
            k.mu_m3_per_s2,
            tb0.sow,
        );
        let s0 = o.state(k, 0.0, false);
        let utc_tb0 = tb0.add_s(-leap_s);
        let mut e = GlonassEphemeris {
            slot,
            tb: tb0,
            tb_utc_sod_s: utc_tb0.sow.rem_euclid(86_400.0),
            tau_n_s: -af0,
            gamma_n: af1,
            frame_time_s: (utc_tb0.sow - 900.0).rem_euclid(604_800.0),
            pos_m: s0.pos_ecef_m,
            vel_mps: s0.vel_ecef_mps,
            acc_mps2: nalgebra::Vector3::zeros(),
            health: 0,
            freq_channel: GLONASS_CHANNELS[j],
            age_days: 0.0,
        };
        for _ in 0..n {
            let next_tb = e.tb.add_s(GLONASS_TB_STEP_S);
            let st = e.sat_state(next_tb);
            let utc = next_tb.add_s(-leap_s);
            let next = GlonassEphemeris {
                tb: next_tb,
                tb_utc_sod_s: utc.sow.rem_euclid(86_400.0),
                tau_n_s: -st.clock_bias_s,
                frame_time_s: (utc.sow - 900.0).rem_euclid(604_800.0),
                pos_m: st.pos_ecef_m,
                vel_mps: st.vel_ecef_mps,
                ..e.clone()
            };
            out.push(std::mem::replace(&mut e, next));
        }
    }
    out.sort_by(|a, b| a.tb.diff_s(&b.tb).total_cmp(&0.0).then(a.slot.cmp(&b.slot)));
    out
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

#[cfg(test)]
mod multi_tests {
    use super::*;
    use crate::ephemeris::beidou::bdt_to_gpst;
    use crate::ephemeris::Ephemeris;
    use crate::ephemeris_store::EphemerisStore;
    use nalgebra::Vector3;
    use navfuse_core::sat::System;

    /// Radius, speed and period of each record over a day; the period from the
    /// angle swept in inertial space over 1 h.
    fn check_orbits(store: &EphemerisStore, t0: GpsTime, a_m: &dyn Fn(u8) -> f64) {
        for e in store.iter() {
            let sat = e.sat();
            let a = a_m(sat.prn);
            let period = 2.0 * std::f64::consts::PI * (a * a * a / 3.986_004_418e14).sqrt();
            for h in 0..24 {
                let t = t0.add_s(f64::from(h) * 3_600.0);
                let s = e.sat_state(t);
                let r = s.pos_ecef_m.norm();
                assert!((r - a).abs() < 1.0, "{sat} r {r} a {a}");
                // Inertial speed = sqrt(mu / a): ECEF velocity + w x r (plus the J2
                // node drift, r Omega_dot < 0.2 m/s).
                let w = Vector3::new(0.0, 0.0, 7.292_115e-5);
                let v_i = s.vel_ecef_mps + w.cross(&s.pos_ecef_m);
                let v0 = (3.986_004_418e14 / a).sqrt();
                assert!((v_i.norm() - v0).abs() < 0.3, "{sat} v {} {v0}", v_i.norm());
                // Angular rate in inertial space vs 2 pi / period (the node drift is
                // < 1e-4 of the mean motion).
                let rate = s.pos_ecef_m.cross(&v_i).norm() / (r * r);
                assert!((rate * period / (2.0 * std::f64::consts::PI) - 1.0).abs() < 1e-4);
                assert!(s.clock_bias_s.abs() < 3e-4);
            }
        }
    }

    /// The bundled Galileo and BeiDou constellations over a day from t0, re-issued
    /// hourly as the simulator does.
    fn bundled(t0: GpsTime) -> (EphemerisStore, EphemerisStore) {
        let t1 = t0.add_s(86_400.0);
        let g = reissued_galileo(&nominal_galileo24(galileo_toe_near(t0)), t0, t1, 3_600.0);
        let b = reissued_beidou(&nominal_beidou27(beidou_toe_near(t0)), t0, t1, 3_600.0);
        (
            EphemerisStore::new(g.into_iter().map(Ephemeris::Galileo)),
            EphemerisStore::new(b.into_iter().map(Ephemeris::BeiDou)),
        )
    }

    #[test]
    fn galileo_and_beidou_orbits_are_physical() {
        let t0 = GpsTime::new(2381, 604_800.0 - 30_000.0);
        let (gal, bds) = bundled(t0);
        assert_eq!(gal.sats().len(), 24);
        check_orbits(&gal, t0, &|_| GALILEO_NOMINAL_A_M);
        assert_eq!(bds.sats().len(), 27);
        check_orbits(&bds, t0, &|p| {
            if p >= BEIDOU_FIRST_IGSO_PRN {
                BEIDOU_IGSO_A_M
            } else {
                BEIDOU_MEO_A_M
            }
        });
        // Periods: Galileo 14 h 05 min, BeiDou MEO 12 h 53 min, IGSO one sidereal day.
        let period = |a: f64| 2.0 * std::f64::consts::PI * (a.powi(3) / 3.986_004_418e14).sqrt();
        assert!((period(GALILEO_NOMINAL_A_M) / 60.0 - 845.0).abs() < 1.0);
        assert!((period(BEIDOU_MEO_A_M) / 60.0 - 773.0).abs() < 1.0);
        assert!((period(BEIDOU_IGSO_A_M) - 86_164.1).abs() < 5.0);
        // Inclinations and the IGSO node over 118 E (a day later too).
        for e in bds.iter() {
            let Ephemeris::BeiDou(b) = e else {
                unreachable!()
            };
            assert!((b.orbit.i0_rad.to_degrees() - 55.0).abs() < 1e-9);
            if b.prn >= BEIDOU_FIRST_IGSO_PRN {
                for h in [0.0, 24.0] {
                    // Ground track crosses the equator near 118 E.
                    let mut best = (f64::MAX, 0.0);
                    for m in 0..(24 * 60) {
                        let t = t0.add_s(h * 3_600.0 + f64::from(m) * 60.0);
                        let p = e.sat_state(t).pos_ecef_m;
                        let lat = (p.z / p.norm()).asin();
                        if lat.abs() < best.0 {
                            best = (lat.abs(), p.y.atan2(p.x).to_degrees());
                        }
                    }
                    assert!((best.1 - 118.0).abs() < 1.0, "C{} node {}", b.prn, best.1);
                }
            }
        }
        // Records in reach at every time of the day, each system.
        for k in 0..=288 {
            let t = t0.add_s(f64::from(k) * 300.0);
            for s in gal.sats().into_iter().chain(bds.sats()) {
                let st = if s.system == System::Galileo {
                    &gal
                } else {
                    &bds
                };
                let e = st.select(s, t).expect("a record in reach");
                let age = t.diff_s(&e.toe_gpst());
                if s.system == System::Galileo {
                    // The latest batch before t (EphemerisStore's Galileo rule);
                    // before a satellite's first toe of the day, that first batch.
                    let first_hour = k * 300 < 3_600;
                    assert!(
                        age <= 3_600.0 + 1.0 && (age >= 0.0 || first_hour),
                        "{s} {age}"
                    );
                } else {
                    assert!(age.abs() <= 1_800.0 + 1.0, "{s} {age}");
                }
            }
        }
        // BDT toe is a whole BDT hour, 14 s after the GPST hour.
        let b0 = beidou_toe_near(t0);
        assert_eq!(b0.sow % 3_600.0, 0.0);
        assert_eq!(bdt_to_gpst(b0).sow % 3_600.0, 14.0);
    }

    #[test]
    fn glonass_records_continue_one_orbit_every_30_min() {
        let t0 = GpsTime::new(2381, 604_800.0 - 30_000.0);
        let recs = glonass_records(t0, t0.add_s(86_400.0), 18.0);
        let store = EphemerisStore::new(recs.iter().cloned().map(Ephemeris::Glonass));
        assert_eq!(store.sats().len(), 24);
        // tb on hh:15 / hh:45 UTC.
        for e in &recs {
            assert_eq!(e.tb_utc_sod_s % 1_800.0, 900.0);
            assert_eq!(
                e.l1_frequency_hz(),
                1_602.0e6 + f64::from(e.freq_channel) * 562.5e3
            );
        }
        let (mut worst_jump, mut r_min, mut r_max) = (0.0f64, f64::MAX, 0.0f64);
        for sat in store.sats() {
            let list: Vec<&GlonassEphemeris> = recs.iter().filter(|e| e.slot == sat.prn).collect();
            assert!(list.len() >= 49);
            for w in list.windows(2) {
                // The two records agree half way between their tb.
                let mid = w[0].tb.add_s(900.0);
                let (a, b) = (w[0].sat_state(mid), w[1].sat_state(mid));
                worst_jump = worst_jump.max((a.pos_ecef_m - b.pos_ecef_m).norm());
                assert!((a.clock_bias_s - b.clock_bias_s).abs() < 1e-15);
            }
            for m in 0..=(24 * 12) {
                let t = t0.add_s(f64::from(m) * 300.0);
                let e = store.select(sat, t).expect("a record within 15 min");
                let r = e.sat_state(t).pos_ecef_m.norm();
                r_min = r_min.min(r);
                r_max = r_max.max(r);
            }
        }
        eprintln!("GLONASS: radius {r_min:.0}..{r_max:.0} m, record switch {worst_jump:.2e} m");
        assert!(worst_jump < 1e-3, "{worst_jump}");
        // J2 makes the initially circular orbit breathe by a few km.
        assert!(r_min > GLONASS_A_M - 20e3 && r_max < GLONASS_A_M + 20e3);
    }

    #[test]
    fn at_least_four_of_each_system_above_10_deg_at_mid_latitudes() {
        let t0 = GpsTime::new(2381, 345_600.0);
        let gps = EphemerisStore::new(
            reissued(&nominal_gps24(t0), t0, t0.add_s(86_400.0), 7_200.0)
                .into_iter()
                .map(Ephemeris::Gps),
        );
        let (gal, bds) = bundled(t0);
        let glo = EphemerisStore::new(
            glonass_records(t0, t0.add_s(86_400.0), 18.0)
                .into_iter()
                .map(Ephemeris::Glonass),
        );
        let stores = [
            (System::Gps, gps),
            (System::Galileo, gal),
            (System::BeiDou, bds),
            (System::Glonass, glo),
        ];
        for (lat, lon) in super::tests::SITES {
            let lla = Vector3::new(lat.to_radians(), lon.to_radians(), 100.0);
            for (sys, store) in &stores {
                let (mut min, mut sum) = (usize::MAX, 0usize);
                for step in 0..=(24 * 12) {
                    let t = t0.add_s(f64::from(step) * 300.0);
                    let recs = store
                        .sats()
                        .into_iter()
                        .map(|s| store.select(s, t).expect("record"));
                    let n = super::tests::above_10_deg(recs, &lla, t);
                    min = min.min(n);
                    sum += n;
                }
                eprintln!(
                    "site ({lat}, {lon}) {}: min {min}, mean {:.1}",
                    sys.letter(),
                    sum as f64 / 289.0
                );
                assert!(min >= 4, "site ({lat}, {lon}) {sys:?}: min {min}");
            }
        }
    }
}
