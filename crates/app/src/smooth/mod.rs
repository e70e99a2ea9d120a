//! Post-processing after the forward run (`[smoother]`, docs/ALGORITHMS.md
//! "Smoothing"): the forward pass writes what the smoother needs to scratch files
//! ([`ForwardLog`]); afterwards the RTS backward pass (mode "rts") or an independent
//! backward filter (mode "combined") gives the smoothed solution, pushed into the
//! sink with the separation report.

pub(crate) mod codec;
pub(crate) mod spill;

use crate::error::Error;
use crate::sink::{OutputLayout, SmoothedEpoch, SmoothedLayout, SolutionSink};
use crate::summary::JobResult;
use codec::{Dec, Enc};
use indicatif::{ProgressBar, ProgressStyle};
use nalgebra::DVector;
use navfuse_core::smoother::combine::{combine, difference};
use navfuse_core::smoother::rts::{Gain, GainMaker};
use navfuse_core::smoother::{self, extra_names, Nominal, RtsBackward, RtsRecord};
use navfuse_core::state::{StateLayout, ATT, N_INS};
use navfuse_core::time::split_week;
use navfuse_core::BackwardStart;
use navfuse_core::{ImuSample, Navigator, SolutionState};
use navfuse_io::input::{SmootherMode, SmootherSpec};
use navfuse_io::nav::SolutionRecord;
use navfuse_io::smoothed::SeparationRow;
use spill::Spill;
use std::path::Path;
use std::time::Instant;

/// What smoothing did (in summary.json as "smoother").
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SmootherReport {
    pub mode: &'static str,
    /// The smoothed states beyond the 21 INS ones (smoothed_states.csv columns).
    pub states: Vec<String>,
    /// Covariance epochs recorded by the forward pass (mode "rts").
    pub records: u64,
    /// Output epochs smoothed.
    pub epochs: u64,
    /// Size of the scratch files \[bytes\].
    pub scratch_bytes: u64,
    /// Wall time of the smoothing after the forward run \[s\], and of its backward
    /// pass alone.
    pub wall_s: f64,
    pub backward_s: f64,
    /// RTS steps whose prior covariance needed an eigen-decomposition.
    pub pseudo_inverses: u64,
    /// Rows of the separation report, and how many are flagged.
    pub separation_rows: u64,
    pub separation_flagged: u64,
    /// Largest |difference| / sigma in the separation report.
    pub separation_max_ratio: f64,
    /// Output epochs the backward filter did not reach (mode "combined"; they keep
    /// the forward solution).
    pub forward_only: u64,
}

impl SmootherReport {
    /// Hand one smoothed epoch, and its separation row when one is due, to the sink.
    fn emit(
        &mut self,
        sink: &mut dyn SolutionSink,
        out: &SmoothedEpoch,
        row: Option<SeparationRow>,
        bar: &Option<ProgressBar>,
    ) -> Result<(), Error> {
        if let Some(row) = row {
            self.separation_rows += 1;
            self.separation_flagged += u64::from(row.flagged);
            self.separation_max_ratio = self.separation_max_ratio.max(row.max_ratio);
            sink.separation(&row)?;
        }
        sink.smoothed(out)?;
        self.epochs += 1;
        if let Some(b) = bar {
            if self.epochs.is_multiple_of(8192) {
                b.set_position(self.epochs);
            }
        }
        Ok(())
    }

    pub fn to_json(&self) -> serde_json::Value {
        serde_json::json!({
            "mode": self.mode,
            "states": self.states,
            "records": self.records,
            "epochs": self.epochs,
            "scratch_bytes": self.scratch_bytes,
            "wall_s": self.wall_s,
            "backward_s": self.backward_s,
            "pseudo_inverses": self.pseudo_inverses,
            "separation_rows": self.separation_rows,
            "separation_flagged": self.separation_flagged,
            "separation_max_ratio": self.separation_max_ratio,
            "forward_only": self.forward_only,
        })
    }
}

fn io_err(what: &str) -> impl Fn(std::io::Error) -> Error + '_ {
    move |e| Error::io(format!("smoother scratch file ({what})"), e)
}

/// What the backward filter (mode "combined") runs on: the forward run's navigator
/// configuration (after the time-offset estimate), its measurements and sources.
pub(crate) struct BackwardInputs<'a> {
    pub nav: &'a navfuse_core::config::NavConfig,
    pub measurements: &'a [navfuse_core::Measurement],
    pub extra_sources: Option<navfuse_core::SourceFactory>,
}

/// The records' scratch file: encoded and written on a thread of its own while the
/// forward run goes on (the navigator only hands the records over), then kept.
enum RecordSpill {
    Writing {
        tx: std::sync::mpsc::SyncSender<RtsRecord>,
        writer: std::thread::JoinHandle<std::io::Result<Spill>>,
    },
    Done(Spill),
    Failed,
}

impl RecordSpill {
    fn start(mut spill: Spill) -> Self {
        let (tx, rx) = std::sync::mpsc::sync_channel::<RtsRecord>(256);
        let writer = std::thread::spawn(move || {
            let mut enc = Enc::default();
            for r in rx {
                enc.clear();
                codec::put_record(&mut enc, &r);
                spill.push(&enc.0)?;
            }
            spill.close()?;
            Ok(spill)
        });
        RecordSpill::Writing { tx, writer }
    }

    fn send(&mut self, r: RtsRecord) -> Result<(), Error> {
        if let RecordSpill::Writing { tx, .. } = self {
            if tx.send(r).is_err() {
                // The writer stopped: its error.
                return self.finish();
            }
        }
        Ok(())
    }

    /// Wait for the writer; its error, if it had one.
    fn finish(&mut self) -> Result<(), Error> {
        match std::mem::replace(self, RecordSpill::Failed) {
            RecordSpill::Writing { tx, writer } => {
                drop(tx);
                let spill = writer
                    .join()
                    .map_err(|_| Error::Other("smoothing: the record writer panicked".into()))?
                    .map_err(io_err("records"))?;
                *self = RecordSpill::Done(spill);
                Ok(())
            }
            done => {
                *self = done;
                Ok(())
            }
        }
    }

    /// The file (after `finish`).
    fn spill(&mut self) -> Result<&mut Spill, Error> {
        match self {
            RecordSpill::Done(s) => Ok(s),
            _ => Err(Error::Other(
                "smoothing: the records' scratch file is not complete".into(),
            )),
        }
    }
}

/// What the forward pass keeps for the smoother, on disk.
pub(crate) struct ForwardLog {
    spec: SmootherSpec,
    /// The records' scratch file, on its writer thread during the forward run.
    records: RecordSpill,
    epochs: Spill,
    imu: Option<Spill>,
    layout: Option<StateLayout>,
    source_idx: Vec<usize>,
    week: u32,
    enc: Enc,
}

impl ForwardLog {
    /// Scratch files in `dir`; `week`: the GPS week the run's times count from.
    pub fn create(dir: &Path, spec: &SmootherSpec, week: u32) -> Result<Self, Error> {
        let e = |err| {
            Error::io(
                format!(
                    "cannot create the smoother's scratch files in {}",
                    dir.display()
                ),
                err,
            )
        };
        Ok(ForwardLog {
            spec: spec.clone(),
            records: RecordSpill::start(Spill::create(dir, "rts").map_err(e)?),
            epochs: Spill::create(dir, "epochs").map_err(e)?,
            imu: match spec.mode {
                SmootherMode::Combined => Some(Spill::create(dir, "imu").map_err(e)?),
                SmootherMode::Rts => None,
            },
            layout: None,
            source_idx: Vec::new(),
            week,
            enc: Enc::default(),
        })
    }

    /// Keep an IMU sample for the backward filter (mode "combined").
    pub fn imu(&mut self, s: &ImuSample) -> Result<(), Error> {
        if let Some(sp) = self.imu.as_mut() {
            self.enc.clear();
            codec::put_imu(&mut self.enc, s);
            sp.push(&self.enc.0).map_err(io_err("imu"))?;
        }
        Ok(())
    }

    /// Keep a record of the forward filter.
    pub fn record(&mut self, r: RtsRecord) -> Result<(), Error> {
        if self.spec.mode == SmootherMode::Rts {
            self.records.send(r)?;
        }
        Ok(())
    }

    /// Keep an output epoch: its nominal state, the record it belongs to, its GNSS
    /// integrity flag; in mode "combined" also its variances.
    pub fn epoch(
        &mut self,
        n: &Navigator,
        integrity: Option<u8>,
        state: Option<SolutionState>,
    ) -> Result<(), Error> {
        if self.layout.is_none() {
            let l = n.layout().clone();
            self.source_idx = smoother::nominal::source_ranges(&l).flatten().collect();
            self.layout = Some(l);
        }
        let e = &mut self.enc;
        e.clear();
        e.u(n.smoother_record_index().unwrap_or(0));
        e.u(integrity.map_or(255, u64::from));
        e.u(state.map_or(255, |s| {
            SolutionState::ALL
                .iter()
                .position(|a| *a == s)
                .unwrap_or(255) as u64
        }));
        codec::put_nominal(e, &n.nominal(), &self.source_idx);
        if self.spec.mode == SmootherMode::Combined {
            let p = n.covariance();
            e.fs((0..p.nrows()).map(|i| &p[(i, i)]).collect::<Vec<_>>());
        }
        self.epochs.push(&self.enc.0).map_err(io_err("epochs"))
    }
}

struct Epoch {
    record: u64,
    integrity: Option<u8>,
    state: Option<SolutionState>,
    nominal: Nominal,
    var: Option<DVector<f64>>,
}

fn get_epoch(b: &[u8], n: usize, source_idx: &[usize], with_var: bool) -> std::io::Result<Epoch> {
    let mut d = Dec::new(b);
    let record = d.u()?;
    let flag = d.u()?;
    let state = SolutionState::ALL.get(d.u()? as usize).copied();
    let nominal = codec::get_nominal(&mut d, n, source_idx)?;
    let var = if with_var { Some(d.vec(n)?) } else { None };
    Ok(Epoch {
        record,
        integrity: (flag != 255).then_some(flag as u8),
        state,
        nominal,
        var,
    })
}

fn bar(progress: bool, len: u64, what: &str) -> Option<ProgressBar> {
    progress.then(|| {
        let b = ProgressBar::new(len.max(1));
        b.set_style(
            ProgressStyle::with_template("{spinner} [{elapsed_precise}] {wide_bar} {msg}")
                .unwrap_or_else(|_| ProgressStyle::default_bar()),
        );
        b.set_message(what.to_string());
        b
    })
}

/// The smoothed output record of one epoch.
fn output(
    week: u32,
    m: &Nominal,
    var: &DVector<f64>,
    base: &OutputLayout,
    integrity: Option<u8>,
    state: Option<SolutionState>,
    layout: &StateLayout,
) -> SmoothedEpoch {
    let (wk, t) = split_week(week, m.nav.t - m.time_offset_s);
    let mut std = [0.0; N_INS];
    for (i, s) in std.iter_mut().enumerate() {
        *s = var[i].max(0.0).sqrt();
    }
    SmoothedEpoch {
        record: SolutionRecord {
            gps_week: wk,
            nav: navfuse_core::NavState { t, ..m.nav },
            imu_errors: m.imu_errors,
            std: base.std.then_some(std),
            gnss_integrity: integrity,
            state,
        },
        states: m.extra_values(layout),
        states_std: (N_INS..layout.len())
            .map(|i| var[i].max(0.0).sqrt())
            .collect(),
    }
}

/// The separation row of difference `d` (error-state, forward minus the other)
/// with variances `var_d`.
fn separation_row(
    rec: &SolutionRecord,
    d: &DVector<f64>,
    var_d: impl Fn(usize) -> f64,
    k_sigma: f64,
) -> SeparationRow {
    let mut diff = [0.0; 9];
    let mut sigma = [0.0; 9];
    let mut max_ratio: f64 = 0.0;
    for i in 0..9 {
        diff[i] = d[i];
        sigma[i] = var_d(i).max(0.0).sqrt();
        // A difference with no spread (state not improved) cannot be judged.
        if sigma[i] > 1e-12 * (1.0 + diff[i].abs()) || (i >= ATT && sigma[i] > 0.0) {
            max_ratio = max_ratio.max(diff[i].abs() / sigma[i]);
        }
    }
    SeparationRow {
        gps_week: rec.gps_week,
        t: rec.nav.t,
        diff,
        sigma,
        max_ratio,
        flagged: max_ratio > k_sigma,
    }
}

/// Separation cadence: the first epoch at or after each multiple of the period.
struct Cadence {
    period: f64,
    last: Option<f64>,
}

impl Cadence {
    fn due(&mut self, t: f64) -> bool {
        let due = match self.last {
            None => true,
            Some(_) if self.period <= 0.0 => true,
            Some(l) => ((t + 1e-6) / self.period).floor() > ((l + 1e-6) / self.period).floor(),
        };
        if due {
            self.last = Some(t);
        }
        due
    }
}

impl ForwardLog {
    /// Smooth after a completed forward run and push the result into `sink`.
    pub fn smooth(
        mut self,
        base: &OutputLayout,
        sink: &mut dyn SolutionSink,
        progress: bool,
        job: &mut JobResult,
        inputs: &BackwardInputs,
    ) -> Result<SmootherReport, Error> {
        let t0 = Instant::now();
        self.records.finish()?;
        let Some(layout) = self.layout.clone() else {
            return Err(Error::Other(
                "smoothing: the forward run gave no output epoch".into(),
            ));
        };
        let mut rep = SmootherReport {
            mode: self.spec.mode.name(),
            ..Default::default()
        };
        let slayout = SmoothedLayout {
            base: *base,
            mode: rep.mode,
            state_names: extra_names(&layout),
        };
        rep.states = slayout.state_names.clone();
        sink.begin_smoothed(&slayout, &mut job.files)?;
        let r = match self.spec.mode {
            SmootherMode::Rts => self.rts(&layout, base, sink, progress, &mut rep),
            SmootherMode::Combined => {
                self.combined(&layout, base, sink, progress, &mut rep, inputs)
            }
        };
        let ended = sink.end_smoothed();
        r?;
        ended?;
        rep.wall_s = t0.elapsed().as_secs_f64();
        Ok(rep)
    }

    fn rts(
        &mut self,
        layout: &StateLayout,
        base: &OutputLayout,
        sink: &mut dyn SolutionSink,
        progress: bool,
        rep: &mut SmootherReport,
    ) -> Result<(), Error> {
        let n = layout.len();
        rep.records = self.records.spill()?.len();
        let dir = std::env::temp_dir();
        let mut smoothed = Spill::create(self.records_dir().as_deref().unwrap_or(&dir), "smoothed")
            .map_err(io_err("smoothed"))?;
        // Backward pass, last record first.
        let t_back = Instant::now();
        let b = bar(progress, rep.records, "smoothing: backward pass");
        // The gains depend on the forward records only: made on a second thread,
        // ahead of the recursion.
        let mut rd = self
            .records
            .spill()?
            .backward()
            .map_err(io_err("records"))?;
        let (tx, rx) = std::sync::mpsc::sync_channel::<Result<Gain, Error>>(64);
        let maker = std::thread::spawn(move || {
            let mut gm = GainMaker::new();
            loop {
                let g = match rd.next_entry() {
                    Ok(None) => break,
                    Ok(Some(bytes)) => codec::get_record(bytes)
                        .map_err(io_err("records"))
                        .and_then(|r| {
                            gm.gain(r)
                                .map_err(|e| Error::Other(format!("smoothing: {e}")))
                        }),
                    Err(e) => Err(io_err("records")(e)),
                };
                let failed = g.is_err();
                if tx.send(g).is_err() || failed {
                    break;
                }
            }
            gm.pseudo_inverses
        });
        let mut back = RtsBackward::new();
        let mut k = 0u64;
        for g in rx {
            let g = g?;
            let var_fwd = g.forward_var();
            let s = back
                .smooth(g)
                .map_err(|e| Error::Other(format!("smoothing: {e}")))?;
            self.enc.clear();
            codec::put_smoothed(&mut self.enc, &s, &var_fwd);
            smoothed.push(&self.enc.0).map_err(io_err("smoothed"))?;
            k += 1;
            if let Some(b) = &b {
                if k.is_multiple_of(1024) {
                    b.set_position(k);
                }
            }
        }
        if let Some(b) = &b {
            b.finish_and_clear();
        }
        rep.pseudo_inverses = maker
            .join()
            .map_err(|_| Error::Other("smoothing: the gain thread panicked".into()))?;
        rep.backward_s = t_back.elapsed().as_secs_f64();
        rep.scratch_bytes = self.records.spill()?.bytes() + self.epochs.bytes() + smoothed.bytes();
        // Forward again: the epochs with the smoothed records in time order.
        let b = bar(progress, self.epochs.len(), "smoothing: output");
        let mut sm = smoothed.backward().map_err(io_err("smoothed"))?;
        let mut next_sm = || -> Result<Option<_>, Error> {
            match sm.next_entry().map_err(io_err("smoothed"))? {
                Some(b) => Ok(Some(codec::get_smoothed(b).map_err(io_err("smoothed"))?)),
                None => Ok(None),
            }
        };
        let mut cur = next_sm()?;
        let mut nxt = next_sm()?;
        let mut cur_index = 0u64;
        let mut ep = self.epochs.forward().map_err(io_err("epochs"))?;
        let mut cadence = Cadence {
            period: self.spec.separation_period_s,
            last: None,
        };
        while let Some(bytes) = ep.next_entry().map_err(io_err("epochs"))? {
            let e = get_epoch(bytes, n, &self.source_idx, false).map_err(io_err("epochs"))?;
            while cur_index < e.record {
                cur = nxt.take();
                nxt = next_sm()?;
                cur_index += 1;
            }
            let Some((at, var_fwd)) = cur.as_ref() else {
                return Err(Error::Other(format!(
                    "smoothing: no record {} for the output epoch at t = {:.3}",
                    e.record, e.nominal.nav.t
                )));
            };
            let s = smoother::error_at(e.nominal.nav.t, at, nxt.as_ref().map(|x| &x.0));
            let m = e.nominal.corrected(layout, &s);
            let out = output(self.week, &m, &at.var, base, e.integrity, e.state, layout);
            let row = cadence.due(m.nav.t).then(|| {
                let k = self.spec.separation_sigma;
                separation_row(&out.record, &s, |i| var_fwd[i] - at.var[i], k)
            });
            rep.emit(sink, &out, row, &b)?;
        }
        if let Some(b) = &b {
            b.finish_and_clear();
        }
        Ok(())
    }

    /// Mode "combined": the backward filter over the kept IMU samples, then each
    /// output epoch combined with it state by state.
    fn combined(
        &mut self,
        layout: &StateLayout,
        base: &OutputLayout,
        sink: &mut dyn SolutionSink,
        progress: bool,
        rep: &mut SmootherReport,
        inputs: &BackwardInputs,
    ) -> Result<(), Error> {
        let n = layout.len();
        let src = self.source_idx.clone();
        // The forward run's first and last output epochs bound the backward run.
        let first = {
            let mut f = self.epochs.forward().map_err(io_err("epochs"))?;
            let b = f.next_entry().map_err(io_err("epochs"))?.ok_or_else(|| {
                Error::Other("smoothing: the forward run gave no output epoch".into())
            })?;
            get_epoch(b, n, &src, true).map_err(io_err("epochs"))?
        };
        let last = {
            let mut b = self.epochs.backward().map_err(io_err("epochs"))?;
            let e = b
                .next_entry()
                .map_err(io_err("epochs"))?
                .unwrap_or_default();
            get_epoch(e, n, &src, true).map_err(io_err("epochs"))?
        };
        let mut cfg = inputs.nav.clone();
        cfg.start_time = first.nominal.nav.t;
        let start = BackwardStart {
            t: last.nominal.nav.t,
            lla: last.nominal.nav.lla,
            v_n: last.nominal.nav.v_n,
            rpy: navfuse_core::attitude::euler_from_q_bn(&last.nominal.nav.q_bn),
        };
        let dir = self.epochs.dir().unwrap_or_else(std::env::temp_dir);
        let mut bwd = Spill::create(&dir, "backward").map_err(io_err("backward"))?;
        let imu_spill = self
            .imu
            .as_mut()
            .ok_or_else(|| Error::Other("smoothing: no IMU samples kept".into()))?;
        let mut imu = imu_spill.backward().map_err(io_err("imu"))?;
        let imu_iter = std::iter::from_fn(|| match imu.next_entry() {
            Ok(Some(b)) => Some(codec::get_imu(b).map_err(io_err("imu"))),
            Ok(None) => None,
            Err(e) => Some(Err(io_err("imu")(e))),
        });
        let span = (start.t - cfg.start_time).max(0.0);
        let b = bar(progress, (span * 10.0) as u64, "smoothing: backward filter");
        let t_back = Instant::now();
        let mut enc = Enc::default();
        let mut bad_layout = false;
        let summary = navfuse_core::run_backward(
            &cfg,
            |c: &navfuse_core::config::NavConfig, t0| {
                inputs.extra_sources.map_or_else(Vec::new, |f| f(c, t0))
            },
            start,
            imu_iter,
            inputs.measurements,
            None,
            |nv: &Navigator| {
                if nv.layout().len() != n {
                    bad_layout = true;
                }
                enc.clear();
                codec::put_nominal(&mut enc, &nv.nominal(), &src);
                let p = nv.covariance();
                enc.fs((0..p.nrows()).map(|i| &p[(i, i)]).collect::<Vec<_>>());
                bwd.push(&enc.0).map_err(io_err("backward"))
            },
            |t| {
                if let Some(b) = &b {
                    b.set_position(((start.t - t) * 10.0).max(0.0) as u64);
                }
            },
        )?;
        if let Some(b) = &b {
            b.finish_and_clear();
        }
        if bad_layout {
            return Err(Error::Other(
                "smoothing: the backward filter's states differ from the forward one's".into(),
            ));
        }
        rep.backward_s = t_back.elapsed().as_secs_f64();
        rep.records = summary.imu_samples as u64;
        rep.scratch_bytes = self.epochs.bytes() + imu_spill.bytes() + bwd.bytes();
        // Forward epochs with the backward ones in time order, matched by IMU time.
        let mut bk = bwd.backward().map_err(io_err("backward"))?;
        let mut next_b = || -> Result<Option<(Nominal, DVector<f64>)>, Error> {
            match bk.next_entry().map_err(io_err("backward"))? {
                Some(bytes) => {
                    let mut d = Dec::new(bytes);
                    let m = codec::get_nominal(&mut d, n, &src).map_err(io_err("backward"))?;
                    Ok(Some((m, d.vec(n).map_err(io_err("backward"))?)))
                }
                None => Ok(None),
            }
        };
        let mut cur_b = next_b()?;
        let b = bar(progress, self.epochs.len(), "smoothing: combining");
        let mut ep = self.epochs.forward().map_err(io_err("epochs"))?;
        let mut cadence = Cadence {
            period: self.spec.separation_period_s,
            last: None,
        };
        while let Some(bytes) = ep.next_entry().map_err(io_err("epochs"))? {
            let e = get_epoch(bytes, n, &src, true).map_err(io_err("epochs"))?;
            let t = e.nominal.nav.t;
            while cur_b.as_ref().is_some_and(|(m, _)| m.nav.t < t - 1e-6) {
                cur_b = next_b()?;
            }
            let var_f = e.var.unwrap_or_else(|| DVector::zeros(n));
            let (m, var, sep) = match &cur_b {
                Some((mb, var_b)) if (mb.nav.t - t).abs() <= 1e-6 => {
                    let (m, var) = combine(layout, &e.nominal, &var_f, mb, var_b);
                    let d = difference(layout, &e.nominal, mb);
                    let v: Vec<f64> = (0..9).map(|i| var_f[i] + var_b[i]).collect();
                    (m, var, Some((d, v)))
                }
                _ => {
                    rep.forward_only += 1;
                    (e.nominal.clone(), var_f, None)
                }
            };
            let out = output(self.week, &m, &var, base, e.integrity, e.state, layout);
            let row = match sep {
                Some((d, v)) if cadence.due(t) => Some(separation_row(
                    &out.record,
                    &d,
                    |i| v[i],
                    self.spec.separation_sigma,
                )),
                _ => None,
            };
            rep.emit(sink, &out, row, &b)?;
        }
        if let Some(b) = &b {
            b.finish_and_clear();
        }
        Ok(())
    }

    fn records_dir(&self) -> Option<std::path::PathBuf> {
        self.epochs.dir()
    }
}
