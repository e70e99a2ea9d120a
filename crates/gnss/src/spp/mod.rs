//! Single point positioning (SPP) from GPS L1 C/A pseudoranges and Doppler.
//!
//! Per epoch: iterated weighted least squares for the receiver position (ECEF) and
//! clock bias from pseudoranges, then velocity and clock drift from Doppler, with a
//! residual chi-square test and fault exclusion (FDE). Pure computation; the caller
//! supplies the measurements and the broadcast ephemerides. See docs/GNSS.md, "Single
//! point positioning".
//!
//! Pseudorange model (SYSTEM.md §3b, with the satellite clock subtracted as in
//! IS-GPS-200 20.3.3.3.3.1-2):
//!
//! `P = |R3(We tau) x_sat(t_tx) - x_rx| + c dt_rx - c (dt_sv - TGD) + I + T + eps`
//!
//! where dt_sv includes the relativistic term (`SignalPath::sat_clock_bias_s`), TGD is
//! the L1 C/A group delay (20.3.3.3.3.2), I the Klobuchar delay (20.3.3.5.2.5), T the
//! Saastamoinen slant delay. The light time is solved for the true reception time
//! `t_rx - dt_rx`, so a receiver clock offset of milliseconds (common with u-blox) does
//! not bias the satellite positions.

use crate::ephemeris::SPEED_OF_LIGHT_MPS;
use crate::time::GpsTime;
use nalgebra::{Matrix4, Vector3};
use std::fmt;

mod config;
mod solve;
#[cfg(test)]
mod tests;
mod velocity;

pub use config::{IonoModel, SppConfig, SppErrorModel};
pub use solve::{solve_epoch, SppSolver};

/// GPS L1 carrier frequency \[Hz\] (IS-GPS-200 3.3.1.1).
pub const GPS_L1_HZ: f64 = 1_575.42e6;
/// GPS L1 wavelength c / f_L1 \[m\] (0.1903 m).
pub const GPS_L1_WAVELENGTH_M: f64 = SPEED_OF_LIGHT_MPS / GPS_L1_HZ;

/// Satellites needed to identify (not only detect) one faulty measurement: with
/// n = 5 the residuals have one degree of freedom and every normalised residual has
/// the same size, so exclusion needs n >= 6 (and leaves n >= 5, still tested).
pub const FDE_MIN_SATELLITES: usize = 6;

/// A receiver position estimate is "near the surface" (elevations and atmosphere make
/// sense) above this ellipsoidal height [m]; the Earth-centre start is far below it.
const NEAR_SURFACE_MIN_H_M: f64 = -100e3;

/// One satellite's GPS L1 C/A measurements at one epoch.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SppMeasurement {
    /// GPS PRN.
    pub prn: u8,
    /// C1C pseudorange \[m\].
    pub pseudorange_m: f64,
    /// D1C Doppler \[Hz\] (positive when the satellite approaches), if measured.
    pub doppler_hz: Option<f64>,
    /// DGPS correction to add to the pseudorange, evaluated at this epoch
    /// (prc + rrc (t - t_s), `dgps::DgpsCorrection::at_m`) \[m\]. When present the
    /// ionosphere and troposphere models are not applied to this satellite (the
    /// correction contains them) and its variance uses `dgps_sigma_m`.
    pub dgps_prc_m: Option<f64>,
}

/// One satellite used in the solution.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SppSatellite {
    pub prn: u8,
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
    /// Receiver clock bias c dt_rx \[m\].
    pub clock_bias_m: f64,
    /// Antenna velocity, ECEF [m/s], when at least 4 used satellites have Doppler.
    pub vel_ecef_mps: Option<Vector3<f64>>,
    /// Receiver clock drift c d(dt_rx)/dt [m/s], with the velocity.
    pub clock_drift_mps: Option<f64>,
    /// Satellites used.
    pub n_used: usize,
    /// Their PRNs, in input order.
    pub used_prns: Vec<u8>,
    /// Satellites excluded by FDE, in exclusion order.
    pub excluded_prns: Vec<u8>,
    /// Satellites below the elevation mask at the solution.
    pub masked_prns: Vec<u8>,
    /// Satellites without a usable ephemeris (none, unhealthy or outside its fit
    /// interval) or with an invalid pseudorange.
    pub unusable_prns: Vec<u8>,
    /// Per used satellite: geometry, residuals, corrections.
    pub satellites: Vec<SppSatellite>,
    /// Dilutions of precision.
    pub dops: Dops,
    /// Covariance of (x, y, z, c dt_rx) from the a priori weights [m^2].
    pub cov_m2: Matrix4<f64>,
    /// Position 1-sigma north, east, down \[m\] (from `cov_m2`).
    pub std_ned_m: Vector3<f64>,
    /// Velocity 1-sigma north, east, down [m/s] (from the Doppler sigma).
    pub vel_std_ned_mps: Option<Vector3<f64>>,
    /// Sum of squared weighted residuals.
    pub chi2: f64,
    /// Chi-square threshold at `chi2_probability` for n - 4 degrees of freedom (None
    /// with 4 satellites).
    pub chi2_threshold: Option<f64>,
    /// Gauss-Newton iterations of the final fit.
    pub iterations: usize,
}

/// Why an epoch has no solution.
#[derive(Clone, Debug, PartialEq)]
pub enum SppError {
    /// No measurement has a usable ephemeris and pseudorange.
    NoEphemeris { prns: Vec<u8> },
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
        excluded_prns: Vec<u8>,
    },
}

impl fmt::Display for SppError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SppError::NoEphemeris { prns } => {
                write!(f, "no satellite has a usable ephemeris and pseudorange")?;
                if !prns.is_empty() {
                    let list: Vec<String> = prns.iter().map(|p| format!("G{p:02}")).collect();
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
                excluded_prns,
            } => {
                write!(
                    f,
                    "residual chi-square test failed: {chi2:.1} > {threshold:.1} \
                     with {n_used} satellites"
                )?;
                if !excluded_prns.is_empty() {
                    let list: Vec<String> =
                        excluded_prns.iter().map(|p| format!("G{p:02}")).collect();
                    write!(f, " after excluding {}", list.join(" "))?;
                }
                Ok(())
            }
        }
    }
}

impl std::error::Error for SppError {}
