//! Scenarios as values: a built-in or user scenario file, loaded, then changed in code
//! (segments, events, seed) and validated again; never edited as text.

use anyhow::Result;
use navfuse_sim::scenario::{Scenario, ScenarioFile};
use std::path::Path;

/// A scenario built into the binary (the text of a scenarios/*.toml file).
pub(crate) fn builtin(name: &str, text: &str) -> Result<Scenario> {
    Ok(Scenario::from_text(Path::new(name), text.to_string())?)
}

/// `base` with its file replaced by `file` (a changed copy of `base.file`), validated
/// as a scenario file is. The copy the simulator writes (scenario.toml) is the file
/// as written under comment lines saying what `change` made of it.
pub(crate) fn changed(base: &Scenario, file: ScenarioFile, change: &str) -> Result<Scenario> {
    let mut sc = Scenario::from_file(&base.path, file, base.text.clone())?;
    let mut text = String::new();
    for line in format!(
        "Changed in code ({change}); below, {} as written.",
        base.path.display()
    )
    .lines()
    {
        text.push_str("# navfuse: ");
        text.push_str(line);
        text.push('\n');
    }
    text.push_str(&base.text);
    sc.text = text;
    Ok(sc)
}
