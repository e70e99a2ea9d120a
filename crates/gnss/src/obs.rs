//! Receiver observations as read from RINEX (GPS L1 C/A): the GNSS layer's input.
//! navfuse-io reads and writes them (`rinex_obs`), the simulator produces them.

use crate::time::GpsTime;

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

/// One epoch of GPS observations.
#[derive(Clone, Debug, PartialEq)]
pub struct ObsEpoch {
    /// Receiver time tag (GPST).
    pub t: GpsTime,
    /// Epoch flag, 0 or 1.
    pub flag: u8,
    /// Receiver clock offset \[s\], if the file gives it.
    pub rx_clock_offset_s: Option<f64>,
    /// GPS satellites, in file order.
    pub sats: Vec<SatObs>,
}
