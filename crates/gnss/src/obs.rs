//! Receiver observations as read from RINEX: the GNSS layer's input. navfuse-io
//! reads and writes them (`rinex_obs`), the simulator produces them.
//!
//! - [`MultiObsEpoch`]: every system and signal (RINEX 3 codes, [`ObsCode`]) with
//!   value, LLI and signal strength;
//! - [`ObsEpoch`]: the GPS L1 C/A view of it ([`MultiObsEpoch::gps_l1ca`]) that SPP,
//!   tight coupling and DGPS use today.

use crate::signal::ObsCode;
use crate::time::GpsTime;
use navfuse_core::sat::{SatId, System};

/// One satellite's L1 C/A observations at one epoch.
#[derive(Clone, Debug, PartialEq)]
pub struct SatObs {
    pub prn: u8,
    /// C1C \[m\].
    pub pseudorange_m: Option<f64>,
    /// L1C \[cycles\].
    pub carrier_cycles: Option<f64>,
    /// D1C \[Hz\].
    pub doppler_hz: Option<f64>,
    /// S1C [dB-Hz].
    pub cn0_dbhz: Option<f64>,
    /// Loss-of-lock indicator of the carrier phase (RINEX 3.04 §5.3: bit 0 lost lock,
    /// bit 1 half-cycle ambiguity, bit 2 BOC tracking); 0 = OK.
    pub lli: u8,
}

/// One epoch of observations: `S` is [`SatObs`] (GPS L1 C/A, [`ObsEpoch`]) or
/// [`SatSignals`] (every system and signal, [`MultiObsEpoch`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Epoch<S> {
    /// Receiver time tag (GPST).
    pub t: GpsTime,
    /// Epoch flag, 0 or 1.
    pub flag: u8,
    /// Receiver clock offset \[s\], if the file gives it.
    pub rx_clock_offset_s: Option<f64>,
    /// Satellites, in file order (ObsEpoch: GPS only).
    pub sats: Vec<S>,
}

/// One epoch of GPS L1 C/A observations.
pub type ObsEpoch = Epoch<SatObs>;

/// One epoch of every system's observations.
pub type MultiObsEpoch = Epoch<SatSignals>;

/// One observation of a RINEX record: the value (F14.3; units by type: m, cycles,
/// Hz, dB-Hz) with its loss-of-lock indicator and signal-strength digit (RINEX 3.05
/// §5.3 / §5.7; None where the column is blank). A record with flags but a blank
/// value is kept with `value: None`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ObsValue {
    pub value: Option<f64>,
    pub lli: Option<u8>,
    pub ssi: Option<u8>,
}

impl ObsValue {
    /// A value without flags.
    pub fn new(value: f64) -> Self {
        ObsValue {
            value: Some(value),
            lli: None,
            ssi: None,
        }
    }
}

/// One satellite's observations at one epoch, every signal the file gives, in the
/// order of the system's `SYS / # / OBS TYPES` list (RINEX 2: mapped codes).
#[derive(Clone, Debug, PartialEq)]
pub struct SatSignals {
    pub sat: SatId,
    pub signals: Vec<(ObsCode, ObsValue)>,
}

impl SatSignals {
    /// The observation with this code, if the record has it.
    pub fn get(&self, code: ObsCode) -> Option<&ObsValue> {
        self.signals
            .iter()
            .find(|(c, _)| *c == code)
            .map(|(_, v)| v)
    }

    fn value(&self, code: &[u8; 3]) -> Option<f64> {
        self.get(ObsCode(*code)).and_then(|v| v.value)
    }
}

impl MultiObsEpoch {
    /// Today's GPS L1 C/A view: the GPS satellites' C1C, L1C, D1C, S1C with the LLI of
    /// L1C (0 when blank), as [`ObsEpoch`] (what SPP, tight coupling and DGPS read).
    pub fn gps_l1ca(&self) -> ObsEpoch {
        let sats = self
            .sats
            .iter()
            .filter(|s| s.sat.system == System::Gps)
            .map(|s| SatObs {
                prn: s.sat.prn,
                pseudorange_m: s.value(b"C1C"),
                carrier_cycles: s.value(b"L1C"),
                doppler_hz: s.value(b"D1C"),
                cn0_dbhz: s.value(b"S1C"),
                lli: s.get(ObsCode(*b"L1C")).and_then(|v| v.lli).unwrap_or(0),
            })
            .collect();
        ObsEpoch {
            t: self.t,
            flag: self.flag,
            rx_clock_offset_s: self.rx_clock_offset_s,
            sats,
        }
    }
}

/// A `SYS / PHASE SHIFT` record (RINEX 3.05 §5.2.13): the phase correction \[cycles\]
/// applied to one signal of one system (None: blank, unknown).
#[derive(Clone, Debug, PartialEq)]
pub struct PhaseShift {
    pub system: System,
    pub code: ObsCode,
    pub shift_cycles: Option<f64>,
}

/// What an observation header tells about the signals.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ObsSignalsHeader {
    /// RINEX version of the file (2.11, 3.05, 4.00, ...).
    pub version: f64,
    /// Observation codes per system, in the header's order (RINEX 2: mapped).
    pub types: Vec<(System, Vec<ObsCode>)>,
    /// GLONASS slot -> frequency channel (`GLONASS SLOT / FRQ #`).
    pub glonass_channels: Vec<(u8, i8)>,
    pub phase_shifts: Vec<PhaseShift>,
}

impl ObsSignalsHeader {
    /// The frequency channel of GLONASS slot `slot`, if the header gives it.
    pub fn glonass_channel(&self, slot: u8) -> Option<i8> {
        self.glonass_channels
            .iter()
            .find(|(s, _)| *s == slot)
            .map(|(_, k)| *k)
    }
}
