//! Tests of SPP on a synthetic constellation.

use super::*;
use crate::atmosphere::{klobuchar_l1_delay_m, saastamoinen_slant_m};
use crate::constellation::nominal_gps24;
use crate::ephemeris_set::EphemerisSet;
use crate::geometry::{az_el, signal_path};
use crate::orbit_source::ura_variance_m2;
use navfuse_core::earth::c_ne;
use navfuse_core::earth::lla_to_ecef;
use navfuse_core::sat::SatId;

const ALPHA: [f64; 4] = [1.1176e-8, 1.4901e-8, -5.9605e-8, -1.1921e-7];
const BETA: [f64; 4] = [1.1469e5, 8.1920e4, -1.3107e5, -5.2429e5];

/// A receiver near Boulder, moving, with a u-blox-like clock (-1.5 ms, drifting).
struct Truth {
    pos_ecef_m: Vector3<f64>,
    lla: Vector3<f64>,
    vel_ecef_mps: Vector3<f64>,
    clock_bias_m: f64,
    clock_drift_mps: f64,
}

fn truth() -> Truth {
    let lla = Vector3::new(
        40.0967f64.to_radians(),
        (-105.1472f64).to_radians(),
        1_601.4,
    );
    let vel_ned = Vector3::new(1.2, -0.7, 0.1);
    Truth {
        pos_ecef_m: lla_to_ecef(&lla),
        lla,
        vel_ecef_mps: c_ne(lla.x, lla.y) * vel_ned,
        clock_bias_m: -1.5e-3 * SPEED_OF_LIGHT_MPS,
        clock_drift_mps: -60.0,
    }
}

/// The nominal constellation with non-zero clocks, TGDs and URAs.
fn ephemerides(toe: GpsTime) -> EphemerisSet {
    let mut ephs = nominal_gps24(toe);
    for (k, e) in ephs.iter_mut().enumerate() {
        let k = k as f64;
        e.af0_s = (k - 11.5) * 3e-5;
        e.af1_s_per_s = (k - 7.0) * 1e-12;
        e.tgd_s = (k - 12.0) * 1e-9;
        e.e = 0.002 + 0.0005 * k; // relativistic clock term non-zero
    }
    EphemerisSet::new(ephs)
}

/// Exact measurements of every satellite above `mask_deg` for the truth.
fn measure(ephs: &EphemerisSet, t_rx: GpsTime, tr: &Truth, mask_deg: f64) -> Vec<SppMeasurement> {
    let t_true = t_rx.add_s(-tr.clock_bias_m / SPEED_OF_LIGHT_MPS);
    let mut out = Vec::new();
    for prn in ephs.prns() {
        let eph = ephs.select(prn, t_rx).unwrap();
        let sp = signal_path(eph, &tr.pos_ecef_m, &tr.vel_ecef_mps, t_true);
        let (az, el) = az_el(&tr.lla, &sp.los_unit);
        if el < mask_deg.to_radians() {
            continue;
        }
        let iono = klobuchar_l1_delay_m(&ALPHA, &BETA, tr.lla.x, tr.lla.y, az, el, t_rx.sow);
        let tropo = saastamoinen_slant_m(tr.lla.x, tr.lla.z, el);
        let pr = sp.geometric_range_m + tr.clock_bias_m
            - SPEED_OF_LIGHT_MPS * (sp.sat_clock_bias_s - eph.tgd_s)
            + iono
            + tropo;
        let rr = sp.range_rate_mps + tr.clock_drift_mps
            - SPEED_OF_LIGHT_MPS * sp.sat_clock_drift_s_per_s;
        out.push(SppMeasurement::gps_l1(
            prn,
            pr,
            Some(-rr / GPS_L1_WAVELENGTH_M),
        ));
    }
    out
}

fn config() -> SppConfig {
    SppConfig {
        iono: IonoModel::Klobuchar {
            alpha: ALPHA,
            beta: BETA,
        },
        ..SppConfig::default()
    }
}

fn setup() -> (EphemerisSet, GpsTime, Truth, Vec<SppMeasurement>) {
    let toe = GpsTime::new(2381, 410_400.0);
    let ephs = ephemerides(toe);
    let t_rx = toe.add_s(500.252); // 8 satellites above 10 deg
    let tr = truth();
    let meas = measure(&ephs, t_rx, &tr, 5.0);
    (ephs, t_rx, tr, meas)
}

#[test]
fn recovers_position_velocity_and_clock_without_noise() {
    let (ephs, t_rx, tr, meas) = setup();
    assert!(meas.len() >= 6, "{} satellites", meas.len());
    let sol = solve_epoch(&ephs, t_rx, &meas, &config(), None).unwrap();
    let err = (sol.pos_ecef_m - tr.pos_ecef_m).norm();
    assert!(err < 1e-3, "position error {err} m");
    assert!((sol.clock_bias_m - tr.clock_bias_m).abs() < 1e-3);
    let v = sol.vel_ecef_mps.unwrap();
    assert!(
        (v - tr.vel_ecef_mps).norm() < 1e-3,
        "{v} vs {}",
        tr.vel_ecef_mps
    );
    assert!((sol.clock_drift_mps.unwrap() - tr.clock_drift_mps).abs() < 1e-3);
    assert!(sol.excluded_sats.is_empty());
    assert!(sol.chi2 < 1e-6);
    // Satellites between 5 and 10 deg are measured but masked.
    assert_eq!(sol.n_used + sol.masked_sats.len(), meas.len());
    assert!(sol
        .satellites
        .iter()
        .all(|s| s.el_rad >= 10f64.to_radians()));
    assert!(sol.dops.gdop >= sol.dops.pdop && sol.dops.pdop >= sol.dops.hdop);
    assert!(sol.std_ned_m.iter().all(|s| s.is_finite() && *s > 0.0));
    assert!((sol.lla - tr.lla).xy().norm() < 1e-9);
    let dt = sol.t_fix.diff_s(&t_rx) + tr.clock_bias_m / SPEED_OF_LIGHT_MPS;
    assert!(dt.abs() < 1e-9);

    // The same from the previous solution, through the solver, in fewer iterations.
    let mut solver = SppSolver::new(config());
    let first = solver.solve(&ephs, t_rx, &meas).unwrap();
    let second = solver.solve(&ephs, t_rx, &meas).unwrap();
    assert!((second.pos_ecef_m - tr.pos_ecef_m).norm() < 1e-3);
    assert!(second.iterations < first.iterations);
    // A start 3000 km off (a stale solution) is recovered from the Earth centre.
    let far = (tr.pos_ecef_m + Vector3::new(3e6, -1e6, 0.0), 5e5);
    let s = solve_epoch(&ephs, t_rx, &meas, &config(), Some(far)).unwrap();
    assert!((s.pos_ecef_m - tr.pos_ecef_m).norm() < 1e-3);
}

#[test]
fn dgps_corrections_replace_the_models() {
    // Per-satellite errors, removed by a DGPS correction that also holds the
    // atmosphere; satellites without one keep the models.
    let (ephs, t_rx, tr, meas) = setup();
    let clean = solve_epoch(&ephs, t_rx, &meas, &config(), None).unwrap();
    let corrected: Vec<SatId> = clean.used_sats.iter().copied().step_by(2).collect();
    let dgps: Vec<SppMeasurement> = meas
        .iter()
        .map(|m| match clean.satellites.iter().find(|s| s.sat == m.sat) {
            Some(s) if corrected.contains(&m.sat) => {
                let err = 4.0 * f64::from(m.sat.prn).sin();
                SppMeasurement {
                    pseudorange_m: m.pseudorange_m + err,
                    dgps_prc_m: Some(-(err + s.iono_m + s.tropo_m)),
                    ..*m
                }
            }
            _ => *m,
        })
        .collect();
    let sol = solve_epoch(&ephs, t_rx, &dgps, &config(), None).unwrap();
    assert!((sol.pos_ecef_m - tr.pos_ecef_m).norm() < 1e-3);
    assert!((sol.clock_bias_m - tr.clock_bias_m).abs() < 1e-3);
    assert_eq!(sol.used_sats, clean.used_sats);
    let em = &config().errors;
    for s in &sol.satellites {
        let dgps = corrected.contains(&s.sat);
        assert_eq!(dgps, s.iono_m == 0.0 && s.tropo_m == 0.0, "{}", s.sat);
        if dgps {
            let var = em.elevation_variance_m2(s.el_rad) + em.dgps_sigma_m.powi(2);
            assert!((s.sigma_m - var.sqrt()).abs() < 1e-12);
        }
    }
    // A non-finite correction makes the measurement unusable.
    let mut bad = dgps.clone();
    bad[0].dgps_prc_m = Some(f64::NAN);
    let sol = solve_epoch(&ephs, t_rx, &bad, &config(), None).unwrap();
    assert_eq!(sol.unusable_sats, vec![bad[0].sat]);
}

#[test]
fn every_model_term_matters() {
    // Leaving out TGD, iono or tropo on the solver side moves the solution.
    let (ephs, t_rx, tr, meas) = setup();
    let no_iono = SppConfig {
        fde: false,
        ..SppConfig::default()
    };
    let s = solve_epoch(&ephs, t_rx, &meas, &no_iono, None).unwrap();
    assert!((s.pos_ecef_m - tr.pos_ecef_m).norm() > 0.5);
    let no_tropo = SppConfig {
        tropo_saastamoinen: false,
        fde: false,
        ..config()
    };
    let s = solve_epoch(&ephs, t_rx, &meas, &no_tropo, None).unwrap();
    assert!((s.pos_ecef_m - tr.pos_ecef_m).norm() > 0.5);
}

#[test]
fn fde_excludes_a_biased_satellite() {
    let (ephs, t_rx, tr, mut meas) = setup();
    let cfg = config();
    let clean = solve_epoch(&ephs, t_rx, &meas, &cfg, None).unwrap();
    assert!(clean.n_used > 4 + FDE_MIN_REDUNDANCY, "{}", clean.n_used);
    for k in 0..clean.n_used {
        let bad = clean.used_sats[k];
        let m = meas.iter_mut().find(|m| m.sat == bad).unwrap();
        m.pseudorange_m += 100.0;
        let sol = solve_epoch(&ephs, t_rx, &meas, &cfg, None).unwrap();
        assert_eq!(sol.excluded_sats, vec![bad]);
        assert!(!sol.used_sats.contains(&bad));
        assert!((sol.pos_ecef_m - tr.pos_ecef_m).norm() < 1e-3);
        assert!(sol.chi2 <= sol.chi2_threshold.unwrap());
        // Without FDE the bias goes into the solution.
        let raw = SppConfig {
            fde: false,
            ..cfg.clone()
        };
        let sol = solve_epoch(&ephs, t_rx, &meas, &raw, None).unwrap();
        assert!((sol.pos_ecef_m - tr.pos_ecef_m).norm() > 1.0);
        assert!(sol.chi2 > sol.chi2_threshold.unwrap());
        let m = meas.iter_mut().find(|m| m.sat == bad).unwrap();
        m.pseudorange_m -= 100.0;
    }
}

#[test]
fn fde_with_five_satellites_detects_but_cannot_exclude() {
    let (ephs, t_rx, _, meas) = setup();
    let clean = solve_epoch(&ephs, t_rx, &meas, &config(), None).unwrap();
    let keep: Vec<SatId> = clean.used_sats[..5].to_vec();
    let mut five: Vec<SppMeasurement> = meas
        .iter()
        .filter(|m| keep.contains(&m.sat))
        .copied()
        .collect();
    five[2].pseudorange_m += 100.0;
    match solve_epoch(&ephs, t_rx, &five, &config(), None) {
        Err(e @ SppError::ResidualTestFailed { n_used: 5, .. }) => {
            assert!(e.to_string().contains("chi-square"), "{e}");
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn errors_instead_of_panics() {
    let (ephs, t_rx, _, meas) = setup();
    let cfg = config();
    let three = &meas[..3];
    let e = solve_epoch(&ephs, t_rx, three, &cfg, None).unwrap_err();
    assert_eq!(
        e,
        SppError::TooFewSatellites {
            available: 3,
            required: 4
        }
    );
    assert_eq!(e.to_string(), "too few satellites: 3 usable, 4 required");
    // Unknown PRNs, NaN and zero pseudoranges: nothing usable.
    let junk = [
        SppMeasurement {
            pseudorange_m: 2.1e7,
            ..SppMeasurement::gps_l1(31, 0.0, None)
        },
        SppMeasurement {
            pseudorange_m: f64::NAN,
            ..SppMeasurement::gps_l1(1, 0.0, None)
        },
        SppMeasurement {
            pseudorange_m: 0.0,
            ..SppMeasurement::gps_l1(2, 0.0, None)
        },
    ];
    let e = solve_epoch(&ephs, t_rx, &junk, &cfg, None).unwrap_err();
    assert_eq!(
        e,
        SppError::NoEphemeris {
            sats: vec![SatId::gps(31), SatId::gps(1), SatId::gps(2)]
        }
    );
    assert!(e.to_string().contains("G31 G01 G02"), "{e}");
    // Outside every ephemeris' fit interval.
    let e = solve_epoch(&ephs, t_rx.add_s(86_400.0), &meas, &cfg, None).unwrap_err();
    assert!(matches!(e, SppError::NoEphemeris { .. }));
    // Garbage pseudoranges: an error, never NaN.
    let mut bad = meas.clone();
    for (k, m) in bad.iter_mut().enumerate() {
        m.pseudorange_m = 1.0 + k as f64 * 1e7;
    }
    if let Ok(s) = solve_epoch(&ephs, t_rx, &bad, &cfg, None) {
        assert!(s.pos_ecef_m.iter().all(|x| x.is_finite()));
    }
    // A duplicated PRN counts once.
    let mut dup = meas[..3].to_vec();
    dup.push(meas[0]);
    assert!(matches!(
        solve_epoch(&ephs, t_rx, &dup, &cfg, None),
        Err(SppError::TooFewSatellites { available: 3, .. })
    ));
    // A min_satellites of 5 is honoured.
    let five = SppConfig {
        min_satellites: 5,
        ..cfg.clone()
    };
    assert!(matches!(
        solve_epoch(&ephs, t_rx, &meas[..4], &five, None),
        Err(SppError::TooFewSatellites { required: 5, .. })
    ));
    for e in [
        SppError::SingularGeometry,
        SppError::NotConverged {
            iterations: 10,
            last_step_m: 2.0,
        },
        SppError::PoorGeometry {
            gdop: 45.0,
            max_gdop: 30.0,
        },
    ] {
        assert!(!e.to_string().is_empty());
    }
}

#[test]
fn velocity_needs_four_dopplers() {
    let (ephs, t_rx, _, mut meas) = setup();
    let n = meas.len();
    for m in meas.iter_mut().take(n - 3) {
        m.doppler_hz = None;
    }
    let sol = solve_epoch(&ephs, t_rx, &meas, &config(), None).unwrap();
    assert!(sol.vel_ecef_mps.is_none() && sol.clock_drift_mps.is_none());
}

#[test]
fn elevation_weighting() {
    let mut em = SppErrorModel::default();
    let el = 30f64.to_radians();
    assert!((em.elevation_variance_m2(el) - (0.09 + 0.09 / 0.25)).abs() < 1e-12);
    em.elevation_sin_power = 1.0;
    assert!((em.elevation_variance_m2(el) - (0.09 + 0.09 / 0.5)).abs() < 1e-12);
    assert!(em.elevation_variance_m2(-0.1).is_finite());
}

#[test]
fn ura_rounds_up_to_the_is_gps_200_bound() {
    assert_eq!(ura_variance_m2(2.0), 2.4 * 2.4);
    assert_eq!(ura_variance_m2(2.4), 2.4 * 2.4);
    assert_eq!(ura_variance_m2(2.5), 3.4 * 3.4);
    assert_eq!(ura_variance_m2(1e5), 6144.0 * 6144.0);
    assert_eq!(ura_variance_m2(f64::NAN), 6144.0 * 6144.0);
}

#[test]
fn cn0_weighting_adds_the_signal_strength_term() {
    let (ephs, t_rx, _, mut meas) = setup();
    let mut cfg = config();
    let plain = solve_epoch(&ephs, t_rx, &meas, &cfg, None).unwrap();
    meas.iter_mut()
        .enumerate()
        .for_each(|(k, m)| m.cn0_dbhz = Some(if k == 0 { 32.0 } else { 52.0 }));
    // Off by default: C/N0 given, weights unchanged.
    let same = solve_epoch(&ephs, t_rx, &meas, &cfg, None).unwrap();
    assert_eq!(plain.satellites, same.satellites);
    cfg.errors.cn0_sigma_m = Some(0.5);
    let w = solve_epoch(&ephs, t_rx, &meas, &cfg, None).unwrap();
    for (a, b) in plain.satellites.iter().zip(&w.satellites) {
        // 20 dB below the reference: 0.5^2 x 100 = 25 m^2 more; at it: 0.25 m^2.
        let extra = if a.sat == meas[0].sat { 25.0 } else { 0.25 };
        assert!(
            (b.sigma_m.powi(2) - a.sigma_m.powi(2) - extra).abs() < 1e-9,
            "{}",
            a.sat
        );
    }
    assert_eq!(cfg.errors.cn0_variance_m2(None), 0.0);
    assert_eq!(cfg.errors.cn0_variance_m2(Some(f64::NAN)), 0.0);
}
