//! A [`SolutionSink`] that keeps a run's output as columns for Python, and hands every
//! call on to a [`FileSink`] when the run also writes its files (`out=`). The columns
//! are those of `solution.csv` / `smoothed.csv` (header `CSV_NAV_HEADER`, the std
//! columns, `gnss_integrity`, `state`), `states.csv` and `imu_err.txt`, with the
//! values a reader of those files gets (9 decimals: `fixed9_value`), so a DataFrame
//! equals the file read with pandas.

use crate::frame::Frame;
use navfuse_app::{
    Error, FileSink, JobResult, OutputLayout, SmoothedEpoch, SmoothedLayout, SolutionRecord,
    SolutionSink, StateValues,
};
use navfuse_core::InnovationRow;
use navfuse_io::config::RunConfig;
use navfuse_io::fmt::fixed9_value;
use navfuse_io::nav::{imu_err_fields, nav_fields, std_fields, CSV_NAV_HEADER, CSV_STD_HEADER};
use navfuse_io::smoothed::SeparationRow;
use std::path::PathBuf;

/// `solution.csv` columns (also `smoothed.csv`).
pub struct SolutionCols {
    pub frame: Frame,
    with_std: bool,
    with_integrity: bool,
    /// Column index of the first nav value, std, integrity, state.
    nav0: usize,
    std0: usize,
    integrity: usize,
    state: usize,
    week: usize,
}

impl SolutionCols {
    pub fn new(layout: &OutputLayout) -> Self {
        let mut frame = Frame::new();
        let mut names = CSV_NAV_HEADER.split(',');
        let week = frame.i64(names.next().unwrap_or("gps_week"));
        let nav0 = week + 1;
        for n in names {
            frame.f64(n);
        }
        let std0 = nav0 + 10;
        if layout.std {
            for n in CSV_STD_HEADER.split(',') {
                frame.f64(n);
            }
        }
        let integrity = if layout.integrity {
            frame.i64("gnss_integrity")
        } else {
            usize::MAX
        };
        let state = frame.str("state");
        SolutionCols {
            frame,
            with_std: layout.std,
            with_integrity: layout.integrity,
            nav0,
            std0,
            integrity,
            state,
            week,
        }
    }

    pub fn push(&mut self, r: &SolutionRecord) {
        let f = &mut self.frame;
        f.push_i64(self.week, Some(i64::from(r.gps_week)));
        for (k, v) in nav_fields(r).iter().skip(1).enumerate() {
            f.push_f64(self.nav0 + k, fixed9_value(*v));
        }
        if self.with_std {
            let std = r.std.map(|s| std_fields(&s));
            for k in 0..21 {
                f.push_f64(self.std0 + k, std.map_or(f64::NAN, |s| fixed9_value(s[k])));
            }
        }
        if self.with_integrity {
            f.push_i64(self.integrity, r.gnss_integrity.map(i64::from));
        }
        f.push_str(self.state, r.state.map(|s| s.name()));
    }
}

/// `imu_err.txt` columns, named as the std ones.
pub struct ImuErrCols {
    pub frame: Frame,
}

impl ImuErrCols {
    const NAMES: [&'static str; 12] = [
        "bgx_degph",
        "bgy_degph",
        "bgz_degph",
        "bax_mgal",
        "bay_mgal",
        "baz_mgal",
        "sgx_ppm",
        "sgy_ppm",
        "sgz_ppm",
        "sax_ppm",
        "say_ppm",
        "saz_ppm",
    ];

    fn new() -> Self {
        let mut frame = Frame::new();
        frame.i64("gps_week");
        frame.f64("t_s");
        for n in Self::NAMES {
            frame.f64(n);
        }
        ImuErrCols { frame }
    }

    fn push(&mut self, r: &SolutionRecord) {
        self.frame.push_i64(0, Some(i64::from(r.gps_week)));
        self.frame.push_f64(1, fixed9_value(r.nav.t));
        for (k, v) in imu_err_fields(&r.imu_errors).iter().enumerate() {
            self.frame.push_f64(2 + k, fixed9_value(*v));
        }
    }
}

/// `states.csv` / `smoothed_states.csv` columns: gps_week, gps_sow, then each state
/// and `sd_` its 1-sigma (shortest round-trip values in the files: exact here).
pub struct StateCols {
    pub frame: Frame,
    n: usize,
}

impl StateCols {
    fn new(names: &[String]) -> Self {
        let mut frame = Frame::new();
        frame.i64("gps_week");
        frame.f64("gps_sow");
        for n in names {
            frame.f64(n);
            frame.f64(&format!("sd_{n}"));
        }
        StateCols {
            frame,
            n: names.len(),
        }
    }

    fn push(&mut self, week: u32, t: f64, values: &[f64], std: &[f64]) {
        self.frame.push_i64(0, Some(i64::from(week)));
        self.frame.push_f64(1, fixed9_value(t));
        for k in 0..self.n {
            self.frame
                .push_f64(2 + 2 * k, values.get(k).copied().unwrap_or(f64::NAN));
            self.frame
                .push_f64(3 + 2 * k, std.get(k).copied().unwrap_or(f64::NAN));
        }
    }
}

/// What a run leaves for Python.
#[derive(Default)]
pub struct Collected {
    pub solution: Option<SolutionCols>,
    pub imu_errors: Option<ImuErrCols>,
    pub states: Option<StateCols>,
    pub smoothed: Option<SolutionCols>,
    pub smoothed_states: Option<StateCols>,
    /// summary.json, as written.
    pub summary_json: String,
    /// events.log, as written.
    pub events_log: String,
}

/// Collects [`Collected`], and forwards to a [`FileSink`] when there is one.
pub struct CollectSink {
    pub files: Option<FileSink>,
    pub out: Collected,
}

impl SolutionSink for CollectSink {
    fn configuration(&mut self, cfg: &RunConfig, files: &mut Vec<PathBuf>) -> Result<(), Error> {
        match self.files.as_mut() {
            Some(f) => f.configuration(cfg, files),
            None => Ok(()),
        }
    }

    fn begin(&mut self, layout: &OutputLayout, files: &mut Vec<PathBuf>) -> Result<(), Error> {
        self.out.solution = Some(SolutionCols::new(layout));
        self.out.imu_errors = Some(ImuErrCols::new());
        match self.files.as_mut() {
            Some(f) => f.begin(layout, files),
            None => Ok(()),
        }
    }

    fn epoch(&mut self, r: &SolutionRecord) -> Result<(), Error> {
        if let Some(s) = self.out.solution.as_mut() {
            s.push(r);
        }
        if let Some(s) = self.out.imu_errors.as_mut() {
            s.push(r);
        }
        match self.files.as_mut() {
            Some(f) => f.epoch(r),
            None => Ok(()),
        }
    }

    fn states(&mut self, s: &StateValues) -> Result<(), Error> {
        self.out
            .states
            .get_or_insert_with(|| StateCols::new(s.names))
            .push(s.gps_week, s.t, s.values, s.std);
        match self.files.as_mut() {
            Some(f) => f.states(s),
            None => Ok(()),
        }
    }

    fn innovations(&mut self, rows: &[InnovationRow]) -> Result<(), Error> {
        match self.files.as_mut() {
            Some(f) => f.innovations(rows),
            None => Ok(()),
        }
    }

    fn location(&self) -> String {
        self.files
            .as_ref()
            .map_or_else(|| "memory".to_string(), |f| f.location())
    }

    fn end(&mut self) -> Result<(), Error> {
        match self.files.as_mut() {
            Some(f) => f.end(),
            None => Ok(()),
        }
    }

    fn begin_smoothed(
        &mut self,
        layout: &SmoothedLayout,
        files: &mut Vec<PathBuf>,
    ) -> Result<(), Error> {
        self.out.smoothed = Some(SolutionCols::new(&layout.base));
        if !layout.state_names.is_empty() {
            self.out.smoothed_states = Some(StateCols::new(&layout.state_names));
        }
        match self.files.as_mut() {
            Some(f) => f.begin_smoothed(layout, files),
            None => Ok(()),
        }
    }

    fn smoothed(&mut self, e: &SmoothedEpoch) -> Result<(), Error> {
        if let Some(s) = self.out.smoothed.as_mut() {
            s.push(&e.record);
        }
        if let Some(s) = self.out.smoothed_states.as_mut() {
            s.push(e.record.gps_week, e.record.nav.t, &e.states, &e.states_std);
        }
        match self.files.as_mut() {
            Some(f) => f.smoothed(e),
            None => Ok(()),
        }
    }

    fn separation(&mut self, row: &SeparationRow) -> Result<(), Error> {
        match self.files.as_mut() {
            Some(f) => f.separation(row),
            None => Ok(()),
        }
    }

    fn end_smoothed(&mut self) -> Result<(), Error> {
        match self.files.as_mut() {
            Some(f) => f.end_smoothed(),
            None => Ok(()),
        }
    }

    fn scratch_dir(&self) -> Option<PathBuf> {
        self.files.as_ref().and_then(|f| f.scratch_dir())
    }

    fn report(&mut self, job: &mut JobResult, progress: bool) -> Result<(), Error> {
        let r = match self.files.as_mut() {
            Some(f) => f.report(job, progress),
            None => Ok(()),
        };
        self.out.events_log = navfuse_app::events_log_text(job);
        self.out.summary_json = serde_json::to_string_pretty(&job.to_json())? + "\n";
        r
    }
}
