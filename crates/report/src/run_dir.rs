//! Reading a finished run's directory (the files of `navfuse run`, docs/FORMATS.md)
//! for the report, thinned as it is read: every `stride`-th epoch of the solution
//! tables (so that an hour at 200 Hz is about [`PLOT_EPOCHS`] epochs), plus the two
//! epochs around each reference epoch to be scored, so that the errors are those of
//! the full-rate solution.

use crate::Error;
use nalgebra::Vector3;
use navfuse_core::SolutionState;
use std::collections::BTreeMap;
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};

/// About this many epochs of each solution table are kept for plotting.
pub const PLOT_EPOCHS: usize = 20_000;

/// One solution epoch (SI units, angles in radians).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Epoch {
    /// GPS seconds of week (as the files' `t_s` / `gps_sow`).
    pub t: f64,
    pub lla: Vector3<f64>,
    pub v_n: Vector3<f64>,
    pub rpy: Vector3<f64>,
    /// 1-sigma: position N E D \[m\], velocity N E D \[m/s\], roll pitch yaw \[rad\].
    pub std: Option<[f64; 9]>,
    /// 1-sigma of the IMU errors in imu_err.txt's units and order (gyro bias deg/h,
    /// accel bias mGal, gyro and accel scale ppm), from the CSV's std columns.
    pub std_imu: Option<[f64; 12]>,
    pub state: Option<SolutionState>,
    pub integrity: Option<u8>,
    /// Kept for plotting (not only as a neighbour of a scored epoch).
    pub plotted: bool,
}

/// The filter's 1-sigma at one epoch: position N E D \[m\], velocity N E D [m/s],
/// roll pitch yaw \[rad\]; the IMU errors in imu_err.txt's units (deg/h, mGal, ppm).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sigma {
    pub t: f64,
    pub nav: [f64; 9],
    pub imu: Option<[f64; 12]>,
}

/// The sigma nearest `t` (`sigma` sorted by time, not empty).
pub fn sigma_at(sigma: &[Sigma], t: f64) -> &Sigma {
    let i = sigma.partition_point(|s| s.t < t);
    match (i.checked_sub(1).and_then(|j| sigma.get(j)), sigma.get(i)) {
        (Some(a), Some(b)) if (t - a.t) < (b.t - t) => a,
        (_, Some(b)) => b,
        (Some(a), None) => a,
        (None, None) => &sigma[0],
    }
}

/// The extra states of `states.csv` / `smoothed_states.csv`.
#[derive(Clone, Debug, Default)]
pub struct StateTable {
    pub names: Vec<String>,
    /// (t, values, 1-sigma).
    pub rows: Vec<(f64, Vec<f64>, Vec<f64>)>,
}

/// One row of `separation.csv`.
#[derive(Clone, Copy, Debug)]
pub struct SeparationRow {
    pub t: f64,
    /// d N E D \[m\], d vN vE vD \[m/s\], d att N E D \[deg\].
    pub diff: [f64; 9],
    pub sigma: [f64; 9],
    pub max_ratio: f64,
    pub flagged: bool,
}

/// The innovations of one source, thinned: per time bucket the update with the
/// largest NIS, and every rejected one (up to a cap).
#[derive(Clone, Debug, Default)]
pub struct SourceInnovations {
    pub tried: usize,
    pub rejected: usize,
    pub singular: usize,
    /// (t, NIS) of applied updates, the largest per bucket.
    pub applied: Vec<(f64, f64)>,
    /// (t, NIS) of rejected updates.
    pub rejected_points: Vec<(f64, f64)>,
    /// The gate (the last one seen), and the rows it applies to.
    pub gate: Option<f64>,
    pub rows: usize,
    /// Sum of NIS / rows over applied updates (mean NIS per row = 1 when consistent).
    pub nis_per_row_sum: f64,
}

/// When updates were applied, by kind, thinned to one time per 0.1 s: what the
/// solution state is derived from when the solution table has no `state` column.
#[derive(Clone, Debug, Default)]
pub struct AidedTimes {
    /// GNSS position-type updates (`gnss_position`, `pseudorange`).
    pub gnss: Vec<f64>,
    /// Odometer and NHC updates.
    pub vehicle: Vec<f64>,
    /// Zero-velocity / zero-rate updates.
    pub zupt: Vec<f64>,
}

impl AidedTimes {
    fn note(&mut self, source: &str, t: f64) {
        let v = match source {
            "gnss_position" | "pseudorange" => &mut self.gnss,
            "nhc" | "odometer" => &mut self.vehicle,
            "zupt" | "zaru" => &mut self.zupt,
            _ => return,
        };
        if v.last().is_none_or(|l| (t - l).abs() >= 0.1) {
            v.push(t);
        }
    }

    /// The state at `t` by the rule of `Navigator::solution_state` (without the
    /// integrity monitor): GNSS within 1.5 of its median interval + 0.5 s, ZUPT
    /// within 1 s, odometer / NHC within 1 s.
    pub fn state_at(&self, t: f64, gnss_window_s: f64) -> SolutionState {
        let recent = |v: &[f64], w: f64| {
            let i = v.partition_point(|x| *x <= t + 1e-6);
            i > 0 && t - v[i - 1] <= w
        };
        if recent(&self.zupt, 1.0) {
            SolutionState::Static
        } else if recent(&self.gnss, gnss_window_s) {
            SolutionState::Gnss
        } else if recent(&self.vehicle, 1.0) {
            SolutionState::DeadReckoning
        } else {
            SolutionState::Inertial
        }
    }

    /// 1.5 x the median interval between GNSS updates + 0.5 s.
    pub fn gnss_window_s(&self) -> f64 {
        let mut d: Vec<f64> = self
            .gnss
            .windows(2)
            .map(|w| w[1] - w[0])
            .filter(|d| *d < 30.0)
            .collect();
        d.sort_by(f64::total_cmp);
        1.5 * d.get(d.len() / 2).copied().unwrap_or(1.0) + 0.5
    }
}

/// Everything the report shows of one run.
#[derive(Clone, Debug, Default)]
pub struct RunData {
    pub dir: PathBuf,
    pub solution: Vec<Epoch>,
    /// Rows in the solution table and the stride kept for plotting.
    pub solution_rows: usize,
    pub stride: usize,
    pub smoothed: Option<Vec<Epoch>>,
    /// The forward filter's 1-sigma (from solution.csv, else std.txt), thinned as the
    /// solution; and where it came from.
    pub sigma: Vec<Sigma>,
    pub sigma_file: Option<&'static str>,
    /// (t, 12 IMU error values in KF-GINS units: gyro bias deg/h, accel bias mGal,
    /// gyro scale ppm, accel scale ppm).
    pub imu_err: Vec<(f64, [f64; 12])>,
    pub states: Option<StateTable>,
    pub smoothed_states: Option<StateTable>,
    pub separation: Vec<SeparationRow>,
    pub innovations: BTreeMap<String, SourceInnovations>,
    /// The solution state was derived from innovations.csv (no `state` column).
    pub state_derived: bool,
    pub summary: Option<serde_json::Value>,
    /// tuning.json of a run with `[tuning]` (or `navfuse tune`'s output directory).
    pub tuning: Option<serde_json::Value>,
    pub config: Option<String>,
    pub events: Vec<String>,
}

impl RunData {
    /// The first and last solution times.
    pub fn span(&self) -> Option<(f64, f64)> {
        Some((self.solution.first()?.t, self.solution.last()?.t))
    }
}

fn open(path: &Path) -> Result<BufReader<std::fs::File>, Error> {
    let f = std::fs::File::open(path)
        .map_err(|e| Error::new(format!("{}: cannot open: {e}", path.display())))?;
    Ok(BufReader::with_capacity(1 << 20, f))
}

fn lines(path: &Path) -> Result<impl Iterator<Item = Result<(usize, String), Error>>, Error> {
    let p = path.to_path_buf();
    Ok(open(path)?.lines().enumerate().map(move |(i, l)| {
        l.map(|l| (i + 1, l))
            .map_err(|e| Error::new(format!("{}:{}: cannot read: {e}", p.display(), i + 1)))
    }))
}

fn count_lines(path: &Path) -> Result<usize, Error> {
    use std::io::Read;
    let mut r = open(path)?;
    let mut buf = vec![0u8; 1 << 20];
    let mut n = 0;
    loop {
        let k = r
            .read(&mut buf)
            .map_err(|e| Error::new(format!("{}: cannot read: {e}", path.display())))?;
        if k == 0 {
            return Ok(n);
        }
        n += buf[..k].iter().filter(|&&b| b == b'\n').count();
    }
}

fn parse(path: &Path, line: usize, name: &str, v: &str) -> Result<f64, Error> {
    if v.is_empty() {
        return Ok(f64::NAN);
    }
    v.trim().parse().map_err(|_| {
        Error::new(format!(
            "{}:{line}: field {name} = `{v}`: expected a number",
            path.display()
        ))
    })
}

/// Column indices of a navfuse solution CSV header.
struct CsvColumns {
    t: usize,
    nav: [usize; 9],
    std: Option<[usize; 9]>,
    std_imu: Option<[usize; 12]>,
    integrity: Option<usize>,
    state: Option<usize>,
    width: usize,
}

const NAV_COLS: [&str; 9] = [
    "lat_deg",
    "lon_deg",
    "h_m",
    "vn_mps",
    "ve_mps",
    "vd_mps",
    "roll_deg",
    "pitch_deg",
    "yaw_deg",
];
const STD_COLS: [&str; 9] = [
    "std_pn_m",
    "std_pe_m",
    "std_pd_m",
    "std_vn_mps",
    "std_ve_mps",
    "std_vd_mps",
    "std_roll_deg",
    "std_pitch_deg",
    "std_yaw_deg",
];

const STD_IMU_COLS: [&str; 12] = [
    "std_bgx_degph",
    "std_bgy_degph",
    "std_bgz_degph",
    "std_bax_mgal",
    "std_bay_mgal",
    "std_baz_mgal",
    "std_sgx_ppm",
    "std_sgy_ppm",
    "std_sgz_ppm",
    "std_sax_ppm",
    "std_say_ppm",
    "std_saz_ppm",
];

impl CsvColumns {
    fn of(path: &Path, header: &str) -> Result<Self, Error> {
        let h: Vec<&str> = header.split(',').map(str::trim).collect();
        let col = |n: &str| h.iter().position(|c| *c == n);
        let need = |n: &str| {
            col(n).ok_or_else(|| {
                Error::new(format!(
                    "{}:1: no column `{n}`; expected a navfuse solution CSV header (gps_week,t_s,lat_deg,...)",
                    path.display()
                ))
            })
        };
        let mut nav = [0; 9];
        for (k, n) in NAV_COLS.iter().enumerate() {
            nav[k] = need(n)?;
        }
        let std = STD_COLS
            .iter()
            .map(|n| col(n))
            .collect::<Option<Vec<_>>>()
            .map(|v| std::array::from_fn(|k| v[k]));
        let std_imu = STD_IMU_COLS
            .iter()
            .map(|n| col(n))
            .collect::<Option<Vec<_>>>()
            .map(|v| std::array::from_fn(|k| v[k]));
        Ok(CsvColumns {
            t: need("t_s")?,
            nav,
            std,
            std_imu,
            integrity: col("gnss_integrity"),
            state: col("state"),
            width: h.len(),
        })
    }

    fn epoch(&self, path: &Path, no: usize, line: &str, plotted: bool) -> Result<Epoch, Error> {
        let f: Vec<&str> = line.split(',').collect();
        if f.len() != self.width {
            return Err(Error::new(format!(
                "{}:{no}: {} fields; the header has {}",
                path.display(),
                f.len(),
                self.width
            )));
        }
        let v = |k: usize, name: &str| parse(path, no, name, f[k]);
        let mut nav = [0.0; 9];
        for (k, n) in NAV_COLS.iter().enumerate() {
            nav[k] = v(self.nav[k], n)?;
        }
        let std = match self.std {
            Some(cols) => {
                let mut s = [0.0; 9];
                for (k, n) in STD_COLS.iter().enumerate() {
                    s[k] = v(cols[k], n)?;
                    if k >= 6 {
                        s[k] = s[k].to_radians();
                    }
                }
                s.iter().all(|x| x.is_finite()).then_some(s)
            }
            None => None,
        };
        let std_imu = match self.std_imu {
            Some(cols) => {
                let mut s = [0.0; 12];
                for (k, n) in STD_IMU_COLS.iter().enumerate() {
                    s[k] = v(cols[k], n)?;
                }
                s.iter().all(|x| x.is_finite()).then_some(s)
            }
            None => None,
        };
        Ok(Epoch {
            t: v(self.t, "t_s")?,
            lla: Vector3::new(nav[0].to_radians(), nav[1].to_radians(), nav[2]),
            v_n: Vector3::new(nav[3], nav[4], nav[5]),
            rpy: Vector3::new(
                nav[6].to_radians(),
                nav[7].to_radians(),
                nav[8].to_radians(),
            ),
            std,
            std_imu,
            state: self
                .state
                .and_then(|k| SolutionState::from_name(f[k].trim())),
            integrity: self.integrity.and_then(|k| f[k].trim().parse().ok()),
            plotted,
        })
    }
}

/// Read a solution CSV keeping every `stride`-th epoch and the two epochs around
/// each time in `score_t` (sorted).
pub fn read_solution_csv(path: &Path, stride: usize, score_t: &[f64]) -> Result<Vec<Epoch>, Error> {
    let mut it = lines(path)?;
    let header = match it.next() {
        Some(r) => r?.1,
        None => return Err(Error::new(format!("{}: empty file", path.display()))),
    };
    let cols = CsvColumns::of(path, &header)?;
    let mut out: Vec<Epoch> = Vec::new();
    let mut prev: Option<(usize, String, f64)> = None;
    let mut k = 0usize;
    for (row, r) in it.enumerate() {
        let (no, line) = r?;
        if line.trim().is_empty() {
            continue;
        }
        let t_field = line.split(',').nth(cols.t).unwrap_or("");
        let t = parse(path, no, "t_s", t_field)?;
        // Scored times passed since the previous row: keep both neighbours.
        let mut bracket = false;
        while k < score_t.len() && score_t[k] <= t {
            bracket |= prev.as_ref().is_none_or(|p| score_t[k] >= p.2);
            k += 1;
        }
        if bracket {
            if let Some((pno, pline, pt)) = prev.take() {
                if out.last().is_none_or(|e| e.t < pt) {
                    out.push(cols.epoch(path, pno, &pline, false)?);
                }
            }
        }
        let plotted = row % stride == 0;
        if plotted || bracket {
            out.push(cols.epoch(path, no, &line, plotted)?);
        }
        prev = Some((no, line, t));
    }
    // The last epoch is always plotted.
    if let Some((no, line, t)) = prev {
        if out.last().is_none_or(|e| e.t < t) {
            out.push(cols.epoch(path, no, &line, true)?);
        }
    }
    Ok(out)
}

/// Read a `.nav` file (no CSV: no std, no state) the same way.
fn read_solution_nav(path: &Path, stride: usize, score_t: &[f64]) -> Result<Vec<Epoch>, Error> {
    let all = navfuse_io::nav::read_nav(path).map_err(|e| Error::new(e.to_string()))?;
    let mut out = Vec::new();
    let mut k = 0usize;
    for (i, (_, n)) in all.iter().enumerate() {
        let mut bracket = false;
        while k < score_t.len() && score_t[k] <= n.t {
            bracket = true;
            k += 1;
        }
        let plotted = i % stride == 0 || i + 1 == all.len();
        if bracket && i > 0 && out.last().is_none_or(|e: &Epoch| e.t < all[i - 1].1.t) {
            out.push(nav_epoch(&all[i - 1].1, false));
        }
        if plotted || bracket {
            out.push(nav_epoch(n, plotted));
        }
    }
    Ok(out)
}

fn nav_epoch(n: &navfuse_core::NavState, plotted: bool) -> Epoch {
    Epoch {
        t: n.t,
        lla: n.lla,
        v_n: n.v_n,
        rpy: navfuse_core::attitude::euler_from_q_bn(&n.q_bn),
        std: None,
        std_imu: None,
        state: None,
        integrity: None,
        plotted,
    }
}

/// A CSV with a header, every `stride`-th row: (line number, fields).
/// A table's header and its kept rows with their line numbers.
type TableRows = (Vec<String>, Vec<(usize, Vec<f64>)>);

fn read_table(path: &Path, stride: usize) -> Result<TableRows, Error> {
    let mut it = lines(path)?;
    let header: Vec<String> = match it.next() {
        Some(r) => r?.1.split(',').map(|s| s.trim().to_string()).collect(),
        None => return Ok((Vec::new(), Vec::new())),
    };
    let mut rows = Vec::new();
    let mut last = None;
    for (i, r) in it.enumerate() {
        let (no, line) = r?;
        if line.trim().is_empty() {
            continue;
        }
        if i % stride == 0 {
            rows.push((no, row(path, no, &header, &line)?));
            last = None;
        } else {
            last = Some((no, line));
        }
    }
    if let Some((no, line)) = last {
        rows.push((no, row(path, no, &header, &line)?));
    }
    Ok((header, rows))
}

fn row(path: &Path, no: usize, header: &[String], line: &str) -> Result<Vec<f64>, Error> {
    let f: Vec<&str> = line.split(',').collect();
    if f.len() != header.len() {
        return Err(Error::new(format!(
            "{}:{no}: {} fields; the header has {}",
            path.display(),
            f.len(),
            header.len()
        )));
    }
    f.iter()
        .zip(header)
        .map(|(v, n)| parse(path, no, n, v))
        .collect()
}

fn read_states(path: &Path, stride: usize) -> Result<Option<StateTable>, Error> {
    if !path.is_file() {
        return Ok(None);
    }
    let (header, rows) = read_table(path, stride)?;
    if header.len() < 2 || header[1] != "gps_sow" {
        return Err(Error::new(format!(
            "{}:1: expected `gps_week,gps_sow,NAME,sd_NAME,...`",
            path.display()
        )));
    }
    let names: Vec<String> = header[2..].iter().step_by(2).cloned().collect();
    let rows = rows
        .into_iter()
        .map(|(_, v)| {
            let values = v[2..].iter().step_by(2).copied().collect();
            let std = v[3..].iter().step_by(2).copied().collect();
            (v[1], values, std)
        })
        .collect();
    Ok(Some(StateTable { names, rows }))
}

fn read_separation(path: &Path) -> Result<Vec<SeparationRow>, Error> {
    if !path.is_file() {
        return Ok(Vec::new());
    }
    let (header, rows) = read_table(path, 1)?;
    if header.len() != 22 {
        return Err(Error::new(format!(
            "{}:1: {} columns; expected the 22 of separation.csv",
            path.display(),
            header.len()
        )));
    }
    Ok(rows
        .into_iter()
        .map(|(_, v)| SeparationRow {
            t: v[1],
            diff: std::array::from_fn(|k| v[2 + k]),
            sigma: std::array::from_fn(|k| v[11 + k]),
            max_ratio: v[20],
            flagged: v[21] != 0.0,
        })
        .collect())
}

/// A whitespace table of `N` numeric columns (KF-GINS STD, IMU_ERR), every
/// `stride`-th row; `what` names the columns for the error.
fn read_columns<const N: usize>(
    path: &Path,
    stride: usize,
    what: &str,
) -> Result<Vec<[f64; N]>, Error> {
    if !path.is_file() {
        return Ok(Vec::new());
    }
    let mut out = Vec::new();
    let mut kept = 0usize;
    for r in lines(path)? {
        let (no, line) = r?;
        if line.trim().is_empty() || line.starts_with('#') {
            continue;
        }
        kept += 1;
        if !(kept - 1).is_multiple_of(stride) {
            continue;
        }
        let v: Vec<&str> = line.split_whitespace().collect();
        if v.len() != N {
            return Err(Error::new(format!(
                "{}:{no}: {} columns; expected {N} ({what})",
                path.display(),
                v.len()
            )));
        }
        let mut x = [0.0; N];
        for (k, f) in v.iter().enumerate() {
            x[k] = parse(path, no, what, f)?;
        }
        out.push(x);
    }
    Ok(out)
}

/// The KF-GINS STD file (t and 21 columns: position, velocity, attitude [deg], then
/// the IMU errors).
fn read_std_txt(path: &Path, stride: usize) -> Result<Vec<Sigma>, Error> {
    let rows = read_columns::<22>(path, stride, "t and the 21 standard deviations")?;
    Ok(rows
        .into_iter()
        .map(|x| {
            let mut nav: [f64; 9] = std::array::from_fn(|k| x[1 + k]);
            for a in &mut nav[6..] {
                *a = a.to_radians();
            }
            Sigma {
                t: x[0],
                nav,
                imu: Some(std::array::from_fn(|k| x[10 + k])),
            }
        })
        .collect())
}

/// imu_err.txt: (t, the 12 IMU errors).
fn read_imu_err(path: &Path, stride: usize) -> Result<Vec<(f64, [f64; 12])>, Error> {
    let rows = read_columns::<13>(path, stride, "t and the 12 IMU errors")?;
    Ok(rows
        .into_iter()
        .map(|x| (x[0], std::array::from_fn(|k| x[1 + k])))
        .collect())
}

/// Read innovations.csv streaming: per source, per `bucket_s`, the applied update
/// with the largest NIS; every rejected one up to `max_rejected`.
type Innovations = (BTreeMap<String, SourceInnovations>, AidedTimes);

fn read_innovations(path: &Path, bucket_s: f64) -> Result<Innovations, Error> {
    const MAX_REJECTED: usize = 20_000;
    let mut out: BTreeMap<String, SourceInnovations> = BTreeMap::new();
    let mut aided = AidedTimes::default();
    if !path.is_file() {
        return Ok((out, aided));
    }
    let mut buckets: BTreeMap<String, (i64, f64, f64)> = BTreeMap::new();
    for r in lines(path)? {
        let (no, line) = r?;
        if no == 1 || line.trim().is_empty() {
            continue;
        }
        let f: Vec<&str> = line.split(',').collect();
        if f.len() != 9 {
            return Err(Error::new(format!(
                "{}:{no}: {} fields; expected 9 (t_s,source,rows,y1,y2,y3,nis,gate,outcome)",
                path.display(),
                f.len()
            )));
        }
        let t = parse(path, no, "t_s", f[0])?;
        let nis = parse(path, no, "nis", f[6])?;
        let gate = parse(path, no, "gate", f[7])?;
        let s = out.entry(f[1].to_string()).or_default();
        s.tried += 1;
        s.rows = f[2].parse().unwrap_or(s.rows);
        if gate.is_finite() {
            s.gate = Some(gate);
        }
        match f[8] {
            "applied" => {
                aided.note(f[1], t);
                s.nis_per_row_sum += nis / s.rows.max(1) as f64;
                let b = (t / bucket_s).floor() as i64;
                let e = buckets.entry(f[1].to_string()).or_insert((b, t, nis));
                if e.0 != b {
                    s.applied.push((e.1, e.2));
                    *e = (b, t, nis);
                } else if nis > e.2 {
                    *e = (b, t, nis);
                }
            }
            "rejected" => {
                s.rejected += 1;
                if s.rejected_points.len() < MAX_REJECTED {
                    s.rejected_points.push((t, nis));
                }
            }
            "singular" => s.singular += 1,
            o => {
                return Err(Error::new(format!(
                    "{}:{no}: field outcome = `{o}`; expected applied, rejected or singular",
                    path.display()
                )))
            }
        }
    }
    for (name, (_, t, nis)) in buckets {
        if let Some(s) = out.get_mut(&name) {
            s.applied.push((t, nis));
        }
    }
    Ok((out, aided))
}

/// Read `dir` for the report; `score_t`: the reference epochs to be scored (sorted;
/// empty without a truth).
pub fn read_run(dir: &Path, score_t: &[f64]) -> Result<RunData, Error> {
    let csv = dir.join("solution.csv");
    let nav = dir.join("solution.nav");
    let (table, rows) = if csv.is_file() {
        (csv.clone(), count_lines(&csv)?.saturating_sub(1))
    } else if nav.is_file() {
        (nav.clone(), count_lines(&nav)?)
    } else {
        return Err(Error::new(format!(
            "{}: no solution.csv or solution.nav; expected the output directory of `navfuse run`",
            dir.display()
        )));
    };
    let stride = rows.div_ceil(PLOT_EPOCHS).max(1);
    let read = |p: &Path| {
        if p.extension().is_some_and(|e| e == "csv") {
            read_solution_csv(p, stride, score_t)
        } else {
            read_solution_nav(p, stride, score_t)
        }
    };
    let mut solution = read(&table)?;
    if solution.is_empty() {
        return Err(Error::new(format!("{}: no epochs", table.display())));
    }
    let smoothed_csv = dir.join("smoothed.csv");
    let smoothed = if smoothed_csv.is_file() {
        Some(read(&smoothed_csv)?)
    } else {
        None
    };
    let span = solution[solution.len() - 1].t - solution[0].t;
    let bucket_s = (span / 3000.0).max(1e-3);
    let (innovations, aided) = read_innovations(&dir.join("innovations.csv"), bucket_s)?;
    let state_derived = solution.iter().all(|e| e.state.is_none()) && !innovations.is_empty();
    if state_derived {
        let w = aided.gnss_window_s();
        for e in solution.iter_mut() {
            e.state = Some(aided.state_at(e.t, w));
        }
    }
    let from_csv: Vec<Sigma> = solution
        .iter()
        .filter(|e| e.plotted)
        .filter_map(|e| {
            Some(Sigma {
                t: e.t,
                nav: e.std?,
                imu: e.std_imu,
            })
        })
        .collect();
    let (sigma, sigma_file) = if !from_csv.is_empty() {
        (from_csv, Some("solution.csv"))
    } else {
        let s = read_std_txt(&dir.join("std.txt"), stride)?;
        let f = (!s.is_empty()).then_some("std.txt");
        (s, f)
    };
    let summary = match std::fs::read_to_string(dir.join("summary.json")) {
        Ok(s) => Some(serde_json::from_str(&s).map_err(|e| {
            Error::new(format!(
                "{}: not JSON: {e}",
                dir.join("summary.json").display()
            ))
        })?),
        Err(_) => None,
    };
    let tuning = match std::fs::read_to_string(dir.join("tuning.json")) {
        Ok(s) => Some(serde_json::from_str(&s).map_err(|e| {
            Error::new(format!(
                "{}: not JSON: {e}",
                dir.join("tuning.json").display()
            ))
        })?),
        Err(_) => None,
    };
    let events = std::fs::read_to_string(dir.join("events.log"))
        .map(|s| s.lines().map(str::to_string).collect())
        .unwrap_or_default();
    Ok(RunData {
        dir: dir.to_path_buf(),
        solution,
        solution_rows: rows,
        stride,
        smoothed,
        sigma,
        sigma_file,
        imu_err: read_imu_err(&dir.join("imu_err.txt"), stride)?,
        states: read_states(&dir.join("states.csv"), stride)?,
        smoothed_states: read_states(&dir.join("smoothed_states.csv"), stride)?,
        separation: read_separation(&dir.join("separation.csv"))?,
        innovations,
        state_derived,
        summary,
        tuning,
        config: std::fs::read_to_string(dir.join("config.toml")).ok(),
        events,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_thinning_keeps_the_neighbours_of_scored_epochs() {
        let dir = std::env::temp_dir().join(format!("navfuse_report_rd_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("solution.csv");
        let mut s = String::from("gps_week,t_s,lat_deg,lon_deg,h_m,vn_mps,ve_mps,vd_mps,roll_deg,pitch_deg,yaw_deg,state\n");
        for i in 0..1000 {
            s.push_str(&format!(
                "2000,{}.005,30,114,10,1,0,0,0,0,90,gnss\n",
                100 + i
            ));
        }
        std::fs::write(&p, s).unwrap();
        let e = read_solution_csv(&p, 100, &[350.5, 350.7, 999.0]).unwrap();
        let ts: Vec<f64> = e.iter().map(|e| e.t).collect();
        assert!(ts.windows(2).all(|w| w[0] < w[1]), "{ts:?}");
        for t in [
            100.005, 200.005, 350.005, 351.005, 998.005, 999.005, 1099.005,
        ] {
            assert!(ts.iter().any(|x| (x - t).abs() < 1e-9), "{t} in {ts:?}");
        }
        assert_eq!(e.iter().filter(|e| e.plotted).count(), 11);
        assert_eq!(e[0].state, Some(SolutionState::Gnss));
        std::fs::write(&p, "gps_week,t_s,lat_deg\n1,2,3\n").unwrap();
        let err = read_solution_csv(&p, 1, &[]).unwrap_err().to_string();
        assert!(
            err.contains("solution.csv:1") && err.contains("lon_deg"),
            "{err}"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
