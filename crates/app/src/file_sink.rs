//! [`FileSink`]: the files of `navfuse run` in one output directory: solution.nav
//! (KF-GINS), imu_err.txt, std.txt, solution.csv as configured, then events.log,
//! integrity.csv (with the monitor) and summary.json.
//!
//! Records go to a writer thread in batches: formatting text costs about as much as
//! navigating, and the machine may have two cores. Every batch is handed to the files,
//! so that after a crash, a full disk or a stop they end within a batch of each other
//! (or, when the run stops cleanly, at the same epoch).

use crate::error::{Error, ResultExt};
use crate::sink::{OutputLayout, SmoothedEpoch, SmoothedLayout, SolutionSink, StateValues};
use crate::summary::JobResult;
use navfuse_core::InnovationRow;
use navfuse_io::config::RunConfig;
use navfuse_io::innovations::InnovationWriter;
use navfuse_io::nav::{
    CsvWriter, ImuErrWriter, NavWriter, RecordWriter, SolutionRecord, StdWriter,
};
use navfuse_io::smoothed::{SeparationRow, SeparationWriter, StatesWriter};
use navfuse_io::InputError;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::mpsc::SyncSender;
use std::thread::JoinHandle;

/// Records per batch handed to the writer thread.
const BATCH: usize = 2048;

/// Writes a run's output into a directory, as `navfuse run --out DIR` does.
pub struct FileSink {
    dir: PathBuf,
    main: Threaded,
    smoothed: Threaded,
    /// smoothed.csv on a thread of its own: after the forward run the writers are
    /// the bottleneck and the navigator's core is free.
    smoothed_csv: Threaded,
    states: Option<StatesWriter>,
    separation: Option<SeparationWriter>,
    /// states.csv (the forward run's extra states) and innovations.csv, created at
    /// their first row.
    forward_states: Option<Threaded<StatesRow>>,
    innovations: Option<InnovationWriter>,
    /// Files created after `begin`, listed in the summary at the end.
    late_files: Vec<PathBuf>,
}

/// Writers on their own thread, fed in batches of `T` (solution records; rows of
/// states.csv).
struct Threaded<T = SolutionRecord> {
    batch: Vec<T>,
    tx: Option<SyncSender<Vec<T>>>,
    writer: Option<JoinHandle<Result<(), InputError>>>,
}

impl<T> Default for Threaded<T> {
    fn default() -> Self {
        Threaded {
            batch: Vec::new(),
            tx: None,
            writer: None,
        }
    }
}

impl Threaded<SolutionRecord> {
    fn start(writers: Vec<Box<dyn RecordWriter>>) -> Self {
        Self::spawn(move |rx| write_batches(writers, rx))
    }
}

/// A row of states.csv: week, t, then the values and the 1-sigma.
type StatesRow = (u32, f64, Vec<f64>);

impl Threaded<StatesRow> {
    fn start_states(mut w: StatesWriter) -> Self {
        Self::spawn(move |rx| {
            let mut failed = None;
            'batches: for batch in rx {
                for (week, t, v) in batch {
                    let (values, std) = v.split_at(v.len() / 2);
                    if let Err(e) = w.write(week, t, values, std) {
                        failed = Some(e);
                        break 'batches;
                    }
                }
            }
            let finished = w.finish();
            failed.map_or(finished, Err)
        })
    }
}

impl<T: Send + 'static> Threaded<T> {
    fn spawn(
        work: impl FnOnce(std::sync::mpsc::Receiver<Vec<T>>) -> Result<(), InputError> + Send + 'static,
    ) -> Self {
        let (tx, rx) = std::sync::mpsc::sync_channel::<Vec<T>>(8);
        Threaded {
            batch: Vec::with_capacity(BATCH),
            tx: Some(tx),
            writer: Some(std::thread::spawn(move || work(rx))),
        }
    }

    fn push(&mut self, item: T) -> Result<(), Error> {
        self.batch.push(item);
        if self.batch.len() == BATCH {
            self.send()?;
        }
        Ok(())
    }

    /// Hand the current batch to the writer thread.
    fn send(&mut self) -> Result<(), Error> {
        let full = std::mem::replace(&mut self.batch, Vec::with_capacity(BATCH));
        match &self.tx {
            Some(tx) => tx
                .send(full)
                .map_err(|_| Error::Other("the output writer stopped".into())),
            None => Ok(()),
        }
    }

    /// Send the rest, wait for the writer; its error first (the real cause when the
    /// run stopped on it).
    fn end(&mut self, dir: &Path) -> Result<(), Error> {
        let sent = if self.batch.is_empty() {
            Ok(())
        } else {
            self.send()
        };
        self.tx = None;
        let Some(writer) = self.writer.take() else {
            return sent;
        };
        let written = writer
            .join()
            .map_err(|_| Error::Other("the output writer panicked".into()))?;
        written.with_context(|| {
            format!(
                "writing the solution into {} (the files hold whole records up to where writing stopped)",
                dir.display()
            )
        })?;
        sent
    }
}

impl FileSink {
    /// Prepare `dir` (created if missing): leftovers of an earlier run (events.log,
    /// summary.json, integrity.csv, the smoothed files) are removed and summary.json
    /// is reserved, saying `"status": "running"` until the run ends.
    pub fn create(dir: &Path) -> Result<Self, Error> {
        // Leftovers of an earlier run in the same directory must not sit beside this one's.
        for stale in STALE {
            let _ = std::fs::remove_file(dir.join(stale));
        }
        std::fs::create_dir_all(dir).map_err(|e| {
            Error::io(
                format!("cannot create output directory {}", dir.display()),
                e,
            )
        })?;
        let sum_path = dir.join("summary.json");
        reserve_summary(&sum_path)
            .map_err(|e| Error::io(format!("cannot write {}", sum_path.display()), e))?;
        Ok(FileSink {
            dir: dir.to_path_buf(),
            main: Threaded::default(),
            smoothed: Threaded::default(),
            smoothed_csv: Threaded::default(),
            states: None,
            separation: None,
            forward_states: None,
            innovations: None,
            late_files: Vec::new(),
        })
    }

    /// The output directory.
    pub fn dir(&self) -> &Path {
        &self.dir
    }
}

/// Files of an earlier run that this run may not write.
const STALE: [&str; 23] = [
    "config.toml",
    "states.csv",
    "innovations.csv",
    "report.html",
    "solution.pos",
    "solution.nmea",
    "solution.kml",
    "solution.geojson",
    "solution.gpx",
    "smoothed.pos",
    "smoothed.nmea",
    "smoothed.kml",
    "smoothed.geojson",
    "smoothed.gpx",
    "events.log",
    "summary.json",
    "integrity.csv",
    "smoothed.nav",
    "smoothed_imu_err.txt",
    "smoothed_std.txt",
    "smoothed.csv",
    "smoothed_states.csv",
    "separation.csv",
];

/// The record writers of one solution: `STEM.nav`, then as `layout` says
/// `STEM_imu_err.txt` (`imu_err.txt` for the forward one), `STEM_std.txt`, `STEM.csv`.
fn record_writers(
    dir: &Path,
    stem: &str,
    layout: &OutputLayout,
    files: &mut Vec<PathBuf>,
) -> Result<Vec<Box<dyn RecordWriter>>, Error> {
    let name = |suffix: &str| match stem {
        "solution" => dir.join(suffix.trim_start_matches('_')),
        _ => dir.join(format!("{stem}{suffix}")),
    };
    files.push(dir.join(format!("{stem}.nav")));
    let mut writers: Vec<Box<dyn RecordWriter>> =
        vec![Box::new(NavWriter::create(files.last().unwrap())?)];
    if layout.imu_err {
        files.push(name("_imu_err.txt"));
        writers.push(Box::new(ImuErrWriter::create(files.last().unwrap())?));
    }
    if layout.std {
        files.push(name("_std.txt"));
        writers.push(Box::new(StdWriter::create(files.last().unwrap())?));
    }
    // With the integrity monitor, the CSV carries its flag column.
    if layout.csv || layout.integrity {
        files.push(dir.join(format!("{stem}.csv")));
        let w = CsvWriter::create(files.last().unwrap(), layout.std, layout.integrity);
        writers.push(Box::new(w?));
    }
    for f in layout.exports.iter() {
        files.push(dir.join(f.file_name(stem)));
        writers.push(f.create(files.last().unwrap())?);
    }
    Ok(writers)
}

impl SolutionSink for FileSink {
    /// `config.toml`: every key of the configuration the run used (paths absolute),
    /// so that `navfuse run DIR/config.toml` repeats it and the report shows it.
    fn configuration(&mut self, cfg: &RunConfig, files: &mut Vec<PathBuf>) -> Result<(), Error> {
        let p = self.dir.join("config.toml");
        std::fs::write(&p, cfg.to_toml_string())
            .map_err(|e| Error::io(format!("cannot write {}", p.display()), e))?;
        files.push(p);
        Ok(())
    }

    fn tuning(
        &mut self,
        tuned: &crate::tune::Tuned,
        files: &mut Vec<PathBuf>,
    ) -> Result<(), Error> {
        let header = "# Written by [tuning]: the input configuration with the noise model estimated from the data (tuning.txt).\n";
        let json = serde_json::to_string_pretty(&tuned.result.to_json())
            .map_err(|e| Error::Other(format!("tuning.json: {e}")))?;
        for (name, text) in [
            (
                "tuned.toml",
                header.to_string() + &tuned.config.to_toml_string(),
            ),
            ("tuning.json", json + "\n"),
            ("tuning.txt", tuned.text.clone()),
        ] {
            let p = self.dir.join(name);
            std::fs::write(&p, text)
                .map_err(|e| Error::io(format!("cannot write {}", p.display()), e))?;
            files.push(p);
        }
        Ok(())
    }

    fn begin(&mut self, layout: &OutputLayout, files: &mut Vec<PathBuf>) -> Result<(), Error> {
        self.main = Threaded::start(record_writers(&self.dir, "solution", layout, files)?);
        Ok(())
    }

    fn location(&self) -> String {
        self.dir.display().to_string()
    }

    fn epoch(&mut self, record: &SolutionRecord) -> Result<(), Error> {
        self.main.push(*record)
    }

    fn states(&mut self, s: &StateValues) -> Result<(), Error> {
        if self.forward_states.is_none() {
            let p = self.dir.join("states.csv");
            self.forward_states = Some(Threaded::start_states(StatesWriter::create(&p, s.names)?));
            self.late_files.push(p);
        }
        match self.forward_states.as_mut() {
            Some(w) => w.push((s.gps_week, s.t, [s.values, s.std].concat())),
            None => Ok(()),
        }
    }

    fn innovations(&mut self, rows: &[InnovationRow]) -> Result<(), Error> {
        if self.innovations.is_none() {
            let p = self.dir.join("innovations.csv");
            self.innovations = Some(InnovationWriter::create(&p)?);
            self.late_files.push(p);
        }
        if let Some(w) = self.innovations.as_mut() {
            for r in rows {
                w.write(r)?;
            }
        }
        Ok(())
    }

    fn end(&mut self) -> Result<(), Error> {
        let main = self.main.end(&self.dir);
        let states = self
            .forward_states
            .take()
            .map_or(Ok(()), |mut w| w.end(&self.dir));
        let innovations = self.innovations.take().map_or(Ok(()), |w| w.finish());
        main?;
        states?;
        Ok(innovations?)
    }

    fn begin_smoothed(
        &mut self,
        layout: &SmoothedLayout,
        files: &mut Vec<PathBuf>,
    ) -> Result<(), Error> {
        // The smoothed CSV always: it is what users plot.
        let base = OutputLayout {
            csv: true,
            ..layout.base
        };
        let mut writers = record_writers(&self.dir, "smoothed", &base, files)?;
        // smoothed.csv comes right after the KF-GINS tables.
        let n_tables = 1 + usize::from(base.imu_err) + usize::from(base.std);
        let csv = writers.split_off(n_tables);
        self.smoothed = Threaded::start(writers);
        self.smoothed_csv = Threaded::start(csv);
        if !layout.state_names.is_empty() {
            files.push(self.dir.join("smoothed_states.csv"));
            let p = files.last().unwrap();
            self.states = Some(StatesWriter::create(p, &layout.state_names)?);
        }
        files.push(self.dir.join("separation.csv"));
        self.separation = Some(SeparationWriter::create(files.last().unwrap())?);
        Ok(())
    }

    fn smoothed(&mut self, epoch: &SmoothedEpoch) -> Result<(), Error> {
        self.smoothed.push(epoch.record)?;
        self.smoothed_csv.push(epoch.record)?;
        if let Some(w) = self.states.as_mut() {
            let r = &epoch.record;
            w.write(r.gps_week, r.nav.t, &epoch.states, &epoch.states_std)?;
        }
        Ok(())
    }

    fn separation(&mut self, row: &SeparationRow) -> Result<(), Error> {
        match self.separation.as_mut() {
            Some(w) => Ok(w.write(row)?),
            None => Ok(()),
        }
    }

    fn end_smoothed(&mut self) -> Result<(), Error> {
        let records = self.smoothed.end(&self.dir);
        let csv = self.smoothed_csv.end(&self.dir);
        let states = self.states.take().map_or(Ok(()), |w| w.finish());
        let sep = self.separation.take().map_or(Ok(()), |w| w.finish());
        records?;
        csv?;
        states?;
        Ok(sep?)
    }

    fn scratch_dir(&self) -> Option<PathBuf> {
        Some(self.dir.clone())
    }

    fn report(&mut self, job: &mut JobResult, progress: bool) -> Result<(), Error> {
        job.files.append(&mut self.late_files);
        write_reports(&self.dir, job, progress)
    }
}

/// The writer thread: every record of every batch to every writer, each batch flushed.
fn write_batches(
    mut writers: Vec<Box<dyn RecordWriter>>,
    rx: std::sync::mpsc::Receiver<Vec<SolutionRecord>>,
) -> Result<(), InputError> {
    let mut failed = None;
    'batches: for batch in rx {
        for rec in &batch {
            for w in writers.iter_mut() {
                if let Err(e) = w.write_record(rec) {
                    failed = Some(e);
                    break 'batches;
                }
            }
        }
        for w in writers.iter_mut() {
            if let Err(e) = w.flush() {
                failed = Some(e);
                break 'batches;
            }
        }
    }
    // Whatever happened, keep what was computed: flush every writer.
    for w in writers {
        if let Err(e) = w.finish_boxed() {
            failed.get_or_insert(e);
        }
    }
    failed.map_or(Ok(()), Err)
}

/// The text of `events.log`: input notes and findings (`# ` lines), the run's events,
/// and last how it ended when it did not complete.
pub fn events_log_text(job: &JobResult) -> String {
    let mut text = String::new();
    for n in &job.notes {
        text.push_str(&format!("# input: {n}\n"));
    }
    // Errors are in the last line (how the run ended).
    for f in job.findings.iter().filter(|f| !f.is_error()) {
        text.push_str(&format!("# {f}\n"));
    }
    if let Some(f) = &job.time_offset {
        text.push_str(&format!("# time offset: {}\n", f.note));
    }
    for e in &job.summary.events {
        text.push_str(&format!("{e}\n"));
    }
    if let Some(e) = &job.error {
        text.push_str(&format!("# {}: {e}\n", job.status));
    }
    text
}

/// Write `events.log` (input notes, findings, the run's events, how it ended),
/// `integrity.csv` (with the monitor) and `summary.json`, and list them in `job.files`.
fn write_reports(out_dir: &Path, job: &mut JobResult, progress: bool) -> Result<(), Error> {
    let ev_path = out_dir.join("events.log");
    let ev = std::fs::write(&ev_path, events_log_text(job))
        .map_err(|e| Error::io(format!("cannot write {}", ev_path.display()), e));
    if ev.is_ok() {
        job.files.push(ev_path);
    }
    if job.integrity_table && job.status != "failed" {
        let p = out_dir.join("integrity.csv");
        let mut t = String::from("t_s,from,to,detector,statistic,threshold\n");
        let mut spoofed = 0;
        for e in &job.summary.events {
            if let navfuse_core::Event::Integrity(tr) = e {
                spoofed += usize::from(tr.to == navfuse_core::integrity::IntegrityState::Spoofed);
                t.push_str(&format!(
                    "{:.3},{},{},{},{:.4},{}\n",
                    tr.t,
                    tr.from.name(),
                    tr.to.name(),
                    tr.detector.name(),
                    tr.statistic,
                    if tr.threshold.is_finite() {
                        format!("{:.4}", tr.threshold)
                    } else {
                        String::new()
                    }
                ));
            }
        }
        std::fs::write(&p, t).map_err(|e| Error::io(format!("cannot write {}", p.display()), e))?;
        job.files.push(p);
        if progress && spoofed > 0 {
            eprintln!(
                "navfuse: GNSS integrity: declared spoofed {spoofed} time(s) (see integrity.csv)"
            );
        }
    }
    let sum_path = out_dir.join("summary.json");
    job.files.push(sum_path.clone());
    let full = serde_json::to_string_pretty(&job.to_json())? + "\n";
    if let Err(e) = write_reserved(&sum_path, &full) {
        // A full disk: the events list (also in events.log) may be what does not fit.
        let mut short = job.to_json();
        short["events"] = serde_json::json!(["(left out: the disk is full; see events.log)"]);
        write_reserved(&sum_path, &(serde_json::to_string_pretty(&short)? + "\n"))
            .map_err(|_| Error::io(format!("cannot write {}", sum_path.display()), e))?;
    }
    ev
}

/// Space kept for summary.json from the start of a run, so that a run that fills the
/// disk can still say so.
const SUMMARY_RESERVE: usize = 16 << 10;

/// Write a placeholder summary (`"status": "running"`, padded with blanks to
/// [`SUMMARY_RESERVE`] bytes): found after a crash, it says the run never ended.
fn reserve_summary(path: &Path) -> std::io::Result<()> {
    let mut s = String::from("{\n  \"status\": \"running\"\n}\n");
    s.push_str(&" ".repeat(SUMMARY_RESERVE - s.len() - 1));
    s.push('\n');
    std::fs::write(path, s)
}

/// Overwrite `path` in place with `text` (into the blocks reserved by
/// [`reserve_summary`]), then cut it to that length.
fn write_reserved(path: &Path, text: &str) -> std::io::Result<()> {
    let mut f = std::fs::OpenOptions::new()
        .write(true)
        .create(true)
        .truncate(false)
        .open(path)?;
    f.write_all(text.as_bytes())?;
    f.set_len(text.len() as u64)?;
    f.sync_data().or(Ok(()))
}
