//! DGPS pseudorange corrections (RTCM-style PRC/RRC): a store with the lookup a rover
//! uses, and the corrections a reference station at a known position computes from
//! its own observations. See docs/GNSS.md, "Tight-coupling measurements and DGPS",
//! and SYSTEM.md §3b (seed 000 eq. 13).
//!
//! Convention (as the simulator's dgps.csv): the corrected pseudorange at time t is
//! `P + prc_m + rrc_mps (t - t_s)`, rrc = d(prc)/dt; prc removes the satellite clock
//! and orbit errors and the atmospheric delays seen at the reference station (the
//! broadcast models' part included), so a corrected pseudorange gets no ionosphere or
//! troposphere model, only the models' difference between rover and station when
//! the station position is known (`with_reference_position`).

use crate::ephemeris::SPEED_OF_LIGHT_MPS;
use crate::ephemeris_set::EphemerisSet;
use crate::geometry::{az_el, signal_path};
use crate::obs::ObsEpoch;
use crate::spp::GPS_L1_WAVELENGTH_M;
use nalgebra::Vector3;
use navfuse_core::earth::ecef_to_lla;

/// One satellite's pseudorange correction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DgpsCorrection {
    /// Time the correction refers to: GPS seconds of week, continuing past 604800
    /// after a week rollover (one continuous scale per store) \[s\].
    pub t_s: f64,
    pub prn: u8,
    /// Pseudorange correction, added to the measured pseudorange \[m\].
    pub prc_m: f64,
    /// Its rate [m/s].
    pub rrc_mps: f64,
    /// IODE of the ephemeris the reference station used, if known.
    pub iode: Option<u16>,
}

impl DgpsCorrection {
    /// The correction at time `t_s` (same scale as `self.t_s`): prc + rrc (t - t_s) \[m\].
    pub fn at_m(&self, t_s: f64) -> f64 {
        self.prc_m + self.rrc_mps * (t_s - self.t_s)
    }
}

/// Corrections for all satellites, by PRN and time.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DgpsCorrections {
    /// Index = PRN; each list sorted by `t_s` (stable: for equal times the later
    /// input wins the lookup).
    by_prn: Vec<Vec<DgpsCorrection>>,
    len: usize,
    first_t_s: Option<f64>,
    /// Reference station antenna, ECEF [m], when known.
    reference_pos_ecef_m: Option<Vector3<f64>>,
}

impl DgpsCorrections {
    /// Build the store; corrections with a non-finite time, prc or rrc are dropped.
    pub fn new(corrections: Vec<DgpsCorrection>) -> Self {
        let mut by_prn: Vec<Vec<DgpsCorrection>> = vec![Vec::new(); 256];
        let mut len = 0;
        for c in corrections {
            if c.t_s.is_finite() && c.prc_m.is_finite() && c.rrc_mps.is_finite() {
                if let Some(list) = by_prn.get_mut(usize::from(c.prn)) {
                    list.push(c);
                    len += 1;
                }
            }
        }
        for list in &mut by_prn {
            list.sort_by(|a, b| a.t_s.total_cmp(&b.t_s));
        }
        let first_t_s = by_prn
            .iter()
            .filter_map(|l| l.first())
            .map(|c| c.t_s)
            .min_by(f64::total_cmp);
        DgpsCorrections {
            by_prn,
            len,
            first_t_s,
            reference_pos_ecef_m: None,
        }
    }

    /// The same with the reference station position (ECEF \[m\]; ignored unless
    /// finite). With it the rover also removes the difference of the broadcast
    /// atmosphere models between itself and the station (the station's model delays
    /// are inside prc): metres for a UAV kilometres above the station.
    pub fn with_reference_position(mut self, pos_ecef_m: Vector3<f64>) -> Self {
        self.reference_pos_ecef_m = pos_ecef_m
            .iter()
            .all(|x| x.is_finite())
            .then_some(pos_ecef_m);
        self
    }

    /// The reference station position, ECEF \[m\], if known.
    pub fn reference_pos_ecef_m(&self) -> Option<Vector3<f64>> {
        self.reference_pos_ecef_m
    }

    /// Number of corrections kept.
    pub fn len(&self) -> usize {
        self.len
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Earliest correction time \[s\], if any.
    pub fn first_t_s(&self) -> Option<f64> {
        self.first_t_s
    }

    /// The latest correction for `prn` with `t_s` at or before `t_s` (1 ns tolerance),
    /// at most `max_age_s` old, whose IODE matches `iode` (the ephemeris in use; a
    /// correction or query without IODE matches any). During an ephemeris changeover
    /// an older correction for the ephemeris in use is taken if it is young enough.
    pub fn lookup(
        &self,
        prn: u8,
        t_s: f64,
        max_age_s: f64,
        iode: Option<u16>,
    ) -> Option<&DgpsCorrection> {
        let list = self.by_prn.get(usize::from(prn))?;
        let end = list.partition_point(|c| c.t_s <= t_s + 1e-9);
        list.get(..end)?
            .iter()
            .rev()
            .take_while(|c| t_s - c.t_s <= max_age_s)
            .find(|c| match (c.iode, iode) {
                (Some(a), Some(b)) => a == b,
                _ => true,
            })
    }
}

/// Weight of the reference clock gain: the smoothed clock moves this fraction of the
/// way to each epoch's code mean (time constant ~20 epochs).
const REF_CLOCK_GAIN: f64 = 0.05;
/// Beta of the alpha-beta filter, for the drift when no satellite gives a rate.
const REF_CLOCK_DRIFT_GAIN: f64 = REF_CLOCK_GAIN * REF_CLOCK_GAIN / (2.0 - REF_CLOCK_GAIN);
/// A code-mean innovation above this is a receiver clock jump (ms steering): the
/// smoothed clock restarts from the code mean [m].
const REF_CLOCK_JUMP_M: f64 = 1_000.0;
/// Epochs further apart restart the clock filter and break carrier continuity [s].
const REF_MAX_GAP_S: f64 = 30.0;

/// Per-PRN reference-station state of the previous epoch.
#[derive(Clone, Copy)]
struct RefPrn {
    epoch: usize,
    /// lambda L + c (dt_sv - TGD) - geometric range [m].
    carrier_minus_range_m: Option<f64>,
    /// Carrier rate over the interval ending at this epoch [m/s], its length [s].
    carrier_rate: Option<(f64, f64)>,
}

/// One satellite at one reference epoch.
struct RefSat {
    prn: u8,
    iode: u16,
    el_rad: f64,
    /// P + c (dt_sv - TGD) - range = c dt_ref + errors [m].
    code_res_m: f64,
    /// d(code_res)/dt from the carrier: mean over the last interval [m/s], and
    /// that interval [s].
    carrier_rate: Option<(f64, f64)>,
    /// The same extrapolated to this epoch [m/s].
    carrier_rate_now_mps: Option<f64>,
    /// d(code_res)/dt from the Doppler [m/s].
    doppler_rate_mps: Option<f64>,
    /// Carrier minus range, for the next epoch [m].
    carrier_minus_range_m: Option<f64>,
}

/// Corrections computed by a reference station at `ref_pos_ecef_m` from its
/// observations (one correction per satellite above `elevation_mask_rad` with a
/// pseudorange and an ephemeris, at every epoch).
///
/// `prc = -(P - rho + c (dt_sv - TGD) - c dt_ref)` (IS-GPS-200 20.3.3.3.3.1-2), rho the
/// geometric range with light time and Sagnac at the true reception time. The
/// reference clock c dt_ref is, per epoch, the sin^2(el)-weighted mean of
/// `P - rho + c (dt_sv - TGD)` over the satellites, smoothed by a complementary
/// filter: propagated with the epoch's weighted-mean carrier rate (Doppler when no
/// carrier is continuous; the last drift otherwise, alpha-beta), pulled towards the
/// code mean with gain 0.05, restarted on a jump above 1 km (ms clock steering) or a
/// gap above 30 s. So the ms-level clock and its drift leave the corrections; what is
/// left is common to all satellites and goes into the rover's clock states.
///
/// `rrc = -(rate - drift_ref)`. The rate of `P - rho + c (dt_sv - TGD)` is measured
/// by the time difference of `lambda L + c (dt_sv - TGD) - rho` over the last
/// interval when the carrier is continuous (LLI bit 0 clear, epoch flag 0, previous
/// epoch present), extrapolated from mid-interval to the epoch with the interval
/// before (rrc is the rate at t_s); else by `-lambda D + c d(dt_sv)/dt - d(rho)/dt`;
/// else rrc = 0. drift_ref is the weighted mean of the same kind of rate over the
/// satellites with a continuous carrier (all, when none has one), so a carrier
/// rate and a Doppler rate are both taken relative to the same satellites (a clock
/// jump seen by the carrier, a Doppler bias cancel). The carrier sees the
/// ionosphere's rate with the phase sign: for the code the rrc is off by 2 dI/dt
/// (mm/s in quiet conditions).
///
/// `t_s` is the true time (tag - dt_ref) in seconds of the first epoch's GPS week.
pub fn corrections_from_reference_station(
    ephs: &EphemerisSet,
    epochs: &[ObsEpoch],
    ref_pos_ecef_m: Vector3<f64>,
    elevation_mask_rad: f64,
) -> Vec<DgpsCorrection> {
    let c = SPEED_OF_LIGHT_MPS;
    let ref_lla = ecef_to_lla(&ref_pos_ecef_m);
    let Some(week) = epochs.first().map(|e| e.t.week) else {
        return Vec::new();
    };
    let mut out = Vec::new();
    let mut prns: Vec<Option<RefPrn>> = vec![None; 256];
    // Smoothed clock: (tag time [s of week], c dt_ref [m], drift [m/s]).
    let mut clock: Option<(f64, f64, f64)> = None;
    for (k, ep) in epochs.iter().enumerate() {
        let t_tag = ep.t.seconds_of_week(week);
        let gap = clock.map(|(tp, _, _)| t_tag - tp);
        let continuous_epoch =
            ep.flag == 0 && gap.is_some_and(|dt| dt > 0.0 && dt <= REF_MAX_GAP_S);
        // Predicted clock for the light time (a ms error would move the satellites).
        let mut clk_m = match (clock, gap) {
            (Some((_, x, v)), Some(dt)) => x + v * dt,
            _ => 0.0,
        };
        let mut sats: Vec<RefSat> = Vec::new();
        for _pass in 0..3 {
            sats.clear();
            let t_true = ep.t.add_s(-clk_m / c);
            // Interval since the previous epoch in true time (a clock jump changes it).
            let dt_true = clock
                .map(|(tp, x, _)| (t_tag - clk_m / c) - (tp - x / c))
                .filter(|dt| continuous_epoch && *dt > 0.0);
            for s in &ep.sats {
                let Some(p) = s.pseudorange_m.filter(|p| p.is_finite() && *p > 0.0) else {
                    continue;
                };
                if sats.iter().any(|x| x.prn == s.prn) {
                    continue;
                }
                let Some(eph) = ephs.select(s.prn, ep.t) else {
                    continue;
                };
                let sp = signal_path(eph, &ref_pos_ecef_m, &Vector3::zeros(), t_true);
                let (_, el) = az_el(&ref_lla, &sp.los_unit);
                if el.is_nan() || el < elevation_mask_rad {
                    continue;
                }
                let sat_clock_m = c * (sp.sat_clock_bias_s - eph.tgd_s);
                let cmr = s
                    .carrier_cycles
                    .filter(|l| l.is_finite())
                    .map(|l| GPS_L1_WAVELENGTH_M * l + sat_clock_m - sp.geometric_range_m);
                let prev = prns
                    .get(usize::from(s.prn))
                    .copied()
                    .flatten()
                    .filter(|pv| pv.epoch + 1 == k && s.lli & 1 == 0);
                let before = prev.and_then(|p| p.carrier_minus_range_m);
                let carrier = match (cmr, before, dt_true) {
                    (Some(now), Some(before), Some(dt)) => Some(((now - before) / dt, dt)),
                    _ => None,
                };
                // The mean rate is the rate at mid-interval: extrapolate it to this
                // epoch with the previous interval's (rrc is the rate at t_s).
                let carrier_rate_now_mps =
                    carrier.map(|(m, dt)| match prev.and_then(|p| p.carrier_rate) {
                        Some((m_prev, dt_prev)) => m + (m - m_prev) * dt / (dt + dt_prev),
                        None => m,
                    });
                let doppler_rate = s.doppler_hz.filter(|d| d.is_finite()).map(|d| {
                    -GPS_L1_WAVELENGTH_M * d + c * sp.sat_clock_drift_s_per_s - sp.range_rate_mps
                });
                sats.push(RefSat {
                    prn: s.prn,
                    iode: eph.iode,
                    el_rad: el,
                    code_res_m: p + sat_clock_m - sp.geometric_range_m,
                    carrier_rate: carrier,
                    carrier_rate_now_mps,
                    doppler_rate_mps: doppler_rate,
                    carrier_minus_range_m: cmr,
                });
            }
            let Some(z) = weighted_mean(sats.iter().map(|s| (s.el_rad, Some(s.code_res_m)))) else {
                break;
            };
            // Re-solve the light time unless the clock moved by less than 10 ns
            // (satellite range rates < 1 km/s: < 10 um of range).
            let moved = (z - clk_m).abs() > 3.0;
            clk_m = z;
            if !moved {
                break;
            }
        }
        let Some(z) = weighted_mean(sats.iter().map(|s| (s.el_rad, Some(s.code_res_m)))) else {
            continue;
        };
        // Clock drift over the interval: the mean carrier rate if any satellite has
        // one, else the Doppler rate.
        let any_carrier = sats.iter().any(|s| s.carrier_rate.is_some());
        let d = if any_carrier {
            weighted_mean(sats.iter().map(|s| (s.el_rad, s.carrier_rate.map(|r| r.0))))
        } else {
            weighted_mean(sats.iter().map(|s| (s.el_rad, s.doppler_rate_mps)))
        };
        let (x, v) = match (clock, gap) {
            (Some((tp, x, v)), Some(dt)) if dt > 0.0 && dt <= REF_MAX_GAP_S => {
                // Carrier rates are means over the true-time interval.
                let dt_true = (t_tag - z / c) - (tp - x / c);
                let pred = x + d.map_or(v * dt, |d| d * dt_true);
                let innov = z - pred;
                if innov.abs() > REF_CLOCK_JUMP_M {
                    (z, d.unwrap_or(v))
                } else {
                    let v = d.unwrap_or(v + REF_CLOCK_DRIFT_GAIN * innov / dt);
                    (pred + REF_CLOCK_GAIN * innov, v)
                }
            }
            _ => (z, d.unwrap_or(0.0)),
        };
        clock = Some((t_tag, x, v));
        let t_s = t_tag - x / c;
        // The station's drift at this epoch, on the satellites that have carrier
        // rates (else all), from those rates and from their Dopplers: each rrc is
        // taken relative to the same satellites (a clock jump or a Doppler bias
        // cancels), so what is common goes to the rover's clock drift.
        let in_ref = |s: &RefSat| !any_carrier || s.carrier_rate.is_some();
        let drift_now = weighted_mean(sats.iter().map(|s| {
            let r = if any_carrier {
                s.carrier_rate_now_mps
            } else {
                s.doppler_rate_mps
            };
            (s.el_rad, r)
        }));
        let drift_doppler = weighted_mean(
            sats.iter()
                .map(|s| (s.el_rad, s.doppler_rate_mps.filter(|_| in_ref(s)))),
        );
        for s in &sats {
            let rrc_mps = match (s.carrier_rate_now_mps, s.doppler_rate_mps) {
                (Some(r), _) => drift_now.map_or(0.0, |d| d - r),
                (None, Some(r)) => drift_doppler.map_or(0.0, |d| d - r),
                _ => 0.0,
            };
            out.push(DgpsCorrection {
                t_s,
                prn: s.prn,
                prc_m: -(s.code_res_m - x),
                rrc_mps,
                iode: Some(s.iode),
            });
            if let Some(slot) = prns.get_mut(usize::from(s.prn)) {
                *slot = Some(RefPrn {
                    epoch: k,
                    carrier_minus_range_m: s.carrier_minus_range_m,
                    carrier_rate: s.carrier_rate,
                });
            }
        }
    }
    out
}

/// sin^2(el)-weighted mean of the values present; None if none.
fn weighted_mean(items: impl Iterator<Item = (f64, Option<f64>)>) -> Option<f64> {
    let (mut sw, mut swx) = (0.0, 0.0);
    for (el, x) in items {
        if let Some(x) = x {
            let w = el.sin().powi(2).max(1e-6);
            sw += w;
            swx += w * x;
        }
    }
    (sw > 0.0).then(|| swx / sw)
}
#[cfg(test)]
mod tests {
    use super::*;
    use crate::tight_prep::tests::{ephemerides, observe, t0, Receiver, NO_ATM};

    fn corr(t_s: f64, prn: u8, prc_m: f64, iode: Option<u16>) -> DgpsCorrection {
        DgpsCorrection {
            t_s,
            prn,
            prc_m,
            rrc_mps: 0.5,
            iode,
        }
    }

    #[test]
    fn lookup_latest_within_age_with_matching_iode() {
        let store = DgpsCorrections::new(vec![
            corr(20.0, 5, 2.0, Some(7)),
            corr(10.0, 5, 1.0, Some(7)),
            corr(30.0, 5, 3.0, Some(8)), // new ephemeris at the station
            corr(30.0, 6, 9.0, None),
            corr(f64::NAN, 5, 0.0, None),       // dropped
            corr(40.0, 6, f64::INFINITY, None), // dropped
        ]);
        assert_eq!(store.len(), 4);
        assert_eq!(store.first_t_s(), Some(10.0));
        let prc = |prn, t, age, iode| store.lookup(prn, t, age, iode).map(|c| c.prc_m);
        assert_eq!(prc(5, 9.9, 30.0, Some(7)), None); // nothing yet
        assert_eq!(prc(5, 10.0, 30.0, Some(7)), Some(1.0)); // at t_s
        assert_eq!(prc(5, 25.0, 30.0, Some(7)), Some(2.0)); // latest before
        assert_eq!(prc(5, 35.0, 30.0, Some(8)), Some(3.0));
        // The rover still uses IODE 7: the older correction for it, if young enough.
        assert_eq!(prc(5, 35.0, 30.0, Some(7)), Some(2.0));
        assert_eq!(prc(5, 35.0, 10.0, Some(7)), None);
        assert_eq!(prc(5, 35.0, 30.0, Some(9)), None);
        assert_eq!(prc(5, 35.0, 30.0, None), Some(3.0)); // no IODE check
                                                         // Age limit (inclusive).
        assert_eq!(prc(5, 60.0, 30.0, Some(8)), Some(3.0));
        assert_eq!(prc(5, 60.1, 30.0, Some(8)), None);
        // A correction without IODE matches any ephemeris; other PRNs have none.
        assert_eq!(prc(6, 31.0, 30.0, Some(1)), Some(9.0));
        assert_eq!(prc(7, 31.0, 30.0, None), None);
        let c = store.lookup(5, 25.0, 30.0, None).unwrap();
        assert!((c.at_m(25.0) - (2.0 + 0.5 * 5.0)).abs() < 1e-12);
        assert!(DgpsCorrections::new(Vec::new()).is_empty());
        assert_eq!(DgpsCorrections::default().lookup(5, 1.0, 30.0, None), None);
    }

    #[test]
    fn reference_station_corrections_remove_per_satellite_errors() {
        const C: f64 = SPEED_OF_LIGHT_MPS;
        let ephs = ephemerides();
        // Errors per satellite: bias + drift, and +7 m on one of them.
        let faulty = 9u8;
        let extra = move |prn: u8, dt: f64| {
            let p = f64::from(prn);
            let rate = 0.05 * (p - 12.0);
            let bias = 3.0 * (p * 1.7).sin() + if prn == faulty { 7.0 } else { 0.0 };
            (bias + rate * dt, rate)
        };
        // The station clock jumps by 1 ms at 12 s; the receiver keeps the carrier
        // continuous (only the code and the time tag jump).
        let jump_m = -1e-3 * C;
        let station = Receiver {
            jump: Some((12.0, jump_m)),
            clock0_m: 0.8e-3 * C,
            drift_mps: 30.0,
            vel_ecef_mps: Vector3::zeros(),
            ..Receiver::rover()
        };
        let lli_prn = 13u8;
        let epochs: Vec<ObsEpoch> = (0..25)
            .map(|k| {
                let mut ep = observe(&ephs, t0(), f64::from(k), &station, NO_ATM, &extra);
                for s in &mut ep.sats {
                    // A common Doppler bias cancels; one satellite's shows where its
                    // rrc came from the Doppler.
                    let bias_hz = if s.prn == lli_prn { 0.7 } else { 0.2 };
                    s.doppler_hz = s.doppler_hz.map(|d| d + bias_hz);
                    if k >= 12 {
                        s.carrier_cycles =
                            s.carrier_cycles.map(|l| l - jump_m / GPS_L1_WAVELENGTH_M);
                    }
                    if k == 5 && s.prn == lli_prn {
                        s.lli = 1;
                    }
                }
                ep
            })
            .collect();
        let out = corrections_from_reference_station(
            &ephs,
            &epochs,
            station.pos0_ecef_m,
            5f64.to_radians(),
        );
        assert!(out.iter().any(|c| c.prn == faulty) && out.iter().any(|c| c.prn == lli_prn));
        let doppler_bias_mps = 0.5 * GPS_L1_WAVELENGTH_M; // 0.7 - 0.2 Hz
        for k in 0..25 {
            let dt = f64::from(k);
            let tag = t0().sow + dt;
            let at_k: Vec<&DgpsCorrection> =
                out.iter().filter(|c| (c.t_s - tag).abs() < 0.01).collect();
            assert!(at_k.len() >= 6, "epoch {k}: {}", at_k.len());
            // t_s is the true time: tag - clock / c (to the common error's ~ns).
            assert!((at_k[0].t_s - (tag - station.clock(dt) / C)).abs() < 1e-7);
            // prc + error is the same for every satellite (the residual of the
            // smoothed station clock), so the +7 m is in the faulty one's prc.
            let left: Vec<f64> = at_k
                .iter()
                .map(|c| c.prc_m + extra(c.prn, c.t_s - t0().sow).0)
                .collect();
            let mean = left.iter().sum::<f64>() / left.len() as f64;
            for (c, l) in at_k.iter().zip(&left) {
                assert!(
                    (l - mean).abs() < 1e-3,
                    "epoch {k} G{:02}: {}",
                    c.prn,
                    l - mean
                );
                assert_eq!(c.iode, ephs.select(c.prn, t0()).map(|e| e.iode));
            }
            // rrc + error rate: common too, except where it came from the (biased)
            // Doppler while the others had the carrier (epoch 0: all Doppler).
            let rrc: Vec<(u8, f64)> = at_k
                .iter()
                .map(|c| (c.prn, c.rrc_mps + extra(c.prn, 0.0).1))
                .collect();
            let others = rrc.iter().find(|r| r.0 != lli_prn).unwrap().1;
            for (prn, r) in rrc.iter().filter(|_| k > 0) {
                let expect = if k == 5 && *prn == lli_prn {
                    doppler_bias_mps
                } else {
                    0.0
                };
                assert!(
                    (r - others - expect).abs() < 1e-4,
                    "epoch {k} G{prn:02}: {}",
                    r - others
                );
            }
        }
        assert!(corrections_from_reference_station(&ephs, &[], Vector3::zeros(), 0.1).is_empty());
    }
}
