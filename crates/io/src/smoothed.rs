//! The smoother's own tables (docs/FORMATS.md "Smoothed output"): the separation
//! report `separation.csv` and the extra states `smoothed_states.csv`. The smoothed
//! trajectory itself goes into the usual writers of nav.rs (`smoothed.nav`, ...).

use crate::error::InputError;
use crate::fmt::push_fixed9;
use crate::nav::Out;
use std::path::Path;

/// One row of the separation report: forward minus backward (mode "combined") or
/// forward minus smoothed (mode "rts"), with the 1-sigma of that difference.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SeparationRow {
    pub gps_week: u32,
    /// GPS seconds of week.
    pub t: f64,
    /// Position N E D \[m\], velocity N E D \[m/s\], attitude error about N E D \[rad\].
    pub diff: [f64; 9],
    /// 1-sigma of each difference (same units).
    pub sigma: [f64; 9],
    /// Largest |diff| / sigma over the nine.
    pub max_ratio: f64,
    /// `max_ratio` above the configured limit.
    pub flagged: bool,
}

const SEP_HEADER: &str = "gps_week,gps_sow,d_north_m,d_east_m,d_down_m,d_vn_mps,d_ve_mps,d_vd_mps,d_att_n_deg,d_att_e_deg,d_att_d_deg,sd_north_m,sd_east_m,sd_down_m,sd_vn_mps,sd_ve_mps,sd_vd_mps,sd_att_n_deg,sd_att_e_deg,sd_att_d_deg,max_ratio,flagged\n";

/// Writes `separation.csv`.
pub struct SeparationWriter {
    out: Out,
}

fn unit(k: usize, v: f64) -> f64 {
    if k >= 6 {
        v.to_degrees()
    } else {
        v
    }
}

impl SeparationWriter {
    pub fn create(path: &Path) -> Result<Self, InputError> {
        let mut out = Out::create(path)?;
        out.line.extend_from_slice(SEP_HEADER.as_bytes());
        out.put()?;
        Ok(SeparationWriter { out })
    }

    pub fn write(&mut self, r: &SeparationRow) -> Result<(), InputError> {
        let line = &mut self.out.line;
        line.extend_from_slice(r.gps_week.to_string().as_bytes());
        line.push(b',');
        push_fixed9(line, r.t);
        for (k, v) in r.diff.iter().enumerate() {
            line.push(b',');
            push_fixed9(line, unit(k, *v));
        }
        for (k, v) in r.sigma.iter().enumerate() {
            line.push(b',');
            push_fixed9(line, unit(k, *v));
        }
        line.push(b',');
        push_fixed9(line, r.max_ratio);
        line.extend_from_slice(if r.flagged { b",1\n" } else { b",0\n" });
        self.out.put()
    }

    pub fn finish(self) -> Result<(), InputError> {
        self.out.finish()
    }
}

/// Writes `smoothed_states.csv`: time, then each extra state's value and 1-sigma.
pub struct StatesWriter {
    out: Out,
}

impl StatesWriter {
    /// `names`: the states (with their units in the name, e.g. `odometer_scale`).
    pub fn create(path: &Path, names: &[String]) -> Result<Self, InputError> {
        let mut out = Out::create(path)?;
        out.line.extend_from_slice(b"gps_week,gps_sow");
        for n in names {
            out.line
                .extend_from_slice(format!(",{n},sd_{n}").as_bytes());
        }
        out.line.push(b'\n');
        out.put()?;
        Ok(StatesWriter { out })
    }

    pub fn write(
        &mut self,
        gps_week: u32,
        t: f64,
        values: &[f64],
        std: &[f64],
    ) -> Result<(), InputError> {
        let line = &mut self.out.line;
        line.extend_from_slice(gps_week.to_string().as_bytes());
        line.push(b',');
        push_fixed9(line, t);
        // Shortest round-trip decimal of each value (zmij, as serde_json writes).
        let mut b = zmij::Buffer::new();
        for (v, s) in values.iter().zip(std) {
            line.push(b',');
            line.extend_from_slice(b.format(*v).as_bytes());
            line.push(b',');
            line.extend_from_slice(b.format(*s).as_bytes());
        }
        line.push(b'\n');
        self.out.put()
    }

    pub fn finish(self) -> Result<(), InputError> {
        self.out.finish()
    }
}
