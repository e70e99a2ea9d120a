//! Navigation solution files: KF-GINS `.nav`, `IMU_ERR` and `STD` writers, a CSV
//! writer, and a `.nav` reader (for reference trajectories and solutions).
//!
//! KF-GINS files write every field as C `"%-15.9lf "` (9 decimals, left-justified in
//! 15 characters, then one space), lines ending in `\n`. See docs/FORMATS.md.

use crate::error::InputError;
use crate::fmt::{
    field, is_comment_line, parse_f64, push_fixed9, push_kf_field, split_fields, LineReader,
};
use nalgebra::Vector3;
use navfuse_core::attitude::{euler_from_q_bn, q_bn_from_euler, wrap_2pi};
use navfuse_core::time::SECONDS_PER_WEEK;
use navfuse_core::{ImuErrors, NavState, SolutionState};
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// Capacity of each writer's buffer (1 MiB).
pub(crate) const WRITE_BUF_CAPACITY: usize = 1 << 20;

/// rad/s -> deg/h.
const RADPS_TO_DEGPH: f64 = 180.0 / std::f64::consts::PI * 3600.0;
/// m/s² -> mGal (1 mGal = 1e-5 m/s²).
const MPS2_TO_MGAL: f64 = 1e5;
/// [-] -> ppm.
const TO_PPM: f64 = 1e6;

/// One output epoch.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SolutionRecord {
    /// GPS week that `nav.t` counts from (0 when unknown, as KF-GINS writes).
    pub gps_week: u32,
    pub nav: NavState,
    pub imu_errors: ImuErrors,
    /// 1-sigma in SI, in this order: pos N E D \[m\], vel N E D [m/s], att roll pitch yaw
    /// \[rad\], gyro bias xyz [rad/s], accel bias xyz [m/s²], gyro scale xyz [-], accel
    /// scale xyz [-].
    pub std: Option<[f64; 21]>,
    /// GNSS integrity flag (navfuse_core::integrity::IntegrityState::flag: 0 trusted,
    /// 1 suspect, 2 spoofed, 3 recovering) when the monitor runs.
    pub gnss_integrity: Option<u8>,
    /// What aided the solution at this epoch (navfuse_core::SolutionState), when known.
    pub state: Option<SolutionState>,
}

/// The 11 `.nav` values: week, t, lat \[deg\], lon \[deg\], h \[m\], vN vE vD [m/s],
/// roll pitch yaw \[deg\] with yaw in [0, 360) (also after rounding to 9 decimals).
pub fn nav_fields(r: &SolutionRecord) -> [f64; 11] {
    let n = &r.nav;
    let rpy = euler_from_q_bn(&n.q_bn);
    let mut yaw = wrap_2pi(rpy.z).to_degrees();
    // Values that would print as 360.000000000 become 0.
    if yaw >= 359.999_999_999_49 && yaw.is_finite() {
        yaw = 0.0;
    }
    [
        f64::from(r.gps_week),
        n.t,
        n.lla.x.to_degrees(),
        n.lla.y.to_degrees(),
        n.lla.z,
        n.v_n.x,
        n.v_n.y,
        n.v_n.z,
        rpy.x.to_degrees(),
        rpy.y.to_degrees(),
        yaw,
    ]
}

/// The 12 IMU error values in KF-GINS units: gyro bias [deg/h], accel bias \[mGal\],
/// gyro scale \[ppm\], accel scale \[ppm\], x y z each.
pub fn imu_err_fields(e: &ImuErrors) -> [f64; 12] {
    let g = e.gyro_bias * RADPS_TO_DEGPH;
    let a = e.accel_bias * MPS2_TO_MGAL;
    let sg = e.gyro_scale * TO_PPM;
    let sa = e.accel_scale * TO_PPM;
    [
        g.x, g.y, g.z, a.x, a.y, a.z, sg.x, sg.y, sg.z, sa.x, sa.y, sa.z,
    ]
}

/// The 21 std values in KF-GINS units: pos \[m\], vel [m/s], att \[deg\], gyro bias
/// [deg/h], accel bias \[mGal\], gyro scale \[ppm\], accel scale \[ppm\].
pub fn std_fields(std: &[f64; 21]) -> [f64; 21] {
    let mut out = *std;
    for (k, v) in out.iter_mut().enumerate() {
        *v *= match k {
            0..=5 => 1.0,
            6..=8 => 180.0 / std::f64::consts::PI,
            9..=11 => RADPS_TO_DEGPH,
            12..=14 => MPS2_TO_MGAL,
            _ => TO_PPM,
        };
    }
    out
}

/// A buffered output file with a reused line buffer.
pub(crate) struct Out {
    path: PathBuf,
    w: BufWriter<File>,
    pub(crate) line: Vec<u8>,
}

impl Out {
    pub(crate) fn create(path: &Path) -> Result<Self, InputError> {
        let f = File::create(path).map_err(|e| InputError::create(path, &e))?;
        Ok(Out {
            path: path.to_path_buf(),
            w: BufWriter::with_capacity(WRITE_BUF_CAPACITY, f),
            line: Vec::with_capacity(512),
        })
    }

    /// Write the line buffer (then clear it).
    pub(crate) fn put(&mut self) -> Result<(), InputError> {
        let r = self.w.write_all(&self.line);
        self.line.clear();
        r.map_err(|e| InputError::write(&self.path, &e))
    }

    /// Hand the buffered lines to the file.
    pub(crate) fn flush(&mut self) -> Result<(), InputError> {
        self.w
            .flush()
            .map_err(|e| InputError::write(&self.path, &e))
    }

    /// Flush and close. When the flush fails (disk full), what could not be written
    /// is dropped and the file is cut after its last complete line, so that it holds
    /// only whole records.
    pub(crate) fn finish(self) -> Result<(), InputError> {
        let Out { path, mut w, .. } = self;
        match w.flush() {
            Ok(()) => Ok(()),
            Err(e) => {
                let (file, _) = w.into_parts();
                let _ = cut_after_last_line(&file, &path);
                Err(InputError::write(&path, &e))
            }
        }
    }
}

/// Truncate `file` (open for writing at `path`) after its last newline.
fn cut_after_last_line(file: &File, path: &Path) -> std::io::Result<()> {
    use std::io::{Read, Seek, SeekFrom};
    let len = file.metadata()?.len();
    let from = len.saturating_sub(1 << 16);
    let mut tail = Vec::new();
    let mut r = File::open(path)?;
    r.seek(SeekFrom::Start(from))?;
    r.read_to_end(&mut tail)?;
    let keep = match tail.iter().rposition(|&b| b == b'\n') {
        Some(i) => from + i as u64 + 1,
        None if from == 0 => 0,
        None => return Ok(()),
    };
    if keep < len {
        file.set_len(keep)?;
    }
    Ok(())
}

/// What `navfuse run` needs of every solution writer: write records, hand them to
/// the file now and then, and close (each flushes; see `finish` on a full disk).
pub trait RecordWriter: Send {
    fn write_record(&mut self, r: &SolutionRecord) -> Result<(), InputError>;
    fn flush(&mut self) -> Result<(), InputError>;
    fn finish_boxed(self: Box<Self>) -> Result<(), InputError>;
}

macro_rules! record_writer {
    ($($t:ty),*) => {$(
        impl RecordWriter for $t {
            fn write_record(&mut self, r: &SolutionRecord) -> Result<(), InputError> {
                self.write(r)
            }
            fn flush(&mut self) -> Result<(), InputError> {
                self.out.flush()
            }
            fn finish_boxed(self: Box<Self>) -> Result<(), InputError> {
                self.out.finish()
            }
        }
    )*};
}
record_writer!(NavWriter, ImuErrWriter, StdWriter, CsvWriter);

/// KF-GINS navigation result (`.nav`), 11 columns: week, t \[s\], lat \[deg\], lon \[deg\],
/// h \[m\], vN vE vD [m/s], roll pitch yaw \[deg\].
pub struct NavWriter {
    out: Out,
}

impl NavWriter {
    pub fn create(path: &Path) -> Result<Self, InputError> {
        Ok(NavWriter {
            out: Out::create(path)?,
        })
    }

    pub fn write(&mut self, r: &SolutionRecord) -> Result<(), InputError> {
        for v in nav_fields(r) {
            push_kf_field(&mut self.out.line, v);
        }
        self.out.line.push(b'\n');
        self.out.put()
    }

    /// Flush and close.
    pub fn finish(self) -> Result<(), InputError> {
        self.out.finish()
    }
}

/// KF-GINS `IMU_ERR` file, 13 columns: t \[s\], gyro bias xyz [deg/h], accel bias xyz
/// \[mGal\], gyro scale xyz \[ppm\], accel scale xyz \[ppm\].
pub struct ImuErrWriter {
    out: Out,
    same: SameText<12>,
}

impl ImuErrWriter {
    pub fn create(path: &Path) -> Result<Self, InputError> {
        Ok(ImuErrWriter {
            out: Out::create(path)?,
            same: SameText::default(),
        })
    }

    pub fn write(&mut self, r: &SolutionRecord) -> Result<(), InputError> {
        push_kf_field(&mut self.out.line, r.nav.t);
        self.same
            .push(&mut self.out.line, imu_err_fields(&r.imu_errors));
        self.out.line.push(b'\n');
        self.out.put()
    }

    /// Flush and close.
    pub fn finish(self) -> Result<(), InputError> {
        self.out.finish()
    }
}

/// Formatted KF-GINS fields of the last values written. IMU errors change only at
/// measurement updates and the covariance only every propagation interval, so most
/// records repeat the previous values bit for bit: their text is copied, not formatted.
struct SameText<const N: usize> {
    values: Option<[f64; N]>,
    text: Vec<u8>,
}

impl<const N: usize> Default for SameText<N> {
    fn default() -> Self {
        SameText {
            values: None,
            text: Vec::with_capacity(N * 24),
        }
    }
}

impl<const N: usize> SameText<N> {
    fn push(&mut self, out: &mut Vec<u8>, values: [f64; N]) {
        let same = self.values.is_some_and(|p| {
            p.iter()
                .zip(&values)
                .all(|(a, b)| a.to_bits() == b.to_bits())
        });
        if !same {
            self.text.clear();
            for v in values {
                push_kf_field(&mut self.text, v);
            }
            self.values = Some(values);
        }
        out.extend_from_slice(&self.text);
    }
}

/// KF-GINS `STD` file, 22 columns: t \[s\], pos std N E D \[m\], vel std N E D [m/s], att
/// std roll pitch yaw \[deg\], gyro bias std [deg/h], accel bias std \[mGal\], gyro scale
/// std \[ppm\], accel scale std \[ppm\] (x y z each).
pub struct StdWriter {
    out: Out,
    same: SameText<21>,
}

impl StdWriter {
    pub fn create(path: &Path) -> Result<Self, InputError> {
        Ok(StdWriter {
            out: Out::create(path)?,
            same: SameText::default(),
        })
    }

    /// Errors if the record has no std.
    pub fn write(&mut self, r: &SolutionRecord) -> Result<(), InputError> {
        let Some(std) = &r.std else {
            return Err(InputError::new(
                &self.out.path,
                format!("record at t = {} has no std to write", r.nav.t),
            ));
        };
        push_kf_field(&mut self.out.line, r.nav.t);
        self.same.push(&mut self.out.line, std_fields(std));
        self.out.line.push(b'\n');
        self.out.put()
    }

    /// Flush and close.
    pub fn finish(self) -> Result<(), InputError> {
        self.out.finish()
    }
}

/// Header of the navigation columns of [`CsvWriter`].
pub const CSV_NAV_HEADER: &str =
    "gps_week,t_s,lat_deg,lon_deg,h_m,vn_mps,ve_mps,vd_mps,roll_deg,pitch_deg,yaw_deg";
/// Header of the std columns of [`CsvWriter`] (KF-GINS STD units).
pub const CSV_STD_HEADER: &str = "std_pn_m,std_pe_m,std_pd_m,std_vn_mps,std_ve_mps,std_vd_mps,\
std_roll_deg,std_pitch_deg,std_yaw_deg,std_bgx_degph,std_bgy_degph,std_bgz_degph,\
std_bax_mgal,std_bay_mgal,std_baz_mgal,std_sgx_ppm,std_sgy_ppm,std_sgz_ppm,\
std_sax_ppm,std_say_ppm,std_saz_ppm";

/// `solution.csv`: a header row, then per record the week (integer) and the `.nav`
/// values with 9 decimals; with `with_std`, the 21 std columns follow (empty fields
/// for a record without std); last the solution state (`gnss`, `static`,
/// `dead_reckoning`, `inertial`, `gnss_excluded`; empty when unknown).
pub struct CsvWriter {
    out: Out,
    with_std: bool,
    with_integrity: bool,
}

impl CsvWriter {
    /// `with_integrity`: a last column `gnss_integrity` (0 trusted, 1 suspect, 2
    /// spoofed, 3 recovering; empty for a record without it).
    pub fn create(path: &Path, with_std: bool, with_integrity: bool) -> Result<Self, InputError> {
        let mut out = Out::create(path)?;
        out.line.extend_from_slice(CSV_NAV_HEADER.as_bytes());
        if with_std {
            out.line.push(b',');
            out.line.extend_from_slice(CSV_STD_HEADER.as_bytes());
        }
        if with_integrity {
            out.line.extend_from_slice(b",gnss_integrity");
        }
        out.line.extend_from_slice(b",state");
        out.line.push(b'\n');
        out.put()?;
        Ok(CsvWriter {
            out,
            with_std,
            with_integrity,
        })
    }

    pub fn write(&mut self, r: &SolutionRecord) -> Result<(), InputError> {
        let line = &mut self.out.line;
        let f = nav_fields(r);
        line.extend_from_slice(r.gps_week.to_string().as_bytes());
        for &v in f.iter().skip(1) {
            line.push(b',');
            push_fixed9(line, v);
        }
        if self.with_std {
            match &r.std {
                Some(s) => {
                    for v in std_fields(s) {
                        line.push(b',');
                        push_fixed9(line, v);
                    }
                }
                None => line.extend_from_slice(&[b','; 21]),
            }
        }
        if self.with_integrity {
            line.push(b',');
            if let Some(f) = r.gnss_integrity {
                line.extend_from_slice(f.to_string().as_bytes());
            }
        }
        line.push(b',');
        if let Some(s) = r.state {
            line.extend_from_slice(s.name().as_bytes());
        }
        line.push(b'\n');
        self.out.put()
    }

    /// Flush and close.
    pub fn finish(self) -> Result<(), InputError> {
        self.out.finish()
    }
}

/// Read a KF-GINS-style `.nav` file (11 columns: week, t, lat \[deg\], lon \[deg\], h \[m\],
/// vN vE vD [m/s], roll pitch yaw \[deg\]). Checks: 11 columns, finite numbers, week a
/// non-negative integer, lat in [-90, 90], time (week * 604800 + t) strictly
/// increasing. Attitude becomes q_bn via ZYX Euler angles.
pub fn read_nav(path: &Path) -> Result<Vec<(u32, NavState)>, InputError> {
    read_nav_table(path, false)
}

/// Read navfuse's own `solution.csv` / `smoothed.csv` ([`CsvWriter`]): the header row
/// [`CSV_NAV_HEADER`] (more columns may follow it: std, integrity), then the `.nav`
/// values comma-separated; the columns after the 11th are not read. Same checks as
/// [`read_nav`].
pub fn read_solution_csv(path: &Path) -> Result<Vec<(u32, NavState)>, InputError> {
    read_nav_table(path, true)
}

/// True when `line` is [`CSV_NAV_HEADER`], alone or followed by more columns (after a
/// UTF-8 byte-order mark, as spreadsheets save CSV).
pub fn is_csv_nav_header(line: &[u8]) -> bool {
    let line = line.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(line);
    line.strip_prefix(CSV_NAV_HEADER.as_bytes())
        .is_some_and(|rest| rest.is_empty() || rest[0] == b',')
}

/// The `.nav` values, 11 columns (`csv`: after the CSV header, 11 or more columns).
fn read_nav_table(path: &Path, csv: bool) -> Result<Vec<(u32, NavState)>, InputError> {
    const NAMES: [&str; 11] = [
        "week", "t", "lat", "lon", "h", "vn", "ve", "vd", "roll", "pitch", "yaw",
    ];
    let mut lines = LineReader::open(path)?;
    let mut fields = Vec::with_capacity(16);
    let mut out = Vec::new();
    let mut prev: Option<f64> = None;
    let mut need_header = csv;
    while let Some((ln, text)) = lines.next_line()? {
        split_fields(text, &mut fields);
        if is_comment_line(text, &fields) {
            continue;
        }
        if need_header {
            if !is_csv_nav_header(text) {
                return Err(InputError::at_line(
                    path,
                    ln,
                    format!(
                        "expected the navfuse CSV header \"{CSV_NAV_HEADER}\", found \"{}\"",
                        crate::error::shorten(text)
                    ),
                ));
            }
            need_header = false;
            continue;
        }
        if fields.len() != 11 && !(csv && fields.len() > 11) {
            return Err(InputError::columns(
                path,
                ln,
                if csv { "11 or more" } else { "11" },
                "week, t, lat lon h, vN vE vD, roll pitch yaw",
                fields.len(),
            ));
        }
        let mut v = [0.0; 11];
        for (k, (slot, name)) in v.iter_mut().zip(NAMES).enumerate() {
            let txt = field(text, &fields, k);
            *slot = match parse_f64(txt) {
                Some(x) if x.is_finite() => x,
                Some(x) => return Err(InputError::not_finite(path, ln, name, x)),
                None => return Err(InputError::not_a_number(path, ln, name, txt)),
            };
        }
        let [week, t, lat, lon, h, vn, ve, vd, roll, pitch, yaw] = v;
        if week < 0.0 || week.fract() != 0.0 || week > 1e6 {
            return Err(InputError::at_field(
                path,
                ln,
                "week",
                format!("expected a GPS week number (integer >= 0), found {week}"),
            ));
        }
        if !(-90.0..=90.0).contains(&lat) {
            return Err(InputError::at_field(
                path,
                ln,
                "lat",
                format!("expected a latitude in [-90, 90] deg, found {lat}"),
            ));
        }
        let key = week * SECONDS_PER_WEEK + t;
        match prev {
            Some(p) if key == p => {
                return Err(InputError::at_field(
                    path,
                    ln,
                    "t",
                    format!("duplicate epoch: time {t} repeats the previous epoch"),
                ))
            }
            Some(p) if key < p => {
                return Err(InputError::at_field(
                    path,
                    ln,
                    "t",
                    format!(
                        "time {t} goes backwards (previous {})",
                        p - week * SECONDS_PER_WEEK
                    ),
                ))
            }
            _ => {}
        }
        prev = Some(key);
        let rpy = Vector3::new(roll.to_radians(), pitch.to_radians(), yaw.to_radians());
        out.push((
            week as u32,
            NavState {
                t,
                lla: Vector3::new(lat.to_radians(), lon.to_radians(), h),
                v_n: Vector3::new(vn, ve, vd),
                q_bn: q_bn_from_euler(&rpy),
            },
        ));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rec() -> SolutionRecord {
        let rpy = Vector3::new(0.854208367f64, -2.034815106, 185.702345681).map(f64::to_radians);
        SolutionRecord {
            gps_week: 0,
            nav: NavState {
                t: 456300.104412029,
                lla: Vector3::new(
                    30.444787370f64.to_radians(),
                    114.471863205f64.to_radians(),
                    20.899019775,
                ),
                v_n: Vector3::new(0.000224390, -0.000235729, -0.000285753),
                q_bn: q_bn_from_euler(&rpy),
            },
            imu_errors: ImuErrors {
                gyro_bias: Vector3::new(1.0, -2.0, 0.5) / RADPS_TO_DEGPH,
                accel_bias: Vector3::new(-11.5, 4.0, 30.0) * 1e-5,
                gyro_scale: Vector3::new(100e-6, -200e-6, 0.0),
                accel_scale: Vector3::new(1e-6, 2e-6, 3e-6),
            },
            std: Some([0.01; 21]),
            gnss_integrity: None,
            state: None,
        }
    }

    #[test]
    fn nav_line_matches_kfgins_layout() {
        let dir = std::env::temp_dir().join(format!("navfuse-nav-unit-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("a.nav");
        let mut w = NavWriter::create(&p).unwrap();
        w.write(&rec()).unwrap();
        w.finish().unwrap();
        let s = std::fs::read_to_string(&p).unwrap();
        assert_eq!(
            s,
            "0.000000000     456300.104412029 30.444787370    114.471863205   20.899019775    \
             0.000224390     -0.000235729    -0.000285753    0.854208367     -2.034815106    \
             185.702345681   \n"
        );
        let back = read_nav(&p).unwrap();
        assert_eq!(back.len(), 1);
        assert_eq!(back[0].0, 0);
        let n = &back[0].1;
        assert!((n.q_bn.angle_to(&rec().nav.q_bn)) < 1e-9);
        assert!((n.lla - rec().nav.lla).norm() < 1e-10);
    }

    #[test]
    fn unit_conversions() {
        let r = rec();
        let e = imu_err_fields(&r.imu_errors);
        let want = [
            1.0, -2.0, 0.5, -11.5, 4.0, 30.0, 100.0, -200.0, 0.0, 1.0, 2.0, 3.0,
        ];
        for (a, b) in e.iter().zip(want) {
            assert!((a - b).abs() < 1e-9, "{e:?}");
        }
        let s = std_fields(&[1.0; 21]);
        assert_eq!(s[0], 1.0);
        assert!((s[6] - 57.29577951308232).abs() < 1e-12);
        assert!((s[9] - 206_264.806_247_096_36).abs() < 1e-6);
        assert_eq!(s[12], 1e5);
        assert_eq!(s[20], 1e6);
    }

    #[test]
    fn yaw_is_in_0_360() {
        let mut r = rec();
        for yaw in [-1e-13, 0.0, -0.5, 359.9999999999, 720.25] {
            r.nav.q_bn = q_bn_from_euler(&Vector3::new(0.0, 0.0, f64::to_radians(yaw)));
            let y = nav_fields(&r)[10];
            assert!((0.0..360.0).contains(&y), "{yaw} -> {y}");
            assert!(format!("{y:.9}") != "360.000000000");
        }
    }
}
