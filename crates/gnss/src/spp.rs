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

use crate::atmosphere::{klobuchar_l1_delay_m, saastamoinen_slant_m};
use crate::ephemeris::{GpsEphemeris, SPEED_OF_LIGHT_MPS};
use crate::ephemeris_set::EphemerisSet;
use crate::geometry::{az_el, signal_path, SignalPath};
use crate::time::GpsTime;
use nalgebra::{Matrix3, Matrix4, Vector3, Vector4};
use navfuse_core::chi2::chi2_quantile;
use navfuse_core::earth::{c_ne, ecef_to_lla};
use std::fmt;

/// GPS L1 carrier frequency [Hz] (IS-GPS-200 3.3.1.1).
pub const GPS_L1_HZ: f64 = 1_575.42e6;
/// GPS L1 wavelength c / f_L1 [m] (0.1903 m).
pub const GPS_L1_WAVELENGTH_M: f64 = SPEED_OF_LIGHT_MPS / GPS_L1_HZ;

/// Upper bounds of the URA index intervals [m] (IS-GPS-200 20.3.3.3.1.3), index 0-14.
const URA_BOUNDS_M: [f64; 15] = [
    2.4, 3.4, 4.85, 6.85, 9.65, 13.65, 24.0, 48.0, 96.0, 192.0, 384.0, 768.0, 1536.0, 3072.0,
    6144.0,
];

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
    /// C1C pseudorange [m].
    pub pseudorange_m: f64,
    /// D1C Doppler [Hz] (positive when the satellite approaches), if measured.
    pub doppler_hz: Option<f64>,
    /// DGPS correction to add to the pseudorange, evaluated at this epoch
    /// (prc + rrc (t - t_s), `dgps::DgpsCorrection::at_m`) [m]. When present the
    /// ionosphere and troposphere models are not applied to this satellite (the
    /// correction contains them) and its variance uses `dgps_sigma_m`.
    pub dgps_prc_m: Option<f64>,
}

/// Ionospheric correction.
#[derive(Clone, Debug, PartialEq)]
pub enum IonoModel {
    /// No correction (the delay is left in the residuals and weighted as an error).
    None,
    /// Broadcast Klobuchar model (IS-GPS-200 20.3.3.5.2.5) with the broadcast
    /// coefficients alpha [s, s/sc, s/sc^2, s/sc^3] and beta [s, s/sc, s/sc^2, s/sc^3].
    Klobuchar { alpha: [f64; 4], beta: [f64; 4] },
}

impl IonoModel {
    /// Klobuchar when both coefficient sets are given (e.g. from a navigation file
    /// header), otherwise no correction.
    pub fn from_broadcast(alpha: Option<[f64; 4]>, beta: Option<[f64; 4]>) -> Self {
        match (alpha, beta) {
            (Some(alpha), Some(beta)) => IonoModel::Klobuchar { alpha, beta },
            _ => IonoModel::None,
        }
    }
}

/// Pseudorange error budget (1-sigma values). The defaults are RTKLIB's single-point
/// defaults (code/phase error ratio 100 x 0.003 m, GPS error factor 1, code bias
/// 0.3 m, broadcast-iono error 50 %, Saastamoinen error 0.3 m / (sin el + 0.1),
/// 5 m and 3 m without an iono / tropo model, broadcast URA).
#[derive(Clone, Debug, PartialEq)]
pub struct SppErrorModel {
    /// Constant term a of sigma_el^2 = F^2 (a^2 + b^2 / sin^p el) [m].
    pub sigma_a_m: f64,
    /// Elevation term b [m].
    pub sigma_b_m: f64,
    /// Error factor F for the system (GPS: 1).
    pub error_factor: f64,
    /// Power p of sin(el) in the elevation term b^2 / sin^p el: 2 (default, the
    /// usual model and RTKLIB's manual); RTKLIB 2.4.3's `pntpos` code uses 1, which
    /// reproduces its weights exactly.
    pub elevation_sin_power: f64,
    /// Add the broadcast user range accuracy squared, the RINEX value rounded up to
    /// the IS-GPS-200 20.3.3.3.1.3 URA bound (2.4, 3.4, 4.85, ... 6144 m).
    pub use_ura: bool,
    /// Code bias (TGD / receiver) error [m].
    pub code_bias_sigma_m: f64,
    /// Klobuchar model error as a fraction of the modelled delay.
    pub iono_model_fraction: f64,
    /// Ionospheric error without a model [m].
    pub iono_none_sigma_m: f64,
    /// Saastamoinen model error s, mapped as s / (sin el + 0.1) [m].
    pub tropo_model_sigma_m: f64,
    /// Tropospheric error without a model [m].
    pub tropo_none_sigma_m: f64,
    /// Error left after a DGPS correction (reference station noise and multipath,
    /// spatial and temporal decorrelation) [m]; replaces the URA, code bias, iono and
    /// tropo terms for a corrected satellite.
    pub dgps_sigma_m: f64,
    /// Doppler error [Hz] (sets the velocity covariance; the velocity fit is
    /// unweighted).
    pub doppler_sigma_hz: f64,
}

impl Default for SppErrorModel {
    fn default() -> Self {
        SppErrorModel {
            sigma_a_m: 0.3,
            sigma_b_m: 0.3,
            error_factor: 1.0,
            elevation_sin_power: 2.0,
            use_ura: true,
            code_bias_sigma_m: 0.3,
            iono_model_fraction: 0.5,
            iono_none_sigma_m: 5.0,
            tropo_model_sigma_m: 0.3,
            tropo_none_sigma_m: 3.0,
            dgps_sigma_m: 1.0,
            doppler_sigma_hz: 1.0,
        }
    }
}

impl SppErrorModel {
    /// Elevation-dependent measurement variance F^2 (a^2 + b^2 / sin^p el) [m^2].
    pub fn elevation_variance_m2(&self, el_rad: f64) -> f64 {
        let s = el_rad.sin().max(1e-3).powf(self.elevation_sin_power);
        self.error_factor.powi(2) * (self.sigma_a_m.powi(2) + self.sigma_b_m.powi(2) / s)
    }
}

/// SPP settings.
#[derive(Clone, Debug, PartialEq)]
pub struct SppConfig {
    /// Elevation mask [rad] (default 10 deg).
    pub elevation_mask_rad: f64,
    /// Ionospheric correction (default none; use `IonoModel::from_broadcast`).
    pub iono: IonoModel,
    /// Saastamoinen tropospheric correction (default on).
    pub tropo_saastamoinen: bool,
    /// Error budget and weighting.
    pub errors: SppErrorModel,
    /// Maximum Gauss-Newton iterations per solution (default 10).
    pub max_iterations: usize,
    /// Convergence: norm of the state update (position and clock) below this [m].
    pub convergence_m: f64,
    /// Chi-square test of the weighted residuals with fault exclusion (default on).
    pub fde: bool,
    /// Probability of the chi-square test (1 - false-alarm rate; default 0.999).
    pub chi2_probability: f64,
    /// Minimum satellites for a solution (default 4; values below 4 act as 4).
    pub min_satellites: usize,
    /// Largest accepted GDOP (default 30).
    pub max_gdop: f64,
}

impl SppConfig {
    /// Modelled (ionospheric, tropospheric) L1 delays [m] for a receiver at `lla`
    /// (rad, rad, m), a satellite at `az_rad`, `el_rad`, at `sow` (GPS s of week):
    /// Klobuchar (IS-GPS-200 20.3.3.5.2.5) and Saastamoinen as configured, else 0.
    pub fn atmosphere_m(
        &self,
        lla: &Vector3<f64>,
        az_rad: f64,
        el_rad: f64,
        sow: f64,
    ) -> (f64, f64) {
        let iono_m = match &self.iono {
            IonoModel::Klobuchar { alpha, beta } => {
                klobuchar_l1_delay_m(alpha, beta, lla.x, lla.y, az_rad, el_rad, sow)
            }
            IonoModel::None => 0.0,
        };
        let tropo_m = if self.tropo_saastamoinen {
            saastamoinen_slant_m(lla.x, lla.z, el_rad)
        } else {
            0.0
        };
        (iono_m, tropo_m)
    }

    /// A priori pseudorange variance [m^2] of one satellite at `el_rad`:
    /// F^2 (a^2 + b^2 / sin^p el) + URA^2 + sigma_cb^2 + sigma_I^2 + sigma_T^2, or
    /// F^2 (a^2 + b^2 / sin^p el) + sigma_DGPS^2 when `dgps` (docs/GNSS.md).
    /// `iono_m` is the modelled delay (sets sigma_I with Klobuchar).
    pub fn pseudorange_variance_m2(
        &self,
        eph: &GpsEphemeris,
        el_rad: f64,
        iono_m: f64,
        dgps: bool,
    ) -> f64 {
        let em = &self.errors;
        let var = if dgps {
            em.elevation_variance_m2(el_rad) + em.dgps_sigma_m.powi(2)
        } else {
            let iono_var = match self.iono {
                IonoModel::Klobuchar { .. } => (em.iono_model_fraction * iono_m).powi(2),
                IonoModel::None => em.iono_none_sigma_m.powi(2),
            };
            let tropo_var = if self.tropo_saastamoinen {
                (em.tropo_model_sigma_m / (el_rad.sin() + 0.1)).powi(2)
            } else {
                em.tropo_none_sigma_m.powi(2)
            };
            let ura_var = if em.use_ura {
                ura_variance_m2(eph.sv_accuracy_m)
            } else {
                0.0
            };
            em.elevation_variance_m2(el_rad)
                + ura_var
                + em.code_bias_sigma_m.powi(2)
                + iono_var
                + tropo_var
        };
        var.max(1e-6)
    }
}

impl Default for SppConfig {
    fn default() -> Self {
        SppConfig {
            elevation_mask_rad: 10f64.to_radians(),
            iono: IonoModel::None,
            tropo_saastamoinen: true,
            errors: SppErrorModel::default(),
            max_iterations: 10,
            convergence_m: 1e-4,
            fde: true,
            chi2_probability: 0.999,
            min_satellites: 4,
            max_gdop: 30.0,
        }
    }
}

/// One satellite used in the solution.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SppSatellite {
    pub prn: u8,
    /// Azimuth from north, clockwise [rad].
    pub az_rad: f64,
    /// Elevation [rad].
    pub el_rad: f64,
    /// Post-fit pseudorange residual, measured minus modelled [m].
    pub residual_m: f64,
    /// A priori 1-sigma of the pseudorange [m].
    pub sigma_m: f64,
    /// Modelled ionospheric delay [m].
    pub iono_m: f64,
    /// Modelled tropospheric delay [m].
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
    /// Antenna position, ECEF [m].
    pub pos_ecef_m: Vector3<f64>,
    /// Latitude [rad], longitude [rad], ellipsoidal height [m].
    pub lla: Vector3<f64>,
    /// Receiver clock bias c dt_rx [m].
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
    /// Position 1-sigma north, east, down [m] (from `cov_m2`).
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

/// A measurement with its ephemeris.
struct Candidate<'a> {
    prn: u8,
    /// Measured pseudorange, plus the DGPS correction when `dgps` [m].
    pseudorange_m: f64,
    dgps: bool,
    doppler_hz: Option<f64>,
    eph: &'a GpsEphemeris,
}

/// One pseudorange row of the linearised system.
struct Row {
    /// Index into the candidates.
    idx: usize,
    /// Design row d(P)/d(x, y, z, c dt_rx).
    h: Vector4<f64>,
    /// Pre-fit residual (measured - modelled) [m].
    v_m: f64,
    var_m2: f64,
    az_rad: f64,
    el_rad: f64,
    iono_m: f64,
    tropo_m: f64,
    los_unit: Vector3<f64>,
}

/// A converged fit on one satellite set.
struct Fit {
    pos_ecef_m: Vector3<f64>,
    clock_bias_m: f64,
    rows: Vec<Row>,
    /// Post-fit residuals, one per row [m].
    post_m: Vec<f64>,
    /// (H^T W H)^-1.
    cov_m2: Matrix4<f64>,
    masked: Vec<u8>,
    iterations: usize,
}

/// True reception time: the receiver tag corrected by the clock estimate.
fn true_rx_time(t_rx: GpsTime, clock_bias_m: f64) -> GpsTime {
    t_rx.add_s(-clock_bias_m / SPEED_OF_LIGHT_MPS)
}

/// Variance of the broadcast URA: the smallest IS-GPS-200 URA bound at or above the
/// RINEX value, squared (6144 m for unknown or larger values) [m^2].
fn ura_variance_m2(sv_accuracy_m: f64) -> f64 {
    let bound = if sv_accuracy_m.is_finite() {
        URA_BOUNDS_M
            .iter()
            .copied()
            .find(|&b| b >= sv_accuracy_m)
            .unwrap_or(URA_BOUNDS_M[14])
    } else {
        URA_BOUNDS_M[14]
    };
    bound * bound
}

/// Build the pseudorange rows at (pos, clock) for the active candidates.
fn build_rows(
    cands: &[Candidate<'_>],
    active: &[bool],
    cfg: &SppConfig,
    t_rx: GpsTime,
    pos_ecef_m: &Vector3<f64>,
    clock_bias_m: f64,
    masked: &mut Vec<u8>,
) -> Vec<Row> {
    let lla = ecef_to_lla(pos_ecef_m);
    let near_surface = lla.z > NEAR_SURFACE_MIN_H_M;
    let t_true = true_rx_time(t_rx, clock_bias_m);
    masked.clear();
    let mut rows = Vec::with_capacity(cands.len());
    for (idx, c) in cands.iter().enumerate() {
        if !active[idx] {
            continue;
        }
        let sp: SignalPath = signal_path(c.eph, pos_ecef_m, &Vector3::zeros(), t_true);
        // Far from the surface (the Earth-centre start) elevations mean nothing:
        // every satellite is taken, without atmospheric corrections.
        let (az, el) = if near_surface {
            az_el(&lla, &sp.los_unit)
        } else {
            (0.0, std::f64::consts::FRAC_PI_2)
        };
        if near_surface && el < cfg.elevation_mask_rad {
            masked.push(c.prn);
            continue;
        }
        // A DGPS-corrected pseudorange already has the atmosphere removed.
        let (iono_m, tropo_m) = if near_surface && !c.dgps {
            cfg.atmosphere_m(&lla, az, el, t_rx.sow)
        } else {
            (0.0, 0.0)
        };
        // IS-GPS-200 20.3.3.3.3.2: the L1 C/A user's clock is dt_sv - TGD.
        let sat_clock_l1_m = SPEED_OF_LIGHT_MPS * (sp.sat_clock_bias_s - c.eph.tgd_s);
        let modelled = sp.geometric_range_m + clock_bias_m - sat_clock_l1_m + iono_m + tropo_m;
        let var_m2 = cfg.pseudorange_variance_m2(c.eph, el, iono_m, c.dgps);
        let los = sp.los_unit;
        rows.push(Row {
            idx,
            h: Vector4::new(-los.x, -los.y, -los.z, 1.0),
            v_m: c.pseudorange_m - modelled,
            var_m2,
            az_rad: az,
            el_rad: el,
            iono_m,
            tropo_m,
            los_unit: los,
        });
    }
    rows
}

/// Iterated weighted least squares on the active satellites, from (pos, clock).
fn fit(
    cands: &[Candidate<'_>],
    active: &[bool],
    cfg: &SppConfig,
    t_rx: GpsTime,
    start_pos_ecef_m: Vector3<f64>,
    start_clock_bias_m: f64,
) -> Result<Fit, SppError> {
    let required = cfg.min_satellites.max(4);
    let mut pos = start_pos_ecef_m;
    let mut clk = start_clock_bias_m;
    let mut masked = Vec::new();
    let mut last_step = f64::INFINITY;
    let max_iter = cfg.max_iterations.max(1);
    for it in 0..max_iter {
        let rows = build_rows(cands, active, cfg, t_rx, &pos, clk, &mut masked);
        if rows.len() < required {
            return Err(SppError::TooFewSatellites {
                available: rows.len(),
                required,
            });
        }
        let mut n = Matrix4::zeros();
        let mut b = Vector4::zeros();
        for r in &rows {
            let w = 1.0 / r.var_m2;
            n += r.h * r.h.transpose() * w;
            b += r.h * (r.v_m * w);
        }
        let chol = n.cholesky().ok_or(SppError::SingularGeometry)?;
        let dx = chol.solve(&b);
        if !dx.iter().all(|x| x.is_finite()) {
            return Err(SppError::SingularGeometry);
        }
        pos += dx.fixed_rows::<3>(0);
        clk += dx[3];
        last_step = dx.norm();
        if last_step < cfg.convergence_m {
            // Post-fit residuals of the linearised system at the converged state.
            let post_m = rows.iter().map(|r| r.v_m - r.h.dot(&dx)).collect();
            return Ok(Fit {
                pos_ecef_m: pos,
                clock_bias_m: clk,
                rows,
                post_m,
                cov_m2: chol.inverse(),
                masked,
                iterations: it + 1,
            });
        }
        if !pos.iter().all(|x| x.is_finite()) || pos.norm() > 1e9 {
            break;
        }
    }
    Err(SppError::NotConverged {
        iterations: max_iter,
        last_step_m: last_step,
    })
}

/// DOPs from the used lines of sight (unit weights), in NED at `lla`.
fn dops(rows: &[Row], lla: &Vector3<f64>) -> Option<Dops> {
    let c_en = c_ne(lla.x, lla.y).transpose();
    let mut n = Matrix4::zeros();
    for r in rows {
        let l = c_en * r.los_unit;
        let h = Vector4::new(-l.x, -l.y, -l.z, 1.0);
        n += h * h.transpose();
    }
    let g = n.try_inverse()?;
    let d = g.diagonal();
    if d.iter().any(|x| !x.is_finite() || *x < 0.0) {
        return None;
    }
    Some(Dops {
        gdop: d.sum().sqrt(),
        pdop: (d[0] + d[1] + d[2]).sqrt(),
        hdop: (d[0] + d[1]).sqrt(),
        vdop: d[2].sqrt(),
    })
}

/// A Doppler velocity solution.
struct Velocity {
    vel_ecef_mps: Vector3<f64>,
    clock_drift_mps: f64,
    std_ned_mps: Vector3<f64>,
    /// Post-fit range-rate residual per pseudorange row (None without Doppler) [m/s].
    range_rate_residuals_mps: Vec<Option<f64>>,
}

/// Velocity and clock drift from Doppler on the used satellites: range rate
/// -lambda_L1 D = los . (v_sat - v_rx) + c (d(dt_rx)/dt - d(dt_sv)/dt) (SYSTEM.md §3b
/// eq. 16-18 with the clock drifts). Needs 4 satellites with Doppler.
fn solve_velocity(
    cands: &[Candidate<'_>],
    fit: &Fit,
    t_rx: GpsTime,
    doppler_sigma_hz: f64,
    lla: &Vector3<f64>,
) -> Option<Velocity> {
    let with_doppler: Vec<(usize, f64)> = fit
        .rows
        .iter()
        .enumerate()
        .filter_map(|(k, r)| {
            cands[r.idx]
                .doppler_hz
                .filter(|d| d.is_finite())
                .map(|d| (k, d))
        })
        .collect();
    if with_doppler.len() < 4 {
        return None;
    }
    let t_true = true_rx_time(t_rx, fit.clock_bias_m);
    let mut vel = Vector3::zeros();
    let mut drift = 0.0;
    let mut n_inv = Matrix4::zeros();
    let mut res = vec![0.0; with_doppler.len()];
    // Linear in (v, drift) up to the light-time factor (~1e-6): a second pass settles it.
    for _ in 0..3 {
        let mut n = Matrix4::zeros();
        let mut b = Vector4::zeros();
        let mut rows = Vec::with_capacity(with_doppler.len());
        for &(k, d_hz) in &with_doppler {
            let c = &cands[fit.rows[k].idx];
            let sp = signal_path(c.eph, &fit.pos_ecef_m, &vel, t_true);
            let measured = -GPS_L1_WAVELENGTH_M * d_hz;
            let modelled =
                sp.range_rate_mps + drift - SPEED_OF_LIGHT_MPS * sp.sat_clock_drift_s_per_s;
            let h = Vector4::new(-sp.los_unit.x, -sp.los_unit.y, -sp.los_unit.z, 1.0);
            let v = measured - modelled;
            n += h * h.transpose();
            b += h * v;
            rows.push((h, v));
        }
        let chol = n.cholesky()?;
        let dx = chol.solve(&b);
        if !dx.iter().all(|x| x.is_finite()) {
            return None;
        }
        vel += dx.fixed_rows::<3>(0);
        drift += dx[3];
        n_inv = chol.inverse();
        for (r, (h, v)) in res.iter_mut().zip(&rows) {
            *r = v - h.dot(&dx);
        }
        if dx.norm() < 1e-6 {
            break;
        }
    }
    let sigma_mps = doppler_sigma_hz * GPS_L1_WAVELENGTH_M;
    let c = c_ne(lla.x, lla.y);
    let p_ned: Matrix3<f64> =
        c.transpose() * n_inv.fixed_view::<3, 3>(0, 0) * c * (sigma_mps * sigma_mps);
    let std_ned = p_ned.diagonal().map(|x| x.max(0.0).sqrt());
    let mut per_row = vec![None; fit.rows.len()];
    for (&(k, _), r) in with_doppler.iter().zip(&res) {
        per_row[k] = Some(*r);
    }
    Some(Velocity {
        vel_ecef_mps: vel,
        clock_drift_mps: drift,
        std_ned_mps: std_ned,
        range_rate_residuals_mps: per_row,
    })
}

/// Solve one epoch. `start` is the initial (position ECEF [m], clock bias [m]), e.g.
/// the previous solution; `None` starts at the Earth centre with zero clock. A fit
/// that fails from `start` is retried from the Earth centre.
pub fn solve_epoch(
    ephs: &EphemerisSet,
    t_rx: GpsTime,
    meas: &[SppMeasurement],
    cfg: &SppConfig,
    start: Option<(Vector3<f64>, f64)>,
) -> Result<SppSolution, SppError> {
    // Candidates: valid pseudorange, a usable ephemeris, first occurrence of a PRN.
    let mut cands: Vec<Candidate<'_>> = Vec::with_capacity(meas.len());
    let mut unusable = Vec::new();
    for m in meas {
        if cands.iter().any(|c| c.prn == m.prn) {
            continue;
        }
        let pr_ok = m.pseudorange_m.is_finite()
            && m.pseudorange_m > 0.0
            && m.dgps_prc_m.is_none_or(f64::is_finite);
        match ephs.select(m.prn, t_rx) {
            Some(eph) if pr_ok => cands.push(Candidate {
                prn: m.prn,
                pseudorange_m: m.pseudorange_m + m.dgps_prc_m.unwrap_or(0.0),
                dgps: m.dgps_prc_m.is_some(),
                doppler_hz: m.doppler_hz,
                eph,
            }),
            _ => unusable.push(m.prn),
        }
    }
    if cands.is_empty() {
        return Err(SppError::NoEphemeris { prns: unusable });
    }
    let required = cfg.min_satellites.max(4);
    if cands.len() < required {
        return Err(SppError::TooFewSatellites {
            available: cands.len(),
            required,
        });
    }

    let mut active = vec![true; cands.len()];
    let mut excluded: Vec<u8> = Vec::new();
    let (mut pos0, mut clk0) = start
        .filter(|(p, c)| p.iter().all(|x| x.is_finite()) && c.is_finite())
        .unwrap_or((Vector3::zeros(), 0.0));
    loop {
        let fitted = match fit(&cands, &active, cfg, t_rx, pos0, clk0) {
            // A far-off start (stale or bad previous solution) can mask the wrong
            // satellites or diverge: retry from the Earth centre.
            Err(_) if pos0 != Vector3::zeros() => {
                fit(&cands, &active, cfg, t_rx, Vector3::zeros(), 0.0)
            }
            r => r,
        }?;
        let n_used = fitted.rows.len();
        let chi2: f64 = fitted
            .rows
            .iter()
            .zip(&fitted.post_m)
            .map(|(r, v)| v * v / r.var_m2)
            .sum();
        let threshold = (n_used > 4).then(|| chi2_quantile(n_used - 4, cfg.chi2_probability));
        if let (true, Some(thr)) = (cfg.fde, threshold) {
            if chi2 > thr {
                if n_used < FDE_MIN_SATELLITES {
                    return Err(SppError::ResidualTestFailed {
                        chi2,
                        threshold: thr,
                        n_used,
                        excluded_prns: excluded,
                    });
                }
                // Exclude the largest normalised residual |v_i| / sqrt(Q_v,ii),
                // Q_v = R - H (H^T W H)^-1 H^T (Baarda's w-test).
                let worst = fitted
                    .rows
                    .iter()
                    .zip(&fitted.post_m)
                    .enumerate()
                    .filter_map(|(k, (r, v))| {
                        let qv = r.var_m2 - (r.h.transpose() * fitted.cov_m2 * r.h)[0];
                        (qv > 1e-9 * r.var_m2).then(|| (k, v.abs() / qv.sqrt()))
                    })
                    .max_by(|a, b| a.1.total_cmp(&b.1));
                let Some((k, _)) = worst else {
                    return Err(SppError::ResidualTestFailed {
                        chi2,
                        threshold: thr,
                        n_used,
                        excluded_prns: excluded,
                    });
                };
                let idx = fitted.rows[k].idx;
                active[idx] = false;
                excluded.push(cands[idx].prn);
                pos0 = fitted.pos_ecef_m;
                clk0 = fitted.clock_bias_m;
                continue;
            }
        }
        return finish(
            &cands, fitted, excluded, unusable, cfg, t_rx, chi2, threshold,
        );
    }
}

/// Assemble the solution from an accepted fit.
#[allow(clippy::too_many_arguments)]
fn finish(
    cands: &[Candidate<'_>],
    fitted: Fit,
    excluded: Vec<u8>,
    unusable: Vec<u8>,
    cfg: &SppConfig,
    t_rx: GpsTime,
    chi2: f64,
    chi2_threshold: Option<f64>,
) -> Result<SppSolution, SppError> {
    let lla = ecef_to_lla(&fitted.pos_ecef_m);
    let dops = dops(&fitted.rows, &lla).ok_or(SppError::SingularGeometry)?;
    if dops.gdop.is_nan() || dops.gdop > cfg.max_gdop {
        return Err(SppError::PoorGeometry {
            gdop: dops.gdop,
            max_gdop: cfg.max_gdop,
        });
    }
    let c = c_ne(lla.x, lla.y);
    let p_ned = c.transpose() * fitted.cov_m2.fixed_view::<3, 3>(0, 0) * c;
    let std_ned_m = p_ned.diagonal().map(|x| x.max(0.0).sqrt());
    let velocity = solve_velocity(cands, &fitted, t_rx, cfg.errors.doppler_sigma_hz, &lla);
    let rr_res = velocity.as_ref().map(|v| &v.range_rate_residuals_mps);
    let satellites: Vec<SppSatellite> = fitted
        .rows
        .iter()
        .zip(&fitted.post_m)
        .enumerate()
        .map(|(k, (r, v))| SppSatellite {
            prn: cands[r.idx].prn,
            az_rad: r.az_rad,
            el_rad: r.el_rad,
            residual_m: *v,
            sigma_m: r.var_m2.sqrt(),
            iono_m: r.iono_m,
            tropo_m: r.tropo_m,
            range_rate_residual_mps: rr_res.and_then(|x| x[k]),
        })
        .collect();
    Ok(SppSolution {
        t: t_rx,
        t_fix: true_rx_time(t_rx, fitted.clock_bias_m),
        pos_ecef_m: fitted.pos_ecef_m,
        lla,
        clock_bias_m: fitted.clock_bias_m,
        vel_ecef_mps: velocity.as_ref().map(|v| v.vel_ecef_mps),
        clock_drift_mps: velocity.as_ref().map(|v| v.clock_drift_mps),
        n_used: satellites.len(),
        used_prns: satellites.iter().map(|s| s.prn).collect(),
        excluded_prns: excluded,
        masked_prns: fitted.masked,
        unusable_prns: unusable,
        satellites,
        dops,
        cov_m2: fitted.cov_m2,
        std_ned_m,
        vel_std_ned_mps: velocity.as_ref().map(|v| v.std_ned_mps),
        chi2,
        chi2_threshold,
        iterations: fitted.iterations,
    })
}

/// An SPP solver that starts each epoch from its previous solution.
#[derive(Clone, Debug, Default)]
pub struct SppSolver {
    pub config: SppConfig,
    last: Option<(Vector3<f64>, f64)>,
}

impl SppSolver {
    pub fn new(config: SppConfig) -> Self {
        SppSolver { config, last: None }
    }

    /// Solve one epoch, starting from the last solution (or the Earth centre).
    pub fn solve(
        &mut self,
        ephs: &EphemerisSet,
        t_rx: GpsTime,
        meas: &[SppMeasurement],
    ) -> Result<SppSolution, SppError> {
        let r = solve_epoch(ephs, t_rx, meas, &self.config, self.last);
        if let Ok(s) = &r {
            self.last = Some((s.pos_ecef_m, s.clock_bias_m));
        }
        r
    }

    /// Forget the previous solution.
    pub fn reset(&mut self) {
        self.last = None;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::constellation::nominal_gps24;
    use navfuse_core::earth::lla_to_ecef;

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
    fn measure(
        ephs: &EphemerisSet,
        t_rx: GpsTime,
        tr: &Truth,
        mask_deg: f64,
    ) -> Vec<SppMeasurement> {
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
            out.push(SppMeasurement {
                prn,
                pseudorange_m: pr,
                doppler_hz: Some(-rr / GPS_L1_WAVELENGTH_M),
                dgps_prc_m: None,
            });
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
        assert!(sol.excluded_prns.is_empty());
        assert!(sol.chi2 < 1e-6);
        // Satellites between 5 and 10 deg are measured but masked.
        assert_eq!(sol.n_used + sol.masked_prns.len(), meas.len());
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
        let corrected: Vec<u8> = clean.used_prns.iter().copied().step_by(2).collect();
        let dgps: Vec<SppMeasurement> = meas
            .iter()
            .map(|m| match clean.satellites.iter().find(|s| s.prn == m.prn) {
                Some(s) if corrected.contains(&m.prn) => {
                    let err = 4.0 * f64::from(m.prn).sin();
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
        assert_eq!(sol.used_prns, clean.used_prns);
        let em = &config().errors;
        for s in &sol.satellites {
            let dgps = corrected.contains(&s.prn);
            assert_eq!(dgps, s.iono_m == 0.0 && s.tropo_m == 0.0, "G{:02}", s.prn);
            if dgps {
                let var = em.elevation_variance_m2(s.el_rad) + em.dgps_sigma_m.powi(2);
                assert!((s.sigma_m - var.sqrt()).abs() < 1e-12);
            }
        }
        // A non-finite correction makes the measurement unusable.
        let mut bad = dgps.clone();
        bad[0].dgps_prc_m = Some(f64::NAN);
        let sol = solve_epoch(&ephs, t_rx, &bad, &config(), None).unwrap();
        assert_eq!(sol.unusable_prns, vec![bad[0].prn]);
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
        assert!(clean.n_used > FDE_MIN_SATELLITES, "{}", clean.n_used);
        for k in 0..clean.n_used {
            let bad = clean.used_prns[k];
            let m = meas.iter_mut().find(|m| m.prn == bad).unwrap();
            m.pseudorange_m += 100.0;
            let sol = solve_epoch(&ephs, t_rx, &meas, &cfg, None).unwrap();
            assert_eq!(sol.excluded_prns, vec![bad]);
            assert!(!sol.used_prns.contains(&bad));
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
            let m = meas.iter_mut().find(|m| m.prn == bad).unwrap();
            m.pseudorange_m -= 100.0;
        }
    }

    #[test]
    fn fde_with_five_satellites_detects_but_cannot_exclude() {
        let (ephs, t_rx, _, meas) = setup();
        let clean = solve_epoch(&ephs, t_rx, &meas, &config(), None).unwrap();
        let keep: Vec<u8> = clean.used_prns[..5].to_vec();
        let mut five: Vec<SppMeasurement> = meas
            .iter()
            .filter(|m| keep.contains(&m.prn))
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
                prn: 31,
                pseudorange_m: 2.1e7,
                doppler_hz: None,
                dgps_prc_m: None,
            },
            SppMeasurement {
                prn: 1,
                pseudorange_m: f64::NAN,
                doppler_hz: None,
                dgps_prc_m: None,
            },
            SppMeasurement {
                prn: 2,
                pseudorange_m: 0.0,
                doppler_hz: None,
                dgps_prc_m: None,
            },
        ];
        let e = solve_epoch(&ephs, t_rx, &junk, &cfg, None).unwrap_err();
        assert_eq!(
            e,
            SppError::NoEphemeris {
                prns: vec![31, 1, 2]
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
}
