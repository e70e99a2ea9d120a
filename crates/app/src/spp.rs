//! `navfuse spp`: the GNSS-only single point solution of a RINEX observation file
//! with broadcast ephemerides (navfuse_gnss::spp), epoch by epoch, written as an
//! RTKLIB `.pos` file so that it can be compared with RTKLIB's `rnx2rtkp` directly.
//! GPS L1 C/A for now; the other constellations come with issue 19's
//! multi-system SPP (asking for them is an error that says so).

use crate::error::Error;
use navfuse_core::earth::c_ne;
use navfuse_core::sat::System;
use navfuse_gnss::spp::{IonoModel, SppConfig, SppError, SppMeasurement, SppSolution, SppSolver};
use navfuse_gnss::{EphemerisSet, GpsTime};
use navfuse_io::export::{PosFile, PosLine};
use navfuse_io::rinex_nav::read_rinex_nav;
use navfuse_io::rinex_obs::{read_rinex_obs, ObsEpoch};
use std::path::{Path, PathBuf};

/// What to solve and how (the settings RTKLIB's single mode has).
#[derive(Clone, Debug)]
pub struct SppJob {
    pub obs: PathBuf,
    pub navs: Vec<PathBuf>,
    pub systems: Vec<System>,
    pub elevation_mask_deg: f64,
    /// Broadcast Klobuchar ionosphere when the navigation header has its
    /// coefficients (RTKLIB `ionoopt=brdc`); false: none.
    pub broadcast_iono: bool,
    /// Saastamoinen troposphere (RTKLIB `tropopt=saas`).
    pub troposphere: bool,
    /// Chi-square fault detection and exclusion.
    pub fde: bool,
    /// Power p of the elevation weighting b^2 / sin^p el: 2 (navfuse's default), 1
    /// (what RTKLIB 2.4.3's pntpos computes, to compare with it).
    pub elevation_sin_power: f64,
}

/// The solutions, one per observation epoch, and what the run found.
#[derive(Clone, Debug)]
pub struct SppRun {
    pub epochs: Vec<(GpsTime, Result<SppSolution, SppError>)>,
    pub notes: Vec<String>,
}

impl SppRun {
    pub fn solved(&self) -> usize {
        self.epochs.iter().filter(|e| e.1.is_ok()).count()
    }
}

/// Read the files and solve every epoch.
pub fn run_spp(job: &SppJob) -> Result<SppRun, Error> {
    let others: Vec<String> = job
        .systems
        .iter()
        .filter(|s| **s != System::Gps)
        .map(|s| format!("{} ({})", s.letter(), s.name()))
        .collect();
    if !others.is_empty() {
        return Err(Error::Other(format!(
            "--systems {}: not supported yet (the multi-constellation SPP is issue 19's next step); use --systems G",
            others.join(", ")
        )));
    }
    let mut notes = Vec::new();
    let mut ephs = Vec::new();
    let (mut alpha, mut beta) = (None, None);
    for p in &job.navs {
        let nav = read_rinex_nav(p)?;
        if nav.skipped_records > 0 {
            notes.push(format!(
                "{}: {} records of other systems skipped",
                p.display(),
                nav.skipped_records
            ));
        }
        notes.extend(nav.warnings.iter().map(|w| format!("{}: {w}", p.display())));
        alpha = alpha.or(nav.iono_alpha);
        beta = beta.or(nav.iono_beta);
        ephs.extend(nav.gps);
    }
    if ephs.is_empty() {
        return Err(Error::Other(format!(
            "{}: no GPS ephemerides",
            job.navs
                .iter()
                .map(|p| p.display().to_string())
                .collect::<Vec<_>>()
                .join(", ")
        )));
    }
    let iono = if job.broadcast_iono {
        let m = IonoModel::from_broadcast(alpha, beta);
        if matches!(m, IonoModel::None) {
            notes.push(
                "no Klobuchar coefficients in the navigation header(s): no ionospheric correction"
                    .into(),
            );
        }
        m
    } else {
        IonoModel::None
    };
    let set = EphemerisSet::new(ephs);
    let obs = read_rinex_obs(&job.obs)?;
    if obs.is_empty() {
        return Err(Error::Other(format!(
            "{}: no GPS observation epochs",
            job.obs.display()
        )));
    }
    let mut cfg = SppConfig {
        elevation_mask_rad: job.elevation_mask_deg.to_radians(),
        iono,
        tropo_saastamoinen: job.troposphere,
        fde: job.fde,
        ..SppConfig::default()
    };
    cfg.errors.elevation_sin_power = job.elevation_sin_power;
    let epochs = solve_epochs(&obs, &set, cfg);
    Ok(SppRun { epochs, notes })
}

/// Solve every epoch's GPS L1 C/A pseudoranges (and Dopplers) with `cfg`.
pub fn solve_epochs(
    obs: &[ObsEpoch],
    ephs: &EphemerisSet,
    cfg: SppConfig,
) -> Vec<(GpsTime, Result<SppSolution, SppError>)> {
    let mut solver = SppSolver::new(cfg);
    obs.iter()
        .map(|e| {
            let meas: Vec<SppMeasurement> = e
                .sats
                .iter()
                .filter_map(|s| {
                    s.pseudorange_m.map(|pr| SppMeasurement {
                        prn: s.prn,
                        pseudorange_m: pr,
                        doppler_hz: s.doppler_hz,
                        dgps_prc_m: None,
                    })
                })
                .collect();
            (e.t, solver.solve(ephs, e.t, &meas))
        })
        .collect()
}

/// Write the solved epochs as an RTKLIB `.pos` file (Q = 5 single, ns, the
/// position covariance in east-north-up as RTKLIB writes it), at the time of
/// validity as RTKLIB does.
pub fn write_spp_pos(path: &Path, run: &SppRun, elevation_mask_deg: f64) -> Result<(), Error> {
    let mut f = PosFile::create(
        path,
        "single point positioning, navfuse spp",
        "Single (GPS L1 C/A, broadcast ephemerides)",
        elevation_mask_deg,
    )?;
    for (_, r) in &run.epochs {
        let Ok(s) = r else { continue };
        // Covariance of the position in the local east-north-up frame.
        let c = c_ne(s.lla.x, s.lla.y);
        let p_ecef = s.cov_m2.fixed_view::<3, 3>(0, 0).into_owned();
        let p_ned = c.transpose() * p_ecef * c;
        let enu = |i: usize| [1, 0, 2][i];
        let sign = |i: usize| if i == 2 { -1.0 } else { 1.0 };
        let cov = |i: usize, j: usize| sign(i) * sign(j) * p_ned[(enu(i), enu(j))];
        // RTKLIB: sdn sde sdu, then sdne sdeu sdun as sign(c) sqrt(|c|).
        let sq = |v: f64| v.signum() * v.abs().sqrt();
        let t = s.t_fix;
        f.write(&PosLine {
            gps_week: u32::try_from(t.week).unwrap_or(0),
            sow: t.sow,
            lla: s.lla,
            q: 5,
            ns: s.n_used,
            sd_m: [
                cov(1, 1).max(0.0).sqrt(),
                cov(0, 0).max(0.0).sqrt(),
                cov(2, 2).max(0.0).sqrt(),
                sq(cov(1, 0)),
                sq(cov(0, 2)),
                sq(cov(2, 1)),
            ],
            age_s: 0.0,
            ratio: 0.0,
        })?;
    }
    Ok(f.finish()?)
}
