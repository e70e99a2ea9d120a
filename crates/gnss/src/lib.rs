//! navfuse-gnss: the GNSS layer. GPS time, broadcast ephemerides of GPS, QZSS,
//! Galileo, BeiDou and GLONASS (`ephemeris`, `ephemeris_store`),
//! signal geometry with light time and Earth rotation, Klobuchar and Saastamoinen
//! delays, synthetic constellations, single point positioning (`spp`), DGPS
//! corrections (`dgps`) and tight-coupling measurement preparation (`tight_prep`).
//! Pure computation: no file I/O (RINEX files are read and written by navfuse-io).
//! See docs/GNSS.md.

pub mod atmosphere;
pub mod constellation;
pub mod dgps;
pub mod ephemeris;
pub mod ephemeris_set;
pub mod ephemeris_store;
pub mod geometry;
pub mod obs;
pub mod orbit_source;
pub mod precise;
pub mod signal;
pub mod signal_plan;
pub mod spp;
pub mod tight_prep;
pub mod time;

pub use dgps::{corrections_from_reference_station, DgpsCorrection, DgpsCorrections};
pub use ephemeris::{
    BeiDouEphemeris, Ephemeris, GalileoEphemeris, GalileoMessage, GlonassEphemeris, GpsEphemeris,
    SatState,
};
pub use ephemeris_set::EphemerisSet;
pub use ephemeris_store::EphemerisStore;
pub use geometry::{az_el, signal_path, SatOrbit, SignalPath};
pub use navfuse_core::sat::{SatId, System};
pub use obs::{MultiObsEpoch, ObsEpoch, ObsValue, SatObs, SatSignals};
pub use orbit_source::{OrbitSource, PreciseSource, SelectedOrbit};
pub use signal::ObsCode;
pub use spp::{SppConfig, SppError, SppMeasurement, SppSolution, SppSolver};
pub use tight_prep::{EpochPreparer, PreparedEpoch, TightPrepConfig};
pub use time::{GpsTime, GpstCalendar};
