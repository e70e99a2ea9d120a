//! `navfuse spp OBS NAV...`: GNSS-only single point positioning (navfuse_app::spp).

use anyhow::{bail, Result};
use navfuse_app::spp::{run_spp, write_spp_pos, SppJob};
use navfuse_core::sat::System;
use std::path::PathBuf;

/// `navfuse spp` (its --help).
#[derive(clap::Args)]
pub struct SppArgs {
    /// RINEX 2/3 observation file.
    pub obs: PathBuf,
    /// RINEX navigation file(s) with the broadcast ephemerides.
    #[arg(required = true)]
    pub nav: Vec<PathBuf>,
    /// Constellations, comma-separated RINEX letters (G GPS, R GLONASS, E Galileo, C
    /// BeiDou, J QZSS). Only G works today; the others are refused with a message.
    #[arg(long, default_value = "G", value_name = "LIST")]
    pub systems: String,
    /// Elevation mask [deg].
    #[arg(long, default_value_t = 10.0, value_name = "DEG")]
    pub elevation_mask: f64,
    /// Ionosphere: brdc (Klobuchar from the navigation header) or off.
    #[arg(long, default_value = "brdc", value_parser = ["brdc", "off"])]
    pub iono: String,
    /// Troposphere: saas (Saastamoinen) or off.
    #[arg(long, default_value = "saas", value_parser = ["saas", "off"])]
    pub tropo: String,
    /// No fault detection and exclusion (the chi-square test of the residuals).
    #[arg(long)]
    pub no_fde: bool,
    /// Weight the pseudoranges as RTKLIB 2.4.3's pntpos does (b^2 / sin el) instead
    /// of navfuse's b^2 / sin^2 el, to compare with rnx2rtkp epoch by epoch.
    #[arg(long)]
    pub rtklib_weights: bool,
    /// The solution as an RTKLIB .pos file (GPST, llh, Q = 5, ns, sdn..sdun).
    #[arg(long, value_name = "FILE.pos")]
    pub out: Option<PathBuf>,
}

pub fn main(a: &SppArgs) -> Result<()> {
    let mut systems = Vec::new();
    for s in a
        .systems
        .split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
    {
        let sys = s
            .chars()
            .next()
            .filter(|_| s.len() == 1)
            .and_then(System::from_letter)
            .filter(|_| s != " ");
        match sys {
            Some(sys) => systems.push(sys),
            None => bail!("--systems: `{s}` is not a constellation letter (G, R, E, C, J)"),
        }
    }
    let job = SppJob {
        obs: a.obs.clone(),
        navs: a.nav.clone(),
        systems,
        elevation_mask_deg: a.elevation_mask,
        broadcast_iono: a.iono == "brdc",
        troposphere: a.tropo == "saas",
        fde: !a.no_fde,
        elevation_sin_power: if a.rtklib_weights { 1.0 } else { 2.0 },
    };
    let run = run_spp(&job)?;
    for n in &run.notes {
        eprintln!("navfuse: note: {n}");
    }
    let solved = run.solved();
    if let Some(out) = &a.out {
        write_spp_pos(out, &run, a.elevation_mask)?;
    }
    let mean_ns = run
        .epochs
        .iter()
        .filter_map(|e| e.1.as_ref().ok())
        .map(|s| s.n_used as f64)
        .sum::<f64>()
        / solved.max(1) as f64;
    eprintln!(
        "navfuse spp: {solved} of {} epochs solved, {mean_ns:.1} satellites on average{}",
        run.epochs.len(),
        a.out
            .as_ref()
            .map_or(String::new(), |p| format!("; written to {}", p.display()))
    );
    if solved == 0 {
        bail!("no epoch could be solved (see the notes above)");
    }
    Ok(())
}
