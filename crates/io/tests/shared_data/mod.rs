//! The shared data folder (../shared/data next to the repository) for the io tests
//! that read real files; a missing file prints a skip line instead of failing.

use std::path::PathBuf;

/// `../shared/data/REL`, or None with a printed `SKIP:` line when it is missing.
pub fn data(rel: &str) -> Option<PathBuf> {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data")
        .join(rel);
    if p.exists() {
        Some(p)
    } else {
        eprintln!("SKIP: {} not found", p.display());
        None
    }
}
