//! The batch manifest (docs/CONFIG.md "Batch manifest"): a list of run
//! configurations (`[[run]]`) or one simulator scenario over many seeds
//! (`[monte_carlo]`), read, checked and turned into the list of cases. Paths are
//! relative to the manifest's folder; unknown keys, bad values, missing files and
//! duplicate names are errors naming the manifest, the line and the key.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use anyhow::{anyhow, bail, Result};
use nalgebra::Vector3;
use navfuse_core::outage::OutageSchedule;
use navfuse_io::config::{toml_error, toml_line_of};
use navfuse_sim::scenario::Scenario;
use serde::Deserialize;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawManifest {
    run: Option<Vec<RawRun>>,
    monte_carlo: Option<RawMonteCarlo>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawRun {
    config: Option<String>,
    kf_gins: Option<String>,
    name: Option<String>,
    truth: Option<String>,
    lever_arm: Option<[f64; 3]>,
    gaps: Option<String>,
    outages: Option<String>,
    smooth: Option<bool>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawMonteCarlo {
    scenario: String,
    seeds: u64,
    first_seed: Option<u64>,
    name: Option<String>,
    gaps: Option<String>,
    outages: Option<String>,
    smooth: Option<bool>,
}

/// Where a case's data come from.
#[derive(Clone, Debug)]
pub(crate) enum Source {
    /// A run configuration: navfuse TOML, or KF-GINS YAML when `kf_gins`; scored
    /// against `truth` when given.
    Config {
        path: PathBuf,
        kf_gins: bool,
        truth: Option<PathBuf>,
        lever_arm: Option<Vector3<f64>>,
    },
    /// The scenario simulated with the case's seed, run with its run.toml and scored
    /// against its truth.nav.
    Sim { scenario: Arc<Scenario> },
}

/// One case of a batch.
#[derive(Clone, Debug)]
pub(crate) struct Case {
    pub name: String,
    pub seed: Option<u64>,
    pub source: Source,
    /// `navfuse eval --gaps`: the spec, as given (it is checked when loading).
    pub gaps: Option<OutageSchedule>,
    /// `navfuse run --outages`.
    pub outages: Option<OutageSchedule>,
    /// `navfuse run --smooth`.
    pub smooth: bool,
}

/// A batch manifest: parsed, checked, its paths resolved against its folder.
#[derive(Clone, Debug)]
pub struct Manifest {
    path: PathBuf,
    pub(crate) cases: Vec<Case>,
}

/// Errors at a key of the manifest: `FILE:LINE: key 'K': MESSAGE`.
struct At<'a> {
    file: &'a Path,
    text: &'a str,
}

impl At<'_> {
    fn err(&self, key: &str, msg: impl std::fmt::Display) -> anyhow::Error {
        let line = toml_line_of(self.text, key).map_or(String::new(), |l| format!(":{l}"));
        anyhow!("{}{line}: key '{key}': {msg}", self.file.display())
    }

    fn line(&self, key: &str) -> String {
        toml_line_of(self.text, key).map_or("?".to_string(), |l| l.to_string())
    }

    /// An outage / gap specification (`a:b,L/P@T[..U]`).
    fn schedule(&self, key: &str, spec: Option<&String>) -> Result<Option<OutageSchedule>> {
        spec.map(|s| OutageSchedule::parse(s).map_err(|e| self.err(key, format!("'{s}': {e}"))))
            .transpose()
    }

    /// `rel` against `base`, which must be an existing file.
    fn file(&self, key: &str, entry: &str, base: &Path, rel: &str) -> Result<PathBuf> {
        let p = base.join(rel);
        if !p.is_file() {
            let resolved = if p.as_path() == Path::new(rel) {
                String::new()
            } else {
                format!(" ({})", p.display())
            };
            return Err(self.err(key, format!("{entry}: no such file '{rel}'{resolved}")));
        }
        Ok(p)
    }
}

/// A case name is a folder name in the batch's output.
fn check_name(at: &At<'_>, key: &str, name: &str) -> Result<()> {
    let bad = name.is_empty()
        || name == "."
        || name == ".."
        || name.contains(['/', '\\'])
        || name.chars().any(char::is_control);
    if bad {
        return Err(at.err(
            key,
            format!("'{name}' cannot be a case name (it names the case's folder)"),
        ));
    }
    Ok(())
}

fn stem(p: &Path) -> String {
    p.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default()
}

impl Manifest {
    /// Read and check the manifest file `path`.
    pub fn load(path: &Path) -> Result<Manifest> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| anyhow!("{}: cannot read the batch manifest: {e}", path.display()))?;
        let base = path.parent().map(Path::to_path_buf).unwrap_or_default();
        Manifest::from_text(&text, &base, path)
    }

    /// A manifest from its text: relative paths resolve against `base_dir`, errors
    /// name `name_for_errors`.
    pub fn from_text(text: &str, base_dir: &Path, name_for_errors: &Path) -> Result<Manifest> {
        let file = name_for_errors;
        let raw: RawManifest = toml::from_str(text).map_err(|e| toml_error(file, text, &e))?;
        let at = At { file, text };
        let cases = match (raw.run, raw.monte_carlo) {
            (Some(_), Some(_)) => bail!(
                "{}: a manifest has either [[run]] entries or one [monte_carlo] section, not both",
                file.display()
            ),
            (None, None) => bail!(
                "{}: no cases: the manifest needs [[run]] entries or a [monte_carlo] section (docs/CONFIG.md \"Batch manifest\")",
                file.display()
            ),
            (Some(runs), None) => run_cases(&at, base_dir, runs)?,
            (None, Some(mc)) => monte_carlo_cases(&at, base_dir, mc)?,
        };
        if cases.is_empty() {
            bail!("{}: no cases: the [[run]] list is empty", file.display());
        }
        Ok(Manifest {
            path: file.to_path_buf(),
            cases,
        })
    }

    /// The number of cases.
    pub fn len(&self) -> usize {
        self.cases.len()
    }

    /// Whether there are no cases (never, for a loaded manifest).
    pub fn is_empty(&self) -> bool {
        self.cases.is_empty()
    }

    /// The case names, in manifest order (unique; each names its output folder).
    pub fn case_names(&self) -> Vec<String> {
        self.cases.iter().map(|c| c.name.clone()).collect()
    }

    /// The manifest file (as given).
    pub fn path(&self) -> &Path {
        &self.path
    }
}

fn run_cases(at: &At<'_>, base: &Path, runs: Vec<RawRun>) -> Result<Vec<Case>> {
    let mut cases = Vec::with_capacity(runs.len());
    let mut seen: HashMap<String, usize> = HashMap::new();
    for (i, r) in runs.into_iter().enumerate() {
        let entry = format!("run[{i}]");
        let (key, rel, kf_gins) = match (&r.config, &r.kf_gins) {
            (Some(c), None) => (format!("{entry}.config"), c, false),
            (None, Some(k)) => (format!("{entry}.kf_gins"), k, true),
            (Some(_), Some(_)) => {
                return Err(at.err(&format!("{entry}.kf_gins"), "give config or kf_gins, not both"))
            }
            (None, None) => {
                return Err(at.err(
                    &entry,
                    "needs config = \"FILE.toml\" (a navfuse run configuration) or kf_gins = \"FILE.yaml\"",
                ))
            }
        };
        let label = match &r.name {
            Some(n) => format!("{entry} '{n}'"),
            None => entry.clone(),
        };
        let path = at.file(&key, &label, base, rel)?;
        let (name_key, name) = match r.name {
            Some(n) => (format!("{entry}.name"), n),
            None => (key.clone(), stem(&path)),
        };
        check_name(at, &name_key, &name)?;
        if let Some(&j) = seen.get(&name) {
            return Err(at.err(
                &name_key,
                format!(
                    "the case name '{name}' is also run[{j}]'s (line {}); names must be unique (set name = \"...\")",
                    at.line(&format!("run[{j}]"))
                ),
            ));
        }
        seen.insert(name.clone(), i);
        let truth = r
            .truth
            .as_deref()
            .map(|t| at.file(&format!("{entry}.truth"), &label, base, t))
            .transpose()?;
        let lever_arm = r.lever_arm.map(Vector3::from);
        if let Some(l) = lever_arm {
            if l.iter().any(|x| !x.is_finite()) {
                return Err(at.err(
                    &format!("{entry}.lever_arm"),
                    "expected three finite numbers [m]",
                ));
            }
            if truth.is_none() {
                return Err(at.err(&format!("{entry}.lever_arm"), "only with truth = \"...\""));
            }
        }
        if r.gaps.is_some() && truth.is_none() {
            return Err(at.err(&format!("{entry}.gaps"), "only with truth = \"...\""));
        }
        cases.push(Case {
            name,
            seed: None,
            source: Source::Config {
                path,
                kf_gins,
                truth,
                lever_arm,
            },
            gaps: at.schedule(&format!("{entry}.gaps"), r.gaps.as_ref())?,
            outages: at.schedule(&format!("{entry}.outages"), r.outages.as_ref())?,
            smooth: r.smooth.unwrap_or(false),
        });
    }
    Ok(cases)
}

/// Most seeds of a Monte Carlo manifest.
const MAX_SEEDS: u64 = 1_000_000;

/// Digits of the seeds in the case names: those of the last seed, at least 4.
fn seed_width(last: u64) -> usize {
    last.to_string().len().max(4)
}

fn monte_carlo_cases(at: &At<'_>, base: &Path, mc: RawMonteCarlo) -> Result<Vec<Case>> {
    let path = at.file("monte_carlo.scenario", "[monte_carlo]", base, &mc.scenario)?;
    let scenario = Arc::new(
        Scenario::load(&path).map_err(|e| at.err("monte_carlo.scenario", format!("{e}")))?,
    );
    if mc.seeds == 0 || mc.seeds > MAX_SEEDS {
        return Err(at.err(
            "monte_carlo.seeds",
            format!("must be 1 to {MAX_SEEDS}, found {}", mc.seeds),
        ));
    }
    let first = mc.first_seed.unwrap_or(1);
    let last = first
        .checked_add(mc.seeds - 1)
        .ok_or_else(|| at.err("monte_carlo.seeds", "first_seed + seeds - 1 overflows"))?;
    let (name_key, name) = match mc.name {
        Some(n) => ("monte_carlo.name", n),
        None => ("monte_carlo.scenario", stem(&path)),
    };
    check_name(at, name_key, &name)?;
    let gaps = at.schedule("monte_carlo.gaps", mc.gaps.as_ref())?;
    let outages = at.schedule("monte_carlo.outages", mc.outages.as_ref())?;
    let width = seed_width(last);
    Ok((first..=last)
        .map(|seed| Case {
            name: format!("{name}_seed{seed:0width$}"),
            seed: Some(seed),
            source: Source::Sim {
                scenario: Arc::clone(&scenario),
            },
            gaps: gaps.clone(),
            outages: outages.clone(),
            smooth: mc.smooth.unwrap_or(false),
        })
        .collect())
}
