//! run.toml is the simulator's `RunConfig` written by the configuration's writer:
//! loading it gives that value back exactly, for every scenario in scenarios/.
//!
//! With `NAVFUSE_OLD_SIM_DIR=DIR` (DIR/NAME/run.toml written by an earlier `navfuse
//! sim scenarios/NAME.toml --out DIR/NAME`), also: the new run.toml loads to the
//! same configuration as that one (a check across a change of the writer).

use std::path::{Path, PathBuf};

use navfuse_io::config::{load, RunConfig};
use navfuse_sim::run_config::{run_config, run_config_text};
use navfuse_sim::scenario::Scenario;

fn scenarios() -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios");
    let mut v: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    v.sort();
    assert!(v.len() >= 10, "{}", dir.display());
    v
}

fn write(sc: &Scenario, dir: &Path, name: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, run_config_text(sc, dir)).unwrap();
    p
}

/// The configuration without where it came from, printed: equal strings are equal
/// bit for bit (-0.0 and 0.0 differ), which `==` does not check.
fn without_source(c: RunConfig) -> String {
    format!(
        "{:?}",
        RunConfig {
            source_path: PathBuf::new(),
            ..c
        }
    )
}

#[test]
fn run_toml_loads_to_the_simulators_config() {
    let root = std::env::temp_dir().join(format!("navfuse-sim-runcfg-{}", std::process::id()));
    for p in scenarios() {
        let sc = Scenario::load(&p).unwrap();
        let name = p.file_stem().unwrap().to_string_lossy().into_owned();
        let dir = root.join(&name);
        std::fs::create_dir_all(&dir).unwrap();
        let cfg = run_config(&sc, &dir);
        let loaded = load(&write(&sc, &dir, "run.toml")).unwrap();
        assert_eq!(loaded, cfg, "{}", p.display());
        assert_eq!(
            without_source(loaded),
            without_source(cfg),
            "{}",
            p.display()
        );
    }
    let _ = std::fs::remove_dir_all(&root);
}

#[test]
fn run_toml_loads_as_the_earlier_one() {
    let Some(old) = std::env::var_os("NAVFUSE_OLD_SIM_DIR") else {
        return;
    };
    let old = PathBuf::from(old);
    let mut n = 0;
    for p in scenarios() {
        let name = p.file_stem().unwrap().to_string_lossy().into_owned();
        let dir = old.join(&name);
        let sc = Scenario::load(&p).unwrap();
        let new = load(&write(&sc, &dir, "run.new.toml")).unwrap();
        let earlier = load(&dir.join("run.toml")).unwrap();
        assert_eq!(new.nav, earlier.nav, "{}", p.display());
        assert_eq!(
            without_source(new),
            without_source(earlier),
            "{}",
            p.display()
        );
        n += 1;
    }
    eprintln!("{n} scenarios: the new run.toml loads as the earlier one");
}
