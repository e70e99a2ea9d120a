//! Noise identification (`navfuse tune`, `[tuning]`): maximum-likelihood estimates of
//! the IMU noise, each aiding source's measurement noise and the GNSS fix-error model
//! from the run's own data (docs/ALGORITHMS.md "Noise identification").
//!
//! Expectation-maximisation over the RTS smoother (REFERENCES \[SS82\], \[GH96\],
//! \[SARKKA\] ch. 12): each iteration runs the filter forward, smooths it, and replaces
//! every noise parameter by the mean expected square of its noise under the smoothed
//! estimate (params.rs, smoother/em.rs). The innovation likelihood of each forward run
//! (\[SCHWEPPE65\]) is tracked; the configuration of highest likelihood is the answer.
//! EM moves slowly when a parameter is far off, so a parameter that keeps moving the
//! same way takes doubled steps (up to 4x its EM step), which the likelihood check
//! keeps honest. Without `[imu_noise]` the IMU model starts from the data's own white
//! noise (init.rs). Whether the GNSS fixes' errors are white or time-correlated, and
//! with which time constant, is decided by the likelihood among white and three
//! correlation times.

mod init;
mod params;
mod pass;

use crate::error::Error;
use crate::summary::JobResult;
use crate::RunOptions;
use navfuse_core::config::NavConfig;
use navfuse_core::{ImuSample, Measurement, RunSummary};
use navfuse_io::config::RunConfig;
use params::{ParamDef, Stat, Target};
use std::collections::BTreeMap;
use std::time::Instant;

pub use init_public::DataNoiseReport;

/// What to estimate and how long to try.
#[derive(Clone, Debug, PartialEq)]
pub struct TuneOptions {
    /// Most expectation-maximisation passes (each a forward run and a backward pass).
    pub max_iterations: usize,
    /// Stop when no parameter moves by more than this fraction in a pass.
    pub tolerance: f64,
    /// Start the IMU noise from the data even where the configuration gives it.
    pub from_data: bool,
    /// Decide between white and time-correlated GNSS fix errors (loose coupling).
    pub fix_error_model: bool,
}

impl Default for TuneOptions {
    fn default() -> Self {
        TuneOptions {
            max_iterations: 8,
            tolerance: 0.05,
            from_data: false,
            fix_error_model: true,
        }
    }
}

/// One estimated parameter.
#[derive(Clone, Debug, PartialEq)]
pub struct Estimate {
    /// The configuration key (and the axes it covers).
    pub key: &'static str,
    pub unit: &'static str,
    /// In the configuration given, where the estimation started, and the estimate.
    pub given: f64,
    pub start: f64,
    pub value: f64,
    /// Relative standard error of the estimate (batch means over ten blocks of the
    /// run), when it could be computed.
    pub rel_se: Option<f64>,
    /// Updates or transitions the estimate rests on.
    pub samples: u64,
}

/// One pass of the estimation.
#[derive(Clone, Debug, PartialEq)]
pub struct Iteration {
    /// Innovation log-likelihood of the forward run.
    pub log_likelihood: f64,
    /// Mean NIS per row of each source's applied updates.
    pub nis_per_row: BTreeMap<String, f64>,
    /// The parameters the pass ran with (key, value).
    pub values: Vec<(&'static str, f64)>,
}

/// The fix-error model chosen, with the candidates' likelihoods.
#[derive(Clone, Debug, PartialEq)]
pub struct FixErrorChoice {
    /// (correlation time \[s\] or 0 for white, correlated fraction, position std
    /// scale, log-likelihood).
    pub candidates: Vec<(f64, f64, f64, f64)>,
    pub corr_time_s: f64,
    pub corr_fraction: f64,
}

/// What `navfuse tune` found.
#[derive(Clone, Debug)]
pub struct TuneResult {
    /// The configuration with the estimates in it.
    pub tuned: RunConfig,
    pub estimates: Vec<Estimate>,
    pub iterations: Vec<Iteration>,
    pub fix_error: Option<FixErrorChoice>,
    /// The white noise read from the data (and the keys started from it).
    pub data_noise: Option<DataNoiseReport>,
    /// Forward runs made (each EM pass is one, plus the likelihood checks).
    pub forward_runs: usize,
    /// Whether the parameters settled within the tolerance.
    pub converged: bool,
    /// Wall time of the whole estimation, and of one plain forward run \[s\].
    pub wall_s: f64,
    pub forward_wall_s: f64,
    /// The summary of the forward run with the tuned configuration.
    pub final_summary: RunSummary,
}

mod init_public {
    /// The white noise read from the IMU data (deg/sqrt(h), m/s/sqrt(h) per axis) and
    /// the keys of `[imu_noise]` started from it.
    #[derive(Clone, Debug, PartialEq)]
    pub struct DataNoiseReport {
        pub arw_deg_sqrth: [f64; 3],
        pub vrw_mps_sqrth: [f64; 3],
        pub started: Vec<&'static str>,
    }
}

/// The inputs a tuning needs in memory.
struct Prepared {
    cfg: RunConfig,
    imu: Vec<ImuSample>,
    measurements: Vec<Measurement>,
}

/// Read the inputs as `navfuse run` does (week alignment, checks), the IMU into memory.
/// A GNSS-IMU time offset the configuration estimates stays a filter state in every
/// pass (estimated with the noise model, not before it).
fn prepare(cfg: RunConfig, opts: &RunOptions) -> Result<Prepared, Error> {
    let mut job = JobResult::empty();
    let pr = crate::navigate::prepare(cfg, opts, &mut job, false)?;
    let (start, end) = (pr.cfg.nav.start_time, pr.cfg.nav.end_time);
    let mut imu = vec![pr.first];
    for s in pr.reader {
        let s = opts.stop_check(s.map_err(Error::from))?;
        if end.is_some_and(|e| s.t > e + 1.0) {
            break;
        }
        if s.t >= start {
            imu.push(s);
        }
    }
    Ok(Prepared {
        cfg: pr.cfg,
        imu,
        measurements: thin_odometer(pr.measurements),
    })
}

/// Highest odometer rate the passes fuse \[Hz\].
const TUNE_MAX_ODOMETER_HZ: f64 = 2.0;

/// The odometer records at most TUNE_MAX_ODOMETER_HZ apart. Each record carries its
/// own counting interval, so the kept ones are valid measurements; EM on a subset of
/// the data estimates the same parameters (the M-step for R is the mean second moment
/// of the smoothed residuals, which does not depend on how many there are), and every
/// odometer update makes a smoother record: a 10 Hz odometer made the passes 5x
/// dearer than the GNSS alone (16 368 records against 1489 in 25 min).
fn thin_odometer(measurements: Vec<Measurement>) -> Vec<Measurement> {
    let min_dt = 1.0 / TUNE_MAX_ODOMETER_HZ - 1e-6;
    let mut last = f64::NEG_INFINITY;
    measurements
        .into_iter()
        .filter(|m| match m {
            Measurement::Odometer(o) => {
                let keep = o.t - last >= min_dt;
                if keep {
                    last = o.t;
                }
                keep
            }
            _ => true,
        })
        .collect()
}

/// A forward run alone: its summary (innovation statistics, likelihood).
fn forward(nav: &NavConfig, p: &Prepared, opts: &RunOptions) -> Result<RunSummary, Error> {
    navfuse_core::run_with_sources(
        nav,
        |c: &NavConfig, t0| opts.extra_sources.map_or_else(Vec::new, |f| f(c, t0)),
        p.imu.iter().map(|s| Ok::<_, Error>(*s)),
        &p.measurements,
        Some(f64::INFINITY),
        |_| Ok(()),
        |_| {},
    )
}

fn log_likelihood(s: &RunSummary) -> f64 {
    s.innovation_stats.values().map(|x| x.log_likelihood).sum()
}

fn nis_per_row(s: &RunSummary) -> BTreeMap<String, f64> {
    s.aiding_nis
        .iter()
        .map(|(k, (sum, rows))| (k.to_string(), sum / (*rows).max(1) as f64))
        .collect()
}

/// Mean of the terms and its relative standard error by batch means over blocks.
fn mean_and_se(terms: &[(f64, f64)], t0: f64, block_s: f64) -> Option<(f64, Option<f64>, u64)> {
    if terms.is_empty() {
        return None;
    }
    let n = terms.len();
    let mean = terms.iter().map(|(_, v)| v).sum::<f64>() / n as f64;
    let mut blocks: BTreeMap<i64, (f64, u64)> = BTreeMap::new();
    for (t, v) in terms {
        let e = blocks
            .entry(((t - t0) / block_s).floor() as i64)
            .or_default();
        e.0 += v;
        e.1 += 1;
    }
    let means: Vec<f64> = blocks.values().map(|(s, c)| s / *c as f64).collect();
    Some((mean, block_se(&means, mean), n as u64))
}

/// Relative standard error of `mean` from block means.
fn block_se(means: &[f64], mean: f64) -> Option<f64> {
    if means.len() < 4 || mean <= 0.0 {
        return None;
    }
    let k = means.len() as f64;
    let var = means.iter().map(|m| (m - mean).powi(2)).sum::<f64>() / (k - 1.0);
    Some((var / k).sqrt() / mean)
}

/// The EM ratio of each parameter from a pass: (theta, relative SE of theta, samples).
fn ratios(defs: &[ParamDef], pass: &pass::PassOutput) -> Vec<Option<(f64, Option<f64>, u64)>> {
    let t0 = pass.summary.first_t;
    let block_s = ((pass.summary.last_t - t0) / pass::BLOCKS).max(1.0);
    defs.iter()
        .map(|d| match &d.stat {
            Stat::Process(states) => {
                let (mean, _, count) = pass.process.group(states)?;
                let se = block_se(&pass.process.block_means(states), mean);
                Some((mean, se, count))
            }
            Stat::Initial(states) => {
                let (s0, var0, p0) = pass.initial.as_ref()?;
                let terms: Vec<f64> = states
                    .iter()
                    .filter(|&&i| p0[i] > 0.0)
                    .map(|&i| (s0[i] * s0[i] + var0[i]) / p0[i])
                    .collect();
                (!terms.is_empty()).then(|| {
                    (
                        terms.iter().sum::<f64>() / terms.len() as f64,
                        None,
                        terms.len() as u64,
                    )
                })
            }
            Stat::Residual { sources, rows } => {
                let terms: Vec<(f64, f64)> = pass
                    .residuals
                    .iter()
                    .filter(|r| !r.down_weighted && sources.contains(&r.source))
                    .flat_map(|r| {
                        rows.iter()
                            .filter(|&&k| k < r.r_s.len() && r.r[k] > 0.0)
                            .map(|&k| (r.t, (r.r_s[k] * r.r_s[k] + r.var_s[k]) / r.r[k]))
                    })
                    .collect();
                if terms.len() < 10 {
                    return None;
                }
                mean_and_se(&terms, t0, block_s)
            }
        })
        .collect()
}

/// Apply the EM step: each parameter's std times theta^(omega/2). The white and the
/// correlated share of the fix position error are set together (their sum is the
/// fix's variance). Returns the log-factor applied to each parameter.
fn apply(
    defs: &[ParamDef],
    theta: &[Option<(f64, Option<f64>, u64)>],
    omega: &[f64],
    nav: &mut NavConfig,
) -> Vec<f64> {
    let mut steps = vec![0.0; defs.len()];
    let pos = defs
        .iter()
        .position(|d| d.target == Target::GnssPositionScale);
    let cor = defs.iter().position(|d| d.target == Target::GnssCorrelated);
    for (i, d) in defs.iter().enumerate() {
        if Some(i) == pos || Some(i) == cor {
            continue;
        }
        if let Some((th, _, _)) = theta[i] {
            if th > 0.0 && th.is_finite() {
                let f = (0.5 * omega[i] * th.ln()).exp();
                steps[i] = d.target.scale(nav, f).ln();
            }
        }
    }
    if let Some(p) = pos {
        let th_w = theta[p].map(|x| x.0);
        let th_c = cor.and_then(|c| theta[c].map(|x| x.0));
        let rho = nav.gnss.fix_error.corr_fraction;
        let s2 = nav.gnss.position_std_scale.powi(2);
        match (th_w, th_c, cor) {
            (Some(w), Some(c), Some(ci)) if w > 0.0 && c > 0.0 => {
                // In units of the reported variance: white (1 - rho) s² w, correlated
                // rho s² c; the step exponent on each.
                let w = w.powf(omega[p]);
                let c = c.powf(omega[ci]);
                let white = (1.0 - rho) * s2 * w;
                let corr = rho * s2 * c;
                let total = white + corr;
                let new_rho = (corr / total).clamp(0.0, 0.95);
                let new_scale = total.sqrt().clamp(0.01, 100.0);
                steps[p] = (new_scale / nav.gnss.position_std_scale).ln();
                steps[ci] = if rho > 0.0 { (new_rho / rho).ln() } else { 0.0 };
                nav.gnss.position_std_scale = new_scale;
                nav.gnss.fix_error.corr_fraction = new_rho;
            }
            (Some(w), _, _) if w > 0.0 => {
                // White fixes (or the correlated share without data): the white
                // variance (1 - rho) s² moves by w.
                let f = (0.5 * omega[p] * w.ln()).exp();
                steps[p] = defs[p].target.scale(nav, f).ln();
            }
            _ => {}
        }
    }
    steps
}

/// Shortest covariance period of the tuning passes \[s\].
const TUNE_COVARIANCE_PERIOD_S: f64 = 1.0;

/// Estimate the noise model of `cfg` from its data; `run_opts` as for a run (the
/// extra sources, the stop flag).
pub fn tune(
    cfg: RunConfig,
    opts: &TuneOptions,
    run_opts: &RunOptions,
) -> Result<TuneResult, Error> {
    let t_start = Instant::now();
    let given = cfg.nav.clone();
    let defaulted = cfg.defaulted.clone();
    let mut p = prepare(cfg, run_opts)?;
    let scratch = std::env::temp_dir();
    // The IMU noise the data show, as the start where the configuration gives none.
    let data = init::data_noise(&p.imu);
    let noise_keys: Vec<&str> = if opts.from_data {
        params::NOISE_KEYS.to_vec()
    } else {
        defaulted
            .iter()
            .copied()
            .filter(|k| k.starts_with("imu_noise."))
            .collect()
    };
    let data_noise = data.as_ref().map(|d| {
        let started = init::start_from_data(&mut p.cfg.nav.imu_noise, d, &noise_keys);
        // The initial IMU error stds follow the noise model they default to.
        if defaulted.contains(&"imu_noise.gyro_bias_std_degph") || opts.from_data {
            p.cfg.nav.initial.imu_errors_std = p.cfg.nav.imu_noise.error_stds();
        }
        DataNoiseReport {
            arw_deg_sqrth: d.arw.map(|r| r.to_degrees() * 60.0),
            vrw_mps_sqrth: d.vrw.map(|r| r * 60.0),
            started,
        }
    });
    let mut nav = p.cfg.nav.clone();
    // The passes propagate the covariance at least every TUNE_COVARIANCE_PERIOD_S: the
    // smoother's records and the E-step are per covariance epoch, and the noise scales
    // are ratios to Q integrated over the same period, so they do not depend on it
    // (a simulated car: ARW 2.12 against 2.04 deg/sqrt(h) at 0.2 s, 2.5x faster).
    nav.filter.covariance_period_s = nav.filter.covariance_period_s.max(TUNE_COVARIANCE_PERIOD_S);
    let start_nav = nav.clone();
    let t_fwd = Instant::now();
    let first = forward(&nav, &p, run_opts)?;
    let forward_wall_s = t_fwd.elapsed().as_secs_f64();
    let mut forward_runs = 1;
    // The best configuration run so far: its likelihood, and its EM ratios (the
    // plain step from it when an accelerated step overshoots).
    type Theta = Vec<Option<(f64, Option<f64>, u64)>>;
    let mut best: (f64, NavConfig, Option<Theta>) = (log_likelihood(&first), nav.clone(), None);
    let mut best_summary = first;
    let mut iterations = Vec::new();
    let mut defs: Option<Vec<ParamDef>> = None;
    let mut omega: Vec<f64> = Vec::new();
    let mut last_steps: Vec<f64> = Vec::new();
    let mut last_theta = Vec::new();
    let mut converged = false;
    for _ in 0..opts.max_iterations.max(1) {
        run_opts.stop_check(Ok::<(), Error>(()))?;
        let pass = pass::em_pass(
            &nav,
            &p.imu,
            &p.measurements,
            run_opts.extra_sources,
            &scratch,
        )?;
        forward_runs += 1;
        let ll = pass.log_likelihood();
        let d = defs.get_or_insert_with(|| {
            let mut sources: Vec<&str> = pass.residuals.iter().map(|r| r.source).collect();
            sources.sort_unstable();
            sources.dedup();
            params::params(&nav, &pass.layout, &sources)
        });
        iterations.push(Iteration {
            log_likelihood: ll,
            nis_per_row: nis_per_row(&pass.summary),
            values: d.iter().map(|x| (x.key, x.target.value(&nav))).collect(),
        });
        let theta = ratios(d, &pass);
        if omega.is_empty() {
            omega = vec![1.0; d.len()];
            last_steps = vec![0.0; d.len()];
        }
        let tol = (1.0 + opts.tolerance).ln();
        if ll < best.0 {
            // The (accelerated) step lowered the likelihood: a plain EM step from the
            // best configuration instead, whose ratios are known.
            nav = best.1.clone();
            omega.iter_mut().for_each(|w| *w = 1.0);
            last_steps.iter_mut().for_each(|s| *s = 0.0);
            if let Some(th) = best.2.clone() {
                let steps = apply(d, &th, &omega, &mut nav);
                if steps.iter().all(|s| s.abs() < tol) {
                    converged = true;
                    break;
                }
            }
            continue;
        }
        best = (ll, nav.clone(), Some(theta.clone()));
        best_summary = pass.summary;
        let steps = apply(d, &theta, &omega, &mut nav);
        last_theta = theta;
        if steps.iter().all(|s| s.abs() < tol) {
            converged = true;
            break;
        }
        // A parameter moving the same way twice: double its next step (at most 4x).
        for i in 0..steps.len() {
            let (s, l) = (steps[i], last_steps[i]);
            omega[i] = if s * l > 0.0 && s.abs() > 0.3 * l.abs() {
                (omega[i] * 2.0).min(4.0)
            } else {
                1.0
            };
        }
        last_steps = steps;
    }
    // Not converged: the last step's configuration has not been run yet; its
    // likelihood decides against the best one run. Converged: the last step is within
    // the tolerance of the best, which is kept.
    if !converged {
        let last = forward(&nav, &p, run_opts)?;
        forward_runs += 1;
        let ll_last = log_likelihood(&last);
        if ll_last > best.0 {
            best = (ll_last, nav.clone(), None);
            best_summary = last;
        }
    }
    let mut nav = best.1;
    let mut final_summary = best_summary;
    // The fix-error model: white or Gauss-Markov with one of three correlation times,
    // by the likelihood (each candidate one forward run).
    let mut fix_error = None;
    let loose_fixes = p.cfg.gnss.is_some()
        && !nav.tight.enabled
        && iterations
            .last()
            .is_some_and(|it| it.nis_per_row.contains_key("gnss_position"));
    if opts.fix_error_model && loose_fixes {
        let fe0 = nav.gnss.fix_error;
        let s0 = nav.gnss.position_std_scale;
        let tau0 = if fe0.correlated() {
            fe0.corr_time_s
        } else {
            60.0
        };
        let rho0 = if fe0.correlated() {
            fe0.corr_fraction
        } else {
            0.5
        };
        let mut cands: Vec<(f64, f64, f64, f64, NavConfig)> = Vec::new();
        // White: the fixes' variance is the white share found, or all of it (when the
        // correlated share held white noise); correlated: three correlation times.
        let white_share = if fe0.correlated() {
            (1.0 - rho0).sqrt()
        } else {
            1.0
        };
        // The configuration estimated is one candidate, its likelihood known.
        let here = (fe0.corr_time_s, fe0.corr_fraction, s0);
        cands.push((
            here.0,
            here.1,
            here.2,
            best.0 - if here.0 > 0.0 { 2.0 } else { 0.0 },
            nav.clone(),
        ));
        let tried = [
            (0.0, 0.0, s0 * white_share),
            (tau0 / 4.0, rho0, s0),
            (tau0, rho0, s0),
            (tau0 * 4.0, rho0, s0),
        ];
        for (tau, rho, scale) in tried {
            if cands.iter().any(|c| (c.0, c.1, c.2) == (tau, rho, scale)) {
                continue;
            }
            let mut c = nav.clone();
            c.gnss.fix_error.corr_time_s = tau;
            c.gnss.fix_error.corr_fraction = rho;
            c.gnss.position_std_scale = scale;
            let s = forward(&c, &p, run_opts)?;
            forward_runs += 1;
            // Akaike: the correlated model has two more parameters.
            let penalty = if tau > 0.0 { 2.0 } else { 0.0 };
            cands.push((tau, rho, scale, log_likelihood(&s) - penalty, c));
        }
        let (tau, rho, _, _, c) = cands
            .iter()
            .max_by(|a, b| a.3.total_cmp(&b.3))
            .cloned()
            .expect("candidates");
        fix_error = Some(FixErrorChoice {
            candidates: cands
                .iter()
                .map(|(t, r, sc, l, _)| (*t, *r, *sc, *l))
                .collect(),
            corr_time_s: tau,
            corr_fraction: rho,
        });
        if (tau, rho, c.gnss.position_std_scale) != here {
            // One more EM pass for the scales under the model chosen.
            nav = c;
            let pass = pass::em_pass(
                &nav,
                &p.imu,
                &p.measurements,
                run_opts.extra_sources,
                &scratch,
            )?;
            forward_runs += 1;
            let mut sources: Vec<&str> = pass.residuals.iter().map(|r| r.source).collect();
            sources.sort_unstable();
            sources.dedup();
            let d = params::params(&nav, &pass.layout, &sources);
            let theta = ratios(&d, &pass);
            let mut next = nav.clone();
            apply(&d, &theta, &vec![1.0; d.len()], &mut next);
            let s = forward(&next, &p, run_opts)?;
            forward_runs += 1;
            if log_likelihood(&s) > log_likelihood(&pass.summary) {
                nav = next;
                final_summary = s;
            } else {
                final_summary = pass.summary;
            }
            defs = Some(d);
            last_theta = theta;
        }
    }
    let defs = defs.unwrap_or_default();
    let estimates = defs
        .iter()
        .enumerate()
        .map(|(i, d)| Estimate {
            key: d.key,
            unit: d.unit,
            given: d.target.value(&given),
            start: d.target.value(&start_nav),
            value: d.target.value(&nav),
            // theta's SE is that of a variance: half of it for the std.
            rel_se: last_theta
                .get(i)
                .and_then(|t| t.and_then(|x| x.1))
                .map(|se| 0.5 * se),
            samples: last_theta.get(i).and_then(|t| t.map(|x| x.2)).unwrap_or(0),
        })
        .collect();
    let mut tuned = p.cfg;
    let period = tuned.nav.filter.covariance_period_s;
    tuned.nav = nav;
    tuned.nav.filter.covariance_period_s = period;
    // The keys are all set now.
    tuned.defaulted.retain(|k| !k.starts_with("imu_noise."));
    Ok(TuneResult {
        tuned,
        estimates,
        iterations,
        fix_error,
        data_noise,
        forward_runs,
        converged,
        wall_s: t_start.elapsed().as_secs_f64(),
        forward_wall_s,
        final_summary,
    })
}

/// Copy the noise model (every key `navfuse tune` estimates) of `from` into `to`,
/// leaving the rest of `to` (inputs, time offset, outages, ...) as it is.
pub fn copy_noise_model(from: &NavConfig, to: &mut NavConfig) {
    to.imu_noise = from.imu_noise.clone();
    to.initial.imu_errors_std = from.initial.imu_errors_std;
    to.gnss.position_std_scale = from.gnss.position_std_scale;
    to.gnss.velocity_std_scale = from.gnss.velocity_std_scale;
    to.gnss.fix_error.corr_time_s = from.gnss.fix_error.corr_time_s;
    to.gnss.fix_error.corr_fraction = from.gnss.fix_error.corr_fraction;
    to.nhc.std_mps = from.nhc.std_mps;
    to.odometer.std_mps = from.odometer.std_mps;
    to.odometer.std_speed_fraction = from.odometer.std_speed_fraction;
    to.zupt.velocity_std_mps = from.zupt.velocity_std_mps;
    to.zupt.angular_rate_std = from.zupt.angular_rate_std;
    to.tight.pseudorange_sigma_scale = from.tight.pseudorange_sigma_scale;
    to.tight.range_rate_sigma_scale = from.tight.range_rate_sigma_scale;
    to.baro.std_m = from.baro.std_m;
}

/// A tuned configuration as `navfuse tune` and `[tuning]` write it.
#[derive(Clone, Debug)]
pub struct Tuned {
    /// The input with the estimated noise model (`[tuning]` off: a run of it repeats
    /// the tuned run).
    pub config: RunConfig,
    pub result: TuneResult,
    /// `tuning.txt`: the estimates' table and the difference from the input.
    pub text: String,
}

/// [`tune`] with the options of `cfg.tuning`, the estimates copied into `cfg`
/// ([`copy_noise_model`]) and the report text.
pub fn tune_config(cfg: &RunConfig, run_opts: &RunOptions) -> Result<Tuned, Error> {
    let spec = &cfg.tuning;
    let opts = TuneOptions {
        max_iterations: spec.iterations,
        from_data: spec.from_data,
        fix_error_model: spec.fix_error_model,
        ..TuneOptions::default()
    };
    let result = tune(cfg.clone(), &opts, run_opts)?;
    let mut tuned = cfg.clone();
    copy_noise_model(&result.tuned.nav, &mut tuned.nav);
    tuned.defaulted.retain(|k| !k.starts_with("imu_noise."));
    tuned.tuning.enabled = false;
    let mut before = cfg.clone();
    before.tuning.enabled = false;
    let diff = config_diff(&before.to_toml_string(), &tuned.to_toml_string());
    let text = format!("{}\n{diff}", result.table());
    Ok(Tuned {
        config: tuned,
        result,
        text,
    })
}

/// The lines of `after` that differ from `before` (both written by
/// `RunConfig::to_toml_string`, so in the same order), as `- old` / `+ new` under
/// their section.
pub fn config_diff(before: &str, after: &str) -> String {
    let mut out =
        String::from("Difference from the input configuration (every key written out):\n");
    let (mut section, mut printed) = ("", "\0");
    let b: Vec<&str> = before.lines().collect();
    let mut any = false;
    for (i, line) in after.lines().enumerate() {
        if line.starts_with('[') {
            section = line;
        }
        let old = b.get(i).copied().unwrap_or("");
        if old != line {
            if printed != section {
                out.push_str(&format!("{section}\n"));
                printed = section;
            }
            out.push_str(&format!("- {old}\n+ {line}\n"));
            any = true;
        }
    }
    if !any {
        out.push_str("(none)\n");
    }
    out
}

/// Shortest decimal of `v` with 4 significant digits.
fn sig4(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let digits = (3 - v.abs().log10().floor() as i32).max(0) as usize;
    format!("{v:.digits$}")
}

impl TuneResult {
    /// The estimates as a table (key, given, start, estimate, +-%), the likelihood per
    /// pass and the fix-error choice.
    pub fn table(&self) -> String {
        let mut t = navfuse_io::table::TextTable::new([
            "parameter",
            "unit",
            "given",
            "start",
            "estimate",
            "+-",
            "samples",
        ])
        .left_aligned(&[1]);
        for e in &self.estimates {
            t.row([
                e.key.to_string(),
                e.unit.to_string(),
                sig4(e.given),
                sig4(e.start),
                sig4(e.value),
                e.rel_se
                    .map_or("-".into(), |s| format!("{:.0} %", 100.0 * s)),
                e.samples.to_string(),
            ]);
        }
        let mut out = t.render_wrapped(navfuse_io::table::MAX_WIDTH);
        out.push_str("\npass  log-likelihood  NIS per row\n");
        for (i, it) in self.iterations.iter().enumerate() {
            let nis: Vec<String> = it
                .nis_per_row
                .iter()
                .map(|(k, v)| format!("{k} {v:.2}"))
                .collect();
            out.push_str(&format!(
                "{:>4}  {:>14.1}  {}\n",
                i + 1,
                it.log_likelihood,
                nis.join(", ")
            ));
        }
        let fin = nis_per_row(&self.final_summary);
        out.push_str(&format!(
            "tuned {:>14.1}  {}\n",
            log_likelihood(&self.final_summary),
            fin.iter()
                .map(|(k, v)| format!("{k} {v:.2}"))
                .collect::<Vec<_>>()
                .join(", ")
        ));
        if let Some(f) = &self.fix_error {
            let c: Vec<String> = f
                .candidates
                .iter()
                .map(|(tau, rho, sc, ll)| match *tau {
                    t if t > 0.0 => format!(
                        "Gauss-Markov {t:.0} s ({:.0} %, scale {sc:.2}): {ll:.1}",
                        100.0 * rho
                    ),
                    _ => format!("white (scale {sc:.2}): {ll:.1}"),
                })
                .collect();
            out.push_str(&format!(
                "GNSS fix errors: {} (log-likelihood {})\n",
                if f.corr_time_s > 0.0 {
                    format!(
                        "time-correlated, {:.0} s, {:.0} % of the variance",
                        f.corr_time_s,
                        100.0 * f.corr_fraction
                    )
                } else {
                    "white".to_string()
                },
                c.join("; ")
            ));
        }
        if let Some(d) = &self.data_noise {
            out.push_str(&format!(
                "white noise in the data: ARW {} deg/sqrt(h), VRW {} m/s/sqrt(h) (x, y, z){}\n",
                d.arw_deg_sqrth.map(sig4).join(", "),
                d.vrw_mps_sqrth.map(sig4).join(", "),
                if d.started.is_empty() {
                    String::new()
                } else {
                    format!("; started from it: {}", d.started.join(", "))
                }
            ));
        }
        out.push_str(&format!(
            "{} forward runs in {:.2} s ({:.1}x one forward run of {:.2} s){}\n",
            self.forward_runs,
            self.wall_s,
            self.wall_s / self.forward_wall_s.max(1e-9),
            self.forward_wall_s,
            if self.converged {
                ""
            } else {
                "; not converged within the passes allowed: the best configuration seen is kept"
            }
        ));
        out
    }

    /// The estimation as JSON (`tuning.json`).
    pub fn to_json(&self) -> serde_json::Value {
        serde_json::json!({
            "estimates": self.estimates.iter().map(|e| serde_json::json!({
                "key": e.key,
                "unit": e.unit,
                "given": e.given,
                "start": e.start,
                "value": e.value,
                "rel_se": e.rel_se,
                "samples": e.samples,
            })).collect::<Vec<_>>(),
            "iterations": self.iterations.iter().map(|it| serde_json::json!({
                "log_likelihood": it.log_likelihood,
                "nis_per_row": it.nis_per_row,
                "values": it.values.iter().map(|(k, v)| (k.to_string(), *v)).collect::<BTreeMap<_, _>>(),
            })).collect::<Vec<_>>(),
            "tuned": {
                "log_likelihood": log_likelihood(&self.final_summary),
                "nis_per_row": nis_per_row(&self.final_summary),
            },
            "fix_error": self.fix_error.as_ref().map(|f| serde_json::json!({
                "corr_time_s": f.corr_time_s,
                "corr_fraction": f.corr_fraction,
                "candidates": f.candidates.iter().map(|(t, r, sc, l)| serde_json::json!({
                    "corr_time_s": t, "corr_fraction": r, "position_std_scale": sc, "log_likelihood": l,
                })).collect::<Vec<_>>(),
            })),
            "data_noise": self.data_noise.as_ref().map(|d| serde_json::json!({
                "arw_deg_sqrth": d.arw_deg_sqrth,
                "vrw_mps_sqrth": d.vrw_mps_sqrth,
                "started": d.started,
            })),
            "forward_runs": self.forward_runs,
            "converged": self.converged,
            "wall_s": self.wall_s,
            "forward_wall_s": self.forward_wall_s,
        })
    }
}
