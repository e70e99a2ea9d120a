//! What the report draws, section by section, from a [`RunData`] and an optional
//! truth. Time axes are seconds since the first solution epoch.

use crate::chart::{palette, Band, Chart, Colour, Series, Style};
use crate::decimate::{by_distance, min_max};
use crate::run_dir::{sigma_at, Epoch, RunData, Sigma, StateTable};
use crate::{Error, Figure, Report, Table, Truth, SCORED_EPOCHS};
use nalgebra::Vector3;
use navfuse_core::earth::lla_diff_ned;
use navfuse_core::eval::{evaluate, EpochError, EvalOptions, EvalReport, TrajPoint};
use navfuse_core::outage::Window;
use navfuse_core::SolutionState;
use plotters::style::RGBColor;

/// Buckets of the min/max decimation per time-series chart (at most 4x points).
const BUCKETS: usize = 700;
/// Coasting intervals shorter than this are not listed as outages \[s\].
const MIN_OUTAGE_S: f64 = 2.0;

const RED: Colour = RGBColor(200, 30, 30);
const GREY: Colour = RGBColor(160, 160, 160);

fn state_colour(s: Option<SolutionState>) -> Colour {
    match s {
        Some(SolutionState::Gnss) => RGBColor(0, 114, 178),
        Some(SolutionState::Static) => RGBColor(0, 158, 115),
        Some(SolutionState::DeadReckoning) => RGBColor(230, 159, 0),
        Some(SolutionState::Inertial) => RGBColor(213, 94, 0),
        Some(SolutionState::GnssExcluded) => RGBColor(204, 121, 167),
        None => RGBColor(90, 90, 90),
    }
}

fn state_name(s: Option<SolutionState>) -> &'static str {
    s.map_or("solution", SolutionState::name)
}

struct Ctx<'a> {
    run: &'a RunData,
    t0: f64,
    figures: Vec<Figure>,
    tables: Vec<Table>,
    notes: Vec<String>,
}

impl Ctx<'_> {
    fn x_label(&self) -> String {
        format!("time since {:.1} s of the GPS week [s]", self.t0)
    }

    fn chart(&self, title: &str, y: &str) -> Chart {
        Chart::new(title, self.x_label(), y)
    }

    fn push(
        &mut self,
        name: &str,
        section: &'static str,
        caption: String,
        chart: &Chart,
    ) -> Result<(), Error> {
        if chart.is_empty() {
            return Ok(());
        }
        self.figures.push(Figure {
            name: name.to_string(),
            section,
            caption,
            svg: chart.svg().map_err(Error::new)?,
        });
        Ok(())
    }

    fn plotted(&self) -> impl Iterator<Item = &Epoch> {
        self.run.solution.iter().filter(|e| e.plotted)
    }

    /// A decimated time series of the plotted epochs.
    fn series(&self, f: impl Fn(&Epoch) -> f64) -> Vec<(f64, f64)> {
        let pts: Vec<(f64, f64)> = self.plotted().map(|e| (e.t - self.t0, f(e))).collect();
        min_max(&pts, BUCKETS)
    }
}

/// Draw everything.
pub fn draw(run: &RunData, truth: Option<&Truth>) -> Result<Report, Error> {
    let (t0, t1) = run.span().ok_or_else(|| Error::new("no solution epochs"))?;
    let mut c = Ctx {
        run,
        t0,
        figures: Vec::new(),
        tables: Vec::new(),
        notes: Vec::new(),
    };
    if run.stride > 1 {
        c.notes.push(format!(
            "{} solution epochs; plotted: one in {} (then at most {} points per line by min/max decimation, which keeps every peak)",
            run.solution_rows, run.stride, 4 * BUCKETS
        ));
    }
    if run.state_derived {
        c.notes.push(
            "solution state derived from innovations.csv (the run wrote no solution.csv with its `state` column; [output] csv = true writes it)".into(),
        );
    }
    summary_table(&mut c, t1);
    ground_track(&mut c, truth)?;
    trajectory(&mut c)?;
    let outages = coasting_intervals(&run.solution);
    match truth {
        Some(t) => errors(&mut c, t, &outages)?,
        None => c
            .notes
            .push("no truth given (--truth FILE): no error plots".to_string()),
    }
    innovations(&mut c)?;
    imu_errors(&mut c)?;
    extra_states(&mut c, run.states.as_ref(), "states", "States")?;
    integrity(&mut c, &outages)?;
    smoother(&mut c, truth)?;
    tuning(&mut c)?;
    let title = format!("navfuse report: {}", run.dir.display());
    Ok(Report {
        title,
        figures: c.figures,
        tables: c.tables,
        notes: c.notes,
        config: run.config.clone(),
        events: run.events.clone(),
        summary: run.summary.clone(),
    })
}

fn summary_table(c: &mut Ctx, t1: f64) {
    let mut rows = vec![
        vec!["solution epochs".into(), c.run.solution_rows.to_string()],
        vec![
            "time span".into(),
            format!("{:.3} to {:.3} s of week ({:.1} s)", c.t0, t1, t1 - c.t0),
        ],
    ];
    if let Some(s) = &c.run.summary {
        for (label, key) in [
            ("status", "status"),
            ("IMU samples", "imu_samples"),
            ("wall time [s]", "wall_s"),
        ] {
            if let Some(v) = s.get(key).filter(|v| !v.is_null()) {
                rows.push(vec![label.into(), plain(v)]);
            }
        }
        if let Some(g) = s.get("gnss").and_then(|g| g.as_object()) {
            let text: Vec<String> = g.iter().map(|(k, v)| format!("{k} {}", plain(v))).collect();
            rows.push(vec!["GNSS fixes".into(), text.join(", ")]);
        }
        for (label, key) in [
            ("updates applied", "aiding_used"),
            ("updates rejected", "aiding_rejected"),
            ("mean NIS per row", "nis_per_row"),
        ] {
            if let Some(m) = s
                .get(key)
                .and_then(|v| v.as_object())
                .filter(|m| !m.is_empty())
            {
                let text: Vec<String> =
                    m.iter().map(|(k, v)| format!("{k} {}", plain(v))).collect();
                rows.push(vec![label.into(), text.join(", ")]);
            }
        }
        for key in [
            "time_offset",
            "odometer_scale",
            "mounting",
            "source_states",
            "smoother",
        ] {
            if let Some(v) = s.get(key).filter(|v| !v.is_null()) {
                rows.push(vec![key.replace('_', " "), compact(v)]);
            }
        }
        for key in ["warnings", "errors"] {
            if let Some(a) = s.get(key).and_then(|v| v.as_array()) {
                for w in a {
                    rows.push(vec![key.trim_end_matches('s').into(), plain(w)]);
                }
            }
        }
        if let Some(e) = s.get("error").filter(|v| !v.is_null()) {
            rows.push(vec!["error".into(), plain(e)]);
        }
    } else {
        c.notes.push("no summary.json in the run directory".into());
    }
    c.tables.push(Table {
        section: "Summary",
        caption: "The run (summary.json)".into(),
        header: vec!["".into(), "".into()],
        rows,
    });
}

fn plain(v: &serde_json::Value) -> String {
    match v {
        serde_json::Value::String(s) => s.clone(),
        serde_json::Value::Number(n) => match n.as_f64() {
            Some(x) if n.is_f64() => format!("{x:.4}"),
            _ => n.to_string(),
        },
        v => v.to_string(),
    }
}

fn compact(v: &serde_json::Value) -> String {
    match v.as_object() {
        Some(m) => m
            .iter()
            .map(|(k, v)| match v {
                serde_json::Value::Object(_) | serde_json::Value::Array(_) => format!("{k} {v}"),
                v => format!("{k} {}", plain(v)),
            })
            .collect::<Vec<_>>()
            .join(", "),
        None => plain(v),
    }
}

/// North/east of `lla` from `origin` \[m\].
fn en(lla: &Vector3<f64>, origin: &Vector3<f64>) -> (f64, f64) {
    let d = lla_diff_ned(lla, origin);
    (d.y, d.x)
}

fn ground_track(c: &mut Ctx, truth: Option<&Truth>) -> Result<(), Error> {
    let origin = c.run.solution[0].lla;
    let pts: Vec<(Option<SolutionState>, (f64, f64))> = c
        .plotted()
        .map(|e| (e.state, en(&e.lla, &origin)))
        .collect();
    let (mut lo, mut hi) = (
        (f64::INFINITY, f64::INFINITY),
        (f64::NEG_INFINITY, f64::NEG_INFINITY),
    );
    for (_, p) in &pts {
        lo = (lo.0.min(p.0), lo.1.min(p.1));
        hi = (hi.0.max(p.0), hi.1.max(p.1));
    }
    let step = ((hi.0 - lo.0).max(hi.1 - lo.1) / 3000.0).max(1e-3);
    let mut chart = Chart::new(
        "Ground track, coloured by solution state",
        "east of the first epoch [m]",
        "north [m]",
    );
    chart.size = (900, 640);
    chart.equal_aspect = true;
    if let Some(t) = truth {
        let tp: Vec<(f64, f64)> = t.points.iter().map(|p| en(&p.lla, &origin)).collect();
        chart
            .series
            .push(Series::line("truth", GREY, by_distance(&tp, step)));
    }
    // One series per state, one piece per run of that state (joined to the next).
    let mut order: Vec<Option<SolutionState>> = Vec::new();
    type Piece = (Option<SolutionState>, Vec<(f64, f64)>);
    let mut pieces: Vec<Piece> = Vec::new();
    for (s, p) in &pts {
        match pieces.last_mut() {
            Some((ls, v)) if ls == s => v.push(*p),
            _ => {
                if let Some((_, v)) = pieces.last_mut() {
                    v.push(*p);
                }
                pieces.push((*s, vec![*p]));
                if !order.contains(s) {
                    order.push(*s);
                }
            }
        }
    }
    for s in order {
        let mut series = Series::line(state_name(s), state_colour(s), Vec::new());
        series.pieces = pieces
            .iter()
            .filter(|(ps, _)| *ps == s)
            .map(|(_, v)| by_distance(v, step))
            .collect();
        chart.series.push(series);
    }
    let first = pts.first().map(|p| p.1).unwrap_or_default();
    let last = pts.last().map(|p| p.1).unwrap_or_default();
    let mut ends = Series::points("start / end", RGBColor(0, 0, 0), vec![first, last]);
    ends.style = Style::Points(4);
    chart.series.push(ends);
    let caption = "East and north of the first solution epoch (local tangent plane), coloured by the solution state of solution.csv (gnss: GNSS fused lately; static: zero-velocity updates; dead_reckoning: odometer/NHC only; inertial: INS alone; gnss_excluded: the integrity monitor holds GNSS out).".to_string();
    c.push("ground_track", "Trajectory", caption, &chart)
}

fn trajectory(c: &mut Ctx) -> Result<(), Error> {
    let origin = c.run.solution[0].lla;
    let pos = c
        .chart("Position from the first epoch", "m")
        .with(Series::line(
            "north",
            palette(0),
            c.series(|e| en(&e.lla, &origin).1),
        ))
        .with(Series::line(
            "east",
            palette(1),
            c.series(|e| en(&e.lla, &origin).0),
        ))
        .with(Series::line(
            "up",
            palette(2),
            c.series(|e| e.lla.z - origin.z),
        ));
    c.push(
        "position",
        "Trajectory",
        "North, east and up of the first epoch [m]".into(),
        &pos,
    )?;
    let vel = c
        .chart("Velocity", "m/s")
        .with(Series::line("north", palette(0), c.series(|e| e.v_n.x)))
        .with(Series::line("east", palette(1), c.series(|e| e.v_n.y)))
        .with(Series::line("down", palette(2), c.series(|e| e.v_n.z)));
    c.push("velocity", "Trajectory", "NED velocity [m/s]".into(), &vel)?;
    let att = c
        .chart("Roll and pitch", "deg")
        .with(Series::line(
            "roll",
            palette(0),
            c.series(|e| e.rpy.x.to_degrees()),
        ))
        .with(Series::line(
            "pitch",
            palette(1),
            c.series(|e| e.rpy.y.to_degrees()),
        ));
    c.push(
        "attitude",
        "Trajectory",
        "Roll and pitch [deg]".into(),
        &att,
    )?;
    let yaw = c.chart("Yaw", "deg").with(Series::line(
        "yaw",
        palette(2),
        c.series(|e| e.rpy.z.to_degrees().rem_euclid(360.0)),
    ));
    c.push(
        "yaw",
        "Trajectory",
        "Yaw (heading of the body x axis) [deg, 0..360]".into(),
        &yaw,
    )
}

/// Runs of epochs whose state is neither `gnss` nor `static`, at least
/// [`MIN_OUTAGE_S`] long: (start, end, state of most epochs).
fn coasting_intervals(epochs: &[Epoch]) -> Vec<(f64, f64, Option<SolutionState>)> {
    let mut out = Vec::new();
    let mut start: Option<(f64, Option<SolutionState>)> = None;
    let coasting = |s: Option<SolutionState>| {
        matches!(
            s,
            Some(
                SolutionState::DeadReckoning
                    | SolutionState::Inertial
                    | SolutionState::GnssExcluded
            )
        )
    };
    for e in epochs {
        match (start, coasting(e.state)) {
            (None, true) => start = Some((e.t, e.state)),
            (Some((t, s)), false) => {
                if e.t - t >= MIN_OUTAGE_S {
                    out.push((t, e.t, s));
                }
                start = None;
            }
            _ => {}
        }
    }
    if let (Some((t, s)), Some(last)) = (start, epochs.last()) {
        if last.t - t >= MIN_OUTAGE_S {
            out.push((t, last.t, s));
        }
    }
    out
}

fn traj_points(epochs: &[Epoch]) -> Vec<TrajPoint> {
    epochs
        .iter()
        .map(|e| TrajPoint {
            t: e.t,
            lla: e.lla,
            v_n: Some(e.v_n),
            rpy: Some(e.rpy),
        })
        .collect()
}

fn score(epochs: &[Epoch], truth: &Truth, gaps: Vec<Window>) -> EvalReport {
    let k = truth.points.len().div_ceil(SCORED_EPOCHS).max(1);
    let reference: Vec<TrajPoint> = truth.points.iter().step_by(k).copied().collect();
    evaluate(
        &traj_points(epochs),
        &reference,
        &EvalOptions {
            gaps,
            lever_arm_b: truth.lever_arm_b,
            keep_epochs: true,
            ..Default::default()
        },
    )
}

fn errors(
    c: &mut Ctx,
    truth: &Truth,
    outages: &[(f64, f64, Option<SolutionState>)],
) -> Result<(), Error> {
    let gaps = outages
        .iter()
        .map(|o| Window {
            start: o.0,
            end: o.1,
        })
        .collect();
    let rep = score(&c.run.solution, truth, gaps);
    if rep.epochs == 0 {
        c.notes.push(format!(
            "the truth {} has no epoch within the solution's time span: no errors",
            truth.path.display()
        ));
        return Ok(());
    }
    let k = truth.points.len().div_ceil(SCORED_EPOCHS).max(1);
    c.notes.push(format!(
        "errors: {} reference epochs of {} scored{} against the full-rate solution (interpolated between its neighbouring epochs)",
        rep.epochs,
        truth.path.display(),
        if k > 1 { format!(" (one in {k})") } else { String::new() }
    ));
    stats_table(c, &rep, "Errors against the truth", "Errors");
    let t0 = c.t0;
    let e = &rep.per_epoch;
    // Position errors with +-3 sigma of the solution's std.
    let axes = ["north", "east", "down"];
    for (k, axis) in axes.iter().enumerate() {
        let err: Vec<(f64, f64)> = e.iter().map(|x| (x.t - t0, x.pos_ned[k])).collect();
        let mut chart = c
            .chart(&format!("Position error, {axis}"), "m")
            .with(Series::line(
                format!("{axis} error"),
                palette(k),
                min_max(&err, BUCKETS),
            ));
        let banded = band(&mut chart, e, &c.run.sigma, t0, |s| s[k], 1.0);
        c.push(
            &format!("error_{axis}"),
            "Errors",
            format!(
                "Solution minus truth, {axis} [m]{}",
                sigma_note(banded, c.run.sigma_file)
            ),
            &chart,
        )?;
    }
    let has_vel = e.iter().any(|x| x.vel_ned.is_some());
    if has_vel {
        let mut chart = c.chart("Velocity error", "m/s");
        for (k, axis) in axes.iter().enumerate() {
            let v: Vec<(f64, f64)> = e
                .iter()
                .filter_map(|x| x.vel_ned.map(|v| (x.t - t0, v[k])))
                .collect();
            chart
                .series
                .push(Series::line(*axis, palette(k), min_max(&v, BUCKETS)));
        }
        c.push(
            "error_velocity",
            "Errors",
            "Velocity error N, E, D [m/s]".into(),
            &chart,
        )?;
    }
    if e.iter().any(|x| x.att.is_some()) {
        for (k, axis) in ["roll", "pitch", "yaw"].iter().enumerate() {
            let a: Vec<(f64, f64)> = e
                .iter()
                .filter_map(|x| x.att.map(|a| (x.t - t0, a[k].to_degrees())))
                .collect();
            let mut chart = c
                .chart(&format!("Attitude error, {axis}"), "deg")
                .with(Series::line(
                    format!("{axis} error"),
                    palette(k),
                    min_max(&a, BUCKETS),
                ));
            let banded = band(
                &mut chart,
                e,
                &c.run.sigma,
                t0,
                |s| s[6 + k],
                180.0 / std::f64::consts::PI,
            );
            c.push(
                &format!("error_{axis}"),
                "Errors",
                format!(
                    "Attitude error about the body {axis} axis (the rotation between solution and truth) [deg]{}",
                    sigma_note(banded, c.run.sigma_file)
                ),
                &chart,
            )?;
        }
    }
    cdf(c, e, &rep)?;
    outage_drift(c, e, outages, &rep)?;
    Ok(())
}

fn sigma_note(banded: bool, file: Option<&str>) -> String {
    match (banded, file) {
        (true, Some(f)) => format!(", with the filter's +-3 sigma ({f})"),
        _ => " (no std.txt or std columns in solution.csv: no sigma band)".into(),
    }
}

/// +-3 sigma of the filter at each error epoch (nearest sigma row); false when the
/// run has no sigma.
fn band(
    chart: &mut Chart,
    e: &[EpochError],
    sigma: &[Sigma],
    t0: f64,
    pick: impl Fn(&[f64; 9]) -> f64,
    scale: f64,
) -> bool {
    if sigma.is_empty() {
        return false;
    }
    let pts: Vec<(f64, f64)> = e
        .iter()
        .map(|x| (x.t - t0, 3.0 * pick(&sigma_at(sigma, x.t).nav) * scale))
        .collect();
    let upper = min_max(&pts, BUCKETS);
    chart.bands.push(Band {
        name: "+-3 sigma".into(),
        colour: GREY,
        points: upper.iter().map(|&(t, s)| (t, -s, s)).collect(),
    });
    true
}

fn stats_table(c: &mut Ctx, rep: &EvalReport, caption: &str, section: &'static str) {
    let row = |name: &str, s: &navfuse_core::eval::Stat, unit: &str, scale: f64| {
        vec![
            format!("{name} [{unit}]"),
            format!("{:.3}", s.rms * scale),
            format!("{:.3}", s.mean * scale),
            format!("{:.3}", s.max * scale),
        ]
    };
    let mut rows = vec![
        row("north", &rep.north, "m", 1.0),
        row("east", &rep.east, "m", 1.0),
        row("down", &rep.down, "m", 1.0),
        row("horizontal", &rep.horizontal, "m", 1.0),
        row("3D", &rep.pos_3d, "m", 1.0),
    ];
    if let Some(v) = &rep.vel {
        rows.push(row("velocity 3D", &v[3], "m/s", 1.0));
    }
    if let (Some(a), Some(t)) = (&rep.att, &rep.att_total) {
        let d = 180.0 / std::f64::consts::PI;
        rows.push(row("roll", &a[0], "deg", d));
        rows.push(row("pitch", &a[1], "deg", d));
        rows.push(row("yaw", &a[2], "deg", d));
        rows.push(row("attitude total", t, "deg", d));
    }
    c.tables.push(Table {
        section,
        caption: format!("{caption}: {} epochs", rep.epochs),
        header: ["error", "RMS", "mean", "max"].map(String::from).to_vec(),
        rows,
    });
    let p = |v: &[f64; 4]| v.iter().map(|x| format!("{x:.3}")).collect::<Vec<_>>();
    let mut h = vec!["horizontal [m]".to_string()];
    h.extend(p(&rep.horizontal_pct));
    let mut d3 = vec!["3D [m]".to_string()];
    d3.extend(p(&rep.pos_3d_pct));
    c.tables.push(Table {
        section: "Errors",
        caption: "Percentiles (nearest rank; CEP = P50 and R95 = P95 of the horizontal error)"
            .into(),
        header: ["error", "P50", "P68", "P95", "P99"]
            .map(String::from)
            .to_vec(),
        rows: vec![h, d3],
    });
}

fn cdf(c: &mut Ctx, e: &[EpochError], rep: &EvalReport) -> Result<(), Error> {
    let mut h: Vec<f64> = e.iter().map(|x| x.horizontal).collect();
    h.sort_by(f64::total_cmp);
    let n = h.len() as f64;
    let pts: Vec<(f64, f64)> = h
        .iter()
        .enumerate()
        .map(|(i, v)| (*v, (i + 1) as f64 / n))
        .collect();
    // The CDF is monotone: thinning by index keeps its shape.
    let step = pts.len().div_ceil(3000).max(1);
    let mut thin: Vec<(f64, f64)> = pts.iter().step_by(step).copied().collect();
    if let Some(l) = pts.last() {
        thin.push(*l);
    }
    let mut chart = Chart::new(
        "Horizontal error CDF",
        "horizontal error [m]",
        "fraction of epochs",
    );
    chart.series.push(Series::line("CDF", palette(0), thin));
    for (k, (p, label)) in [(0.5, "P50"), (0.68, "P68"), (0.95, "P95")]
        .iter()
        .enumerate()
    {
        chart.series.push(Series {
            name: format!("{label} = {:.3} m", rep.horizontal_pct[k]),
            colour: palette(k + 1),
            style: Style::Points(4),
            pieces: vec![vec![(rep.horizontal_pct[k], *p)]],
        });
    }
    c.push(
        "error_cdf",
        "Errors",
        "Cumulative distribution of the horizontal error, with P50 (CEP), P68 and P95 (R95)".into(),
        &chart,
    )
}

fn outage_drift(
    c: &mut Ctx,
    e: &[EpochError],
    outages: &[(f64, f64, Option<SolutionState>)],
    rep: &EvalReport,
) -> Result<(), Error> {
    if outages.is_empty() {
        return Ok(());
    }
    let rows = rep
        .gaps
        .iter()
        .map(|g| {
            let state = outages
                .iter()
                .find(|o| (o.0 - g.start).abs() < 1e-9)
                .and_then(|o| o.2);
            vec![
                format!("{:.1}", g.start - c.t0),
                format!("{:.1}", g.end - g.start),
                state_name(state).to_string(),
                format!("{:.3}", g.max_horizontal),
                format!("{:.3}", g.max_vertical),
                format!("{:.3}", g.max_yaw.to_degrees()),
            ]
        })
        .collect();
    c.tables.push(Table {
        section: "Errors",
        caption: format!(
            "Coasting intervals (the solution state not gnss or static for {MIN_OUTAGE_S} s or more) and their largest errors"
        ),
        header: ["start [s]", "length [s]", "state", "max horizontal [m]", "max vertical [m]", "max yaw [deg]"]
            .map(String::from)
            .to_vec(),
        rows,
    });
    // The drift of the longest eight against the time since each began.
    let mut longest: Vec<_> = outages.to_vec();
    longest.sort_by(|a, b| (b.1 - b.0).total_cmp(&(a.1 - a.0)));
    longest.truncate(8);
    longest.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut chart = Chart::new(
        "Horizontal drift in coasting intervals",
        "time since the interval began [s]",
        "horizontal error [m]",
    );
    for (k, o) in longest.iter().enumerate() {
        let pts: Vec<(f64, f64)> = e
            .iter()
            .filter(|x| x.t >= o.0 && x.t < o.1)
            .map(|x| (x.t - o.0, x.horizontal))
            .collect();
        chart.series.push(Series::line(
            format!("from {:.0} s", o.0 - c.t0),
            palette(k),
            min_max(&pts, BUCKETS),
        ));
    }
    c.push(
        "outage_drift",
        "Errors",
        "Horizontal error against the time since each coasting interval began (the eight longest)"
            .into(),
        &chart,
    )
}

fn innovations(c: &mut Ctx) -> Result<(), Error> {
    if c.run.innovations.is_empty() {
        c.notes
            .push("no innovations.csv: no innovation plots".into());
        return Ok(());
    }
    let mut rows = Vec::new();
    let names: Vec<String> = c.run.innovations.keys().cloned().collect();
    for name in names {
        let s = &c.run.innovations[&name];
        let applied = s.tried - s.rejected - s.singular;
        rows.push(vec![
            name.clone(),
            s.rows.to_string(),
            s.tried.to_string(),
            s.rejected.to_string(),
            s.singular.to_string(),
            if applied > 0 {
                format!("{:.3}", s.nis_per_row_sum / applied as f64)
            } else {
                String::new()
            },
            s.gate.map_or("none".into(), |g| format!("{g:.2}")),
        ]);
        let mut chart = c.chart(&format!("Normalised innovations: {name}"), "NIS");
        chart.log_y = true;
        let t0 = c.t0;
        chart.series.push(Series::points(
            "applied (largest per interval)",
            palette(0),
            s.applied.iter().map(|p| (p.0 - t0, p.1)).collect(),
        ));
        if !s.rejected_points.is_empty() {
            chart.series.push(Series::points(
                "rejected",
                RED,
                s.rejected_points.iter().map(|p| (p.0 - t0, p.1)).collect(),
            ));
        }
        if let Some(g) = s.gate {
            chart
                .hlines
                .push((g, format!("gate {g:.2}"), RGBColor(0, 0, 0)));
        }
        chart.size = (900, 240);
        c.push(
            &format!("nis_{}", file_name(&name)),
            "Innovations",
            format!(
                "Normalised innovation squared of every {name} update ({} rows each; a consistent filter averages {} per update), the gate, and the rejected updates in red",
                s.rows, s.rows
            ),
            &chart,
        )?;
    }
    c.tables.push(Table {
        section: "Innovations",
        caption: "Updates per measurement (innovations.csv)".into(),
        header: [
            "measurement",
            "rows",
            "tried",
            "rejected",
            "singular",
            "mean NIS per row",
            "gate",
        ]
        .map(String::from)
        .to_vec(),
        rows,
    });
    Ok(())
}

fn file_name(s: &str) -> String {
    s.chars()
        .map(|ch| if ch.is_ascii_alphanumeric() { ch } else { '_' })
        .collect()
}

fn imu_errors(c: &mut Ctx) -> Result<(), Error> {
    if c.run.imu_err.is_empty() {
        return Ok(());
    }
    let t0 = c.t0;
    for (k, (name, unit)) in [
        ("Gyroscope bias", "deg/h"),
        ("Accelerometer bias", "mGal"),
        ("Gyroscope scale factor", "ppm"),
        ("Accelerometer scale factor", "ppm"),
    ]
    .iter()
    .enumerate()
    {
        let mut chart = c.chart(name, unit);
        let sigma = &c.run.sigma;
        let with_std = sigma.iter().any(|s| s.imu.is_some());
        for (j, axis) in ["x", "y", "z"].iter().enumerate() {
            let i = 3 * k + j;
            let pts: Vec<(f64, f64)> = c.run.imu_err.iter().map(|(t, v)| (t - t0, v[i])).collect();
            chart
                .series
                .push(Series::line(*axis, palette(j), min_max(&pts, BUCKETS)));
            if with_std {
                let step = c.run.imu_err.len().div_ceil(2 * BUCKETS).max(1);
                let points = c
                    .run
                    .imu_err
                    .iter()
                    .step_by(step)
                    .filter_map(|(t, v)| {
                        let s = sigma_at(sigma, *t).imu?[i];
                        Some((t - t0, v[i] - s, v[i] + s))
                    })
                    .collect();
                chart.bands.push(Band {
                    name: format!("{axis} +-1 sigma"),
                    colour: palette(j),
                    points,
                });
            }
        }
        c.push(
            &file_name(&name.to_lowercase()),
            "IMU errors",
            format!(
                "{name} estimate (imu_err.txt) [{unit}]{}",
                match (with_std, c.run.sigma_file) {
                    (true, Some(f)) => format!(", with +-1 sigma ({f})"),
                    _ => String::new(),
                }
            ),
            &chart,
        )?;
    }
    Ok(())
}

/// Unit conversion for the plot: radians to degrees.
fn state_unit(name: &str) -> (String, String, f64) {
    if let Some(base) = name.strip_suffix("_rad") {
        (
            format!("{base}_deg"),
            "deg".into(),
            180.0 / std::f64::consts::PI,
        )
    } else {
        let unit = name
            .rsplit('_')
            .next()
            .filter(|_| name.contains('_'))
            .unwrap_or("");
        let unit = match unit {
            "m" | "s" | "mps" => unit.to_string(),
            _ => "".to_string(),
        };
        (name.to_string(), unit, 1.0)
    }
}

fn extra_states(
    c: &mut Ctx,
    table: Option<&StateTable>,
    file: &str,
    section: &'static str,
) -> Result<(), Error> {
    let Some(table) = table else {
        return Ok(());
    };
    let t0 = c.t0;
    for (k, name) in table.names.iter().enumerate() {
        let (label, unit, scale) = state_unit(name);
        let v: Vec<(f64, f64)> = table
            .rows
            .iter()
            .map(|r| (r.0 - t0, r.1[k] * scale))
            .collect();
        let mut chart = c.chart(&label, &unit).with(Series::line(
            label.clone(),
            palette(0),
            min_max(&v, BUCKETS),
        ));
        let b: Vec<(f64, f64, f64)> = table
            .rows
            .iter()
            .map(|r| {
                (
                    r.0 - t0,
                    (r.1[k] - r.2[k]) * scale,
                    (r.1[k] + r.2[k]) * scale,
                )
            })
            .collect();
        let step = b.len().div_ceil(2 * BUCKETS).max(1);
        chart.bands.push(Band {
            name: "+-1 sigma".into(),
            colour: palette(0),
            points: b.into_iter().step_by(step).collect(),
        });
        chart.size = (900, 240);
        c.push(
            &format!("{file}_{}", file_name(&label)),
            section,
            format!("{label} ({file}.csv) with +-1 sigma"),
            &chart,
        )?;
    }
    Ok(())
}

fn integrity(c: &mut Ctx, outages: &[(f64, f64, Option<SolutionState>)]) -> Result<(), Error> {
    let sol = &c.run.solution;
    if sol.iter().all(|e| e.state.is_none()) {
        return Ok(());
    }
    let code = |s: Option<SolutionState>| match s {
        Some(SolutionState::Gnss) => 0.0,
        Some(SolutionState::Static) => 1.0,
        Some(SolutionState::DeadReckoning) => 2.0,
        Some(SolutionState::Inertial) => 3.0,
        Some(SolutionState::GnssExcluded) => 4.0,
        None => f64::NAN,
    };
    // A step line: one point where each state begins and ends.
    let mut steps: Vec<(f64, f64)> = Vec::new();
    let mut integrity: Vec<(f64, f64)> = Vec::new();
    for (i, e) in sol.iter().enumerate() {
        let y = code(e.state);
        let changed = i == 0 || sol[i - 1].state != e.state;
        if changed {
            if let Some(&(_, prev)) = steps.last() {
                steps.push((e.t - c.t0, prev));
            }
            steps.push((e.t - c.t0, y));
        }
        if let Some(f) = e.integrity {
            let prev = i.checked_sub(1).and_then(|j| sol[j].integrity);
            if prev != Some(f) {
                if let Some(&(_, p)) = integrity.last() {
                    integrity.push((e.t - c.t0, p));
                }
                integrity.push((e.t - c.t0, f64::from(f)));
            }
        }
    }
    if let Some(l) = sol.last() {
        steps.push((l.t - c.t0, code(l.state)));
        if let Some(f) = l.integrity {
            integrity.push((l.t - c.t0, f64::from(f)));
        }
    }
    let mut chart = c.chart(
        "Solution state",
        "0 gnss 1 static 2 dead reck. 3 inertial 4 excluded",
    );
    chart
        .series
        .push(Series::line("solution state", palette(0), steps));
    if !integrity.is_empty() {
        chart.series.push(Series::line(
            "integrity flag (0 trusted 1 suspect 2 spoofed 3 recovering)",
            RED,
            integrity,
        ));
    }
    chart.size = (900, 240);
    c.push(
        "solution_state",
        "Integrity",
        "The solution state per epoch (solution.csv `state`) and, with the [spoofing] monitor, the GNSS integrity flag".into(),
        &chart,
    )?;
    let mut time: std::collections::BTreeMap<&str, f64> = Default::default();
    for w in sol.windows(2) {
        *time.entry(state_name(w[0].state)).or_default() += w[1].t - w[0].t;
    }
    let total: f64 = time.values().sum();
    let mut rows: Vec<Vec<String>> = time
        .iter()
        .map(|(k, v)| {
            vec![
                k.to_string(),
                format!("{v:.1}"),
                format!("{:.1}", 100.0 * v / total.max(1e-9)),
            ]
        })
        .collect();
    rows.push(vec![
        "coasting intervals >= 2 s".into(),
        outages.len().to_string(),
        String::new(),
    ]);
    c.tables.push(Table {
        section: "Integrity",
        caption: "Time per solution state".into(),
        header: ["state", "time [s]", "share [%]"]
            .map(String::from)
            .to_vec(),
        rows,
    });
    Ok(())
}

fn smoother(c: &mut Ctx, truth: Option<&Truth>) -> Result<(), Error> {
    let run = c.run;
    if !run.separation.is_empty() {
        let t0 = c.t0;
        let mut chart = c.chart("Forward/backward separation", "largest |d| / sigma");
        let ok: Vec<(f64, f64)> = run
            .separation
            .iter()
            .filter(|r| !r.flagged)
            .map(|r| (r.t - t0, r.max_ratio))
            .collect();
        let bad: Vec<(f64, f64)> = run
            .separation
            .iter()
            .filter(|r| r.flagged)
            .map(|r| (r.t - t0, r.max_ratio))
            .collect();
        chart
            .series
            .push(Series::points("within the limit", palette(0), ok));
        chart.series.push(Series::points("flagged", RED, bad));
        chart.log_y = true;
        c.push(
            "separation_ratio",
            "Smoother",
            "separation.csv: the largest of the nine differences (position, velocity, attitude) over its sigma, per row; flagged rows in red".into(),
            &chart,
        )?;
        let mut chart = c.chart("Forward minus smoothed position", "m");
        for (k, axis) in ["north", "east", "down"].iter().enumerate() {
            let pts: Vec<(f64, f64)> = run
                .separation
                .iter()
                .map(|r| (r.t - t0, r.diff[k]))
                .collect();
            chart.series.push(Series::line(*axis, palette(k), pts));
        }
        c.push(
            "separation_position",
            "Smoother",
            "separation.csv: the position difference N, E, D [m]".into(),
            &chart,
        )?;
    }
    extra_states(
        c,
        run.smoothed_states.as_ref(),
        "smoothed_states",
        "Smoother",
    )?;
    if let (Some(sm), Some(truth)) = (&run.smoothed, truth) {
        let fwd = score(&run.solution, truth, Vec::new());
        let smo = score(sm, truth, Vec::new());
        if smo.epochs > 0 {
            stats_table(c, &smo, "Smoothed solution against the truth", "Smoother");
            let t0 = c.t0;
            let h = |r: &EvalReport| -> Vec<(f64, f64)> {
                min_max(
                    &r.per_epoch
                        .iter()
                        .map(|x| (x.t - t0, x.horizontal))
                        .collect::<Vec<_>>(),
                    BUCKETS,
                )
            };
            let chart = c
                .chart("Horizontal error: forward and smoothed", "m")
                .with(Series::line("forward", palette(1), h(&fwd)))
                .with(Series::line("smoothed", palette(0), h(&smo)));
            c.push(
                "smoothed_errors",
                "Smoother",
                "Horizontal error of the forward and of the smoothed solution [m]".into(),
                &chart,
            )?;
        }
    }
    Ok(())
}

/// tuning.json (`[tuning]` or `navfuse tune`): the estimates with their uncertainty,
/// the likelihood and NIS per row per pass, the fix-error model's candidates.
fn tuning(c: &mut Ctx) -> Result<(), Error> {
    let Some(t) = c.run.tuning.as_ref() else {
        return Ok(());
    };
    let num = |v: &serde_json::Value| v.as_f64();
    let fmt = |v: Option<f64>| v.map_or("-".to_string(), |x| format!("{x:.4}"));
    let rows: Vec<Vec<String>> = t["estimates"]
        .as_array()
        .into_iter()
        .flatten()
        .map(|e| {
            vec![
                plain(&e["key"]),
                plain(&e["unit"]),
                fmt(num(&e["given"])),
                fmt(num(&e["value"])),
                num(&e["rel_se"]).map_or("-".into(), |x| format!("{:.0} %", 100.0 * x)),
                plain(&e["samples"]),
            ]
        })
        .collect();
    let runs = t["forward_runs"].as_u64().unwrap_or(0);
    let wall = num(&t["wall_s"]).unwrap_or(f64::NAN);
    c.tables.push(Table {
        section: "Tuning",
        caption: format!(
            "Noise model estimated from the data by expectation-maximisation over the RTS smoother ({runs} forward runs, {wall:.2} s{}); +-: relative standard error by batch means",
            if t["converged"].as_bool() == Some(true) { ", converged" } else { ", not converged: the best pass kept" }
        ),
        header: ["parameter", "unit", "given", "estimate", "+-", "samples"]
            .map(String::from)
            .to_vec(),
        rows,
    });
    let passes = t["iterations"].as_array().cloned().unwrap_or_default();
    let mut sources: Vec<String> = passes
        .iter()
        .flat_map(|p| {
            p["nis_per_row"]
                .as_object()
                .into_iter()
                .flatten()
                .map(|(k, _)| k.clone())
        })
        .collect();
    sources.sort();
    sources.dedup();
    let mut header = vec!["pass".to_string(), "log-likelihood".to_string()];
    header.extend(sources.iter().map(|s| format!("NIS/row {s}")));
    let row_of = |name: String, p: &serde_json::Value| {
        let mut r = vec![name, fmt(num(&p["log_likelihood"]))];
        r.extend(sources.iter().map(|s| fmt(num(&p["nis_per_row"][s]))));
        r
    };
    let mut rows: Vec<Vec<String>> = passes
        .iter()
        .enumerate()
        .map(|(i, p)| row_of((i + 1).to_string(), p))
        .collect();
    rows.push(row_of("tuned".into(), &t["tuned"]));
    c.tables.push(Table {
        section: "Tuning",
        caption: "Innovation log-likelihood and NIS per row (1 for a consistent filter) per pass"
            .into(),
        header,
        rows,
    });
    if let Some(f) = t["fix_error"].as_object() {
        let rows = f["candidates"]
            .as_array()
            .into_iter()
            .flatten()
            .map(|k| {
                let tau = num(&k["corr_time_s"]).unwrap_or(0.0);
                vec![
                    if tau > 0.0 {
                        format!("Gauss-Markov {tau:.0} s")
                    } else {
                        "white".into()
                    },
                    fmt(num(&k["corr_fraction"])),
                    fmt(num(&k["position_std_scale"])),
                    fmt(num(&k["log_likelihood"])),
                ]
            })
            .collect();
        c.tables.push(Table {
            section: "Tuning",
            caption: format!(
                "GNSS fix-error model: the candidates' likelihoods; chosen: {}",
                match num(&f["corr_time_s"]) {
                    Some(x) if x > 0.0 => format!(
                        "Gauss-Markov {x:.0} s, {:.0} % of the variance",
                        100.0 * num(&f["corr_fraction"]).unwrap_or(0.0)
                    ),
                    _ => "white".into(),
                }
            ),
            header: [
                "model",
                "correlated fraction",
                "position std scale",
                "log-likelihood",
            ]
            .map(String::from)
            .to_vec(),
            rows,
        });
    }
    let pts: Vec<(f64, f64)> = passes
        .iter()
        .enumerate()
        .filter_map(|(i, p)| Some(((i + 1) as f64, num(&p["log_likelihood"])?)))
        .collect();
    if pts.len() >= 2 {
        let mut chart = Chart::new("Tuning: likelihood per pass", "pass", "log-likelihood");
        chart
            .series
            .push(Series::line("log-likelihood", palette(0), pts.clone()));
        chart.series.push(Series::points("pass", palette(0), pts));
        c.push(
            "tuning_likelihood",
            "Tuning",
            "Innovation log-likelihood of the forward run per expectation-maximisation pass (rises until the noise model fits the data)".into(),
            &chart,
        )?;
    }
    Ok(())
}
