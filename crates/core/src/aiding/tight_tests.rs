//! Tight coupling with several systems (aiding/tight.rs): synthetic epochs of a
//! static receiver seeing GPS and Galileo satellites, the Galileo pseudoranges
//! carrying an inter-system bias, through the whole navigator.

use super::pseudorange::isb_block;
use crate::config::NavConfig;
use crate::earth::{c_ne, lla_add_ned, lla_diff_ned, lla_to_ecef};
use crate::events::{Event, RunSummary};
use crate::nav::navigator::NavError;
use crate::nav::run::run;
use crate::nav::tests::{cfg, static_sample};
use crate::sat::{SatId, System};
use crate::smoother::extra_names;
use crate::types::{GnssRawEpoch, ImuSample, Measurement, SatMeasurement};
use nalgebra::Vector3;
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};
use std::sync::Arc;

/// The true Galileo-to-GPS inter-system bias \[m\].
const ISB_E_M: f64 = 7.0;
/// Receiver clock: bias at t = 0 \[m\] and drift \[m/s\].
const CLOCK_M: f64 = 3000.0;
const DRIFT_MPS: f64 = 0.3;
/// Pseudorange and range-rate noise (1-sigma, as reported) \[m, m/s\].
const PR_SIGMA_M: f64 = 1.0;
const RR_SIGMA_MPS: f64 = 0.05;
/// Convergence with 5 GPS + 4 Galileo satellites, then a blockage with 1 + 2.
const CONVERGED_T: f64 = 300.0;
const END_T: f64 = 360.0;
const IMU_DT: f64 = 0.02;

/// Satellites as (system, PRN, azimuth deg, elevation deg); the blockage keeps
/// those marked true.
const SKY: [(System, u8, f64, f64, bool); 9] = [
    (System::Gps, 5, 0.0, 70.0, true),
    (System::Gps, 12, 60.0, 30.0, false),
    (System::Gps, 17, 150.0, 45.0, false),
    (System::Gps, 24, 240.0, 25.0, false),
    (System::Gps, 30, 300.0, 50.0, false),
    // E05: the same number as G05, a different satellite.
    (System::Galileo, 5, 30.0, 40.0, false),
    (System::Galileo, 11, 120.0, 20.0, true),
    (System::Galileo, 19, 200.0, 60.0, false),
    (System::Galileo, 26, 280.0, 35.0, true),
];

/// A low-cost IMU: white noise on the increments, the filter told the same.
fn config(systems: &[System]) -> NavConfig {
    let mut c = cfg();
    c.imu_noise.arw = Vector3::repeat(2e-4);
    c.imu_noise.vrw = Vector3::repeat(1e-2);
    c.tight.enabled = true;
    c.gnss.systems = systems.to_vec();
    c
}

/// The static IMU's increments with white noise (seeded).
fn imu(c: &NavConfig) -> Vec<ImuSample> {
    let mut rng = rand_pcg::Pcg64::seed_from_u64(19);
    let n = Normal::new(0.0, 1.0).unwrap();
    let mut g = || Vector3::from_fn(|_, _| n.sample(&mut rng));
    let n_imu = (END_T / IMU_DT).round() as usize;
    (0..=n_imu)
        .map(|k| {
            let mut s = static_sample(c, k as f64 * IMU_DT, IMU_DT);
            s.dtheta += g().component_mul(&c.imu_noise.arw) * IMU_DT.sqrt();
            s.dvel += g().component_mul(&c.imu_noise.vrw) * IMU_DT.sqrt();
            s
        })
        .collect()
}

/// The antenna of the static receiver, ECEF \[m\].
fn antenna_ecef(c: &NavConfig) -> Vector3<f64> {
    let lla = c.initial.lla.unwrap();
    let crate::config::AttitudeInit::Given(rpy) = c.initial.attitude else {
        unreachable!()
    };
    let l_n = crate::attitude::c_bn_from_euler(&rpy) * c.gnss.lever_arm_b;
    lla_to_ecef(&lla_add_ned(&lla, &l_n))
}

/// One epoch a second: every satellite of `SKY` up to `CONVERGED_T` (GPS from
/// `gps_from` on), then only the blockage's. Pseudoranges carry the clock, the ISB
/// (Galileo) and noise.
fn epochs(c: &NavConfig, gps_from: f64) -> Vec<Measurement> {
    let mut rng = rand_pcg::Pcg64::seed_from_u64(5);
    let n = Normal::new(0.0, 1.0).unwrap();
    let lla = c.initial.lla.unwrap();
    let r_ant = antenna_ecef(c);
    let c_ne = c_ne(lla.x, lla.y);
    let mut out = Vec::new();
    for k in 1..=END_T as usize {
        let t = k as f64;
        let mut sats = Vec::new();
        for &(system, prn, az, el, kept) in &SKY {
            if (t > CONVERGED_T && !kept) || (system == System::Gps && t < gps_from) {
                continue;
            }
            let (az, el) = (az.to_radians(), el.to_radians());
            let u_n = Vector3::new(az.cos() * el.cos(), az.sin() * el.cos(), -el.sin());
            let sat_pos = r_ant + c_ne * u_n * 2.2e7;
            let isb = if system == System::Galileo {
                ISB_E_M
            } else {
                0.0
            };
            let clock = CLOCK_M + DRIFT_MPS * t;
            sats.push(SatMeasurement {
                sat: SatId::new(system, prn),
                sat_pos_ecef_m: sat_pos,
                sat_vel_ecef_mps: Vector3::zeros(),
                elevation_rad: el,
                pseudorange_m: Some(
                    (sat_pos - r_ant).norm() + clock + isb + PR_SIGMA_M * n.sample(&mut rng),
                ),
                pseudorange_std_m: PR_SIGMA_M,
                range_rate_mps: Some(DRIFT_MPS + RR_SIGMA_MPS * n.sample(&mut rng)),
                range_rate_std_mps: RR_SIGMA_MPS,
                carrier_m: None,
                carrier_std_m: 0.003,
                lost_lock: false,
                dgps: false,
            });
        }
        out.push(Measurement::GnssRaw(Arc::new(GnssRawEpoch {
            t,
            sats,
            fix: None,
        })));
    }
    out
}

/// What a run gives: the Galileo ISB estimate and its 1-sigma at `CONVERGED_T`
/// (None without the state), the largest position error up to then (from 60 s on),
/// the error then, the largest horizontal and 3-D errors over the blockage \[m\], and
/// the summary.
struct Outcome {
    isb: Option<(f64, f64)>,
    converged_err_m: f64,
    /// The position error at `CONVERGED_T` \[m\].
    final_err_m: f64,
    blockage_h_m: f64,
    blockage_3d_m: f64,
    summary: RunSummary,
}

fn navigate(systems: &[System], gps_from: f64) -> Outcome {
    let c = config(systems);
    let truth = c.initial.lla.unwrap();
    let (mut isb, mut converged_err_m, mut final_err_m) = (None, 0.0, 0.0);
    let (mut blockage_h_m, mut blockage_3d_m) = (0.0, 0.0);
    let summary = run::<NavError>(
        &c,
        imu(&c).into_iter().map(Ok),
        &epochs(&c, gps_from),
        None,
        |n| {
            let t = n.nav().t;
            let e = lla_diff_ned(&n.nav().lla, &truth);
            if (60.0..=CONVERGED_T).contains(&t) {
                converged_err_m = f64::max(converged_err_m, e.norm());
            }
            if t > CONVERGED_T {
                blockage_h_m = f64::max(blockage_h_m, e.xy().norm());
                blockage_3d_m = f64::max(blockage_3d_m, e.norm());
            }
            if isb.is_none() && t >= CONVERGED_T {
                final_err_m = e.norm();
                let block = isb_block(System::Galileo).unwrap();
                isb = Some(n.layout().index(block).map(|i| {
                    let names = extra_names(n.layout());
                    let k = names.iter().position(|s| s == "isb_galileo_m").unwrap();
                    let v = n.nominal().extra_values(n.layout())[k];
                    (v, n.covariance()[(i, i)].sqrt())
                }));
            }
            Ok(())
        },
        |_| {},
    )
    .unwrap();
    Outcome {
        isb: isb.flatten(),
        converged_err_m,
        final_err_m,
        blockage_h_m,
        blockage_3d_m,
        summary,
    }
}

/// The run's `IsbSet` events.
fn isb_events(summary: &RunSummary) -> Vec<&Event> {
    summary
        .events
        .iter()
        .filter(|e| matches!(e, Event::IsbSet { .. }))
        .collect()
}

/// GPS + Galileo with a +7 m inter-system bias: the bias is set from the first
/// epoch's Galileo residuals and converges to 7 m, the position stays at the truth,
/// and the bias shows in the summary's source states.
#[test]
fn inter_system_bias_converges_to_the_truth() {
    let o = navigate(&[System::Gps, System::Galileo], 0.0);
    let (isb, sd) = o.isb.expect("Galileo ISB state");
    eprintln!(
        "ISB_E at {CONVERGED_T} s: {isb:.3} m (sigma {sd:.3} m, truth {ISB_E_M}); largest position error 60-{CONVERGED_T} s: {:.3} m",
        o.converged_err_m
    );
    assert!((isb - ISB_E_M).abs() < 0.3 && sd < 0.3, "{isb} {sd}");
    assert!(o.converged_err_m < 1.0, "{}", o.converged_err_m);
    let set = isb_events(&o.summary);
    assert_eq!(set.len(), 1, "{set:?}");
    let Event::IsbSet {
        system,
        isb_m,
        sats,
        ..
    } = set[0]
    else {
        unreachable!()
    };
    assert_eq!((*system, *sats), (System::Galileo, 4));
    assert!((isb_m - ISB_E_M).abs() < 3.0, "{isb_m}");
    let st = o
        .summary
        .source_states
        .iter()
        .find(|s| s.name == "isb_galileo_m")
        .expect("source state");
    assert!((st.value[0] - ISB_E_M).abs() < 0.5, "{st:?}");
    assert_eq!(o.summary.gnss_sats_ignored, 0);
}

/// After convergence, 60 s with only 1 GPS + 2 Galileo satellites: with the ISB
/// known, the two Galileo pseudoranges constrain the position; the same data with
/// Galileo ignored (1 GPS satellite) drifts much further.
#[test]
fn one_gps_two_galileo_hold_the_position_with_the_isb() {
    let multi = navigate(&[System::Gps, System::Galileo], 0.0);
    let gps = navigate(&[System::Gps], 0.0);
    eprintln!(
        "blockage 1 G + 2 E, largest error over {} s: {:.3} m horizontal, {:.3} m 3-D; GPS only (1 G): {:.3} m horizontal, {:.3} m 3-D",
        END_T - CONVERGED_T,
        multi.blockage_h_m,
        multi.blockage_3d_m,
        gps.blockage_h_m,
        gps.blockage_3d_m
    );
    assert!(gps.isb.is_none());
    // Galileo ignored: 4 satellites for 300 epochs, 2 for 60, counted.
    assert_eq!(gps.summary.gnss_sats_ignored, 4 * 300 + 2 * 60);
    assert!(
        multi.blockage_3d_m < 0.3 * gps.blockage_3d_m,
        "{} vs {}",
        multi.blockage_3d_m,
        gps.blockage_3d_m
    );
}

/// No GPS satellite for the first 60 s: Galileo stands in for GPS (the clock bias
/// takes its clock, its ISB starts at 0); once GPS comes the filter moves the 7 m
/// into the ISB, the position back at the truth.
#[test]
fn galileo_stands_in_until_gps_comes() {
    let o = navigate(&[System::Gps, System::Galileo], 60.0);
    let (isb, sd) = o.isb.expect("Galileo ISB state");
    eprintln!(
        "Galileo alone for 60 s: ISB_E at {CONVERGED_T} s {isb:.3} m (sigma {sd:.3} m); position error 60-{CONVERGED_T} s at most {:.3} m, {:.3} m at the end",
        o.converged_err_m, o.final_err_m
    );
    let set = isb_events(&o.summary);
    assert!(
        matches!(set[..], [Event::IsbSet { isb_m, sats: 4, .. }] if *isb_m == 0.0),
        "{set:?}"
    );
    assert!((isb - ISB_E_M).abs() < 0.5, "{isb} {sd}");
    // GPS's arrival moves the solution while the 7 m find their place.
    assert!(o.converged_err_m < 3.0, "{}", o.converged_err_m);
    assert!(o.final_err_m < 1.0, "{}", o.final_err_m);
}
