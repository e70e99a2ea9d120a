//! `navfuse spp OBS NAV...`: GNSS-only single point positioning (navfuse_app::spp).

use anyhow::{anyhow, bail, Result};
use navfuse_app::spp::{run_spp, write_spp_pos, SppJob};
use navfuse_gnss::signal_plan::{parse_codes, parse_systems};
use std::path::PathBuf;

/// `navfuse spp` (its --help).
#[derive(clap::Args)]
pub struct SppArgs {
    /// RINEX 2/3/4 observation file (plain, .gz or Compact RINEX).
    pub obs: PathBuf,
    /// RINEX navigation file(s) with the broadcast ephemerides (mixed or per system).
    #[arg(required = true)]
    pub nav: Vec<PathBuf>,
    /// Constellations, comma-separated RINEX letters or names: G GPS, R GLONASS, E
    /// Galileo, C BeiDou, J QZSS, I NavIC (e.g. G,E or GPS,Galileo). GPS and QZSS share the receiver clock; each other
    /// system gets an inter-system bias.
    #[arg(long, default_value = "G", value_name = "LIST")]
    pub systems: String,
    /// Code preferences per system, e.g. `R:C1P+C1C,E:C1X` (default: L1/E1/G1 and
    /// BeiDou B1I with the priorities of docs/GNSS.md "Signal selection").
    #[arg(long, value_name = "SYS:CODE[+CODE],...")]
    pub signals: Option<String>,
    /// Use the dual-frequency ionosphere-free code where a satellite has two bands
    /// (the others keep their single code and the ionosphere model).
    #[arg(long)]
    pub dual_frequency: bool,
    /// SP3 precise orbit file(s) instead of the broadcast orbits (the broadcast
    /// records still give health and group delays).
    #[arg(long, value_name = "FILE")]
    pub sp3: Vec<PathBuf>,
    /// RINEX clock file(s) with the SP3 orbits (else the SP3 clocks).
    #[arg(long, value_name = "FILE")]
    pub clk: Vec<PathBuf>,
    /// Elevation mask [deg].
    #[arg(long, default_value_t = 10.0, value_name = "DEG")]
    pub elevation_mask: f64,
    /// Ionosphere: brdc (Klobuchar from the navigation header) or off.
    #[arg(long, default_value = "brdc", value_parser = ["brdc", "off"])]
    pub iono: String,
    /// Troposphere: saas (Saastamoinen) or off.
    #[arg(long, default_value = "saas", value_parser = ["saas", "off"])]
    pub tropo: String,
    /// C/N0 weighting: add s^2 10^(0.1 max(REF - C/N0, 0)) to each pseudorange's
    /// variance, with s this value [m] (RTKLIB demo5's stats-errsnr model; off by
    /// default).
    #[arg(long, value_name = "M")]
    pub cn0_sigma: Option<f64>,
    /// REF of --cn0-sigma [dB-Hz].
    #[arg(long, default_value_t = 52.0, value_name = "DBHZ")]
    pub cn0_reference: f64,
    /// No fault detection and exclusion (the chi-square test of the residuals).
    #[arg(long)]
    pub no_fde: bool,
    /// Weight the pseudoranges as RTKLIB 2.4.3's pntpos does (b^2 / sin el instead
    /// of navfuse's b^2 / sin^2 el; Galileo SISA as its RINEX reader indexes it), to
    /// compare with rnx2rtkp epoch by epoch.
    #[arg(long)]
    pub rtklib_weights: bool,
    /// The solution as an RTKLIB .pos file (GPST, llh, Q = 5, ns, sdn..sdun).
    #[arg(long, value_name = "FILE.pos")]
    pub out: Option<PathBuf>,
}

pub fn main(a: &SppArgs) -> Result<()> {
    let systems = parse_systems(&a.systems).map_err(|e| anyhow!("--systems: {e}"))?;
    let signals = match &a.signals {
        Some(x) => parse_codes(x).map_err(|e| anyhow!("--signals: {e}"))?,
        None => Vec::new(),
    };
    if let Some(s) = a.cn0_sigma {
        if !(s.is_finite() && s > 0.0) {
            bail!("--cn0-sigma: expected a sigma > 0 m, got {s}");
        }
    }
    if !(10.0..=70.0).contains(&a.cn0_reference) {
        bail!(
            "--cn0-reference: expected 10-70 dB-Hz, got {}",
            a.cn0_reference
        );
    }
    let job = SppJob {
        obs: a.obs.clone(),
        navs: a.nav.clone(),
        systems,
        signals,
        dual_frequency: a.dual_frequency,
        sp3: a.sp3.clone(),
        clk: a.clk.clone(),
        elevation_mask_deg: a.elevation_mask,
        broadcast_iono: a.iono == "brdc",
        troposphere: a.tropo == "saas",
        fde: !a.no_fde,
        rtklib_weights: a.rtklib_weights,
        cn0_weighting: a.cn0_sigma.map(|s| (s, a.cn0_reference)),
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
