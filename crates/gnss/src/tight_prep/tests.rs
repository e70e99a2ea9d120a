//! Tests of the tight-coupling epoch preparation.

use super::*;
use crate::atmosphere::{klobuchar_l1_delay_m, saastamoinen_slant_m};
use crate::constellation::nominal_gps24;
use crate::spp::IonoModel;
use navfuse_core::earth::lla_to_ecef;

pub(crate) const ALPHA: [f64; 4] = [1.1176e-8, 1.4901e-8, -5.9605e-8, -1.1921e-7];
pub(crate) const BETA: [f64; 4] = [1.1469e5, 8.1920e4, -1.3107e5, -5.2429e5];
const C: f64 = SPEED_OF_LIGHT_MPS;

pub(crate) fn toe() -> GpsTime {
    GpsTime::new(2381, 410_400.0)
}

/// The nominal constellation with non-zero clocks, TGDs, eccentricities, IODEs.
pub(crate) fn ephemerides() -> EphemerisSet {
    let mut ephs = nominal_gps24(toe());
    for (k, e) in ephs.iter_mut().enumerate() {
        let k = k as f64;
        e.af0_s = (k - 11.5) * 3e-5;
        e.af1_s_per_s = (k - 7.0) * 1e-12;
        e.tgd_s = (k - 12.0) * 1e-9;
        e.e = 0.002 + 0.0005 * k;
        e.iode = 40 + k as u16;
    }
    EphemerisSet::new(ephs)
}

/// A receiver moving at constant velocity with a linear clock; `jump` adds a
/// clock step [m] from `jump_at_s` (seconds after the start) on.
#[derive(Clone, Copy)]
pub(crate) struct Receiver {
    pub pos0_ecef_m: Vector3<f64>,
    pub vel_ecef_mps: Vector3<f64>,
    pub clock0_m: f64,
    pub drift_mps: f64,
    pub jump: Option<(f64, f64)>,
}

impl Receiver {
    /// Near Boulder, moving, u-blox-like clock (-1.5 ms, drifting).
    pub(crate) fn rover() -> Self {
        let lla = Vector3::new(40.0967f64.to_radians(), (-105.1472f64).to_radians(), 1601.4);
        Receiver {
            pos0_ecef_m: lla_to_ecef(&lla),
            vel_ecef_mps: c_ne(lla.x, lla.y) * Vector3::new(12.0, -7.0, 0.1),
            clock0_m: -1.5e-3 * C,
            drift_mps: -60.0,
            jump: None,
        }
    }
    pub(crate) fn pos(&self, dt_s: f64) -> Vector3<f64> {
        self.pos0_ecef_m + self.vel_ecef_mps * dt_s
    }
    /// Position at the true time of the tag `t0 + dt_s`.
    pub(crate) fn pos_at_tag(&self, dt_s: f64) -> Vector3<f64> {
        self.pos(dt_s - self.clock(dt_s) / C)
    }
    /// Clock [m] at the tag `t0 + dt_s`.
    pub(crate) fn clock(&self, dt_s: f64) -> f64 {
        let step = match self.jump {
            Some((at, m)) if dt_s >= at => m,
            _ => 0.0,
        };
        self.clock0_m + self.drift_mps * dt_s + step
    }
}

/// Exact observations of every satellite above 5 deg at tag `t0 + dt_s` (the
/// receiver clock defined on the tag scale, the rest at the true time).
/// `extra(prn, dt_s)` = (error added to code and carrier [m], its rate [m/s]) at
/// true time `t0 + dt_s`;
/// `atmosphere` adds the Klobuchar and Saastamoinen delays. Ambiguity 1000 prn.
pub(crate) fn observe(
    ephs: &EphemerisSet,
    t0: GpsTime,
    dt_s: f64,
    rx: &Receiver,
    atm: Atm,
    extra: &dyn Fn(u8, f64) -> (f64, f64),
) -> ObsEpoch {
    let t_tag = t0.add_s(dt_s);
    let clock = rx.clock(dt_s);
    let t_true = t_tag.add_s(-clock / C);
    let pos = rx.pos_at_tag(dt_s);
    let lla = ecef_to_lla(&pos);
    let mut sats = Vec::new();
    for prn in ephs.prns() {
        let eph = ephs.select(prn, t_tag).unwrap();
        let sp = signal_path(eph, &pos, &rx.vel_ecef_mps, t_true);
        let (_, el) = az_el(&lla, &sp.los_unit);
        if el < 5f64.to_radians() {
            continue;
        }
        // Delays at the tag + h (geometry moved on by h).
        let delays = |h: f64| -> (f64, f64) {
            let pos = rx.pos(dt_s + h - clock / C);
            let lla = ecef_to_lla(&pos);
            let sp = signal_path(eph, &pos, &rx.vel_ecef_mps, t_true.add_s(h));
            let (az, el) = az_el(&lla, &sp.los_unit);
            let sow = t_tag.sow + h;
            (
                if atm.iono {
                    klobuchar_l1_delay_m(&ALPHA, &BETA, lla.x, lla.y, az, el, sow)
                } else {
                    0.0
                },
                if atm.tropo {
                    saastamoinen_slant_m(lla.x, lla.z, el)
                } else {
                    0.0
                },
            )
        };
        let (iono, tropo) = delays(0.0);
        // The phase sees -I + T; the Doppler its rate (central difference).
        let phase_atm = |h: f64| {
            let (i, t) = delays(h);
            t - i
        };
        let atm_rate = (phase_atm(0.05) - phase_atm(-0.05)) / 0.1;
        let (e, e_rate) = extra(prn, dt_s - clock / C);
        let geo = sp.geometric_range_m + clock - C * (sp.sat_clock_bias_s - eph.tgd_s) + e;
        let rr =
            sp.range_rate_mps + rx.drift_mps - C * sp.sat_clock_drift_s_per_s + e_rate + atm_rate;
        sats.push(SatObs {
            prn,
            pseudorange_m: Some(geo + iono + tropo),
            carrier_cycles: Some(
                (geo - iono + tropo) / GPS_L1_WAVELENGTH_M + 1000.0 * f64::from(prn),
            ),
            doppler_hz: Some(-rr / GPS_L1_WAVELENGTH_M),
            cn0_dbhz: Some(45.0),
            lli: 0,
        });
    }
    ObsEpoch {
        t: t_tag,
        flag: 0,
        rx_clock_offset_s: None,
        sats,
    }
}

pub(crate) fn no_extra(_: u8, _: f64) -> (f64, f64) {
    (0.0, 0.0)
}

/// Which broadcast-model delays the data hold and the preparation models.
#[derive(Clone, Copy)]
pub(crate) struct Atm {
    pub iono: bool,
    pub tropo: bool,
}
pub(crate) const NO_ATM: Atm = Atm {
    iono: false,
    tropo: false,
};
pub(crate) const TROPO: Atm = Atm {
    iono: false,
    tropo: true,
};
pub(crate) const BOTH: Atm = Atm {
    iono: true,
    tropo: true,
};

pub(crate) fn config(atm: Atm) -> TightPrepConfig {
    let mut cfg = TightPrepConfig::default();
    if atm.iono {
        cfg.spp.iono = IonoModel::Klobuchar {
            alpha: ALPHA,
            beta: BETA,
        };
    }
    cfg.spp.tropo_saastamoinen = atm.tropo;
    cfg
}

/// Start of the test runs: 8 satellites above 10 deg.
pub(crate) fn t0() -> GpsTime {
    toe().add_s(500.0)
}

/// (prn, pseudorange - range - clock, range rate - geometric rate - drift,
/// carrier - range - clock (NaN without carrier)).
pub(crate) type Residual = (u8, f64, f64, f64);

/// Residuals of the prepared measurements against the truth at tag `t0 + dt_s`.
pub(crate) fn residuals(p: &PreparedEpoch, rx: &Receiver, dt_s: f64) -> Vec<Residual> {
    let pos = rx.pos_at_tag(dt_s);
    p.raw
        .sats
        .iter()
        .map(|m| {
            let d = m.sat_pos_ecef_m - pos;
            let los = d / d.norm();
            let rate = los.dot(&(m.sat_vel_ecef_mps - rx.vel_ecef_mps));
            (
                m.sat.prn,
                m.pseudorange_m.unwrap() - d.norm() - rx.clock(dt_s),
                m.range_rate_mps.unwrap() - rate - rx.drift_mps,
                m.carrier_m
                    .map_or(f64::NAN, |l| l - d.norm() - rx.clock(dt_s)),
            )
        })
        .collect()
}

#[test]
fn satellite_clock_and_models_are_removed() {
    let ephs = ephemerides();
    let rx = Receiver::rover();
    let ep = observe(&ephs, t0(), 0.0, &rx, BOTH, &no_extra);
    let mut prep = EpochPreparer::new(ephs, config(BOTH), None);
    let p = prep.prepare(&ep, 2381);
    let spp = p.spp.as_ref().unwrap();
    assert!(p.raw.sats.len() >= 6, "{}", p.raw.sats.len());
    // Satellites between 5 and 10 deg are dropped, as in the SPP.
    assert_eq!(p.raw.sats.len(), spp.n_used);
    assert!(p.raw.sats.len() < ep.sats.len());
    for (prn, pr, rr, cr) in residuals(&p, &rx, 0.0) {
        assert!(pr.abs() < 1e-3, "G{prn:02} pseudorange residual {pr} m");
        // (the Doppler keeps the atmosphere's rate, here < 1 cm/s)
        assert!(rr.abs() < 0.01, "G{prn:02} range-rate residual {rr} m/s");
        // The carrier loses the models too (phase sign): lambda N is left.
        let n = 1000.0 * f64::from(prn) * GPS_L1_WAVELENGTH_M;
        assert!(
            (cr - n).abs() < 1e-3,
            "G{prn:02} carrier residual {}",
            cr - n
        );
    }
    for m in &p.raw.sats {
        assert!(m.elevation_rad >= 10f64.to_radians());
        assert!(!m.dgps && m.lost_lock);
        assert!(m.pseudorange_std_m > 1.0 && m.pseudorange_std_m.is_finite());
        assert!(m.carrier_std_m >= 0.003 && m.carrier_std_m < 0.02);
        assert!(m.range_rate_std_mps >= 0.19 && m.range_rate_std_mps < 1.5);
    }
    assert_eq!((p.dgps_applied, p.dgps_missing), (0, 0));
    // Time of validity: tag - clock / c; the fix is the SPP's.
    assert!((p.raw.t - (t0().sow + 1.5e-3)).abs() < 1e-9);
    let fix = p.raw.fix.unwrap();
    assert_eq!(fix.t, p.raw.t);
    assert!((lla_to_ecef(&fix.lla) - rx.pos_at_tag(0.0)).norm() < 1e-3);
    let lla = ecef_to_lla(&rx.pos_at_tag(0.0));
    let v_ned = c_ne(lla.x, lla.y).transpose() * rx.vel_ecef_mps;
    // (the Doppler velocity has the atmosphere's rates in it: < 1 cm/s)
    assert!((fix.vel_ned.unwrap() - v_ned).norm() < 0.01);
    assert!(fix.std_ned.iter().all(|s| *s > 0.0));
    // A reference week one earlier: t counts on past 604800.
    let p = EpochPreparer::new(ephemerides(), config(BOTH), None).prepare(&ep, 2380);
    assert!((p.raw.t - (604_800.0 + t0().sow + 1.5e-3)).abs() < 1e-9);
}

#[test]
fn carrier_continuity_and_lost_lock() {
    let ephs = ephemerides();
    let rx = Receiver::rover();
    let mut prep = EpochPreparer::new(ephs.clone(), config(NO_ATM), None);
    let first = observe(&ephs, t0(), 0.0, &rx, NO_ATM, &no_extra);
    let prns: Vec<u8> = prep
        .prepare(&first, 2381)
        .raw
        .sats
        .iter()
        .map(|m| m.sat.prn)
        .collect();
    let (a, b, d) = (prns[0], prns[1], prns[2]);
    for k in 1..7 {
        let dt = f64::from(k);
        let mut ep = observe(&ephs, t0(), dt, &rx, NO_ATM, &no_extra);
        match k {
            2 => ep.sats.iter_mut().find(|s| s.prn == a).unwrap().lli = 1,
            3 => {
                ep.sats.retain(|s| s.prn != b);
                ep.sats
                    .iter_mut()
                    .find(|s| s.prn == d)
                    .unwrap()
                    .carrier_cycles = None;
            }
            6 => ep.flag = 1,
            _ => {}
        }
        let p = prep.prepare(&ep, 2381);
        for m in &p.raw.sats {
            let expect = match k {
                2 => m.sat.prn == a,
                4 => m.sat.prn == b || m.sat.prn == d,
                6 => true,
                _ => false,
            };
            assert_eq!(m.lost_lock, expect, "epoch {k} G{:02}", m.sat.prn);
        }
        assert_eq!(p.raw.sats.iter().any(|m| m.sat.prn == b), k != 3);
        for (prn, pr, _, cr) in residuals(&p, &rx, dt) {
            assert!(pr.abs() < 1e-3, "G{prn:02}: {pr}");
            if prn != d || k != 3 {
                // carrier - range - clock = lambda N, the simulated ambiguity.
                let n = 1000.0 * f64::from(prn) * GPS_L1_WAVELENGTH_M;
                assert!((cr - n).abs() < 1e-3, "epoch {k} G{prn:02}: {}", cr - n);
            }
        }
    }
}

#[test]
fn no_position_no_satellites_then_the_last_solution() {
    let ephs = ephemerides();
    let rx = Receiver::rover();
    let mut prep = EpochPreparer::new(ephs.clone(), config(NO_ATM), None);
    let mut three = observe(&ephs, t0(), 0.0, &rx, NO_ATM, &no_extra);
    three.sats.truncate(3);
    let p = prep.prepare(&three, 2381);
    assert!(p.spp.is_err() && p.raw.sats.is_empty() && p.raw.fix.is_none());
    assert_eq!(p.raw.t, t0().sow);
    let good = observe(&ephs, t0(), 1.0, &rx, NO_ATM, &no_extra);
    assert!(prep.prepare(&good, 2381).spp.is_ok());
    // Three satellites: no SPP, but the last solution (moved on with its velocity
    // and clock drift) places them; the range rate still fits.
    let mut three = observe(&ephs, t0(), 2.0, &rx, NO_ATM, &no_extra);
    three.sats.truncate(3);
    let p = prep.prepare(&three, 2381);
    assert!(p.spp.is_err() && p.raw.fix.is_none());
    assert!(!p.raw.sats.is_empty() && p.raw.sats.len() <= 3);
    for (prn, pr, rr, _) in residuals(&p, &rx, 2.0) {
        assert!(pr.abs() < 1e-3 && rr.abs() < 1e-3, "G{prn:02}: {pr} {rr}");
    }
}

#[test]
fn dgps_corrections_replace_the_models() {
    let ephs = ephemerides();
    let rx = Receiver::rover();
    // Errors common to the rover and the reference station: a bias and a drift
    // per satellite, and +7 m on one satellite.
    let faulty = EpochPreparer::new(ephs.clone(), config(TROPO), None)
        .prepare(&observe(&ephs, t0(), 0.0, &rx, NO_ATM, &no_extra), 2381)
        .raw
        .sats[2]
        .sat
        .prn;
    let extra = move |prn: u8, dt: f64| {
        let p = f64::from(prn);
        let rate = 0.05 * (p - 12.0);
        let bias = 3.0 * (p * 1.7).sin() + if prn == faulty { 7.0 } else { 0.0 };
        (bias + rate * dt, rate)
    };
    // Reference station 10 km away and 6.5 km up, static, with its own clock
    // that jumps 1 ms. Data and preparation have the tropospheric model (the
    // phase and code see the troposphere alike, so the station's carrier rrc
    // has it with the code sign).
    let ref_pos = rx.pos0_ecef_m + Vector3::new(6e3, -6e3, 5e3);
    let station = Receiver {
        pos0_ecef_m: ref_pos,
        vel_ecef_mps: Vector3::zeros(),
        clock0_m: 0.8e-3 * C,
        drift_mps: 30.0,
        jump: Some((12.0, -1e-3 * C)),
    };
    let ref_epochs: Vec<ObsEpoch> = (0..40)
        .map(|k| observe(&ephs, t0(), f64::from(k), &station, TROPO, &extra))
        .collect();
    let corr = crate::dgps::corrections_from_reference_station(
        &ephs,
        &ref_epochs,
        ref_pos,
        5f64.to_radians(),
    );
    assert!(corr.len() > 300, "{}", corr.len());
    let store = DgpsCorrections::new(corr).with_reference_position(ref_pos);
    // A corrected satellite gets the model difference to the station only.
    let mut prep = EpochPreparer::new(ephs.clone(), config(TROPO), Some(store.clone()));
    let mut plain = EpochPreparer::new(ephs.clone(), config(TROPO), None);
    let mut plain_ok = EpochPreparer::new(ephs.clone(), config(TROPO), None);
    let mut first: Vec<(u8, f64)> = Vec::new();
    for k in 0..40 {
        let dt = f64::from(k);
        let ep = observe(&ephs, t0(), dt, &rx, TROPO, &extra);
        let p = prep.prepare(&ep, 2381);
        assert_eq!(p.dgps_applied, p.raw.sats.len());
        assert_eq!(p.dgps_missing, 0);
        assert!(p.spp.is_ok());
        let res = residuals(&p, &rx, dt);
        // What is left is common to all satellites (the reference clock
        // residual), to the noise-free data's precision.
        let spread = |f: &dyn Fn(&Residual) -> f64| {
            let v: Vec<f64> = res.iter().map(f).collect();
            v.iter().cloned().fold(f64::MIN, f64::max) - v.iter().cloned().fold(f64::MAX, f64::min)
        };
        assert!(
            spread(&|r| r.1) < 2e-3,
            "epoch {k}: pseudorange spread {}",
            spread(&|r| r.1)
        );
        // (the Doppler keeps the troposphere's rate, which differs 6.5 km up)
        assert!(
            spread(&|r| r.2) < 0.01,
            "epoch {k}: range-rate spread {}",
            spread(&|r| r.2)
        );
        if k == 0 {
            first = res.iter().map(|r| (r.0, r.3)).collect();
        } else {
            // Carrier + integrated rrc: the satellite errors' changes cancel.
            let dc =
                |r: &Residual| r.3 - first.iter().find(|f| f.0 == r.0).map_or(f64::NAN, |f| f.1);
            assert!(
                spread(&dc) < 2e-3,
                "epoch {k}: carrier spread {}",
                spread(&dc)
            );
        }
        for m in &p.raw.sats {
            assert!(m.dgps);
            let em = &prep.config().spp.errors;
            let var = em.elevation_variance_m2(m.elevation_rad) + 1.0;
            assert!((m.pseudorange_std_m - var.sqrt()).abs() < 1e-12);
        }
        // Without DGPS the +7 m stays in the faulty satellite's pseudorange.
        let ep = observe(&ephs, t0(), dt, &rx, TROPO, &extra);
        let with = residuals(&plain.prepare(&ep, 2381), &rx, dt);
        let ep = observe(&ephs, t0(), dt, &rx, TROPO, &|prn, dt| {
            let (e, r) = extra(prn, dt);
            (e - if prn == faulty { 7.0 } else { 0.0 }, r)
        });
        let without = residuals(&plain_ok.prepare(&ep, 2381), &rx, dt);
        for (a, b) in with.iter().zip(&without) {
            let fault = if a.0 == faulty { 7.0 } else { 0.0 };
            // (the models move a little with the SPP position)
            let d = a.1 - b.1 - fault;
            assert!(d.abs() < 0.1, "G{:02}: {d}", a.0);
        }
    }
    // Corrections older than the age limit are not used: fall back to the models.
    let late = observe(&ephs, t0(), 39.0 + 31.0, &rx, TROPO, &extra);
    let p = prep.prepare(&late, 2381);
    assert_eq!(p.dgps_applied, 0);
    assert_eq!(p.dgps_missing, p.raw.sats.len());
    assert!(p.raw.sats.iter().all(|m| !m.dgps));
}

#[test]
fn dgps_station_below_the_rover_model_difference() {
    // Station 1.5 km lower and ~7 km away; the data hold exactly the model
    // delays (ionosphere and troposphere). Code only: the station's carrier
    // rrc has the ionosphere's rate with the phase sign.
    let ephs = ephemerides();
    let rx = Receiver::rover();
    let lla = ecef_to_lla(&rx.pos0_ecef_m);
    let station = Receiver {
        pos0_ecef_m: lla_to_ecef(&Vector3::new(lla.x + 0.001, lla.y - 0.001, 100.0)),
        vel_ecef_mps: Vector3::zeros(),
        clock0_m: 300.0,
        drift_mps: 0.5,
        jump: None,
    };
    let ref_epochs: Vec<ObsEpoch> = (0..10)
        .map(|k| observe(&ephs, t0(), f64::from(k), &station, BOTH, &no_extra))
        .collect();
    let mask = 5f64.to_radians();
    let store = DgpsCorrections::new(crate::dgps::corrections_from_reference_station(
        &ephs,
        &ref_epochs,
        station.pos0_ecef_m,
        mask,
    ));
    let located = store.clone().with_reference_position(station.pos0_ecef_m);
    let mut prep = EpochPreparer::new(ephs.clone(), config(BOTH), Some(located));
    let mut unlocated = EpochPreparer::new(ephs.clone(), config(BOTH), Some(store));
    let spread = |v: &[f64]| {
        v.iter().cloned().fold(f64::MIN, f64::max) - v.iter().cloned().fold(f64::MAX, f64::min)
    };
    for k in 0..10 {
        let dt = f64::from(k);
        let ep = observe(&ephs, t0(), dt, &rx, BOTH, &no_extra);
        let res = residuals(&prep.prepare(&ep, 2381), &rx, dt);
        let pr: Vec<f64> = res.iter().map(|r| r.1).collect();
        assert!(spread(&pr) < 2e-3, "epoch {k}: {pr:?}");
        // Without the station position the tropospheric difference stays in.
        let res = residuals(&unlocated.prepare(&ep, 2381), &rx, dt);
        let pr: Vec<f64> = res.iter().map(|r| r.1).collect();
        assert!(spread(&pr) > 0.3, "epoch {k}: {pr:?}");
    }
}
