//! Per-epoch measurement preparation for tight GNSS/INS coupling (SYSTEM.md §3b,
//! seed 000 eq. 12-18): turns one RINEX observation epoch into a
//! [`navfuse_core::GnssRawEpoch`], with everything the GNSS layer can model removed
//! (IS-GPS-200 20.3.3.3.3.1-2 satellite clock with relativity and TGD, and either the
//! DGPS correction or the Klobuchar and Saastamoinen models). See docs/GNSS.md,
//! "Tight-coupling measurements and DGPS".
//!
//! Conventions (P pseudorange, L carrier \[cycles\], D Doppler \[Hz\], I and T the
//! broadcast model delays at the receiver, I_s and T_s at the DGPS station):
//! `P = rho + c dt_r - c (dt_sv - TGD) + I + T`, `lambda L = rho + c dt_r - c dt_sv - I +
//! T + lambda N`. Prepared:
//! - `pseudorange_m = P + c (dt_sv - TGD) - I - T`, or with DGPS
//!   `P + c (dt_sv - TGD) + prc + rrc (t - t_s) - (I + T - I_s - T_s)`;
//! - `carrier_m = lambda L + c (dt_sv - TGD) + I - T`, with DGPS plus the integral of
//!   rrc and the change of `I_s + T_s` since the start of the arc;
//! - `range_rate_mps = -lambda D + c d(dt_sv)/dt [+ rrc]` (atmospheric rates left).

use crate::dgps::{DgpsCorrection, DgpsCorrections};
use crate::ephemeris::SPEED_OF_LIGHT_MPS;
use crate::ephemeris_set::EphemerisSet;
use crate::geometry::{az_el, signal_path};
use crate::obs::{ObsEpoch, SatObs};
use crate::orbit_source::OrbitSource;
use crate::signal::ObsCode;
use crate::signal_plan::ChosenSignal;
use crate::spp::{
    solve_epoch, SppConfig, SppError, SppErrorModel, SppMeasurement, SppSolution, GPS_L1_HZ,
    GPS_L1_WAVELENGTH_M,
};
use crate::time::{GpsTime, SECONDS_PER_WEEK};
use nalgebra::Vector3;
use navfuse_core::earth::{c_ne, ecef_to_lla};
use navfuse_core::sat::{SatId, System};
use navfuse_core::{GnssFix, GnssRawEpoch, SatMeasurement};
use std::collections::BTreeMap;

#[cfg(test)]
pub(crate) mod tests;

/// A DGPS correction time-tagged up to this much after the measurement is taken as
/// the same epoch's (receiver clocks are steered within 1 ms of GPS time) [s].
const DGPS_SAME_EPOCH_S: f64 = 1e-3;

/// Gain and longest gap [s] of the smoothed model position.
const MODEL_POS_GAIN: f64 = 0.05;
const MODEL_POS_MAX_GAP_S: f64 = 10.0;

/// Settings of the preparation.
#[derive(Clone, Debug, PartialEq)]
pub struct TightPrepConfig {
    /// Elevation mask, ionosphere model, troposphere model, error model (incl.
    /// `dgps_sigma_m`) and FDE, for both the SPP and the prepared measurements.
    pub spp: SppConfig,
    /// Oldest DGPS correction used \[s\] (default 30).
    pub dgps_max_age_s: f64,
    /// Carrier phase 1-sigma at zenith \[m\] (default 0.003), elevation weighted like the
    /// code: times sqrt(var_el(el) / var_el(90 deg)).
    pub carrier_sigma_m: f64,
    /// Range-rate (Doppler) 1-sigma at zenith [m/s], elevation weighted the same way
    /// (default the SPP Doppler sigma 1 Hz x lambda_L1 = 0.19 m/s).
    pub doppler_sigma_mps: f64,
}

impl Default for TightPrepConfig {
    fn default() -> Self {
        TightPrepConfig {
            spp: SppConfig::default(),
            dgps_max_age_s: 30.0,
            carrier_sigma_m: 0.003,
            doppler_sigma_mps: SppErrorModel::default().doppler_sigma_hz * GPS_L1_WAVELENGTH_M,
        }
    }
}

/// One prepared epoch.
#[derive(Clone, Debug, PartialEq)]
pub struct PreparedEpoch {
    /// The measurements; `sats` is empty while no receiver position is known yet.
    pub raw: GnssRawEpoch,
    /// This epoch's SPP (with the DGPS corrections it had).
    pub spp: Result<SppSolution, SppError>,
    /// Prepared satellites with a pseudorange that got a DGPS correction.
    pub dgps_applied: usize,
    /// Prepared satellites with a pseudorange that had none (DGPS configured only).
    pub dgps_missing: usize,
}

/// Per-satellite state carried from the previous epoch.
#[derive(Clone, Copy, Debug)]
struct PrnState {
    /// Index of the epoch it belongs to.
    epoch: u64,
    /// Time of validity [s of the run's week].
    t_s: f64,
    has_carrier: bool,
    /// DGPS range-rate correction applied [m/s].
    rrc_mps: Option<f64>,
    /// Station model delays I + T (the rover's without a station position) [m].
    station_model_m: f64,
    /// Integrated rrc and station model change added to the carrier [m].
    acc_m: f64,
}

/// Receiver position, velocity and clock at a receiver time tag.
#[derive(Clone, Copy, Debug)]
struct RxEstimate {
    /// Receiver time tag [s of the run's week].
    t_tag_s: f64,
    pos_ecef_m: Vector3<f64>,
    vel_ecef_mps: Option<Vector3<f64>>,
    clock_m: f64,
    drift_mps: Option<f64>,
}

impl RxEstimate {
    /// Propagated to another tag with the velocity and drift, when known.
    fn predict(&self, t_tag_s: f64) -> RxEstimate {
        let dt = t_tag_s - self.t_tag_s;
        RxEstimate {
            t_tag_s,
            pos_ecef_m: self.pos_ecef_m + self.vel_ecef_mps.unwrap_or_default() * dt,
            clock_m: self.clock_m + self.drift_mps.unwrap_or(0.0) * dt,
            ..*self
        }
    }
}

/// Prepares successive receiver epochs; keeps the last receiver estimate and the
/// per-satellite carrier continuity and DGPS state. `O` gives the orbits: GPS
/// broadcast records ([`EphemerisSet`], the default), every system's
/// (`EphemerisStore`), or precise products (`PreciseSource`).
#[derive(Clone, Debug)]
pub struct EpochPreparer<O: OrbitSource = EphemerisSet> {
    ephs: O,
    cfg: TightPrepConfig,
    dgps: Option<DgpsCorrections>,
    sats: BTreeMap<SatId, PrnState>,
    last: Option<RxEstimate>,
    /// Smoothed position for the atmosphere models: (tag [s], ECEF [m], velocity).
    model_pos: Option<(f64, Vector3<f64>, Option<Vector3<f64>>)>,
    epoch: u64,
}

/// The GPS L1 C/A observations of a satellite as a chosen signal (C1C, L1C, D1C,
/// S1C); None without any of code, carrier and Doppler.
fn gps_l1(s: &SatObs) -> Option<ChosenSignal> {
    Some(ChosenSignal {
        sat: SatId::gps(s.prn),
        code: ObsCode(*b"C1C"),
        pseudorange_m: s.pseudorange_m.unwrap_or(f64::NAN),
        iono_free_with: None,
        frequency_hz: GPS_L1_HZ,
        carrier_cycles: s.carrier_cycles,
        lli: s.lli,
        doppler_hz: s.doppler_hz,
        cn0_dbhz: s.cn0_dbhz,
    })
    .filter(|_| s.pseudorange_m.is_some() || s.carrier_cycles.is_some() || s.doppler_hz.is_some())
}

impl<O: OrbitSource> EpochPreparer<O> {
    /// `dgps`: corrections of GPS satellites (RTCM 2 types 1/9 and the simulator's
    /// are GPS-only); other systems' pseudoranges keep the broadcast models.
    pub fn new(ephs: O, cfg: TightPrepConfig, dgps: Option<DgpsCorrections>) -> Self {
        EpochPreparer {
            ephs,
            cfg,
            dgps,
            sats: BTreeMap::new(),
            last: None,
            model_pos: None,
            epoch: 0,
        }
    }

    /// The configuration.
    pub fn config(&self) -> &TightPrepConfig {
        &self.cfg
    }

    /// Prepare one epoch (call in time order). `week` = the run's reference GPS week:
    /// `GnssRawEpoch.t` and `fix.t` are seconds of that week (may exceed 604800 across
    /// a rollover). They are times of validity: the receiver tag minus the estimated
    /// receiver clock.
    pub fn prepare(&mut self, epoch: &ObsEpoch, week: i32) -> PreparedEpoch {
        let sats: Vec<ChosenSignal> = epoch.sats.iter().filter_map(gps_l1).collect();
        self.prepare_signals(epoch.t, epoch.flag, &sats, week)
    }

    /// Prepare one epoch of chosen signals of any system (`SignalPlan::choose`;
    /// receiver tag `t`, RINEX epoch flag `flag`); as [`EpochPreparer::prepare`].
    pub fn prepare_signals(
        &mut self,
        t: GpsTime,
        flag: u8,
        sats: &[ChosenSignal],
        week: i32,
    ) -> PreparedEpoch {
        let c = SPEED_OF_LIGHT_MPS;
        self.epoch += 1;
        let t_tag_s = t.seconds_of_week(week);
        let predicted = self.last.map(|l| l.predict(t_tag_s));

        // DGPS corrections of this epoch: tags and correction times lie on the same
        // GPS-time grid up to the receiver clocks (kept within 1 ms), so a correction
        // up to 1 ms after the later of tag and true time belongs to this epoch.
        let t_est_s = t_tag_s - predicted.map_or(0.0, |p| p.clock_m) / c;
        let t_query_s = t_tag_s.max(t_est_s) + DGPS_SAME_EPOCH_S;
        let corrs: Vec<Option<DgpsCorrection>> = sats
            .iter()
            .map(|s| self.dgps_for(s.sat, t, t_query_s))
            .collect();

        // SPP measurements; with DGPS the model difference to the station at
        // `approx` (none without a position: the rover is taken at the station).
        let measurements = |approx: Option<Vector3<f64>>| -> Vec<SppMeasurement> {
            let model_diff = |sat| self.model_difference_m(sat, t, approx);
            sats.iter()
                .zip(&corrs)
                .filter(|(s, _)| s.pseudorange_m.is_finite())
                .map(|(s, corr)| {
                    let m = SppMeasurement::from(s);
                    SppMeasurement {
                        // range rate -lambda D + rrc: the DGPS rate enters the velocity
                        doppler_hz: s
                            .doppler_hz
                            .map(|d| d - corr.map_or(0.0, |k| k.rrc_mps) / m.wavelength_m()),
                        dgps_prc_m: corr.map(|k| k.at_m(t_est_s) - model_diff(s.sat)),
                        ..m
                    }
                })
                .collect()
        };
        let start = predicted.map(|p| (p.pos_ecef_m, p.clock_m));
        let mut meas = measurements(predicted.map(|p| p.pos_ecef_m));
        let mut spp = solve_epoch(&self.ephs, t, &meas, &self.cfg.spp, start);
        let station_known = self
            .dgps
            .as_ref()
            .and_then(|d| d.reference_pos_ecef_m())
            .is_some();
        if let (None, true, Ok(first)) = (predicted, station_known, &spp) {
            // First fix with a located station: redo with the model difference there.
            meas = measurements(Some(first.pos_ecef_m));
            spp = solve_epoch(&self.ephs, t, &meas, &self.cfg.spp, start);
        }
        // A failed residual test still locates the receiver well enough for the
        // geometry (100 m moves a satellite by ~1 mm): refit without FDE, no fix.
        let geometry = match &spp {
            Err(SppError::ResidualTestFailed { .. }) => {
                let cfg = SppConfig {
                    fde: false,
                    ..self.cfg.spp.clone()
                };
                solve_epoch(&self.ephs, t, &meas, &cfg, start).ok()
            }
            r => r.as_ref().ok().cloned(),
        };

        let rx = match geometry {
            Some(s) => {
                let est = RxEstimate {
                    t_tag_s,
                    pos_ecef_m: s.pos_ecef_m,
                    vel_ecef_mps: s.vel_ecef_mps,
                    clock_m: s.clock_bias_m,
                    drift_mps: s.clock_drift_mps,
                };
                self.last = Some(est);
                Some(est)
            }
            None => predicted,
        };
        let Some(rx) = rx else {
            return PreparedEpoch {
                raw: GnssRawEpoch {
                    t: t_tag_s,
                    sats: Vec::new(),
                    fix: None,
                },
                spp,
                dgps_applied: 0,
                dgps_missing: 0,
            };
        };

        let t_s = t_tag_s - rx.clock_m / c;
        let model_pos = self.smoothed_position(&rx);
        let fix = spp.as_ref().ok().map(|s| fix_from_spp(s, t_s));
        let mut prepared: Vec<SatMeasurement> = Vec::with_capacity(sats.len());
        let mut seen: Vec<SatId> = Vec::with_capacity(sats.len());
        let (mut dgps_applied, mut dgps_missing) = (0, 0);
        for (s, corr) in sats.iter().zip(&corrs) {
            if seen.contains(&s.sat) {
                continue;
            }
            seen.push(s.sat);
            let Some(m) = self.prepare_sat(t, flag, s, *corr, &rx, &model_pos, t_s) else {
                continue;
            };
            if m.pseudorange_m.is_some() {
                if m.dgps {
                    dgps_applied += 1;
                } else if self.dgps.is_some() {
                    dgps_missing += 1;
                }
            }
            prepared.push(m);
        }
        PreparedEpoch {
            raw: GnssRawEpoch {
                t: t_s,
                sats: prepared,
                fix,
            },
            spp,
            dgps_applied,
            dgps_missing,
        }
    }

    /// The DGPS correction for GPS satellite `sat` at `t_s` (s of the run's week),
    /// with the ephemeris' IODE, moved onto the run's time scale; None without DGPS
    /// or for another system.
    fn dgps_for(&self, sat: SatId, t: GpsTime, t_s: f64) -> Option<DgpsCorrection> {
        let store = self.dgps.as_ref()?;
        if sat.system != System::Gps {
            return None;
        }
        let iode = self.ephs.select(sat, t)?.iod;
        // The store's scale may start a week off the run's (rollover between them).
        let shift = ((store.first_t_s()? - t_s) / SECONDS_PER_WEEK).round() * SECONDS_PER_WEEK;
        let mut k = *store.lookup(sat.prn, t_s + shift, self.cfg.dgps_max_age_s, Some(iode))?;
        k.t_s -= shift;
        Some(k)
    }

    /// The position at which the atmosphere models are evaluated: the SPP position
    /// smoothed by a complementary filter (predicted with the mean Doppler velocity,
    /// pulled towards each position with gain 0.05), so that the SPP's metres of
    /// noise do not reach the carrier through the models' height gradient (the
    /// troposphere changes by 1.6 mm per metre of height at 10 deg elevation).
    fn smoothed_position(&mut self, rx: &RxEstimate) -> Vector3<f64> {
        let pos = match self.model_pos {
            Some((t0, p0, Some(v0))) => {
                let dt = rx.t_tag_s - t0;
                match rx.vel_ecef_mps {
                    Some(v) if dt > 0.0 && dt <= MODEL_POS_MAX_GAP_S => {
                        let pred = p0 + 0.5 * (v0 + v) * dt;
                        pred + MODEL_POS_GAIN * (rx.pos_ecef_m - pred)
                    }
                    _ => rx.pos_ecef_m,
                }
            }
            _ => rx.pos_ecef_m,
        };
        self.model_pos = Some((rx.t_tag_s, pos, rx.vel_ecef_mps));
        pos
    }

    /// Broadcast model delays (iono, tropo) as configured [m] at `pos_ecef_m` for a
    /// satellite at `sat_pos_ecef_m`, at `sow` (GPS s of week).
    fn models_at_m(
        &self,
        pos_ecef_m: &Vector3<f64>,
        sat_pos_ecef_m: &Vector3<f64>,
        sow: f64,
    ) -> (f64, f64) {
        let lla = ecef_to_lla(pos_ecef_m);
        let (az, el) = az_el(&lla, &(sat_pos_ecef_m - pos_ecef_m).normalize());
        self.cfg.spp.atmosphere_m(&lla, az, el, sow)
    }

    /// Models at `rx_pos_ecef_m` minus at the DGPS station for `sat` at `t` (no light
    /// time: the elevation only), 0 when either position is unknown [m].
    fn model_difference_m(
        &self,
        sat: SatId,
        t: GpsTime,
        rx_pos_ecef_m: Option<Vector3<f64>>,
    ) -> f64 {
        let (Some(rx), Some(eph)) = (rx_pos_ecef_m, self.ephs.select(sat, t)) else {
            return 0.0;
        };
        let sat = crate::geometry::SatOrbit::sat_state(&eph, t).pos_ecef_m;
        let Some((iono_s, tropo_s)) = self.station_models_m(&sat, t.sow) else {
            return 0.0;
        };
        let (iono, tropo) = self.models_at_m(&rx, &sat, t.sow);
        iono + tropo - iono_s - tropo_s
    }

    /// The same at the DGPS reference station, when its position is known.
    fn station_models_m(&self, sat_pos_ecef_m: &Vector3<f64>, sow: f64) -> Option<(f64, f64)> {
        let station = self.dgps.as_ref()?.reference_pos_ecef_m()?;
        Some(self.models_at_m(&station, sat_pos_ecef_m, sow))
    }

    /// One satellite; None without an ephemeris or usable observable, or below the
    /// mask. Updates the satellite's continuity state.
    #[allow(clippy::too_many_arguments)]
    fn prepare_sat(
        &mut self,
        t: GpsTime,
        flag: u8,
        s: &ChosenSignal,
        corr: Option<DgpsCorrection>,
        rx: &RxEstimate,
        model_pos_ecef_m: &Vector3<f64>,
        t_s: f64,
    ) -> Option<SatMeasurement> {
        let c = SPEED_OF_LIGHT_MPS;
        let lambda = c / s.frequency_hz;
        let cfg = &self.cfg.spp;
        let orbit = self.ephs.select(s.sat, t)?;
        let group_delay_s =
            orbit
                .record
                .group_delay_s(s.sat.system, s.code.band(), s.iono_free_with)?;
        let pr = Some(s.pseudorange_m).filter(|p| p.is_finite() && *p > 0.0);
        let doppler = s.doppler_hz.filter(|d| d.is_finite());
        let cycles = s.carrier_cycles.filter(|l| l.is_finite());
        if pr.is_none() && doppler.is_none() && cycles.is_none() {
            return None;
        }
        let lla = ecef_to_lla(&rx.pos_ecef_m);
        let vel = rx.vel_ecef_mps.unwrap_or_default();
        // Light time at the true reception time (tag - clock), as spp.rs.
        let t_true = t.add_s(-rx.clock_m / c);
        let sp = signal_path(&orbit, &rx.pos_ecef_m, &vel, t_true);
        let (_, el) = az_el(&lla, &sp.los_unit);
        if el.is_nan() || el < cfg.elevation_mask_rad {
            return None;
        }
        // IS-GPS-200 20.3.3.3.3.2: the single-frequency user's satellite clock is
        // dt_sv - TGD (each system's group delay of the code, `band_group_delay_s`).
        let sat_clock_m = c * (sp.sat_clock_bias_s - group_delay_s);
        // Broadcast models at the rover and at the DGPS station (taken equal when its
        // position is unknown: then the rover is assumed near it); the L1 Klobuchar
        // delay scaled to the signal, (f_L1 / f)^2.
        let iono_scale = (GPS_L1_HZ / s.frequency_hz).powi(2);
        let scaled = |(i, tr): (f64, f64)| (i * iono_scale, tr);
        let (iono_m, tropo_m) =
            scaled(self.models_at_m(model_pos_ecef_m, &sp.sat_pos_ecef_m, t.sow));
        let (iono_s_m, tropo_s_m) = self
            .station_models_m(&sp.sat_pos_ecef_m, t.sow)
            .map(scaled)
            .unwrap_or((iono_m, tropo_m));
        // An ionosphere-free code has no ionospheric delay left.
        let code_iono_m = if s.iono_free_with.is_some() {
            0.0
        } else {
            iono_m
        };
        // Code: the correction holds the station's delays, models included.
        let pseudorange_m = pr.map(|p| {
            p + sat_clock_m
                + match corr {
                    Some(k) => k.at_m(t_s) - (iono_m + tropo_m - iono_s_m - tropo_s_m),
                    None => -code_iono_m - tropo_m,
                }
        });
        let pr_var = cfg.pseudorange_variance_m2(
            s.sat.system,
            &orbit.accuracy,
            el,
            code_iono_m,
            corr.is_some(),
            s.iono_free_with.is_some(),
        ) + cfg.errors.cn0_variance_m2(s.cn0_dbhz);
        let em = &cfg.errors;
        let el_scale = (em.elevation_variance_m2(el)
            / em.elevation_variance_m2(std::f64::consts::FRAC_PI_2))
        .sqrt();
        let rrc_mps = corr.map(|k| k.rrc_mps);
        let range_rate_mps =
            doppler.map(|d| -lambda * d + c * sp.sat_clock_drift_s_per_s + rrc_mps.unwrap_or(0.0));

        // Carrier continuity: lock kept (LLI bit 0, RINEX 3.04 §5.3), epoch flag 0
        // (1 = power failure), and this satellite prepared with a carrier at the
        // previous epoch.
        let prev = self
            .sats
            .get(&s.sat)
            .copied()
            .filter(|p| p.epoch + 1 == self.epoch && p.has_carrier);
        let lost_lock = flag != 0 || s.lli & 1 != 0 || prev.is_none();
        // Carrier: the rover's models with the phase sign (-I + T) are removed (a
        // climbing UAV's troposphere changes by cm/s). With DGPS the integrated rrc
        // (trapezoids) is added, and the change of the station's models (I + T),
        // which rrc = d(prc)/dt removes with the code sign, put back. Restarts with
        // each arc; no increment across an epoch pair without DGPS, so the carrier
        // stays continuous when DGPS comes and goes.
        let station_model_m = iono_s_m + tropo_s_m;
        let acc_m = match prev {
            Some(p) if !lost_lock => match (p.rrc_mps, rrc_mps) {
                (Some(a), Some(b)) => {
                    p.acc_m + 0.5 * (a + b) * (t_s - p.t_s) + station_model_m - p.station_model_m
                }
                _ => p.acc_m,
            },
            _ => 0.0,
        };
        self.sats.insert(
            s.sat,
            PrnState {
                epoch: self.epoch,
                t_s,
                has_carrier: cycles.is_some(),
                rrc_mps,
                station_model_m,
                acc_m,
            },
        );
        Some(SatMeasurement {
            sat: s.sat,
            sat_pos_ecef_m: sp.sat_pos_ecef_m,
            sat_vel_ecef_mps: sp.sat_vel_ecef_mps,
            elevation_rad: el,
            pseudorange_m,
            pseudorange_std_m: pr_var.sqrt(),
            range_rate_mps,
            range_rate_std_mps: self.cfg.doppler_sigma_mps * el_scale,
            carrier_m: cycles.map(|l| lambda * l + sat_clock_m + iono_m - tropo_m + acc_m),
            carrier_std_m: self.cfg.carrier_sigma_m * el_scale,
            lost_lock,
            dgps: corr.is_some() && pseudorange_m.is_some(),
        })
    }
}

/// The loosely coupled fix of an SPP solution, at time of validity `t_s`.
fn fix_from_spp(s: &SppSolution, t_s: f64) -> GnssFix {
    let c_en = c_ne(s.lla.x, s.lla.y).transpose();
    GnssFix {
        t: t_s,
        lla: s.lla,
        std_ned: s.std_ned_m.map(|x| x.max(1e-3)),
        vel_ned: s.vel_ecef_mps.map(|v| c_en * v),
        vel_std_ned: s.vel_std_ned_mps.map(|v| v.map(|x| x.max(1e-4))),
    }
}
