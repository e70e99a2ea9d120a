//! RINEX GNSS input for the run pipeline: observations of the configured systems and
//! signals, broadcast ephemerides or precise products (and DGPS corrections) go
//! through the GNSS layer (`navfuse_gnss::tight_prep`) and come out as single point
//! fixes (loose coupling) or per-satellite epochs (tight).

use crate::Error;
use nalgebra::Vector3;
use navfuse_core::earth::lla_to_ecef;
use navfuse_core::sat::System;
use navfuse_core::{GnssFix, GnssRawEpoch};
use navfuse_gnss::dgps::{corrections_from_reference_station, DgpsCorrections};
use navfuse_gnss::orbit_source::RunOrbits;
use navfuse_gnss::signal_plan::SignalPlan;
use navfuse_gnss::spp::{IonoModel, SppConfig};
use navfuse_gnss::tight_prep::{EpochPreparer, TightPrepConfig};
use navfuse_gnss::{EphemerisSet, ObsEpoch};
use navfuse_io::input::{DgpsKind, GnssSource, Orbits, RinexGnss};
use navfuse_io::rinex_nav::read_rinex_nav;
use navfuse_io::rinex_obs::{read_rinex_obs, read_rinex_obs_all};

/// What the GNSS layer made of a RINEX input. Times are seconds of `gps_week`
/// (the first observation's week) plus the source's time offset.
pub struct RinexInput {
    /// Single point fixes (every epoch with a solution).
    pub fixes: Vec<GnssFix>,
    /// Per-satellite epochs (empty satellite lists are dropped).
    pub raw: Vec<GnssRawEpoch>,
    pub gps_week: u32,
    /// Facts worth a line in the run summary.
    pub notes: Vec<String>,
    /// The readers' findings that did not stop the read (a damaged last record).
    pub warnings: Vec<String>,
}

/// The GNSS layer's settings for a RINEX input.
pub fn prep_config(r: &RinexGnss, iono: IonoModel) -> TightPrepConfig {
    let d = TightPrepConfig::default();
    let mut errors = d.spp.errors.clone();
    if let Some((sigma, reference)) = r.cn0_weighting {
        errors.cn0_sigma_m = Some(sigma);
        errors.cn0_reference_dbhz = reference;
    }
    TightPrepConfig {
        spp: SppConfig {
            elevation_mask_rad: r.elevation_mask_deg.to_radians(),
            iono,
            fde: r.fde,
            errors,
            ..d.spp
        },
        dgps_max_age_s: r.dgps.as_ref().map_or(d.dgps_max_age_s, |g| g.max_age_s),
        ..d
    }
}

/// Read the observations, navigation data (or precise products) and DGPS source of
/// a RINEX input and prepare every epoch of the systems `systems` (`[gnss] systems`).
pub fn load_rinex(
    src: &GnssSource,
    r: &RinexGnss,
    systems: &[System],
) -> Result<RinexInput, Error> {
    let nav = read_rinex_nav(&r.nav_path)?;
    let obs = read_rinex_obs_all(&src.path)?;
    prepare_observations(
        src,
        r,
        systems,
        ReadObservations {
            nav_name: r.nav_path.display().to_string(),
            nav,
            header: obs.header,
            epochs: obs.epochs,
            warnings: obs.warnings,
        },
    )
}

/// Observations and navigation records as a reader gave them (RINEX files, a UBX
/// log): what [`prepare_observations`] turns into fixes and tight epochs.
pub struct ReadObservations {
    /// The navigation source, for messages.
    pub nav_name: String,
    pub nav: navfuse_io::rinex_nav::RinexNav,
    pub header: navfuse_gnss::obs::ObsSignalsHeader,
    pub epochs: Vec<navfuse_gnss::MultiObsEpoch>,
    /// The observation reader's warnings.
    pub warnings: Vec<String>,
}

/// Prepare every epoch of `read` for the systems `systems` with the settings `r`
/// (its `nav_path` is not read here), orbits and DGPS as configured.
pub fn prepare_observations(
    src: &GnssSource,
    r: &RinexGnss,
    systems: &[System],
    read: ReadObservations,
) -> Result<RinexInput, Error> {
    let systems = systems.to_vec();
    let ReadObservations {
        nav_name,
        nav,
        header,
        epochs,
        warnings: obs_warnings,
    } = read;
    let broadcast = nav.store();
    let counts = broadcast.counts();
    if !systems.iter().any(|s| counts.contains_key(s)) {
        return Err(Error::Other(format!(
            "{nav_name}: no ephemerides of {}",
            systems
                .iter()
                .map(|s| s.name())
                .collect::<Vec<_>>()
                .join(", ")
        )));
    }
    let mut warnings: Vec<String> = Vec::new();
    let iono = IonoModel::from_broadcast(nav.iono_alpha, nav.iono_beta);
    // DGPS corrections from a reference station are computed for GPS.
    let gps_ephs = EphemerisSet::new(nav.gps);
    let orbits = match &r.orbits {
        Orbits::Broadcast => RunOrbits::Broadcast(broadcast),
        Orbits::Sp3 { sp3, clk } => RunOrbits::Precise {
            products: crate::spp::read_precise(sp3, clk)?,
            broadcast,
        },
    };
    for sys in &systems {
        if !counts.contains_key(sys) {
            warnings.push(format!(
                "{nav_name}: no {} ephemerides: its satellites are not used",
                sys.name()
            ));
        }
    }
    let plan = SignalPlan {
        systems: systems.clone(),
        codes: r.signals.clone(),
        dual_frequency: r.dual_frequency,
    };
    warnings.extend(nav.warnings.iter().chain(&obs_warnings).cloned());
    let channels = crate::spp::glonass_channels(&header, orbits.broadcast());
    let Some(week) = epochs.first().map(|e| e.t.week) else {
        return Err(Error::Other(format!(
            "{}: no observation epochs",
            src.path.display()
        )));
    };
    let cfg = prep_config(r, iono);
    let dgps = match r.dgps.as_ref().map(|d| &d.kind) {
        None => None,
        Some(DgpsKind::Corrections(p)) => {
            // With the station position (the file's `#` line), the corrections also
            // carry the model difference between rover and station heights.
            let f = navfuse_io::dgps::read_dgps_file(p)?;
            let c = DgpsCorrections::new(f.corrections);
            Some(match f.reference_lla {
                Some(lla) => c.with_reference_position(lla_to_ecef(&lla)),
                None => c,
            })
        }
        Some(DgpsKind::ReferenceStation {
            obs_path,
            position_lla,
        }) => {
            let base: Vec<ObsEpoch> = read_rinex_obs(obs_path)?;
            let ref_ecef = lla_to_ecef(&Vector3::from(*position_lla));
            Some(
                DgpsCorrections::new(corrections_from_reference_station(
                    &gps_ephs,
                    &base,
                    ref_ecef,
                    cfg.spp.elevation_mask_rad,
                ))
                .with_reference_position(ref_ecef),
            )
        }
    };
    let have_dgps = dgps.is_some();
    let mut prep = EpochPreparer::new(orbits, cfg, dgps);
    let mut out = RinexInput {
        fixes: Vec::new(),
        raw: Vec::with_capacity(epochs.len()),
        gps_week: week.max(0) as u32,
        notes: Vec::new(),
        warnings: std::mem::take(&mut warnings),
    };
    let (mut no_fix, mut dgps_applied, mut dgps_missing) = (0usize, 0usize, 0usize);
    for e in &epochs {
        let chosen = crate::spp::choose_signals(e, &plan, &channels);
        let mut p = prep.prepare_signals(e.t, e.flag, &chosen, week);
        p.raw.t += src.time_offset_s;
        if let Some(f) = p.raw.fix.as_mut() {
            f.t += src.time_offset_s;
            out.fixes.push(*f);
        } else {
            no_fix += 1;
        }
        dgps_applied += p.dgps_applied;
        dgps_missing += p.dgps_missing;
        if !p.raw.sats.is_empty() {
            out.raw.push(p.raw);
        }
    }
    out.notes.push(format!(
        "{}: {} epochs, {} with a single point fix",
        src.path.display(),
        epochs.len(),
        epochs.len() - no_fix
    ));
    if have_dgps {
        out.notes.push(format!(
            "DGPS: {dgps_applied} pseudoranges corrected, {dgps_missing} without a correction (uncorrected, broadcast models)"
        ));
    }
    Ok(out)
}
