//! GNSS simulation: constellation, raw L1 C/A measurements with an error budget,
//! DGPS corrections from a reference station, receiver fixes, dual-antenna heading,
//! and the events that disturb them (outages, blockage, spoofing, cycle slips).
//!
//! Pseudorange (SYSTEM.md §3b; seed 000 eq. 12):
//! `P = rho + c (dt_r - dt_s) + I + T + E_orbit + E_sa + E_clk + E_mp + eps`, where
//! rho is the geometric range with light time and Sagnac (navfuse_gnss::geometry),
//! dt_s the broadcast clock (with relativity, minus TGD), I and T the broadcast
//! Klobuchar and Saastamoinen model delays (when `model_delays`) plus their residual
//! errors. Each error source of seed 000 Table 1 is a time-correlated process with the
//! configured 1-sigma (docs/SIMULATOR.md lists the processes and their mappings).
//! Carrier phase: the same with the ionosphere sign reversed, its own small noise and
//! multipath, plus an integer ambiguity. Doppler: -(d/dt of the phase range)/lambda.

use std::collections::{BTreeMap, VecDeque};

use nalgebra::Vector3;
use navfuse_core::earth::{c_ne, ecef_to_lla, lla_to_ecef};
use navfuse_core::sat::{SatId, System};
use navfuse_gnss::ephemeris::{Ephemeris, SPEED_OF_LIGHT_MPS};
use navfuse_gnss::ephemeris_store::EphemerisStore;
use navfuse_gnss::signal::carrier_frequency_hz;
use navfuse_io::rinex_obs::SatObs;

use crate::random::{GaussMarkov, Stream};

mod epoch;
mod processes;
mod spec;

use processes::SmoothGm;
pub use processes::{elevation_scale, iono_obliquity};
pub use spec::{
    default_isb_m, systems_of, DgpsSpec, ErrorBudget, EventSpec, FixSpec, GnssSpec, HeadingSpec,
    SatRef, SpoofMode,
};

/// GPS L1 frequency \[Hz\] and wavelength \[m\].
pub const L1_HZ: f64 = 1_575.42e6;
pub const L1_WAVELENGTH_M: f64 = SPEED_OF_LIGHT_MPS / L1_HZ;

/// The carrier frequency \[Hz\] of the signal simulated for the satellite of `eph`:
/// GPS L1 C/A, Galileo E1 (1575.42 MHz), BeiDou B1I (1561.098 MHz), GLONASS L1OF on
/// the record's channel (1602 + 0.5625 k MHz), QZSS L1.
pub fn sim_carrier_hz(eph: &Ephemeris) -> f64 {
    let system = eph.sat().system;
    let (band, channel) = match eph {
        Ephemeris::BeiDou(_) => (2, None),
        Ephemeris::Glonass(g) => (1, Some(g.freq_channel)),
        _ => (1, None),
    };
    carrier_frequency_hz(system, band, channel).unwrap_or(L1_HZ)
}

/// Ionosphere single-layer height [m] and mean Earth radius [m] for the obliquity.
const IONO_SHELL_M: f64 = 350e3;
const EARTH_RADIUS_M: f64 = 6_371e3;

// ---------------------------------------------------------------------------------
// Simulator state

/// Per-satellite processes.
struct SatProc {
    iono_common: SmoothGm,
    iono_diff: SmoothGm,
    sat_clock: SmoothGm,
    orbit_common: SmoothGm,
    orbit_diff: SmoothGm,
    sa: SmoothGm,
    multipath: GaussMarkov,
    phase_multipath: GaussMarkov,
    ref_multipath: GaussMarkov,
    rng: Stream,
    ambiguity: i64,
    /// Tracked at the previous epoch.
    tracked: bool,
    /// Loss-of-lock indicator for the next output.
    lli_pending: bool,
}

/// Error components of one pseudorange \[m\] (slant), for gnss_errors.csv.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ErrorParts {
    pub iono: f64,
    pub tropo: f64,
    pub sat_clock: f64,
    pub orbit: f64,
    pub multipath: f64,
    pub noise: f64,
    pub rx_clock: f64,
    pub sa: f64,
}

impl ErrorParts {
    pub fn total(&self) -> f64 {
        self.iono
            + self.tropo
            + self.sat_clock
            + self.orbit
            + self.multipath
            + self.noise
            + self.rx_clock
            + self.sa
    }
}

/// One satellite at one epoch, with its truth.
#[derive(Clone, Debug)]
pub struct SatEpoch {
    /// The satellite (`obs.prn` is its number in its system).
    pub sat: SatId,
    pub obs: SatObs,
    pub el_rad: f64,
    pub az_rad: f64,
    /// Errors in the pseudorange (excluding the broadcast model delays).
    pub errors: ErrorParts,
    /// Residual of each source after the DGPS correction (None without DGPS or
    /// without a correction for this satellite).
    pub dgps_residual: Option<ErrorParts>,
    pub dgps_age_s: Option<f64>,
    /// Spoofing-induced range change \[m\] (0 when not spoofed).
    pub spoof_range_m: f64,
}

/// A DGPS correction (RTCM-style PRC/RRC) for one satellite.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DgpsCorrection {
    /// Time the correction refers to (GPS s of week).
    pub t: f64,
    pub prn: u8,
    /// Add to the measured pseudorange \[m\].
    pub prc_m: f64,
    /// Its rate [m/s]: correction at t' = prc + rrc (t' - t).
    pub rrc_mps: f64,
    pub iode: u16,
    /// Per-source parts of -prc (what the reference station saw), for the residuals.
    parts: ErrorParts,
    parts_rate: ErrorParts,
}

/// A receiver fix (antenna), possibly spoofed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fix {
    pub t: f64,
    pub lla: Vector3<f64>,
    pub std_ned: Vector3<f64>,
    pub vel_ned: Vector3<f64>,
    pub vel_std: f64,
    pub spoofed: bool,
}

/// Everything produced at one GNSS epoch.
#[derive(Clone, Debug, Default)]
pub struct GnssEpoch {
    pub t: f64,
    /// Visible and tracked satellites (empty during an outage).
    pub sats: Vec<SatEpoch>,
    pub fix: Option<Fix>,
    /// Dual-antenna heading \[rad\] and its std \[rad\].
    pub heading: Option<(f64, f64)>,
    /// Corrections computed at this epoch (written to dgps.csv).
    pub corrections: Vec<DgpsCorrection>,
    /// Receiver clock bias \[m\] (truth).
    pub rx_clock_m: f64,
    /// Active spoofing offset of the antenna position (NED, m), if any.
    pub spoof_offset_ned: Option<Vector3<f64>>,
    /// Outage in force (nothing output).
    pub outage: bool,
}

/// The GNSS simulator.
pub struct GnssSim {
    spec: GnssSpec,
    ephs: EphemerisStore,
    iono_alpha: [f64; 4],
    iono_beta: [f64; 4],
    week: i32,
    t0: f64,
    lever_b: Vector3<f64>,
    procs: BTreeMap<SatId, SatProc>,
    tropo_common: SmoothGm,
    tropo_diff: SmoothGm,
    rx_clock: SmoothGm,
    rng_tropo: Stream,
    rng_rx: Stream,
    /// Random-walk part of each non-GPS system's ISB \[m\] and its stream (empty when
    /// `isb_walk_m_per_sqrth` is 0).
    isb_walk: BTreeMap<System, (f64, Stream)>,
    fix_err: [GaussMarkov; 3],
    rng_fix: Stream,
    rng_heading: Stream,
    ref_lla: Option<Vector3<f64>>,
    /// Latest corrections available to the rover, per PRN.
    latest: Vec<Option<DgpsCorrection>>,
    /// Corrections waiting for their latency.
    pending: VecDeque<DgpsCorrection>,
    last_dgps_t: f64,
    /// Antenna truth history for replay spoofing (t, lla, vel_ned).
    history: VecDeque<(f64, Vector3<f64>, Vector3<f64>)>,
    last_t: Option<f64>,
}

/// Broadcast Klobuchar coefficients used when the navigation source has none (a
/// typical set; written to nav.rnx so users can apply the same model).
pub const DEFAULT_IONO_ALPHA: [f64; 4] = [1.1176e-8, 7.4506e-9, -5.9605e-8, -5.9605e-8];
pub const DEFAULT_IONO_BETA: [f64; 4] = [9.0112e4, 3.2768e4, -1.9661e5, -6.5536e4];

impl GnssSim {
    /// `ephs`: the constellation (every simulated system; GPS PRNs 1-32 used);
    /// `iono`: Klobuchar coefficients if known.
    pub fn new(
        spec: &GnssSpec,
        ephs: EphemerisStore,
        iono: Option<([f64; 4], [f64; 4])>,
        seed: u64,
        week: u32,
        t0: f64,
        start_lla: &Vector3<f64>,
    ) -> Self {
        let e = &spec.errors;
        let mut procs = BTreeMap::new();
        let (res_scale, ref_mp, iono_res, tropo_res, orbit_res) = match &spec.dgps {
            Some(d) => (
                d.baseline_km / d.residual_baseline_km,
                d.ref_multipath_m,
                d.iono_residual_m,
                d.tropo_residual_m,
                d.orbit_residual_m,
            ),
            None => (0.0, 0.0, 0.0, 0.0, 0.0),
        };
        // Split each spatially correlated source so that common² + diff² = sigma².
        let split = |sigma: f64, diff: f64| -> (f64, f64) {
            let d = diff.min(sigma);
            ((sigma * sigma - d * d).sqrt(), d)
        };
        let (iono_c, iono_d) = split(e.iono_m, iono_res * res_scale);
        let (tropo_c, tropo_d) = split(e.tropo_m, tropo_res * res_scale);
        let (orbit_c, orbit_d) = split(e.orbit_m, orbit_res * res_scale);
        for sat in ephs.sats() {
            if sat.system == System::Gps && (sat.prn == 0 || sat.prn > 32) {
                continue;
            }
            let mut rng = Stream::new(seed, &format!("gnss.sat.{sat}"));
            let p = SatProc {
                iono_common: SmoothGm::new(iono_c, e.iono_tau_s, &mut rng),
                iono_diff: SmoothGm::new(iono_d, e.iono_tau_s, &mut rng),
                sat_clock: SmoothGm::new(e.sat_clock_m, e.sat_clock_tau_s, &mut rng),
                orbit_common: SmoothGm::new(orbit_c, e.orbit_tau_s, &mut rng),
                orbit_diff: SmoothGm::new(orbit_d, e.orbit_tau_s, &mut rng),
                sa: SmoothGm::new(e.sa_m, e.sa_tau_s, &mut rng),
                multipath: GaussMarkov::new(e.multipath_m, e.multipath_tau_s, &mut rng),
                phase_multipath: GaussMarkov::new(e.phase_multipath_m, e.multipath_tau_s, &mut rng),
                ref_multipath: GaussMarkov::new(ref_mp, e.multipath_tau_s, &mut rng),
                ambiguity: (rng.uniform_range(-1e5, 1e5)).round() as i64,
                tracked: false,
                lli_pending: false,
                rng,
            };
            procs.insert(sat, p);
        }
        let mut rng_tropo = Stream::new(seed, "gnss.tropo");
        let mut rng_rx = Stream::new(seed, "gnss.rx_clock");
        let isb_walk = if e.isb_walk_m_per_sqrth > 0.0 {
            let mut v: Vec<System> = ephs.sats().iter().map(|s| s.system).collect();
            v.dedup();
            v.into_iter()
                .filter(|s| *s != System::Gps)
                .map(|s| {
                    (
                        s,
                        (0.0, Stream::new(seed, &format!("gnss.isb.{}", s.letter()))),
                    )
                })
                .collect()
        } else {
            BTreeMap::new()
        };
        let mut rng_fix = Stream::new(seed, "gnss.fix");
        let (fh, fv, ftau) = match &spec.fix {
            Some(f) => (
                f.horizontal_std_m,
                f.vertical_std_m,
                if f.corr_time_s > 0.0 {
                    f.corr_time_s
                } else {
                    1e-9
                },
            ),
            None => (0.0, 0.0, 1.0),
        };
        let ref_lla = spec.dgps.as_ref().map(|d| {
            let b = d.bearing_deg.to_radians();
            let ned = Vector3::new(b.cos(), b.sin(), 0.0) * d.baseline_km * 1e3;
            let r = lla_to_ecef(start_lla) + c_ne(start_lla.x, start_lla.y) * ned;
            // Same ellipsoidal height as the start.
            let mut lla = ecef_to_lla(&r);
            lla.z = start_lla.z;
            lla
        });
        let (alpha, beta) = iono.unwrap_or((DEFAULT_IONO_ALPHA, DEFAULT_IONO_BETA));
        GnssSim {
            spec: spec.clone(),
            ephs,
            iono_alpha: alpha,
            iono_beta: beta,
            week: week as i32,
            t0,
            lever_b: Vector3::from(spec.antenna_lever_arm_m),
            procs,
            tropo_common: SmoothGm::new(tropo_c, e.tropo_tau_s, &mut rng_tropo),
            tropo_diff: SmoothGm::new(tropo_d, e.tropo_tau_s, &mut rng_tropo),
            rx_clock: SmoothGm::new(e.rx_clock_m, e.rx_clock_tau_s, &mut rng_rx),
            rng_tropo,
            rng_rx,
            isb_walk,
            fix_err: [
                GaussMarkov::new(fh, ftau, &mut rng_fix),
                GaussMarkov::new(fh, ftau, &mut rng_fix),
                GaussMarkov::new(fv, ftau, &mut rng_fix),
            ],
            rng_fix,
            rng_heading: Stream::new(seed, "gnss.heading"),
            ref_lla,
            latest: vec![None; 33],
            pending: VecDeque::new(),
            last_dgps_t: f64::NEG_INFINITY,
            history: VecDeque::new(),
            last_t: None,
        }
    }

    /// Klobuchar coefficients in use.
    pub fn iono_coefficients(&self) -> ([f64; 4], [f64; 4]) {
        (self.iono_alpha, self.iono_beta)
    }

    /// Reference station position (lat, lon rad, h m), when DGPS is on.
    pub fn reference_lla(&self) -> Option<Vector3<f64>> {
        self.ref_lla
    }

    fn in_outage(&self, rel: f64) -> bool {
        self.spec.events.iter().any(|e| match *e {
            EventSpec::Outage { start_s, end_s } => rel > start_s && rel < end_s,
            EventSpec::OutageEvery {
                length_s,
                period_s,
                from_s,
                until_s,
            } => {
                if rel <= from_s {
                    return false;
                }
                let k = ((rel - from_s) / period_s).floor();
                let s = from_s + k * period_s;
                if until_s.is_some_and(|u| s >= u) {
                    return false;
                }
                rel > s && rel < s + length_s
            }
            _ => false,
        })
    }

    fn spoof_at(&self, rel: f64) -> Option<&EventSpec> {
        self.spec.events.iter().find(|e| match e {
            EventSpec::Spoof { start_s, end_s, .. } => rel >= *start_s && rel < *end_s,
            _ => false,
        })
    }

    /// The antenna position and NED velocity the receiver reports (true or false).
    fn antenna_track(
        &self,
        rel: f64,
        lla: Vector3<f64>,
        vel: Vector3<f64>,
    ) -> (Vector3<f64>, Vector3<f64>, Option<Vector3<f64>>) {
        let Some(EventSpec::Spoof {
            mode,
            start_s,
            offset_m,
            velocity_mps,
            delay_s,
            ..
        }) = self.spoof_at(rel)
        else {
            return (lla, vel, None);
        };
        let to_lla = |base: &Vector3<f64>, d_ned: &Vector3<f64>| -> Vector3<f64> {
            ecef_to_lla(&(lla_to_ecef(base) + c_ne(base.x, base.y) * d_ned))
        };
        match mode {
            SpoofMode::Jump => {
                let d = Vector3::from(*offset_m);
                (to_lla(&lla, &d), vel, Some(d))
            }
            SpoofMode::Drift => {
                let v = Vector3::from(*velocity_mps);
                let d = v * (rel - start_s);
                (to_lla(&lla, &d), vel + v, Some(d))
            }
            SpoofMode::Replay => {
                let t_old = self.t0 + rel - delay_s;
                let old = self
                    .history
                    .iter()
                    .min_by(|a, b| (a.0 - t_old).abs().total_cmp(&(b.0 - t_old).abs()))
                    .copied();
                match old {
                    Some((_, old_lla, old_vel)) => {
                        let p = to_lla(&old_lla, &Vector3::from(*offset_m));
                        let d = navfuse_core::earth::lla_diff_ned(&p, &lla);
                        (p, old_vel, Some(d))
                    }
                    None => (lla, vel, None),
                }
            }
        }
    }
}
