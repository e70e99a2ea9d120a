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
use std::sync::mpsc::{sync_channel, SyncSender};
use std::thread::JoinHandle;

/// `solution.csv` columns (also `smoothed.csv`), one vector each.
pub struct SolutionCols {
    week: Vec<Option<i64>>,
    /// t_s .. yaw_deg.
    nav: [Vec<f64>; 10],
    /// The 21 std columns (with `[output] std`).
    std: Option<Vec<Vec<f64>>>,
    integrity: Option<Vec<Option<i64>>>,
    state: Vec<Option<&'static str>>,
}

impl SolutionCols {
    pub fn new(layout: &OutputLayout) -> Self {
        SolutionCols {
            week: Vec::new(),
            nav: Default::default(),
            std: layout.std.then(|| vec![Vec::new(); 21]),
            integrity: layout.integrity.then(Vec::new),
            state: Vec::new(),
        }
    }

    pub fn push(&mut self, r: &SolutionRecord) {
        self.week.push(Some(i64::from(r.gps_week)));
        for (c, v) in self.nav.iter_mut().zip(nav_fields(r).iter().skip(1)) {
            c.push(fixed9_value(*v));
        }
        if let Some(cols) = self.std.as_mut() {
            match r.std.map(|s| std_fields(&s)) {
                Some(s) => cols
                    .iter_mut()
                    .zip(s)
                    .for_each(|(c, v)| c.push(fixed9_value(v))),
                None => cols.iter_mut().for_each(|c| c.push(f64::NAN)),
            }
        }
        if let Some(c) = self.integrity.as_mut() {
            c.push(r.gnss_integrity.map(i64::from));
        }
        self.state.push(r.state.map(|s| s.name()));
    }

    /// The columns, named as the CSV header.
    pub fn frame(self) -> Frame {
        let mut f = Frame::new();
        let mut names = CSV_NAV_HEADER.split(',');
        f.add_i64(names.next().unwrap_or("gps_week"), self.week);
        for (n, c) in names.zip(self.nav) {
            f.add_f64(n, c);
        }
        if let Some(cols) = self.std {
            for (n, c) in CSV_STD_HEADER.split(',').zip(cols) {
                f.add_f64(n, c);
            }
        }
        if let Some(c) = self.integrity {
            f.add_i64("gnss_integrity", c);
        }
        f.add_str("state", self.state);
        f
    }
}

/// `imu_err.txt` columns, named as the std ones.
pub struct ImuErrCols {
    week: Vec<Option<i64>>,
    t: Vec<f64>,
    errors: [Vec<f64>; 12],
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
        ImuErrCols {
            week: Vec::new(),
            t: Vec::new(),
            errors: Default::default(),
        }
    }

    fn push(&mut self, r: &SolutionRecord) {
        self.week.push(Some(i64::from(r.gps_week)));
        self.t.push(fixed9_value(r.nav.t));
        for (c, v) in self.errors.iter_mut().zip(imu_err_fields(&r.imu_errors)) {
            c.push(fixed9_value(v));
        }
    }

    pub fn frame(self) -> Frame {
        let mut f = Frame::new();
        f.add_i64("gps_week", self.week);
        f.add_f64("t_s", self.t);
        for (n, c) in Self::NAMES.iter().zip(self.errors) {
            f.add_f64(n, c);
        }
        f
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

/// `innovations.csv` columns, at full precision (the file rounds to 4-6 decimals).
#[derive(Default)]
pub struct InnovationCols {
    t: Vec<f64>,
    source: Vec<Option<&'static str>>,
    rows: Vec<Option<i64>>,
    y: [Vec<f64>; 3],
    nis: Vec<f64>,
    gate: Vec<f64>,
    outcome: Vec<Option<&'static str>>,
}

impl InnovationCols {
    fn push(&mut self, r: &InnovationRow) {
        self.t.push(r.t);
        self.source.push(Some(r.source));
        self.rows.push(i64::try_from(r.rows).ok());
        for (c, v) in self.y.iter_mut().zip(r.innovation) {
            c.push(v);
        }
        self.nis.push(r.nis);
        self.gate.push(r.gate.unwrap_or(f64::NAN));
        self.outcome.push(Some(r.outcome.name()));
    }

    /// t_s, source, rows, y1 y2 y3 (NaN past `rows`), nis, gate (NaN: not gated),
    /// outcome.
    pub fn frame(self) -> Frame {
        let mut f = Frame::new();
        f.add_f64("t_s", self.t);
        f.add_str("source", self.source);
        f.add_i64("rows", self.rows);
        for (n, c) in ["y1", "y2", "y3"].into_iter().zip(self.y) {
            f.add_f64(n, c);
        }
        f.add_f64("nis", self.nis);
        f.add_f64("gate", self.gate);
        f.add_str("outcome", self.outcome);
        f
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
    pub innovations: InnovationCols,
    /// summary.json, as written.
    pub summary_json: String,
    /// events.log, as written.
    pub events_log: String,
}

/// The forward solution's columns, filled on a thread of their own from batches of
/// records (as FileSink's writers are), so the conversion runs beside the filter.
struct ColumnThread {
    batch: Vec<SolutionRecord>,
    tx: Option<SyncSender<Vec<SolutionRecord>>>,
    handle: Option<JoinHandle<(SolutionCols, ImuErrCols)>>,
}

/// Records per batch handed to the column thread.
const BATCH: usize = 2048;

impl ColumnThread {
    fn start(layout: &OutputLayout) -> Self {
        let (tx, rx) = sync_channel::<Vec<SolutionRecord>>(8);
        let mut sol = SolutionCols::new(layout);
        let handle = std::thread::spawn(move || {
            let mut err = ImuErrCols::new();
            for batch in rx {
                for r in &batch {
                    sol.push(r);
                    err.push(r);
                }
            }
            (sol, err)
        });
        ColumnThread {
            batch: Vec::with_capacity(BATCH),
            tx: Some(tx),
            handle: Some(handle),
        }
    }

    fn push(&mut self, r: &SolutionRecord) {
        self.batch.push(*r);
        if self.batch.len() == BATCH {
            self.send();
        }
    }

    fn send(&mut self) {
        let b = std::mem::replace(&mut self.batch, Vec::with_capacity(BATCH));
        if let Some(tx) = &self.tx {
            // A closed channel means the thread ended (a panic): join reports it.
            let _ = tx.send(b);
        }
    }

    /// The columns, once every record is in.
    fn finish(&mut self) -> Result<Option<(SolutionCols, ImuErrCols)>, Error> {
        if !self.batch.is_empty() {
            self.send();
        }
        self.tx = None;
        match self.handle.take() {
            Some(h) => h
                .join()
                .map(Some)
                .map_err(|_| Error::Other("the column thread of the Python run panicked".into())),
            None => Ok(None),
        }
    }
}

/// Collects [`Collected`], and forwards to a [`FileSink`] when there is one.
pub struct CollectSink {
    files: Option<FileSink>,
    columns: Option<ColumnThread>,
    pub out: Collected,
}

impl CollectSink {
    pub fn new(files: Option<FileSink>) -> Self {
        CollectSink {
            files,
            columns: None,
            out: Collected::default(),
        }
    }

    /// Every forward record into the columns (after the last epoch, or at the report
    /// of a run that ended before its `end`).
    fn join_columns(&mut self) -> Result<(), Error> {
        if let Some(mut c) = self.columns.take() {
            if let Some((sol, err)) = c.finish()? {
                self.out.solution = Some(sol);
                self.out.imu_errors = Some(err);
            }
        }
        Ok(())
    }
}

impl SolutionSink for CollectSink {
    fn configuration(&mut self, cfg: &RunConfig, files: &mut Vec<PathBuf>) -> Result<(), Error> {
        match self.files.as_mut() {
            Some(f) => f.configuration(cfg, files),
            None => Ok(()),
        }
    }

    fn begin(&mut self, layout: &OutputLayout, files: &mut Vec<PathBuf>) -> Result<(), Error> {
        self.columns = Some(ColumnThread::start(layout));
        match self.files.as_mut() {
            Some(f) => f.begin(layout, files),
            None => Ok(()),
        }
    }

    fn epoch(&mut self, r: &SolutionRecord) -> Result<(), Error> {
        if let Some(c) = self.columns.as_mut() {
            c.push(r);
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
        rows.iter().for_each(|r| self.out.innovations.push(r));
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
        let cols = self.join_columns();
        let files = match self.files.as_mut() {
            Some(f) => f.end(),
            None => Ok(()),
        };
        cols.and(files)
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
        let cols = self.join_columns();
        let r = match self.files.as_mut() {
            Some(f) => f.report(job, progress),
            None => Ok(()),
        };
        self.out.events_log = navfuse_app::events_log_text(job);
        self.out.summary_json = serde_json::to_string_pretty(&job.to_json())? + "\n";
        cols.and(r)
    }
}
