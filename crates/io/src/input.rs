//! What to read and how: the input and output descriptions shared by the config
//! loader (`config.rs`) and the readers. Plain data, documented in docs/FORMATS.md.

use serde::{Deserialize, Serialize};
use std::path::PathBuf;

/// What the IMU columns hold.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ImuQuantity {
    /// Angular rate and specific force; converted to increments over each interval.
    Rate,
    /// Angle and velocity increments over (t_{k-1}, t_k].
    Increment,
}

/// How a rate sample relates to its time tag.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RateSampling {
    /// Instantaneous value at t_k: increment = (w_{k-1} + w_k) / 2 * dt (trapezoid).
    Instant,
    /// Mean over (t_{k-1}, t_k] (already integrated by the sensor): increment = w_k * dt.
    IntervalMean,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum TimeUnit {
    #[serde(rename = "s")]
    Seconds,
    #[serde(rename = "ms")]
    Milliseconds,
    #[serde(rename = "us")]
    Microseconds,
    #[serde(rename = "ns")]
    Nanoseconds,
}

/// Which clock the time column counts in.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum TimeScale {
    /// GPS seconds of week (as KF-GINS).
    #[serde(rename = "gps_sow")]
    GpsSecondsOfWeek,
    /// GPS time counted from the Unix epoch with no leap seconds (RTKLIB tag files).
    #[serde(rename = "gpst_unix")]
    GpstUnix,
}

/// Gyro column unit: rates (rad/s, deg/s) or increments (rad, deg).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum GyroUnit {
    Rad,
    Deg,
}

/// Accelerometer column unit (per second for rates; m/s or g*s for increments).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum AccelUnit {
    /// m/s² (rates) or m/s (increments).
    #[serde(rename = "m")]
    Metre,
    /// Standard gravity 9.80665 m/s² (rates) or g*s (increments).
    #[serde(rename = "g")]
    G,
}

/// Generic CSV/whitespace IMU file (docs/FORMATS.md "CSV IMU").
#[derive(Clone, Debug, PartialEq)]
pub struct CsvImuOptions {
    /// Lines to skip at the top (headers).
    pub skip_lines: usize,
    /// 0-based column of the time tag.
    pub time_col: usize,
    /// 0-based columns of gyro x, y, z (sensor frame).
    pub gyro_cols: [usize; 3],
    /// 0-based columns of accelerometer x, y, z (sensor frame).
    pub accel_cols: [usize; 3],
    pub time_unit: TimeUnit,
    pub time_scale: TimeScale,
    pub quantity: ImuQuantity,
    pub rate_sampling: RateSampling,
    pub gyro_unit: GyroUnit,
    pub accel_unit: AccelUnit,
}

impl Default for CsvImuOptions {
    /// `t, gyro x y z, accel x y z` in seconds of GPS week, instantaneous SI rates, no
    /// header: the configuration defaults (docs/CONFIG.md `[imu.csv]`) with that
    /// column layout.
    fn default() -> Self {
        CsvImuOptions {
            skip_lines: 0,
            time_col: 0,
            gyro_cols: [1, 2, 3],
            accel_cols: [4, 5, 6],
            time_unit: TimeUnit::Seconds,
            time_scale: TimeScale::GpsSecondsOfWeek,
            quantity: ImuQuantity::Rate,
            rate_sampling: RateSampling::Instant,
            gyro_unit: GyroUnit::Rad,
            accel_unit: AccelUnit::Metre,
        }
    }
}

/// The rtklibexplorer GNSS_IMU raw IMU log: CSV `ax,ay,az [g], gx,gy,gz [deg/s],
/// counter [ms]` plus an RTKLIB TIMETAG file giving GPST of the log start.
#[derive(Clone, Debug, PartialEq)]
pub struct RtklibExplorerImuOptions {
    /// The `.tag` file beside the CSV.
    pub tag_path: PathBuf,
}

/// Where the IMU data come from.
#[derive(Clone, Debug, PartialEq)]
pub enum ImuFormat {
    /// KF-GINS text: t, dtheta xyz \[rad\], dvel xyz [m/s]; 7 columns or more.
    KfGins,
    Csv(CsvImuOptions),
    RtklibExplorer(RtklibExplorerImuOptions),
    /// PX4 ULog `sensor_combined`, topic instance `multi_id` (docs/FORMATS.md "PX4 ULog").
    Ulog {
        multi_id: u8,
    },
    /// Several CSV files joined (imu/join.rs).
    CsvFiles(Box<CsvImuFiles>),
    /// u-blox UBX ESF-RAW (else ESF-MEAS) IMU data, sensor time mapped to GPS time
    /// (docs/FORMATS.md "ESF-RAW and ESF-MEAS").
    Ubx,
}

/// One gyro or accelerometer file of [`CsvImuFiles`].
#[derive(Clone, Debug, PartialEq)]
pub struct CsvImuPart {
    pub path: PathBuf,
    /// 0-based time column: rows joined on time; None: row by row.
    pub time_col: Option<usize>,
    /// 0-based x, y, z columns.
    pub cols: [usize; 3],
}

/// An IMU in several CSV files: times, gyro and accelerometer (`[imu] files`).
#[derive(Clone, Debug, PartialEq)]
pub struct CsvImuFiles {
    pub time_path: PathBuf,
    pub time_col: usize,
    pub gyro: CsvImuPart,
    pub accel: CsvImuPart,
    /// Lines to skip at the top of every file; None: a first line without a number.
    pub skip_lines: Option<usize>,
    /// Largest time difference of joined rows \[s\].
    pub tolerance_s: f64,
    /// Units, time unit and scale, quantity and sampling (the columns are unused).
    pub csv: CsvImuOptions,
}

/// What the IMU reader does with an interval longer than 0.1 s (a gap in the data).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum GapPolicy {
    /// dt = the real interval, so the filter's covariance grows over the gap. The
    /// sample after the gap is held over it: rates give rate * dt; increments (which
    /// cover one nominal interval) are scaled by interval * rate_hz. A gap longer
    /// than `max_s` is an error.
    Bridge { max_s: Option<f64> },
    /// dt = 1 / rate_hz and the increment as read (KF-GINS): the gap's time is lost.
    Nominal,
}

impl Default for GapPolicy {
    fn default() -> Self {
        GapPolicy::Bridge { max_s: None }
    }
}

#[derive(Clone, Debug, PartialEq)]
pub struct ImuSource {
    pub path: PathBuf,
    pub format: ImuFormat,
    /// Nominal sample rate \[Hz\]; used for the first interval and after gaps.
    pub rate_hz: f64,
    /// Sensor-to-body rotation, ZYX Euler (roll, pitch, yaw) \[deg\]:
    /// v_body = Rz(yaw) Ry(pitch) Rx(roll) v_sensor. Zero for KF-GINS files.
    pub sensor_to_body_rpy_deg: [f64; 3],
    /// Seconds added to every IMU time tag (latency correction).
    pub time_offset_s: f64,
    /// Intervals longer than 0.1 s.
    pub gap_policy: GapPolicy,
}

#[derive(Clone, Debug, PartialEq)]
pub enum GnssFormat {
    /// KF-GINS: t, lat, lon \[deg\], h \[m\], std N E D \[m\] (7 columns); 13 columns add
    /// vel N E D [m/s] and its std.
    KfGins,
    /// RTKLIB solution (.pos), lat/lon/height form, optional velocity columns.
    RtklibPos {
        /// Solution quality flags Q to keep (1 = fix, 2 = float, 5 = single ...).
        quality: Vec<u8>,
    },
    /// RINEX 2/3 observations (the source's `path`) with a RINEX navigation file:
    /// processed by the GNSS layer into single point fixes (loose) or per-satellite
    /// measurements (tight).
    Rinex(RinexGnss),
    /// PX4 ULog `vehicle_gps_position` / `sensor_gps`, topic instance `multi_id`.
    Ulog { multi_id: u8 },
    /// NMEA 0183 log (GGA, RMC, VTG, GST, GSA; nmea.rs).
    Nmea(crate::nmea::NmeaOptions),
    /// Generic CSV with declared columns (gnss_csv.rs).
    Csv(crate::gnss_csv::CsvGnssOptions),
    /// u-blox UBX log (docs/FORMATS.md "u-blox UBX").
    Ubx(UbxGnss),
}

/// How a UBX log is used (`gnss.ubx_source`).
#[derive(Clone, Debug, PartialEq)]
pub enum UbxGnss {
    /// RXM-RAWX observations with the RXM-SFRBX ephemerides of every system, through the GNSS
    /// layer as RINEX observations are, with the same settings. The settings'
    /// `nav_path` is an extra RINEX navigation file whose records are added to the
    /// decoded ones; empty (`PathBuf::new()`) for none ([`UbxGnss::extra_nav`]).
    Raw(RinexGnss),
    /// The receiver's NAV-PVT solutions as fixes (loose coupling).
    Pvt,
}

impl UbxGnss {
    /// The extra RINEX navigation file of a raw source, if one is given.
    pub fn extra_nav(&self) -> Option<&std::path::Path> {
        match self {
            UbxGnss::Raw(r) if !r.nav_path.as_os_str().is_empty() => Some(&r.nav_path),
            _ => None,
        }
    }
}

/// How RINEX observations are used.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Coupling {
    /// Single point positioning fixes (position + Doppler velocity) fused as fixes.
    Loose,
    /// Pseudoranges and range rates fused per satellite (`NavConfig::tight`).
    Tight,
}

/// RINEX GNSS input: navigation file, coupling, elevation mask, DGPS.
#[derive(Clone, Debug, PartialEq)]
pub struct RinexGnss {
    pub nav_path: PathBuf,
    pub coupling: Coupling,
    /// Satellites below this elevation are not used \[deg\].
    pub elevation_mask_deg: f64,
    /// Single point positioning's residual test with fault exclusion. Off for data
    /// whose errors the broadcast error model does not cover (e.g. Selective
    /// Availability), where the test would reject every epoch.
    pub fde: bool,
    /// DGPS corrections; None = uncorrected pseudoranges with the broadcast models.
    pub dgps: Option<DgpsSource>,
    /// Code preferences per system (`gnss.signals`; empty: the documented defaults).
    pub signals: Vec<(navfuse_gnss::System, Vec<navfuse_gnss::ObsCode>)>,
    /// Ionosphere-free code where a satellite has two bands (`gnss.dual_frequency`).
    pub dual_frequency: bool,
    /// Where the orbits and clocks come from (`gnss.orbits`).
    pub orbits: Orbits,
    /// C/N0 weighting: sigma \[m\] of the term s^2 10^(0.1 max(ref - C/N0, 0)) and
    /// ref \[dB-Hz\] (`gnss.cn0_sigma_m`, `gnss.cn0_reference_dbhz`); None: off.
    pub cn0_weighting: Option<(f64, f64)>,
}

/// `gnss.orbits`: broadcast ephemerides (the navigation file) or precise products.
#[derive(Clone, Debug, Default, PartialEq)]
pub enum Orbits {
    #[default]
    Broadcast,
    /// SP3 orbit files and RINEX clock files (none: the SP3 clocks); the navigation
    /// file still gives health and group delays.
    Sp3 {
        sp3: Vec<PathBuf>,
        clk: Vec<PathBuf>,
    },
}

/// Where DGPS pseudorange corrections come from.
#[derive(Clone, Debug, PartialEq)]
pub struct DgpsSource {
    pub kind: DgpsKind,
    /// Corrections older than this are not applied \[s\].
    pub max_age_s: f64,
}

#[derive(Clone, Debug, PartialEq)]
pub enum DgpsKind {
    /// A corrections file (`t_s,prn,prc_m,rrc_mps,iode`, docs/FORMATS.md).
    Corrections(PathBuf),
    /// A reference station's RINEX observations at a known position
    /// (latitude, longitude \[rad\], ellipsoidal height \[m\]).
    ReferenceStation {
        obs_path: PathBuf,
        position_lla: [f64; 3],
    },
}

#[derive(Clone, Debug, PartialEq)]
pub struct GnssSource {
    pub path: PathBuf,
    pub format: GnssFormat,
    /// Keep only epochs within 1 ms of a multiple of this interval \[s\] (e.g. 1.0 to
    /// turn 4 Hz into 1 Hz); None keeps all.
    pub decimate_s: Option<f64>,
    /// Seconds added to every GNSS time tag.
    pub time_offset_s: f64,
    /// Text fix files (KF-GINS, RTKLIB .pos): lines to skip at the top; None: a
    /// first line with no number is a header (KF-GINS) or `%` lines (.pos).
    pub skip_lines: Option<usize>,
}

/// What to write and how often.
#[derive(Clone, Debug, PartialEq)]
pub struct OutputSpec {
    /// Output rate \[Hz\]; None = every IMU epoch (KF-GINS behaviour).
    pub rate_hz: Option<f64>,
    /// `solution.nav` (KF-GINS 11 columns) is always written.
    /// `imu_err.txt` (KF-GINS IMU_ERR, 13 columns).
    pub imu_err: bool,
    /// `std.txt` (KF-GINS STD, 22 columns).
    pub std: bool,
    /// `solution.csv` with a header row.
    pub csv: bool,
    /// Exports beside solution.nav (`solution.kml`, `.pos`, ...; export.rs).
    pub formats: Vec<crate::export::ExportFormat>,
}

impl Default for OutputSpec {
    /// Every IMU epoch, `imu_err.txt` and `std.txt`, no CSV (docs/CONFIG.md `[output]`).
    fn default() -> Self {
        OutputSpec {
            rate_hz: None,
            imu_err: true,
            std: true,
            csv: false,
            formats: Vec::new(),
        }
    }
}

/// How the smoother works (`[smoother] mode`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SmootherMode {
    /// Rauch-Tung-Striebel pass backwards over the forward filter's records.
    Rts,
    /// An independent backward filter combined with the forward one by covariance.
    Combined,
}

impl SmootherMode {
    pub fn name(self) -> &'static str {
        match self {
            SmootherMode::Rts => "rts",
            SmootherMode::Combined => "combined",
        }
    }
}

/// Post-processing after the forward run (`[smoother]`, docs/CONFIG.md).
#[derive(Clone, Debug, PartialEq)]
pub struct SmootherSpec {
    pub enabled: bool,
    pub mode: SmootherMode,
    /// Separation report: epochs where forward and backward (or smoothed) differ by
    /// more than this many sigma are flagged.
    pub separation_sigma: f64,
    /// Separation report period \[s\] (0: every output epoch).
    pub separation_period_s: f64,
}

impl Default for SmootherSpec {
    fn default() -> Self {
        SmootherSpec {
            enabled: false,
            mode: SmootherMode::Rts,
            separation_sigma: 3.0,
            separation_period_s: 1.0,
        }
    }
}

/// Noise identification before the run (`[tuning]`, docs/CONFIG.md): the
/// configuration's noise model replaced by the one estimated from the run's own data
/// (`navfuse tune`), then the run.
#[derive(Clone, Debug, PartialEq)]
pub struct TuningSpec {
    pub enabled: bool,
    /// Most expectation-maximisation passes.
    pub iterations: usize,
    /// Start the IMU white noise from the data even where the configuration gives it.
    pub from_data: bool,
    /// Choose between white and time-correlated GNSS fix errors by likelihood.
    pub fix_error_model: bool,
}

impl Default for TuningSpec {
    fn default() -> Self {
        TuningSpec {
            enabled: false,
            iterations: 8,
            from_data: false,
            fix_error_model: true,
        }
    }
}

/// What an odometer file holds (docs/FORMATS.md "Odometer").
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum OdometerFormat {
    /// 2 columns `t speed_mps`. `speed_is_mean`: the speed is the mean since the
    /// previous record (interval = t - t_prev; the first record only starts the
    /// intervals); false = instantaneous (interval 0).
    Speed { speed_is_mean: bool },
    /// 2 columns `t cumulative_pulses`: speed = meters_per_pulse dN / dt over the
    /// interval since the previous record (the first record only starts the count).
    Pulses { meters_per_pulse: f64 },
    /// The simulator's odometer.txt, 4 columns `t cumulative_pulses
    /// pulses_in_interval speed`: read like `Pulses` from the cumulative count.
    Navfuse { meters_per_pulse: f64 },
    /// The simulator's odometer.txt read from its speed column (the mean over the
    /// interval since the previous record, with the simulated speed noise; the first
    /// record only starts the intervals); the pulse columns are checked, not used.
    NavfuseSpeed,
    /// A u-blox UBX log's ESF-MEAS wheel ticks or speed (docs/FORMATS.md "ESF-RAW
    /// and ESF-MEAS"); times are GPS times of the log.
    Ubx(UbxOdometer),
}

/// Which ESF-MEAS odometer data a UBX log gives (`odometer.ubx_measurement`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum UbxOdometer {
    /// Wheel ticks: the single tick (data type 10) when the log has it, else the
    /// mean of the rear wheels (8, 9), else of the front wheels (6, 7); speed =
    /// meters_per_pulse x ticks / dt, signed by the direction bit.
    Ticks { meters_per_pulse: f64 },
    /// The speed (data type 11, 1e-3 m/s), instantaneous.
    Speed,
}

/// Where the odometer data come from. Times are on the IMU time scale.
#[derive(Clone, Debug, PartialEq)]
pub struct OdometerSource {
    pub path: PathBuf,
    pub format: OdometerFormat,
    /// Lines to skip at the top; None: a first line with no number is a header.
    pub skip_lines: Option<usize>,
}

/// Where the dual-antenna heading comes from: 3 columns `t heading_deg std_deg`
/// (docs/FORMATS.md "Heading"). Times are on the GNSS time scale.
#[derive(Clone, Debug, PartialEq)]
pub struct HeadingSource {
    pub path: PathBuf,
    /// Some: an NMEA log (HDT, THS mode A; nmea.rs) instead of the 3-column text.
    pub nmea: Option<crate::nmea::NmeaOptions>,
    /// 3-column text: lines to skip at the top; None: a first line with no number
    /// is a header.
    pub skip_lines: Option<usize>,
    /// Some: a u-blox UBX log's NAV-RELPOSNED headings instead (not with `nmea`).
    pub ubx: Option<UbxHeading>,
}

/// NAV-RELPOSNED headings of a UBX log (`heading.format = "ubx"`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct UbxHeading {
    /// Also take headings with float ambiguities (carrSoln 1); else fixed only.
    pub float_ok: bool,
}

/// The aiding inputs on the IMU time scale that need no week alignment, read and
/// turned into measurements: one line per reader (the barometer). A reader's
/// warnings (a damaged last line dropped) go to `warnings`.
pub fn read_aiding_inputs(
    cfg: &crate::config::RunConfig,
    warnings: &mut Vec<String>,
) -> Result<Vec<navfuse_core::Measurement>, crate::error::InputError> {
    use navfuse_core::Measurement;
    let mut out = Vec::new();
    if let Some(src) = cfg.baro.as_ref().filter(|_| cfg.nav.baro.enabled) {
        let b = crate::baro::read_baro(src, warnings)?;
        if b.is_empty() {
            warnings.push(format!("{}: no barometer records", src.path.display()));
        }
        out.extend(b.into_iter().map(Measurement::Baro));
    }
    Ok(out)
}
