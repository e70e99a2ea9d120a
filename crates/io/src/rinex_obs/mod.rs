//! RINEX observation files of every system and signal: code (m), carrier phase
//! (cycles), Doppler (Hz), signal strength (dB-Hz), each with its LLI and SSI digits,
//! named by RINEX 3 observation codes (docs/FORMATS.md "RINEX observation files").
//!
//! Writer: [`RinexObsWriter`] produces a GPS-only RINEX 3.04 file (§5.2 header, §5.3
//! epoch records: F14.3 value, LLI digit, SSI digit per observation; blank fields when
//! absent) with C1C, L1C, D1C, S1C; [`RinexMultiObsWriter`] a RINEX 3.05 file of any
//! system mix (`M: Mixed`) from [`MultiObsEpoch`]s.
//!
//! Readers: [`read_rinex_obs_all`] takes the version from `RINEX VERSION / TYPE` and
//! reads RINEX 2.xx, 3.0x and 4.0x files of any system mix, plain, gzip or Compact
//! RINEX 1.0 / 3.0 (`crx.rs`), into [`MultiObsEpoch`]s with the header's signals
//! ([`ObsSignalsHeader`]). [`read_rinex_obs`] / [`read_rinex3_obs`] (3.0x/4.0x only)
//! give its GPS L1 C/A view ([`ObsEpoch`]: C1C, L1C + LLI, D1C, S1C), what the GPS
//! path reads. Epochs with flag 0 (OK) or 1 (power failure since the previous epoch)
//! are kept, flags 2-5 (events, with the header/comment records they announce) and 6
//! (cycle-slip records) are skipped.
//!
//! - 3.0x / 4.0x (`v3.rs`): every type of each system's `SYS / # / OBS TYPES` list;
//!   one line per satellite (`G05` + 16 columns per observation); `GLONASS SLOT /
//!   FRQ #` and `SYS / PHASE SHIFT` are read.
//! - 2.xx (`v2.rs`): every type of `# / TYPES OF OBSERV` (`I6` count, 9 types per
//!   line, continuation lines with a blank count), mapped to RINEX 3 codes per system
//!   (P1 is C1W for GPS: never the L1 C/A pseudorange). Epoch line
//!   ` yy mm dd hh mm ss.sssssss  f nnn` + 12 satellites (`A1,I2`; a blank system is
//!   GPS) + receiver clock offset (F12.9, columns 69-80); more than 12 satellites
//!   continue on lines starting with 32 blanks. Two-digit years 80-99 are 1980-1999,
//!   00-79 are 2000-2079. Each satellite has ceil(types / 5) lines of 5 fields
//!   (F14.3, LLI, SSI); trailing blanks may be missing. An event with flag 3 or 4 may
//!   carry a new `# / TYPES OF OBSERV` list, which applies from the next epoch on.
//!   Flag 6 skips the satellite list and one observation record per satellite.
//! - LLI digits are kept as written: in 2.xx bit 1 means "opposite wavelength factor"
//!   and bit 2 "under anti-spoofing", in 3.0x bit 1 is a half-cycle ambiguity and bit
//!   2 BOC tracking; bit 0 (lost lock) is the same. S types are taken as dB-Hz
//!   (RINEX 2 leaves the unit to the receiver).
//! - Errors name the file, the line and the field and say what was expected
//!   (`obs.11o:14: field 'G05 C1': expected a number, found "2057x396.770"`); truncated
//!   lines read as blank fields, a truncated record is an error at its epoch line.

use self::fields::{open_obs, unsupported};
use self::v2::read_v2_body;
use self::v3::read_v3_body;
use crate::error::InputError;
use std::path::Path;

mod crx;
mod fields;
#[cfg(test)]
mod tests;
mod v2;
mod v3;
mod writer;

pub use writer::{ssi_from_cn0, ObsHeader, RinexMultiObsWriter, RinexObsWriter};

pub use crx::crx_to_rinex;
pub use navfuse_gnss::obs::{
    MultiObsEpoch, ObsEpoch, ObsSignalsHeader, ObsValue, SatObs, SatSignals,
};

/// Read the GPS L1 C/A observations of a RINEX 2.xx, 3.0x or 4.0x observation file
/// (plain, gzip or Compact RINEX); the version is taken from the `RINEX VERSION /
/// TYPE` line. The GPS L1 C/A view ([`MultiObsEpoch::gps_l1ca`]) of
/// [`read_rinex_obs_all`].
/// Warnings (a damaged last epoch dropped) are left out: see [`read_rinex_obs_report`].
pub fn read_rinex_obs(path: &Path) -> Result<Vec<ObsEpoch>, InputError> {
    read_rinex_obs_report(path).map(|r| r.epochs)
}

/// What an observation file gave (GPS L1 C/A view).
#[derive(Clone, Debug, PartialEq)]
pub struct RinexObsRead {
    pub epochs: Vec<ObsEpoch>,
    /// Findings that did not stop the read: a damaged last epoch dropped.
    pub warnings: Vec<String>,
}

/// Every system and signal of an observation file.
#[derive(Clone, Debug, PartialEq)]
pub struct RinexObsAll {
    pub header: ObsSignalsHeader,
    pub epochs: Vec<MultiObsEpoch>,
    /// Findings that did not stop the read: a damaged last epoch dropped.
    pub warnings: Vec<String>,
}

/// What a version's body reader fills: the header's signals, the epochs, and
/// whether the records had started (for the cut-last-line warning).
#[derive(Default)]
pub(super) struct BodyOut {
    header: ObsSignalsHeader,
    epochs: Vec<MultiObsEpoch>,
    records: bool,
}

/// [`read_rinex_obs`] with its warnings. A last epoch cut by the end of the file (a
/// log cut mid-write) is dropped with a warning; damage elsewhere is an error.
pub fn read_rinex_obs_report(path: &Path) -> Result<RinexObsRead, InputError> {
    let all = read_rinex_obs_all(path)?;
    Ok(RinexObsRead {
        epochs: all.epochs.iter().map(MultiObsEpoch::gps_l1ca).collect(),
        warnings: all.warnings,
    })
}

/// Read every system and signal of a RINEX 2.xx, 3.0x or 4.0x observation file,
/// plain, gzip or Compact RINEX 1.0 / 3.0.
pub fn read_rinex_obs_all(path: &Path) -> Result<RinexObsAll, InputError> {
    let (mut rd, ln, version) = open_obs(path)?;
    let body = if version.floor() == 2.0 {
        read_v2_body
    } else if version.floor() == 3.0 || version.floor() == 4.0 {
        read_v3_body
    } else {
        return Err(unsupported(path, ln, version, "2.xx, 3.0x and 4.0x are"));
    };
    let mut b = BodyOut::default();
    let mut warnings = Vec::new();
    match body(&mut rd, path, version, &mut b) {
        Ok(()) => {}
        Err(e) if b.records && rd.cut_last_line() => warnings.push(e.last_line_warning()),
        Err(e) => return Err(e),
    }
    let out = RinexObsAll {
        header: b.header,
        epochs: b.epochs,
        warnings,
    };
    for (k, w) in out.epochs.windows(2).enumerate() {
        if w[1].t.diff_s(&w[0].t) < 0.0 {
            return Err(InputError::new(
                path,
                format!(
                    "epoch {} (week {} {} s) goes backwards (previous {} s): expected \
                     non-decreasing epoch times",
                    k + 2,
                    w[1].t.week,
                    w[1].t.sow,
                    w[0].t.sow
                ),
            )
            .with_field("epoch time"));
        }
    }
    Ok(out)
}

/// Read the GPS C1C/L1C/D1C/S1C observations of a RINEX 3.0x / 4.0x observation
/// file. Other versions are refused; [`read_rinex_obs`] also reads RINEX 2.10/2.11.
pub fn read_rinex3_obs(path: &Path) -> Result<Vec<ObsEpoch>, InputError> {
    let (mut rd, ln, version) = open_obs(path)?;
    if version.floor() != 3.0 && version.floor() != 4.0 {
        return Err(unsupported(
            path,
            ln,
            version,
            "3.0x and 4.0x are; read_rinex_obs also reads 2.10/2.11",
        ));
    }
    let mut b = BodyOut::default();
    read_v3_body(&mut rd, path, version, &mut b)?;
    Ok(b.epochs.iter().map(MultiObsEpoch::gps_l1ca).collect())
}
