//! `navfuse spp`: the GNSS-only single point solution of a RINEX observation file
//! (navfuse_gnss::spp), epoch by epoch, with the broadcast ephemerides of every
//! system or precise SP3 orbits and RINEX clocks, written as an RTKLIB `.pos` file
//! so that it can be compared with RTKLIB's `rnx2rtkp` directly.

use crate::error::Error;
use navfuse_core::earth::c_ne;
use navfuse_core::sat::System;
use navfuse_gnss::obs::ObsSignalsHeader;
use navfuse_gnss::precise::PreciseProducts;
use navfuse_gnss::signal_plan::{ChosenSignal, SignalPlan};
use navfuse_gnss::spp::{IonoModel, SppConfig, SppError, SppMeasurement, SppSolution, SppSolver};
use navfuse_gnss::{
    Ephemeris, EphemerisSet, EphemerisStore, GpsTime, MultiObsEpoch, ObsCode, OrbitSource,
    PreciseSource,
};
use navfuse_io::export::{PosFile, PosLine};
use navfuse_io::rinex_clk::{read_rinex_clk, set_clocks};
use navfuse_io::rinex_nav::read_rinex_nav;
use navfuse_io::rinex_obs::{read_rinex_obs_all, ObsEpoch};
use navfuse_io::sp3::{add_to_products, read_sp3};
use std::path::{Path, PathBuf};

/// What to solve and how (the settings RTKLIB's single mode has).
#[derive(Clone, Debug)]
pub struct SppJob {
    pub obs: PathBuf,
    pub navs: Vec<PathBuf>,
    pub systems: Vec<System>,
    /// Code preferences per system (empty: the documented defaults).
    pub signals: Vec<(System, Vec<ObsCode>)>,
    /// Ionosphere-free code where a satellite has two bands.
    pub dual_frequency: bool,
    /// SP3 orbit files (consecutive days in any order); empty: broadcast orbits.
    pub sp3: Vec<PathBuf>,
    /// RINEX clock files; without them the SP3 clocks are used.
    pub clk: Vec<PathBuf>,
    pub elevation_mask_deg: f64,
    /// Broadcast Klobuchar ionosphere when the navigation header has its
    /// coefficients (RTKLIB `ionoopt=brdc`); false: none.
    pub broadcast_iono: bool,
    /// Saastamoinen troposphere (RTKLIB `tropopt=saas`).
    pub troposphere: bool,
    /// Chi-square fault detection and exclusion.
    pub fde: bool,
    /// Weight as RTKLIB 2.4.3's pntpos does, to compare with rnx2rtkp: elevation
    /// term b^2 / sin el (navfuse: b^2 / sin^2 el) and its Galileo SISA indexing.
    pub rtklib_weights: bool,
    /// C/N0 weighting (sigma \[m\], reference \[dB-Hz\]); None: off.
    pub cn0_weighting: Option<(f64, f64)>,
}

impl SppJob {
    /// `systems` from `obs` with `navs`, RTKLIB's single-mode settings otherwise:
    /// default signals, broadcast orbits, 10 deg mask, broadcast Klobuchar,
    /// Saastamoinen, FDE on, navfuse's weights.
    pub fn new(obs: PathBuf, navs: Vec<PathBuf>, systems: Vec<System>) -> Self {
        SppJob {
            obs,
            navs,
            systems,
            signals: Vec::new(),
            dual_frequency: false,
            sp3: Vec::new(),
            clk: Vec::new(),
            elevation_mask_deg: 10.0,
            broadcast_iono: true,
            troposphere: true,
            fde: true,
            rtklib_weights: false,
            cn0_weighting: None,
        }
    }
}

/// The solutions, one per observation epoch, and what the run found.
#[derive(Clone, Debug)]
pub struct SppRun {
    pub epochs: Vec<(GpsTime, Result<SppSolution, SppError>)>,
    pub notes: Vec<String>,
    /// What was used, for the .pos header: systems, signals, orbits.
    pub description: String,
}

impl SppRun {
    pub fn solved(&self) -> usize {
        self.epochs.iter().filter(|e| e.1.is_ok()).count()
    }
}

fn list(paths: &[PathBuf]) -> String {
    paths
        .iter()
        .map(|p| p.display().to_string())
        .collect::<Vec<_>>()
        .join(", ")
}

/// Precise products from SP3 files (and clock files, which replace the SP3 clocks).
pub fn read_precise(sp3: &[PathBuf], clk: &[PathBuf]) -> Result<PreciseProducts, Error> {
    let mut files = Vec::new();
    for p in sp3 {
        files.push(read_sp3(p)?);
    }
    let first = files
        .iter()
        .filter_map(|f| f.samples.first().map(|s| s.0))
        .min_by(|a, b| a.diff_s(b).total_cmp(&0.0))
        .ok_or_else(|| Error::Other(format!("{}: no SP3 samples", list(sp3))))?;
    let interval = files.iter().map(|f| f.interval_s).fold(0.0, f64::max);
    let mut clocks = Vec::new();
    for p in clk {
        clocks.push(read_rinex_clk(p)?);
    }
    let clock_interval = clocks
        .iter()
        .filter_map(clock_spacing_s)
        .fold(interval, f64::min);
    let mut products = PreciseProducts::new(first, interval, clock_interval);
    for f in &files {
        add_to_products(f, &mut products);
    }
    if !clocks.is_empty() {
        products.clear_clocks();
        for c in &clocks {
            set_clocks(c, &mut products);
        }
    }
    products.finish();
    Ok(products)
}

/// The smallest spacing of a satellite's consecutive clock samples \[s\].
fn clock_spacing_s(c: &navfuse_io::rinex_clk::ClockFile) -> Option<f64> {
    let sat = c.samples.first()?.1;
    let t: Vec<GpsTime> = c
        .samples
        .iter()
        .filter(|s| s.1 == sat)
        .map(|s| s.0)
        .collect();
    t.windows(2)
        .map(|w| w[1].diff_s(&w[0]))
        .filter(|d| *d > 0.0)
        .min_by(f64::total_cmp)
}

/// Read the files and solve every epoch.
pub fn run_spp(job: &SppJob) -> Result<SppRun, Error> {
    let mut notes = Vec::new();
    let mut store = EphemerisStore::default();
    let (mut alpha, mut beta) = (None, None);
    for p in &job.navs {
        let nav = read_rinex_nav(p)?;
        notes.extend(nav.warnings.iter().map(|w| format!("{}: {w}", p.display())));
        alpha = alpha.or(nav.iono_alpha);
        beta = beta.or(nav.iono_beta);
        nav.store().iter().for_each(|e| store.push(e.clone()));
    }
    let counts = store.counts();
    for sys in &job.systems {
        if !counts.contains_key(sys) {
            notes.push(format!(
                "{}: no {} ephemerides: its satellites are not used",
                list(&job.navs),
                sys.name()
            ));
        }
    }
    if !job.systems.iter().any(|s| counts.contains_key(s)) {
        return Err(Error::Other(format!(
            "{}: no ephemerides of the systems asked for ({})",
            list(&job.navs),
            letters(&job.systems)
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
    let obs = read_rinex_obs_all(&job.obs)?;
    notes.extend(
        obs.warnings
            .iter()
            .map(|w| format!("{}: {w}", job.obs.display())),
    );
    if obs.epochs.is_empty() {
        return Err(Error::Other(format!(
            "{}: no observation epochs",
            job.obs.display()
        )));
    }
    let plan = SignalPlan {
        systems: job.systems.clone(),
        codes: job.signals.clone(),
        dual_frequency: job.dual_frequency,
    };
    let mut cfg = SppConfig {
        elevation_mask_rad: job.elevation_mask_deg.to_radians(),
        iono,
        tropo_saastamoinen: job.troposphere,
        fde: job.fde,
        ..SppConfig::default()
    };
    if job.rtklib_weights {
        cfg.errors.elevation_sin_power = 1.0;
        cfg.errors.rtklib_sisa = true;
    }
    if let Some((sigma, reference)) = job.cn0_weighting {
        cfg.errors.cn0_sigma_m = Some(sigma);
        cfg.errors.cn0_reference_dbhz = reference;
    }
    let precise = if job.sp3.is_empty() {
        if !job.clk.is_empty() {
            return Err(Error::Other(
                "--clk needs --sp3 (the clock files go with precise orbits)".into(),
            ));
        }
        None
    } else {
        Some(read_precise(&job.sp3, &job.clk)?)
    };
    let orbits: Box<dyn OrbitSource + '_> = match &precise {
        Some(products) => Box::new(PreciseSource {
            products,
            broadcast: &store,
        }),
        None => Box::new(store.clone()),
    };
    let epochs = solve_multi(
        &obs.epochs,
        &obs.header,
        &store,
        orbits.as_ref(),
        &plan,
        cfg,
    );
    let description = format!(
        "Single ({}; {}; {} orbits)",
        letters(&job.systems),
        if job.dual_frequency {
            "ionosphere-free code where two bands"
        } else {
            "single-frequency code"
        },
        if precise.is_some() {
            "SP3"
        } else {
            "broadcast"
        }
    );
    Ok(SppRun {
        epochs,
        notes,
        description,
    })
}

fn letters(systems: &[System]) -> String {
    systems
        .iter()
        .map(|s| s.letter().to_string())
        .collect::<Vec<_>>()
        .join(",")
}

/// Solve every epoch of every system's observations: the plan's signal per
/// satellite, the GLONASS channel from the observation header or the broadcast
/// record.
pub fn solve_multi(
    obs: &[MultiObsEpoch],
    header: &ObsSignalsHeader,
    broadcast: &EphemerisStore,
    orbits: &dyn OrbitSource,
    plan: &SignalPlan,
    cfg: SppConfig,
) -> Vec<(GpsTime, Result<SppSolution, SppError>)> {
    let channels = glonass_channels(header, broadcast);
    solve_each(obs, orbits, cfg, |e| {
        choose_signals(e, plan, &channels)
            .iter()
            .filter(|c| c.pseudorange_m.is_finite())
            .map(SppMeasurement::from)
            .collect()
    })
}

/// The plan's signal of every satellite of an epoch (`channels`: GLONASS channel by
/// slot, [`glonass_channels`]).
pub fn choose_signals(
    e: &MultiObsEpoch,
    plan: &SignalPlan,
    channels: &[Option<i8>],
) -> Vec<ChosenSignal> {
    e.sats
        .iter()
        .filter_map(|s| {
            let k = (s.sat.system == System::Glonass)
                .then(|| channels.get(usize::from(s.sat.prn)).copied().flatten())
                .flatten();
            plan.choose(s, k)
        })
        .collect()
}

/// Solve the epochs in order, each from the previous solution, with the
/// measurements `meas` makes of it.
fn solve_each<E: HasTime>(
    obs: &[E],
    orbits: &(impl OrbitSource + ?Sized),
    cfg: SppConfig,
    meas: impl Fn(&E) -> Vec<SppMeasurement>,
) -> Vec<(GpsTime, Result<SppSolution, SppError>)> {
    let mut solver = SppSolver::new(cfg);
    obs.iter()
        .map(|e| (e.t(), solver.solve(orbits, e.t(), &meas(e))))
        .collect()
}

/// An observation epoch's receiver time tag.
trait HasTime {
    fn t(&self) -> GpsTime;
}

impl<S> HasTime for navfuse_gnss::obs::Epoch<S> {
    fn t(&self) -> GpsTime {
        self.t
    }
}

/// GLONASS frequency channel by slot (index = slot): the observation header's
/// `GLONASS SLOT / FRQ #`, else the broadcast records'.
pub fn glonass_channels(header: &ObsSignalsHeader, broadcast: &EphemerisStore) -> Vec<Option<i8>> {
    let mut k = vec![None; 64];
    for e in broadcast.iter() {
        if let Ephemeris::Glonass(g) = e {
            if let Some(slot) = k.get_mut(usize::from(g.slot)) {
                *slot = Some(g.freq_channel);
            }
        }
    }
    for &(slot, ch) in &header.glonass_channels {
        if let Some(s) = k.get_mut(usize::from(slot)) {
            *s = Some(ch);
        }
    }
    k
}

/// Solve every epoch's GPS L1 C/A pseudoranges (and Dopplers) with `cfg`.
pub fn solve_epochs(
    obs: &[ObsEpoch],
    ephs: &EphemerisSet,
    cfg: SppConfig,
) -> Vec<(GpsTime, Result<SppSolution, SppError>)> {
    solve_each(obs, ephs, cfg, |e| {
        e.sats
            .iter()
            .filter_map(|s| {
                s.pseudorange_m
                    .map(|pr| SppMeasurement::gps_l1(s.prn, pr, s.doppler_hz))
            })
            .collect()
    })
}

/// Write the solved epochs as an RTKLIB `.pos` file (Q = 5 single, ns, the
/// position covariance in east-north-up as RTKLIB writes it), at the time of
/// validity as RTKLIB does.
pub fn write_spp_pos(path: &Path, run: &SppRun, elevation_mask_deg: f64) -> Result<(), Error> {
    let mut f = PosFile::create(
        path,
        "single point positioning, navfuse spp",
        &run.description,
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
