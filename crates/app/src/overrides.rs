//! What `navfuse run`'s options change in a configuration (`--outages`, `--smooth`,
//! `--smooth-mode`, `--formats`, `--time-snap`), for every caller that offers them (the CLI,
//! `navfuse batch`, Python).

use crate::error::Error;
use navfuse_core::outage::OutageSchedule;
use navfuse_io::config::RunConfig;
use navfuse_io::export::ExportFormat;
use navfuse_io::input::SmootherMode;

/// Changes to a configuration, each as its `navfuse run` option.
#[derive(Clone, Debug, Default)]
pub struct RunOverrides {
    /// `--outages SPEC`: GNSS outages added to the configuration's.
    pub outages: Option<String>,
    /// `--smooth`: smoothing on.
    pub smooth: bool,
    /// `--smooth-mode rts|combined` (smoothing on).
    pub smooth_mode: Option<String>,
    /// `--formats LIST`: exports added to `[output] formats`.
    pub formats: Option<String>,
    /// `--time-snap S`: `[gnss] time_snap_s` \[s\] (KF-GINS: 0.001).
    pub time_snap_s: Option<f64>,
}

impl RunOverrides {
    /// Apply to `cfg`; errors name the option.
    pub fn apply(&self, cfg: &mut RunConfig) -> Result<(), Error> {
        if let Some(spec) = &self.outages {
            let extra =
                OutageSchedule::parse(spec).map_err(|e| Error::Other(format!("--outages: {e}")))?;
            cfg.nav.gnss.outages.windows.extend(extra.windows);
            cfg.nav.gnss.outages.periodic.extend(extra.periodic);
        }
        if let Some(list) = &self.formats {
            let extra = ExportFormat::parse_list(list)
                .map_err(|e| Error::Other(format!("--formats: {e}")))?;
            for f in extra {
                if !cfg.output.formats.contains(&f) {
                    cfg.output.formats.push(f);
                }
            }
        }
        if let Some(s) = self.time_snap_s {
            if !(0.0..=0.05).contains(&s) {
                return Err(Error::Other(format!(
                    "--time-snap: expected a tolerance in [0, 0.05] s (KF-GINS uses 0.001), found {s}"
                )));
            }
            cfg.nav.gnss.time_snap_s = s;
        }
        if self.smooth || self.smooth_mode.is_some() {
            cfg.smoother.enabled = true;
        }
        match self.smooth_mode.as_deref() {
            None => {}
            Some("rts") => cfg.smoother.mode = SmootherMode::Rts,
            Some("combined") => cfg.smoother.mode = SmootherMode::Combined,
            Some(m) => {
                return Err(Error::Other(format!(
                    "--smooth-mode: expected rts or combined, found '{m}'"
                )))
            }
        }
        Ok(())
    }
}
