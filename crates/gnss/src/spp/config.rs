//! SPP settings: the ionospheric model, the pseudorange error budget (with the
//! broadcast URA of IS-GPS-200 20.3.3.3.1.3) and the solver options.

use crate::atmosphere::{klobuchar_l1_delay_m, saastamoinen_slant_m};
use crate::orbit_source::OrbitAccuracy;
use nalgebra::Vector3;
use navfuse_core::sat::System;

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
    /// Constant term a of sigma_el^2 = F^2 (a^2 + b^2 / sin^p el) \[m\].
    pub sigma_a_m: f64,
    /// Elevation term b \[m\].
    pub sigma_b_m: f64,
    /// Error factor F common to all systems (1); each system's own factor
    /// ([`system_error_factor`]) multiplies it.
    pub error_factor: f64,
    /// Power p of sin(el) in the elevation term b^2 / sin^p el: 2 (default, the
    /// usual model and RTKLIB's manual); RTKLIB 2.4.3's `pntpos` code uses 1, which
    /// reproduces its weights exactly.
    pub elevation_sin_power: f64,
    /// Add the orbit and clock error variance of the record: the broadcast user range
    /// accuracy squared, the RINEX value rounded up to the IS-GPS-200 20.3.3.3.1.3 URA
    /// bound (2.4, 3.4, 4.85, ... 6144 m) for GPS, QZSS and BeiDou, the SISA for
    /// Galileo, 5 m for GLONASS (`orbit_source::broadcast_variance_m2`).
    pub use_ura: bool,
    /// Galileo SISA as RTKLIB 2.4.3 indexes it (`OrbitAccuracy::variance_m2`), to
    /// compare with rnx2rtkp; default off (the SISA as broadcast).
    pub rtklib_sisa: bool,
    /// Code bias (TGD / receiver) error \[m\].
    pub code_bias_sigma_m: f64,
    /// Klobuchar model error as a fraction of the modelled delay.
    pub iono_model_fraction: f64,
    /// Ionospheric error without a model \[m\].
    pub iono_none_sigma_m: f64,
    /// Saastamoinen model error s, mapped as s / (sin el + 0.1) \[m\].
    pub tropo_model_sigma_m: f64,
    /// Tropospheric error without a model \[m\].
    pub tropo_none_sigma_m: f64,
    /// Error left after a DGPS correction (reference station noise and multipath,
    /// spatial and temporal decorrelation) \[m\]; replaces the URA, code bias, iono and
    /// tropo terms for a corrected satellite.
    pub dgps_sigma_m: f64,
    /// Doppler error \[Hz\] (sets the velocity covariance; the velocity fit is
    /// unweighted).
    pub doppler_sigma_hz: f64,
    /// Signal-strength term s: s^2 10^(0.1 max(C/N0_ref - C/N0, 0)) is added to the
    /// variance of a measurement with a C/N0 (RTKLIB demo5's `stats-errsnr` model);
    /// None (default): no C/N0 weighting.
    pub cn0_sigma_m: Option<f64>,
    /// C/N0_ref of that term [dB-Hz] (default 52, demo5's `stats-snrmax`).
    pub cn0_reference_dbhz: f64,
}

impl Default for SppErrorModel {
    fn default() -> Self {
        SppErrorModel {
            sigma_a_m: 0.3,
            sigma_b_m: 0.3,
            error_factor: 1.0,
            elevation_sin_power: 2.0,
            use_ura: true,
            rtklib_sisa: false,
            code_bias_sigma_m: 0.3,
            iono_model_fraction: 0.5,
            iono_none_sigma_m: 5.0,
            tropo_model_sigma_m: 0.3,
            tropo_none_sigma_m: 3.0,
            dgps_sigma_m: 1.0,
            doppler_sigma_hz: 1.0,
            cn0_sigma_m: None,
            cn0_reference_dbhz: 52.0,
        }
    }
}

/// Each system's code error factor (RTKLIB's EFACT_*: GLONASS 1.5 for its FDMA
/// inter-frequency code biases and coarser C/A chips, NavIC 1.5, SBAS 3, others 1).
pub fn system_error_factor(system: System) -> f64 {
    match system {
        System::Glonass | System::Navic => 1.5,
        System::Sbas => 3.0,
        System::Gps | System::Galileo | System::BeiDou | System::Qzss => 1.0,
    }
}

impl SppErrorModel {
    /// Elevation-dependent measurement variance F^2 (a^2 + b^2 / sin^p el) of a GPS
    /// satellite [m^2].
    pub fn elevation_variance_m2(&self, el_rad: f64) -> f64 {
        let s = el_rad.sin().max(1e-3).powf(self.elevation_sin_power);
        self.error_factor.powi(2) * (self.sigma_a_m.powi(2) + self.sigma_b_m.powi(2) / s)
    }

    /// The same for a satellite of `system`: times the system's factor squared.
    pub fn system_elevation_variance_m2(&self, system: System, el_rad: f64) -> f64 {
        system_error_factor(system).powi(2) * self.elevation_variance_m2(el_rad)
    }

    /// The signal-strength variance term [m^2] for a measurement with `cn0_dbhz`
    /// (0 without the term or a C/N0).
    pub fn cn0_variance_m2(&self, cn0_dbhz: Option<f64>) -> f64 {
        match (self.cn0_sigma_m, cn0_dbhz.filter(|c| c.is_finite())) {
            (Some(s), Some(c)) => s * s * 10f64.powf(0.1 * (self.cn0_reference_dbhz - c).max(0.0)),
            _ => 0.0,
        }
    }
}

/// SPP settings.
#[derive(Clone, Debug, PartialEq)]
pub struct SppConfig {
    /// Elevation mask \[rad\] (default 10 deg).
    pub elevation_mask_rad: f64,
    /// Ionospheric correction (default none; use `IonoModel::from_broadcast`).
    pub iono: IonoModel,
    /// Saastamoinen tropospheric correction (default on).
    pub tropo_saastamoinen: bool,
    /// Error budget and weighting.
    pub errors: SppErrorModel,
    /// Maximum Gauss-Newton iterations per solution (default 10).
    pub max_iterations: usize,
    /// Convergence: norm of the state update (position and clock) below this \[m\].
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
    /// Modelled (ionospheric, tropospheric) L1 delays \[m\] for a receiver at `lla`
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

    /// A priori pseudorange variance [m^2] of one satellite of `system` at `el_rad`:
    /// F_sys^2 F^2 (a^2 + b^2 / sin^p el) + sigma_eph^2 + sigma_cb^2 + sigma_I^2 +
    /// sigma_T^2, or F_sys^2 F^2 (a^2 + b^2 / sin^p el) + sigma_DGPS^2 when `dgps`
    /// (docs/GNSS.md). `orbit` is the record's stated accuracy (URA, SISA, ...); `iono_m` the modelled delay on the signal (sets sigma_I with
    /// Klobuchar). An ionosphere-free code (`iono_free`) has 3 times the noise and
    /// no ionospheric error term.
    pub fn pseudorange_variance_m2(
        &self,
        system: System,
        orbit: &OrbitAccuracy,
        el_rad: f64,
        iono_m: f64,
        dgps: bool,
        iono_free: bool,
    ) -> f64 {
        let em = &self.errors;
        let noise_factor = if iono_free { 9.0 } else { 1.0 };
        let el_var = noise_factor * em.system_elevation_variance_m2(system, el_rad);
        let var = if dgps {
            el_var + em.dgps_sigma_m.powi(2)
        } else {
            let iono_var = match self.iono {
                _ if iono_free => 0.0,
                IonoModel::Klobuchar { .. } => (em.iono_model_fraction * iono_m).powi(2),
                IonoModel::None => em.iono_none_sigma_m.powi(2),
            };
            let tropo_var = if self.tropo_saastamoinen {
                (em.tropo_model_sigma_m / (el_rad.sin() + 0.1)).powi(2)
            } else {
                em.tropo_none_sigma_m.powi(2)
            };
            let ura_var = if em.use_ura {
                orbit.variance_m2(em.rtklib_sisa)
            } else {
                0.0
            };
            el_var + ura_var + em.code_bias_sigma_m.powi(2) + iono_var + tropo_var
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
