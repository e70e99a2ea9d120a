//! Scenario checks: absurd durations and non-finite spoofing values are rejected.

use navfuse_sim::scenario::Scenario;
use std::path::Path;

fn attack() -> (std::path::PathBuf, String) {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/seed004_attack.toml");
    let t = std::fs::read_to_string(&p).unwrap();
    (p, t)
}

#[test]
fn the_seed_scenario_loads() {
    let (p, t) = attack();
    assert!(Scenario::from_text(&p, t).is_ok());
}

#[test]
fn a_1e12_s_segment_is_rejected() {
    let (p, t) = attack();
    let bad = t.replacen("duration_s = 60", "duration_s = 1e12", 1);
    assert_ne!(bad, t);
    let e = Scenario::from_text(&p, bad).unwrap_err().to_string();
    assert!(e.contains("expected at most 30 days (2592000 s)"), "{e}");
}

#[test]
fn a_nan_spoof_offset_is_rejected() {
    let (p, t) = attack();
    let i = t.find("type = \"spoof\"").unwrap();
    let mut bad = t.clone();
    bad.insert_str(
        i + "type = \"spoof\"\n".len(),
        "offset_m = [nan, 0.0, 0.0]\n",
    );
    let e = Scenario::from_text(&p, bad).unwrap_err().to_string();
    assert!(
        e.contains("offset_m, velocity_mps and delay_s must be finite, got NaN"),
        "{e}"
    );
}
