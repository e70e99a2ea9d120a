//! The `[gnss]` scenario tables: constellation and receiver, the error budget, fixes,
//! dual-antenna heading, DGPS, and the events (outages, blockage, spoofing, cycle
//! slips), with their defaults and checks.

use std::collections::BTreeMap;

use nalgebra::Vector3;
use navfuse_core::sat::{SatId, System};
use serde::Deserialize;

use crate::trajectory::Trajectory;

/// `[gnss]`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GnssSpec {
    /// Epoch rate \[Hz\]; must divide the IMU rate.
    #[serde(default = "one")]
    pub rate_hz: f64,
    /// "nominal24" (bundled 24-slot GPS constellation), "seed000" (seed 000 Table 3's
    /// six satellites) or "rinex" (ephemerides from `rinex_nav`).
    #[serde(default = "nominal")]
    pub constellation: String,
    /// RINEX navigation file (relative to the scenario file) for `constellation = "rinex"`.
    pub rinex_nav: Option<String>,
    /// Systems simulated, by RINEX letter: "G" GPS, "E" Galileo, "C" BeiDou, "R" GLONASS (default
    /// ["G"]). Non-GPS satellites come from the bundled constellations
    /// (navfuse_gnss::constellation), or from `rinex_nav` with `constellation = "rinex"`.
    #[serde(default = "gps_only")]
    pub systems: Vec<String>,
    /// Elevation mask \[deg\].
    #[serde(default = "ten")]
    pub elevation_mask_deg: f64,
    /// Antenna phase centre from the IMU centre, IMU frame F-R-D \[m\].
    #[serde(default)]
    pub antenna_lever_arm_m: [f64; 3],
    /// Write obs.rnx / nav.rnx (raw measurements).
    #[serde(default = "yes")]
    pub raw: bool,
    /// GNSS-IMU time offset tau \[s\] (the convention of navfuse's `[filter]
    /// time_offset`): a GNSS epoch tagged t was taken at IMU time t + tau. The IMU,
    /// odometer and barometer files are tagged tau later than GPS time; GNSS, heading,
    /// DGPS and the truth stay on GPS time.
    #[serde(default)]
    pub time_offset_s: f64,
    #[serde(default)]
    pub errors: ErrorBudget,
    /// Receiver fixes for loose coupling (gnss.txt); absent = none.
    pub fix: Option<FixSpec>,
    /// Dual-antenna heading (heading.txt); absent = none.
    pub heading: Option<HeadingSpec>,
    /// DGPS reference station and corrections (dgps.csv); absent = none.
    pub dgps: Option<DgpsSpec>,
    /// Outages, blockage, spoofing, cycle slips, loss of lock.
    #[serde(default, rename = "event")]
    pub events: Vec<EventSpec>,
}

pub(super) fn one() -> f64 {
    1.0
}
fn ten() -> f64 {
    10.0
}
fn yes() -> bool {
    true
}
fn gps_only() -> Vec<String> {
    vec!["G".into()]
}
fn nominal() -> String {
    "nominal24".into()
}

/// `[gnss.errors]`: 1-sigma of each source \[m\] and its correlation time \[s\]. Defaults:
/// seed 000 Table 1, GPS column (SA on). Ionosphere and troposphere are zenith values
/// (slant = mapping x zenith); multipath and receiver noise are zenith values scaled by
/// sqrt((1 + 1/sin² el) / 2).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ErrorBudget {
    #[serde(default = "d_iono")]
    pub iono_m: f64,
    #[serde(default = "d_1800")]
    pub iono_tau_s: f64,
    #[serde(default = "d_tropo")]
    pub tropo_m: f64,
    #[serde(default = "d_3600")]
    pub tropo_tau_s: f64,
    #[serde(default = "d_clk")]
    pub sat_clock_m: f64,
    #[serde(default = "d_1800")]
    pub sat_clock_tau_s: f64,
    #[serde(default = "d_orbit")]
    pub orbit_m: f64,
    #[serde(default = "d_1800")]
    pub orbit_tau_s: f64,
    #[serde(default = "d_one")]
    pub multipath_m: f64,
    #[serde(default = "d_30")]
    pub multipath_tau_s: f64,
    #[serde(default = "d_one")]
    pub noise_m: f64,
    #[serde(default = "d_rxclk")]
    pub rx_clock_m: f64,
    #[serde(default = "d_600")]
    pub rx_clock_tau_s: f64,
    /// Selective Availability (seed 000 Table 1: 100 m); 0 = off (as since 2000).
    #[serde(default = "d_sa")]
    pub sa_m: f64,
    #[serde(default = "d_120")]
    pub sa_tau_s: f64,
    /// Carrier-phase white noise at zenith \[m\].
    #[serde(default = "d_phase_noise")]
    pub phase_noise_m: f64,
    /// Carrier-phase multipath at zenith \[m\] (tau = multipath_tau_s).
    #[serde(default = "d_phase_mp")]
    pub phase_multipath_m: f64,
    /// Doppler white noise at zenith [m/s].
    #[serde(default = "d_doppler")]
    pub doppler_noise_mps: f64,
    /// C/N0 at zenith [dB-Hz]; lower elevations lose 20 log10 of the noise scaling.
    #[serde(default = "d_cn0")]
    pub cn0_zenith_dbhz: f64,
    /// Put the broadcast Klobuchar and Saastamoinen delays into the measurements (so
    /// the ionosphere/troposphere errors above are the residuals of those models).
    #[serde(default = "yes")]
    pub model_delays: bool,
    /// Receiver inter-system bias of each non-GPS system against GPS \[m\], by letter
    /// (`isb_m = { E = 3.0, C = -5.0, R = 7.0 }`): added to that system's code and phase
    /// ranges. Systems not given use [`default_isb_m`]; GPS is the reference (0).
    #[serde(default)]
    pub isb_m: BTreeMap<String, f64>,
    /// Random walk of each non-GPS system's ISB around `isb_m` [m/sqrt(h)]: 0 = constant
    /// (the default). One walk per system (random stream `gnss.isb.E`, ...); not in the
    /// Doppler (a walk has no rate).
    #[serde(default)]
    pub isb_walk_m_per_sqrth: f64,
}

/// Default receiver inter-system bias \[m\] of `system` against GPS: Galileo +3.0 m,
/// BeiDou -5.0 m, GLONASS +7.0 m, QZSS 0 (non-zero so that solvers must estimate it).
pub fn default_isb_m(system: System) -> f64 {
    match system {
        System::Galileo => 3.0,
        System::BeiDou => -5.0,
        System::Glonass => 7.0,
        _ => 0.0,
    }
}

impl ErrorBudget {
    /// The inter-system bias of `system` in use \[m\] (0 for GPS).
    pub fn isb_of(&self, system: System) -> f64 {
        if system == System::Gps {
            return 0.0;
        }
        let key = system.letter().to_string();
        self.isb_m
            .get(&key)
            .copied()
            .unwrap_or_else(|| default_isb_m(system))
    }
}

/// A satellite named in an event: a plain number (GPS PRN) or "G05", "E11", "C23".
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(untagged)]
pub enum SatRef {
    Prn(u8),
    Name(String),
}

impl SatRef {
    /// The satellite, None when the name is not a system letter and a PRN.
    pub fn sat(&self) -> Option<SatId> {
        match self {
            SatRef::Prn(p) => (*p > 0).then_some(SatId::gps(*p)),
            SatRef::Name(s) if s.starts_with(|c: char| c.is_ascii_alphabetic()) => SatId::parse(s),
            SatRef::Name(_) => None,
        }
    }
}

impl std::fmt::Display for SatRef {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            SatRef::Prn(p) => write!(f, "{p}"),
            SatRef::Name(s) => f.write_str(s),
        }
    }
}

/// The systems simulated, parsed from `systems` (validated).
pub fn systems_of(spec: &GnssSpec) -> Vec<System> {
    let mut v: Vec<System> = spec
        .systems
        .iter()
        .filter_map(|s| s.chars().next().and_then(System::from_letter))
        .collect();
    v.sort();
    v.dedup();
    v
}

fn d_iono() -> f64 {
    5.0
}
fn d_tropo() -> f64 {
    1.5
}
fn d_clk() -> f64 {
    3.0
}
fn d_orbit() -> f64 {
    4.2
}
fn d_one() -> f64 {
    1.0
}
fn d_rxclk() -> f64 {
    5.0
}
fn d_sa() -> f64 {
    100.0
}
fn d_30() -> f64 {
    30.0
}
fn d_120() -> f64 {
    120.0
}
fn d_600() -> f64 {
    600.0
}
fn d_1800() -> f64 {
    1800.0
}
fn d_3600() -> f64 {
    3600.0
}
fn d_phase_noise() -> f64 {
    0.003
}
fn d_phase_mp() -> f64 {
    0.005
}
fn d_doppler() -> f64 {
    0.05
}
fn d_cn0() -> f64 {
    48.0
}

impl Default for ErrorBudget {
    fn default() -> Self {
        toml::from_str("").expect("defaults for every key")
    }
}

/// `[gnss.fix]`: receiver position/velocity fixes from a noise model.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FixSpec {
    /// Horizontal (per axis) and vertical 1-sigma \[m\], also the reported std.
    #[serde(default = "d_fix_h")]
    pub horizontal_std_m: f64,
    #[serde(default = "d_fix_v")]
    pub vertical_std_m: f64,
    /// Correlation time of the position error \[s\]; 0 = white.
    #[serde(default = "d_fix_tau")]
    pub corr_time_s: f64,
    /// Velocity 1-sigma per axis [m/s] (white); also reported.
    #[serde(default = "d_fix_vel")]
    pub velocity_std_mps: f64,
    /// Minimum satellites above the mask for a fix (4 for a 3-D fix).
    #[serde(default = "d_four")]
    pub min_satellites: usize,
}

fn d_fix_h() -> f64 {
    1.5
}
fn d_fix_v() -> f64 {
    3.0
}
fn d_fix_tau() -> f64 {
    60.0
}
fn d_fix_vel() -> f64 {
    0.05
}
fn d_four() -> usize {
    4
}

/// `[gnss.heading]`: dual-antenna heading (SYSTEM.md §3c; seed 001 eq. 10).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HeadingSpec {
    /// Baseline from the primary to the secondary antenna, IMU frame \[m\].
    #[serde(default = "d_baseline")]
    pub baseline_m: [f64; 3],
    /// Heading 1-sigma \[deg\]; default 0.3 deg x 1.2 m / baseline length.
    pub std_deg: Option<f64>,
}

fn d_baseline() -> [f64; 3] {
    [1.2, 0.0, 0.0]
}

/// `[gnss.dgps]`: a reference station and its pseudorange corrections.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DgpsSpec {
    /// Distance \[km\] and bearing \[deg\] of the reference station from the start.
    #[serde(default = "d_dgps_b")]
    pub baseline_km: f64,
    #[serde(default = "d_45")]
    pub bearing_deg: f64,
    /// Corrections computed every `interval_s`, available `latency_s` later.
    #[serde(default = "one")]
    pub interval_s: f64,
    #[serde(default)]
    pub latency_s: f64,
    /// Spatially decorrelated residuals (zenith) at `residual_baseline_km`, growing
    /// linearly with the baseline. Defaults: seed 000 Table 1 DGPS column.
    #[serde(default = "d_res_iono")]
    pub iono_residual_m: f64,
    #[serde(default = "d_res_tropo")]
    pub tropo_residual_m: f64,
    #[serde(default = "d_res_orbit")]
    pub orbit_residual_m: f64,
    #[serde(default = "d_dgps_b")]
    pub residual_baseline_km: f64,
    /// The reference station's own multipath and noise at zenith \[m\].
    #[serde(default = "d_ref")]
    pub ref_multipath_m: f64,
    #[serde(default = "d_ref")]
    pub ref_noise_m: f64,
}

fn d_dgps_b() -> f64 {
    20.0
}
fn d_45() -> f64 {
    45.0
}
fn d_res_iono() -> f64 {
    0.5
}
fn d_res_tropo() -> f64 {
    0.2
}
fn d_res_orbit() -> f64 {
    0.3
}
fn d_ref() -> f64 {
    0.1
}

/// Spoofing modes.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum SpoofMode {
    /// False position = truth + offset_m from start_s.
    Jump,
    /// False position = truth + velocity_mps (t - start_s).
    Drift,
    /// False position = the true track delay_s earlier, plus offset_m.
    Replay,
}

/// One `[[gnss.event]]`; times in seconds from the scenario start.
#[derive(Clone, Debug, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum EventSpec {
    /// No GNSS output at all for start_s < t < end_s.
    Outage { start_s: f64, end_s: f64 },
    /// Outages of length_s every period_s from from_s (until until_s).
    OutageEvery {
        length_s: f64,
        period_s: f64,
        from_s: f64,
        until_s: Option<f64>,
    },
    /// Partial sky blockage: only the `keep` highest satellites (or the listed PRNs)
    /// are tracked; no fix when fewer than the fix needs.
    Blockage {
        start_s: f64,
        end_s: f64,
        keep: Option<usize>,
        /// Satellites kept: GPS PRNs or names ("G05", "E11").
        prns: Option<Vec<SatRef>>,
    },
    /// Spoofing of fixes and raw measurements, consistently.
    Spoof {
        mode: SpoofMode,
        start_s: f64,
        end_s: f64,
        #[serde(default)]
        offset_m: [f64; 3],
        #[serde(default)]
        velocity_mps: [f64; 3],
        #[serde(default)]
        delay_s: f64,
    },
    /// Cycle slip of `cycles` on one satellite at at_s.
    CycleSlip { prn: SatRef, at_s: f64, cycles: i64 },
    /// One satellite not tracked for start_s < t < end_s; reacquired with a new
    /// ambiguity and the loss-of-lock flag.
    LossOfLock {
        prn: SatRef,
        start_s: f64,
        end_s: f64,
    },
}

impl GnssSpec {
    /// Check values; Err((key, message)).
    pub fn validate(&self, traj: &Trajectory) -> Result<(), (String, String)> {
        let bad = |k: &str, m: String| Err((k.to_string(), m));
        if !(self.rate_hz.is_finite() && self.rate_hz > 0.0 && self.rate_hz <= 100.0) {
            return bad(
                "rate_hz",
                format!("expected (0, 100] Hz, got {}", self.rate_hz),
            );
        }
        match self.constellation.as_str() {
            "nominal24" | "seed000" => {}
            "rinex" if self.rinex_nav.is_some() => {}
            "rinex" => {
                return bad(
                    "rinex_nav",
                    "constellation = \"rinex\" needs rinex_nav = \"FILE\"".into(),
                )
            }
            c => {
                return bad(
                    "constellation",
                    format!("expected \"nominal24\", \"seed000\" or \"rinex\", got \"{c}\""),
                )
            }
        }
        if self.systems.is_empty() {
            return bad(
                "systems",
                "expected at least one of \"G\", \"E\", \"C\", \"R\"".into(),
            );
        }
        for sys in &self.systems {
            if !matches!(sys.as_str(), "G" | "E" | "C" | "R") {
                return bad(
                    "systems",
                    format!(
                        "expected \"G\" (GPS), \"E\" (Galileo), \"C\" (BeiDou) or \"R\" (GLONASS), got \"{sys}\""
                    ),
                );
            }
        }
        for (k, v) in &self.errors.isb_m {
            if !matches!(k.as_str(), "E" | "C" | "R") {
                return bad(
                    "errors.isb_m",
                    format!(
                        "expected keys \"E\", \"C\" or \"R\" (GPS is the reference), got \"{k}\""
                    ),
                );
            }
            if !v.is_finite() {
                return bad("errors.isb_m", format!("expected a finite value, got {v}"));
            }
        }
        if !(0.0..=60.0).contains(&self.elevation_mask_deg) {
            return bad(
                "elevation_mask_deg",
                format!("expected [0, 60] deg, got {}", self.elevation_mask_deg),
            );
        }
        let e = &self.errors;
        let sig = [
            ("errors.iono_m", e.iono_m),
            ("errors.tropo_m", e.tropo_m),
            ("errors.sat_clock_m", e.sat_clock_m),
            ("errors.orbit_m", e.orbit_m),
            ("errors.multipath_m", e.multipath_m),
            ("errors.noise_m", e.noise_m),
            ("errors.rx_clock_m", e.rx_clock_m),
            ("errors.sa_m", e.sa_m),
            ("errors.phase_noise_m", e.phase_noise_m),
            ("errors.phase_multipath_m", e.phase_multipath_m),
            ("errors.doppler_noise_mps", e.doppler_noise_mps),
            ("errors.isb_walk_m_per_sqrth", e.isb_walk_m_per_sqrth),
        ];
        for (k, v) in sig {
            if !(v.is_finite() && v >= 0.0) {
                return bad(k, format!("expected a finite value >= 0, got {v}"));
            }
        }
        let taus = [
            ("errors.iono_tau_s", e.iono_tau_s),
            ("errors.tropo_tau_s", e.tropo_tau_s),
            ("errors.sat_clock_tau_s", e.sat_clock_tau_s),
            ("errors.orbit_tau_s", e.orbit_tau_s),
            ("errors.multipath_tau_s", e.multipath_tau_s),
            ("errors.rx_clock_tau_s", e.rx_clock_tau_s),
            ("errors.sa_tau_s", e.sa_tau_s),
        ];
        for (k, v) in taus {
            if !(v.is_finite() && v > 0.0) {
                return bad(k, format!("expected a correlation time > 0 s, got {v}"));
            }
        }
        if !(self.time_offset_s.is_finite() && self.time_offset_s.abs() <= 100.0) {
            return bad(
                "time_offset_s",
                format!(
                    "expected a time offset within +-100 s, got {}",
                    self.time_offset_s
                ),
            );
        }
        if let Some(f) = &self.fix {
            if !(f.horizontal_std_m > 0.0
                && f.vertical_std_m > 0.0
                && f.velocity_std_mps > 0.0
                && f.corr_time_s >= 0.0)
            {
                return bad("fix", "std values must be > 0 and corr_time_s >= 0".into());
            }
        }
        if let Some(h) = &self.heading {
            let b = Vector3::from(h.baseline_m);
            if !(b.norm() > 0.05 && b.iter().all(|x| x.is_finite())) {
                return bad(
                    "heading.baseline_m",
                    format!(
                        "expected a baseline longer than 5 cm, got {:?}",
                        h.baseline_m
                    ),
                );
            }
            if let Some(s) = h.std_deg {
                if !(s.is_finite() && s > 0.0) {
                    return bad("heading.std_deg", format!("expected > 0, got {s}"));
                }
            }
        }
        if let Some(d) = &self.dgps {
            if !(d.baseline_km >= 0.0
                && d.interval_s > 0.0
                && d.latency_s >= 0.0
                && d.residual_baseline_km > 0.0)
            {
                return bad("dgps", "expected baseline_km >= 0, interval_s > 0, latency_s >= 0, residual_baseline_km > 0".into());
            }
        }
        let dur = traj.duration();
        for (k, ev) in self.events.iter().enumerate() {
            let key = format!("event[{}]", k + 1);
            let window = |a: f64, b: f64| -> Result<(), (String, String)> {
                if a.is_finite() && b.is_finite() && a >= 0.0 && b > a {
                    Ok(())
                } else {
                    Err((
                        key.clone(),
                        format!("expected 0 <= start < end, got {a}..{b}"),
                    ))
                }
            };
            match ev {
                EventSpec::Outage { start_s, end_s } => window(*start_s, *end_s)?,
                EventSpec::OutageEvery {
                    length_s,
                    period_s,
                    from_s,
                    ..
                } => {
                    if !(*length_s > 0.0 && period_s > length_s && *from_s >= 0.0) {
                        return Err((
                            key,
                            "expected length_s > 0, period_s > length_s, from_s >= 0".into(),
                        ));
                    }
                }
                EventSpec::Blockage {
                    start_s,
                    end_s,
                    keep,
                    prns,
                } => {
                    window(*start_s, *end_s)?;
                    if keep.is_some() == prns.is_some() {
                        return Err((key, "give exactly one of keep and prns".into()));
                    }
                    if let Some(bad) = prns.iter().flatten().find(|p| p.sat().is_none()) {
                        return Err((
                            format!("{key}.prns"),
                            format!("expected a GPS PRN or a name like \"G05\" / \"E11\", got \"{bad}\""),
                        ));
                    }
                }
                EventSpec::Spoof {
                    start_s,
                    end_s,
                    mode,
                    delay_s,
                    offset_m,
                    velocity_mps,
                } => {
                    window(*start_s, *end_s)?;
                    let vals = offset_m.iter().chain(velocity_mps).chain([delay_s]);
                    if let Some(v) = vals.into_iter().find(|v| !v.is_finite()) {
                        return Err((
                            key,
                            format!("offset_m, velocity_mps and delay_s must be finite, got {v}"),
                        ));
                    }
                    if *mode == SpoofMode::Replay && !(*delay_s > 0.0 && *delay_s <= *start_s) {
                        return Err((
                            key,
                            format!("replay needs 0 < delay_s <= start_s, got {delay_s}"),
                        ));
                    }
                }
                EventSpec::CycleSlip { prn, .. } | EventSpec::LossOfLock { prn, .. }
                    if prn.sat().is_none() =>
                {
                    return Err((
                        format!("{key}.prn"),
                        format!(
                            "expected a GPS PRN or a name like \"G05\" / \"E11\", got \"{prn}\""
                        ),
                    ));
                }
                EventSpec::CycleSlip { at_s, .. } => {
                    if !(*at_s >= 0.0 && *at_s <= dur) {
                        return Err((
                            key,
                            format!("at_s must be within the run (0..{dur}), got {at_s}"),
                        ));
                    }
                }
                EventSpec::LossOfLock { start_s, end_s, .. } => window(*start_s, *end_s)?,
            }
        }
        Ok(())
    }
}
