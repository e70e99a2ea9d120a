//! Where the satellite orbits and clocks come from, for SPP and the tight-coupling
//! preparation: GPS broadcast records ([`EphemerisSet`]), every system's broadcast
//! records ([`EphemerisStore`]), or precise products (SP3 orbits and RINEX clocks,
//! [`PreciseProducts`]) with the broadcast records for health and group delays
//! ([`PreciseSource`]). One face: [`OrbitSource::select`] picks, once per epoch,
//! the orbit to evaluate at the transmission time with its group delay and its error
//! variance. See docs/GNSS.md "Orbits and clocks".

use crate::ephemeris::{Ephemeris, GpsEphemeris, SatState, SPEED_OF_LIGHT_MPS};
use crate::ephemeris_set::EphemerisSet;
use crate::ephemeris_store::EphemerisStore;
use crate::geometry::SatOrbit;
use crate::precise::PreciseProducts;
use crate::time::GpsTime;
use navfuse_core::sat::{SatId, System};

/// Upper bounds of the URA index intervals \[m\] (IS-GPS-200 20.3.3.3.1.3), index 0-14;
/// BeiDou uses the same table (SIS ICD B1I 3.0 §5.2.4.5).
const URA_BOUNDS_M: [f64; 15] = [
    2.4, 3.4, 4.85, 6.85, 9.65, 13.65, 24.0, 48.0, 96.0, 192.0, 384.0, 768.0, 1536.0, 3072.0,
    6144.0,
];

/// GLONASS broadcast orbit and clock error (1-sigma) \[m\]: the navigation message
/// gives no accuracy in RINEX; 5 m is RTKLIB's ERREPH_GLO.
pub const GLONASS_EPHEMERIS_SIGMA_M: f64 = 5.0;

/// Galileo SISA "no accuracy prediction available" (NAPA) taken as this \[m\]
/// (Galileo OS SIS ICD 2.1 §5.1.12; RTKLIB's STD_GAL_NAPA).
pub const GALILEO_NAPA_SIGMA_M: f64 = 500.0;

/// Orbit and clock error assumed for precise products (IGS final / rapid: a few cm
/// orbit, 0.1 ns clock) \[m\].
pub const PRECISE_SIGMA_M: f64 = 0.1;

/// Precise orbits are used only when the state is available this long before the
/// reception time (the longest light time, a BeiDou GEO's 0.13 s, with margin) \[s\].
const PRECISE_LIGHT_TIME_MARGIN_S: f64 = 0.2;

/// The orbit chosen for one satellite at one epoch.
#[derive(Clone, Copy, Debug)]
pub enum OrbitRef<'a> {
    Gps(&'a GpsEphemeris),
    Broadcast(&'a Ephemeris),
    Precise(&'a PreciseProducts, SatId),
}

impl SatOrbit for OrbitRef<'_> {
    fn sat_state(&self, t: GpsTime) -> SatState {
        match self {
            OrbitRef::Gps(e) => e.sat_state(t),
            OrbitRef::Broadcast(e) => e.sat_state(t),
            OrbitRef::Precise(p, sat) => precise_state(p, *sat, t),
        }
    }
}

/// SP3 centre-of-mass state and clock with the periodic relativistic correction
/// -2 r.v / c^2 that IGS clocks leave out (IGS conventions; IS-GPS-200 20.3.3.3.3.1
/// gives the same term as F e sqrt(A) sin E). NaN where the products stop.
fn precise_state(p: &PreciseProducts, sat: SatId, t: GpsTime) -> SatState {
    let nan = f64::NAN;
    match p.state(sat, t) {
        Some(s) => {
            let rel_s = -2.0 * s.pos_ecef_m.dot(&s.vel_ecef_mps) / SPEED_OF_LIGHT_MPS.powi(2);
            SatState {
                pos_ecef_m: s.pos_ecef_m,
                vel_ecef_mps: s.vel_ecef_mps,
                clock_bias_s: s.clock_bias_s.unwrap_or(nan) + rel_s,
                clock_drift_s_per_s: s.clock_drift_s_per_s.unwrap_or(nan),
                relativistic_s: rel_s,
            }
        }
        None => SatState {
            pos_ecef_m: nalgebra::Vector3::repeat(nan),
            vel_ecef_mps: nalgebra::Vector3::repeat(nan),
            clock_bias_s: nan,
            clock_drift_s_per_s: nan,
            relativistic_s: nan,
        },
    }
}

/// The orbit and clock error of a record, as its system states it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum OrbitAccuracy {
    /// GPS, QZSS, BeiDou user range accuracy as RINEX gives it \[m\].
    Ura(f64),
    /// Galileo signal-in-space accuracy \[m\] (<= 0 or >= 500: NAPA).
    Sisa(f64),
    /// A fixed 1-sigma \[m\] (GLONASS 5 m, precise products 0.1 m).
    Sigma(f64),
}

impl OrbitAccuracy {
    /// Variance \[m^2\]: the URA rounded up to its IS-GPS-200 bound, the SISA in
    /// metres (NAPA: 500 m), the fixed sigma. `rtklib_sisa`: the SISA as RTKLIB
    /// 2.4.3's RINEX reader indexes it (above 2 m it truncates the excess to whole
    /// metres before the 0.16 m steps, so 3.12 m becomes 2.96 m), to compare with it.
    pub fn variance_m2(&self, rtklib_sisa: bool) -> f64 {
        match *self {
            OrbitAccuracy::Ura(m) => ura_variance_m2(m),
            OrbitAccuracy::Sisa(m) => {
                let s = if m.is_finite() && m > 0.0 && m < GALILEO_NAPA_SIGMA_M {
                    if rtklib_sisa && m > 2.0 && m <= 6.0 {
                        let index = ((m - 2.0).trunc() / 0.16).trunc();
                        2.0 + 0.16 * index
                    } else {
                        m
                    }
                } else {
                    GALILEO_NAPA_SIGMA_M
                };
                s * s
            }
            OrbitAccuracy::Sigma(m) => m * m,
        }
    }
}

/// A broadcast record of any system, or a GPS LNAV one.
#[derive(Clone, Copy, Debug)]
pub enum RecordRef<'a> {
    Gps(&'a GpsEphemeris),
    Any(&'a Ephemeris),
}

impl RecordRef<'_> {
    /// Group delay of a signal on `band` (`Ephemeris::band_group_delay_s`) \[s\].
    pub fn band_group_delay_s(&self, band: u8) -> Option<f64> {
        match self {
            RecordRef::Gps(e) => e.band_group_delay_s(System::Gps, band),
            RecordRef::Any(e) => e.band_group_delay_s(band),
        }
    }

    /// Group delay of the code a measurement uses \[s\]: one band's, or for the
    /// ionosphere-free combination of `band` (f1) and `second` (f2) the same
    /// combination of the two delays, (f1^2 d1 - f2^2 d2) / (f1^2 - f2^2) (0 for
    /// the pair the clock refers to). None when the record gives no delay.
    pub fn group_delay_s(&self, system: System, band: u8, second: Option<u8>) -> Option<f64> {
        let d1 = self.band_group_delay_s(band)?;
        let Some(b2) = second else { return Some(d1) };
        let d2 = self.band_group_delay_s(b2)?;
        if system == System::Glonass {
            return Some(0.0);
        }
        let f1 = crate::signal::carrier_frequency_hz(system, band, None)?.powi(2);
        let f2 = crate::signal::carrier_frequency_hz(system, b2, None)?.powi(2);
        Some((f1 * d1 - f2 * d2) / (f1 - f2))
    }
}

/// One satellite's orbit for an epoch with what the pseudorange model needs of it.
#[derive(Clone, Copy, Debug)]
pub struct SelectedOrbit<'a> {
    pub orbit: OrbitRef<'a>,
    /// The broadcast record (health, group delays); for a GPS-only set, the GPS one.
    pub record: RecordRef<'a>,
    /// What the record says of its orbit and clock error.
    pub accuracy: OrbitAccuracy,
    /// Issue of data of the broadcast record (DGPS corrections refer to it).
    pub iod: u16,
}

impl SatOrbit for SelectedOrbit<'_> {
    fn sat_state(&self, t: GpsTime) -> SatState {
        self.orbit.sat_state(t)
    }
}

/// Orbits and clocks for every satellite and epoch.
pub trait OrbitSource {
    /// The orbit of `sat` to use for an epoch received at GPST `t`; None without a
    /// healthy record in reach (or outside the precise products).
    fn select(&self, sat: SatId, t: GpsTime) -> Option<SelectedOrbit<'_>>;
}

impl OrbitSource for EphemerisSet {
    fn select(&self, sat: SatId, t: GpsTime) -> Option<SelectedOrbit<'_>> {
        if sat.system != System::Gps {
            return None;
        }
        let e = EphemerisSet::select(self, sat.prn, t)?;
        Some(SelectedOrbit {
            orbit: OrbitRef::Gps(e),
            record: RecordRef::Gps(e),
            accuracy: OrbitAccuracy::Ura(e.sv_accuracy_m),
            iod: e.iode,
        })
    }
}

impl OrbitSource for EphemerisStore {
    fn select(&self, sat: SatId, t: GpsTime) -> Option<SelectedOrbit<'_>> {
        let e = EphemerisStore::select(self, sat, t)?;
        Some(SelectedOrbit {
            orbit: OrbitRef::Broadcast(e),
            record: RecordRef::Any(e),
            accuracy: broadcast_accuracy(e),
            iod: e.iod(),
        })
    }
}

/// Precise orbits and clocks, with the broadcast records for the satellites' health
/// and group delays (the precise clocks refer to the same ionosphere-free signal pair
/// as the broadcast ones, so a single-frequency user applies the same TGD/BGD).
/// Satellite antenna phase-centre offsets are not applied (no ANTEX reader yet): SP3
/// positions are centres of mass, which biases each satellite's range by up to its
/// offset along the line of sight (decimetres to about 1 m for some blocks).
#[derive(Clone, Copy, Debug)]
pub struct PreciseSource<'a> {
    pub products: &'a PreciseProducts,
    pub broadcast: &'a EphemerisStore,
}

impl OrbitSource for PreciseSource<'_> {
    fn select(&self, sat: SatId, t: GpsTime) -> Option<SelectedOrbit<'_>> {
        precise_select(self.products, self.broadcast, sat, t)
    }
}

/// `PreciseSource::select` on borrowed products and records.
fn precise_select<'a>(
    p: &'a PreciseProducts,
    broadcast: &'a EphemerisStore,
    sat: SatId,
    t: GpsTime,
) -> Option<SelectedOrbit<'a>> {
    let e = EphemerisStore::select(broadcast, sat, t)?;
    let covered = |t: GpsTime| p.state(sat, t).is_some_and(|s| s.clock_bias_s.is_some());
    if !(covered(t.add_s(-PRECISE_LIGHT_TIME_MARGIN_S)) && covered(t)) {
        return None;
    }
    Some(SelectedOrbit {
        orbit: OrbitRef::Precise(p, sat),
        record: RecordRef::Any(e),
        accuracy: OrbitAccuracy::Sigma(PRECISE_SIGMA_M),
        iod: e.iod(),
    })
}

/// What a broadcast record states of its accuracy: URA (GPS, QZSS, BeiDou), SISA
/// (Galileo), 5 m for GLONASS (none in RINEX).
pub fn broadcast_accuracy(e: &Ephemeris) -> OrbitAccuracy {
    match e {
        Ephemeris::Gps(g) | Ephemeris::Qzss(g) => OrbitAccuracy::Ura(g.sv_accuracy_m),
        Ephemeris::BeiDou(b) => OrbitAccuracy::Ura(b.sv_accuracy_m),
        Ephemeris::Galileo(g) => OrbitAccuracy::Sisa(g.sisa_m),
        Ephemeris::Glonass(_) => OrbitAccuracy::Sigma(GLONASS_EPHEMERIS_SIGMA_M),
    }
}

/// Variance of the broadcast URA: the smallest IS-GPS-200 URA bound at or above the
/// RINEX value, squared (6144 m for unknown or larger values) [m^2].
pub fn ura_variance_m2(sv_accuracy_m: f64) -> f64 {
    let bound = if sv_accuracy_m.is_finite() {
        URA_BOUNDS_M
            .iter()
            .copied()
            .find(|&b| b >= sv_accuracy_m)
            .unwrap_or(URA_BOUNDS_M[14])
    } else {
        URA_BOUNDS_M[14]
    };
    bound * bound
}

/// Owned orbits for a run: every system's broadcast records, or precise products
/// with them ([`PreciseSource`]).
#[derive(Clone, Debug)]
pub enum RunOrbits {
    Broadcast(EphemerisStore),
    Precise {
        products: PreciseProducts,
        broadcast: EphemerisStore,
    },
}

impl RunOrbits {
    /// The broadcast records (health, group delays, GLONASS channels).
    pub fn broadcast(&self) -> &EphemerisStore {
        match self {
            RunOrbits::Broadcast(b) | RunOrbits::Precise { broadcast: b, .. } => b,
        }
    }
}

impl OrbitSource for RunOrbits {
    fn select(&self, sat: SatId, t: GpsTime) -> Option<SelectedOrbit<'_>> {
        match self {
            RunOrbits::Broadcast(b) => OrbitSource::select(b, sat, t),
            RunOrbits::Precise {
                products,
                broadcast,
            } => precise_select(products, broadcast, sat, t),
        }
    }
}
