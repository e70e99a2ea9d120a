//! Single point positioning (SPP) from the pseudoranges and Dopplers of every
//! system: GPS, QZSS, Galileo, BeiDou, GLONASS.
//!
//! Per epoch: iterated weighted least squares for the receiver position (ECEF), the
//! receiver clock bias and one inter-system bias per further system present, then
//! velocity and clock drift from Doppler, with a residual chi-square test and fault
//! exclusion (FDE) across systems. Pure computation; the caller supplies the
//! measurements and the orbits (`OrbitSource`: broadcast records of any system, or
//! precise products). See docs/GNSS.md, "Single point positioning".
//!
//! Pseudorange model (SYSTEM.md §3b, with the satellite clock subtracted as in
//! IS-GPS-200 20.3.3.3.3.1-2):
//!
//! `P = |R3(We tau) x_sat(t_tx) - x_rx| + c dt_rx + ISB_sys - c (dt_sv - TGD) + I + T + eps`
//!
//! where dt_sv includes the relativistic term (`SignalPath::sat_clock_bias_s`), TGD is
//! the group delay of the system's first civil signal (GPS TGD 20.3.3.3.3.2, Galileo
//! BGD, BeiDou TGD1), ISB_sys = 0 for the reference system (GPS and QZSS, else the
//! first system present), I the Klobuchar delay (20.3.3.5.2.5) scaled to the signal's
//! frequency by (f_L1 / f)^2 (or 0 for an ionosphere-free code), T the Saastamoinen
//! slant delay. The light time is solved for the true reception time
//! `t_rx - dt_rx`, so a receiver clock offset of milliseconds (common with u-blox) does
//! not bias the satellite positions.

use crate::ephemeris::SPEED_OF_LIGHT_MPS;
use crate::time::GpsTime;
use nalgebra::{Matrix4, Vector3};
use navfuse_core::sat::{SatId, System};
use std::fmt;

mod config;
mod solve;
#[cfg(test)]
mod tests;
mod velocity;

pub use config::{system_error_factor, IonoModel, SppConfig, SppErrorModel};
pub use solve::{solve_epoch, SppSolver};

/// GPS L1 carrier frequency \[Hz\] (IS-GPS-200 3.3.1.1).
pub const GPS_L1_HZ: f64 = 1_575.42e6;
/// GPS L1 wavelength c / f_L1 \[m\] (0.1903 m).
pub const GPS_L1_WAVELENGTH_M: f64 = SPEED_OF_LIGHT_MPS / GPS_L1_HZ;

/// Redundancy needed to identify (not only detect) one faulty measurement: with
/// one degree of freedom every normalised residual has the same size, so exclusion
/// needs n >= unknowns + 2 (GPS alone: 6 satellites), and leaves one still tested.
pub const FDE_MIN_REDUNDANCY: usize = 2;

/// A receiver position estimate is "near the surface" (elevations and atmosphere make
/// sense) above this ellipsoidal height [m]; the Earth-centre start is far below it.
const NEAR_SURFACE_MIN_H_M: f64 = -100e3;

/// One satellite's code (and Doppler) measurement at one epoch.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SppMeasurement {
    pub sat: SatId,
    /// Pseudorange \[m\]: one signal (e.g. C1C), or an ionosphere-free combination
    /// when `iono_free`.
    pub pseudorange_m: f64,
    /// Carrier frequency of the signal \[Hz\]: scales the L1 Klobuchar delay by
    /// (f_L1 / f)^2 and gives the Doppler's wavelength c / f.
    pub frequency_hz: f64,
    /// RINEX band of the signal (its group delay, `Ephemeris::band_group_delay_s`).
    pub band: u8,
    /// The pseudorange is a dual-frequency ionosphere-free combination of `band` and
    /// this band: no ionospheric model, the combined group delay, and its noise
    /// taken 3 times the single-signal noise.
    pub iono_free_with: Option<u8>,
    /// Doppler \[Hz\] on `frequency_hz` (positive when the satellite approaches).
    pub doppler_hz: Option<f64>,
    /// Signal strength C/N0 [dB-Hz] (for `SppErrorModel::cn0_sigma_m`).
    pub cn0_dbhz: Option<f64>,
    /// DGPS correction to add to the pseudorange, evaluated at this epoch
    /// (prc + rrc (t - t_s), `dgps::DgpsCorrection::at_m`) \[m\]. When present the
    /// ionosphere and troposphere models are not applied to this satellite (the
    /// correction contains them) and its variance uses `dgps_sigma_m`.
    pub dgps_prc_m: Option<f64>,
}

impl SppMeasurement {
    /// A GPS L1 C/A measurement (C1C, D1C).
    pub fn gps_l1(prn: u8, pseudorange_m: f64, doppler_hz: Option<f64>) -> Self {
        SppMeasurement {
            sat: SatId::gps(prn),
            pseudorange_m,
            frequency_hz: GPS_L1_HZ,
            band: 1,
            iono_free_with: None,
            doppler_hz,
            cn0_dbhz: None,
            dgps_prc_m: None,
        }
    }

    /// Wavelength of the signal \[m\].
    pub fn wavelength_m(&self) -> f64 {
        SPEED_OF_LIGHT_MPS / self.frequency_hz
    }
}

impl From<&crate::signal_plan::ChosenSignal> for SppMeasurement {
    fn from(c: &crate::signal_plan::ChosenSignal) -> Self {
        SppMeasurement {
            sat: c.sat,
            pseudorange_m: c.pseudorange_m,
            frequency_hz: c.frequency_hz,
            band: c.code.band(),
            iono_free_with: c.iono_free_with,
            doppler_hz: c.doppler_hz,
            cn0_dbhz: c.cn0_dbhz,
            dgps_prc_m: None,
        }
    }
}

/// The receiver clock a system's pseudoranges share: GPS and QZSS (QZSS time is
/// kept aligned with GPS time, IS-QZSS-PNT §3.2.3) share one; every other system
/// has its own (its time scale and the receiver's hardware delays differ).
pub fn clock_group(system: System) -> System {
    match system {
        System::Qzss => System::Gps,
        s => s,
    }
}

/// One satellite used in the solution.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SppSatellite {
    pub sat: SatId,
    /// Azimuth from north, clockwise \[rad\].
    pub az_rad: f64,
    /// Elevation \[rad\].
    pub el_rad: f64,
    /// Post-fit pseudorange residual, measured minus modelled \[m\].
    pub residual_m: f64,
    /// A priori 1-sigma of the pseudorange \[m\].
    pub sigma_m: f64,
    /// Modelled ionospheric delay \[m\].
    pub iono_m: f64,
    /// Modelled tropospheric delay \[m\].
    pub tropo_m: f64,
    /// Doppler range-rate residual [m/s], when the velocity was solved with it.
    pub range_rate_residual_mps: Option<f64>,
}

/// Dilutions of precision (unit weights; horizontal/vertical in the local frame).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dops {
    pub gdop: f64,
    pub pdop: f64,
    pub hdop: f64,
    pub vdop: f64,
}

/// One epoch's solution.
#[derive(Clone, Debug, PartialEq)]
pub struct SppSolution {
    /// Receiver time tag of the epoch (GPST as the receiver keeps it).
    pub t: GpsTime,
    /// Time of validity: `t - clock_bias_m / c` (what RTKLIB writes as the epoch).
    pub t_fix: GpsTime,
    /// Antenna position, ECEF \[m\].
    pub pos_ecef_m: Vector3<f64>,
    /// Latitude \[rad\], longitude \[rad\], ellipsoidal height \[m\].
    pub lla: Vector3<f64>,
    /// Receiver clock bias c dt_rx \[m\] of the reference system's time scale.
    pub clock_bias_m: f64,
    /// The reference system: GPS (with QZSS) when present, else the first of
    /// Galileo, BeiDou, GLONASS, NavIC present.
    pub reference_system: System,
    /// Inter-system biases: each further system's receiver clock minus the
    /// reference clock, c (dt_sys - dt_ref) \[m\], with its 1-sigma \[m\].
    pub isb_m: Vec<(System, f64, f64)>,
    /// Antenna velocity, ECEF [m/s], when at least 4 used satellites have Doppler.
    pub vel_ecef_mps: Option<Vector3<f64>>,
    /// Receiver clock drift c d(dt_rx)/dt [m/s], with the velocity.
    pub clock_drift_mps: Option<f64>,
    /// Satellites used.
    pub n_used: usize,
    /// Them, in input order.
    pub used_sats: Vec<SatId>,
    /// Satellites excluded by FDE, in exclusion order.
    pub excluded_sats: Vec<SatId>,
    /// Satellites below the elevation mask at the solution.
    pub masked_sats: Vec<SatId>,
    /// Satellites without a usable ephemeris (none, unhealthy or outside its fit
    /// interval) or with an invalid pseudorange.
    pub unusable_sats: Vec<SatId>,
    /// Per used satellite: geometry, residuals, corrections.
    pub satellites: Vec<SppSatellite>,
    /// Dilutions of precision.
    pub dops: Dops,
    /// Covariance of (x, y, z, c dt_rx of the reference system) from the a priori
    /// weights [m^2].
    pub cov_m2: Matrix4<f64>,
    /// Position 1-sigma north, east, down \[m\] (from `cov_m2`).
    pub std_ned_m: Vector3<f64>,
    /// Velocity 1-sigma north, east, down [m/s] (from the Doppler sigma).
    pub vel_std_ned_mps: Option<Vector3<f64>>,
    /// Sum of squared weighted residuals.
    pub chi2: f64,
    /// Chi-square threshold at `chi2_probability` for n - 3 - (number of clocks)
    /// degrees of freedom (None without redundancy).
    pub chi2_threshold: Option<f64>,
    /// Gauss-Newton iterations of the final fit.
    pub iterations: usize,
}

/// Why an epoch has no solution.
#[derive(Clone, Debug, PartialEq)]
pub enum SppError {
    /// No measurement has a usable ephemeris and pseudorange.
    NoEphemeris { sats: Vec<SatId> },
    /// Fewer satellites than needed (after the mask, ephemeris checks and FDE).
    TooFewSatellites { available: usize, required: usize },
    /// The iteration did not converge.
    NotConverged { iterations: usize, last_step_m: f64 },
    /// The normal matrix is singular (e.g. satellites in a plane with the receiver).
    SingularGeometry,
    /// GDOP above the configured limit.
    PoorGeometry { gdop: f64, max_gdop: f64 },
    /// The chi-square test failed and no satellite could be excluded.
    ResidualTestFailed {
        chi2: f64,
        threshold: f64,
        n_used: usize,
        excluded: Vec<SatId>,
    },
}

impl fmt::Display for SppError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SppError::NoEphemeris { sats } => {
                write!(f, "no satellite has a usable ephemeris and pseudorange")?;
                if !sats.is_empty() {
                    let list: Vec<String> = sats.iter().map(|p| p.to_string()).collect();
                    write!(f, " ({})", list.join(" "))?;
                }
                Ok(())
            }
            SppError::TooFewSatellites {
                available,
                required,
            } => write!(
                f,
                "too few satellites: {available} usable, {required} required"
            ),
            SppError::NotConverged {
                iterations,
                last_step_m,
            } => write!(
                f,
                "not converged after {iterations} iterations (last step {last_step_m:.3e} m)"
            ),
            SppError::SingularGeometry => write!(f, "singular satellite geometry"),
            SppError::PoorGeometry { gdop, max_gdop } => {
                write!(f, "GDOP {gdop:.1} above the limit {max_gdop:.1}")
            }
            SppError::ResidualTestFailed {
                chi2,
                threshold,
                n_used,
                excluded,
            } => {
                write!(
                    f,
                    "residual chi-square test failed: {chi2:.1} > {threshold:.1} \
                     with {n_used} satellites"
                )?;
                if !excluded.is_empty() {
                    let list: Vec<String> = excluded.iter().map(|p| p.to_string()).collect();
                    write!(f, " after excluding {}", list.join(" "))?;
                }
                Ok(())
            }
        }
    }
}

impl std::error::Error for SppError {}
