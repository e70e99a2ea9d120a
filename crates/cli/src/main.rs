//! `navfuse`: the command line: clap, and one call per subcommand. `run_cmd` (the
//! navigator over files, a thin call into `navfuse_app`), `eval_cmd` (scoring a
//! solution file), `sim_cmd` (the simulator), `allan_cmd` (Allan deviation of an IMU
//! file, `navfuse_app::allan`), `batch_cmd` (many runs in one process); `reproduce`
//! (the papers' experiments), `bench` (speed, loose and tight coupling) and the
//! batch runner are `navfuse_experiments`.

// The doc comments below are clap's --help text, where `[spoofing]` names a TOML
// section and `[m]` a unit; rustdoc is not their reader.
#![allow(rustdoc::broken_intra_doc_links)]

mod allan_cmd;
mod batch_cmd;
mod eval_cmd;
mod report_cmd;
mod run_cmd;
mod sim_cmd;
mod spp_cmd;
mod tune_cmd;

use clap::{Parser, Subcommand};
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "navfuse",
    version,
    about = "GNSS/INS integrated navigation: strapdown INS + error-state EKF with GNSS aiding",
    long_about = "GNSS/INS integrated navigation: strapdown INS (NED, WGS-84, coning/sculling) with a \
closed-loop error-state EKF (21 states, plus odometer scale, mounting, receiver clock, GNSS fix error, barometer bias and time-offset states as configured). Aiding: \
loosely coupled GNSS position/velocity; tightly coupled pseudoranges with Doppler or time-differenced \
carrier phase (RINEX 3, broadcast ephemeris, DGPS corrections); heading from course over ground or \
a dual antenna; odometer, non-holonomic constraint, zero velocity; barometric altitude; a GNSS integrity monitor against \
spoofing with dead-reckoning fallback.\n\n\
Inputs: KF-GINS text files, CSV IMU logs (one file or several), the rtklibexplorer raw IMU log, RTKLIB .pos solutions, NMEA \
0183 and generic CSV fixes, RINEX observation and navigation files of GPS, GLONASS, Galileo, BeiDou and QZSS (SP3 and clock \
files), u-blox UBX (RXM-RAWX, RXM-SFRBX, NAV-PVT; ESF-RAW / ESF-MEAS IMU and wheel ticks, NAV-RELPOSNED heading), PX4 ULog (IMU, GPS, barometer; EKF2's estimate for eval), odometer, \
heading and barometer logs, DGPS corrections. \
Outputs: KF-GINS .nav / IMU_ERR / STD files, CSV with the solution state, innovations, extra states, the \
configuration used, events and integrity logs; exports (.pos, NMEA, KML, GeoJSON, GPX); `report` draws an \
offline HTML page. Formats: docs/FORMATS.md; configuration keys: docs/CONFIG.md."
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run the navigator on a configuration (navfuse TOML, or a KF-GINS YAML with --kf-gins).
    ///
    /// Writes DIR/solution.nav (KF-GINS 11 columns), and as configured DIR/imu_err.txt,
    /// DIR/std.txt, DIR/solution.csv (with the solution state per epoch: gnss, static,
    /// dead_reckoning, inertial, gnss_excluded); DIR/states.csv (the extra filter states),
    /// DIR/innovations.csv (every update tried, its NIS and gate); DIR/config.toml (the
    /// configuration used, every key: `navfuse run DIR/config.toml` repeats the run);
    /// DIR/events.log lists
    /// rejected GNSS fixes and input findings; DIR/summary.json holds the run's counts and the estimated GNSS-IMU time
    /// offset. When the configuration estimates the time offset, the data are read twice:
    /// the first pass finds the offset, the second navigates with it and writes the
    /// solution on the GNSS time scale (a search matching turns comes first, so offsets
    /// of a second or two are found). With a `[tuning]` section the noise model is
    /// first estimated from the data (as `navfuse tune`; tuned.toml, tuning.json and
    /// tuning.txt are written) and the run uses it. A progress bar is drawn on stderr
    /// when it is a terminal; a one-line summary is printed at the end.
    ///
    /// Plausibility checks (docs/FORMATS.md) warn about likely mistakes (units, axes,
    /// lever arm in cm, UTC tags, a wide time-offset prior) naming the key to change,
    /// and refuse what would be meaningless (GNSS not overlapping the IMU, a week
    /// mismatch, an empty input, a start after the data): exit status 1. Failed runs
    /// still write events.log and summary.json (`status`, `error`). A run that goes to
    /// its end with a result the program can tell is meaningless (almost every GNSS
    /// epoch refused, a source's innovations beyond 10 sigma most of the time, IMU data
    /// ending long before the GNSS) writes every file, marks summary.json `status`
    /// "unreliable" with the reasons (`unreliable`) and exits with status 3. SIGINT / SIGTERM
    /// stop the run with every output at the same epoch and summary.json marked
    /// "interrupted", exit status 130 / 143.
    Run {
        /// navfuse TOML configuration (docs/CONFIG.md); a .yaml file is read as KF-GINS.
        #[arg(required_unless_present = "kf_gins", conflicts_with = "kf_gins")]
        config: Option<PathBuf>,
        /// An unchanged KF-GINS YAML configuration.
        #[arg(long = "kf-gins", value_name = "FILE.yaml")]
        kf_gins: Option<PathBuf>,
        /// Output directory (created if missing). Default: the config's outputpath
        /// (KF-GINS) or ./out.
        #[arg(long, value_name = "DIR")]
        out: Option<PathBuf>,
        /// Extra GNSS outages, added to the configured ones: comma-separated `a:b`
        /// windows (seconds) and `L/P@T[..U]` (L s every P s from T, starting before U).
        #[arg(long, value_name = "SPEC")]
        outages: Option<String>,
        /// Smooth after the forward run (as `[smoother] enabled = true`): the
        /// forward solution stays in solution.nav, the smoothed one goes to
        /// smoothed.nav, smoothed_std.txt, smoothed.csv (smoothed_states.csv with
        /// the extra states) and the separation report to separation.csv.
        #[arg(long)]
        smooth: bool,
        /// Smoother mode (implies --smooth): `rts` (Rauch-Tung-Striebel over the
        /// forward filter) or `combined` (an independent backward filter weighted
        /// with the forward one). Default: the config's `[smoother] mode`, else rts.
        #[arg(long, value_name = "MODE", value_parser = ["rts", "combined"])]
        smooth_mode: Option<String>,
        /// Exports beside solution.nav (and smoothed.nav), added to `[output]
        /// formats`: comma-separated pos (RTKLIB, GPST), nmea (GGA, RMC, HDT in UTC),
        /// kml, geojson, gpx (docs/FORMATS.md "Exports").
        #[arg(long, value_name = "LIST")]
        formats: Option<String>,
        /// Apply a GNSS fix within S seconds of an IMU epoch at that epoch, as
        /// KF-GINS does with 0.001 (as `[gnss] time_snap_s`; default 0: each fix at
        /// its own time, the IMU interval split there). Moves a fix by up to S: a
        /// position error of up to speed x S.
        #[arg(long = "time-snap", value_name = "S")]
        time_snap: Option<f64>,
        /// No progress bar and no summary line.
        #[arg(long, short)]
        quiet: bool,
    },
    /// Write exports of a finished run: RUN_DIR/solution.nav (with --smoothed,
    /// smoothed.nav) as RTKLIB .pos, NMEA, KML, GeoJSON or GPX beside it
    /// (docs/FORMATS.md "Exports"); the .pos standard deviations come from std.txt
    /// and the NMEA quality (GNSS or dead reckoning) from solution.csv when they are
    /// there.
    Export {
        /// The output directory of `navfuse run`.
        run_dir: PathBuf,
        /// Comma-separated: pos, nmea, kml, geojson, gpx.
        #[arg(long, value_name = "LIST")]
        formats: String,
        /// Export the smoothed solution (smoothed.nav) instead.
        #[arg(long)]
        smoothed: bool,
    },
    /// Write the HTML report of a finished run: one self-contained file (inline SVG,
    /// style and script; opens offline) with the ground track coloured by solution
    /// state, position / velocity / attitude against time, the innovations (NIS) of
    /// every aiding source with their gates and rejections, the IMU error and extra
    /// state estimates with their sigma, the solution-state timeline, the smoother's
    /// separation, the run summary, configuration and events; with --truth also the
    /// errors against time with +-3 sigma bands, the horizontal-error CDF with
    /// P50/P68/P95, and the drift in each coasting interval. Long runs are thinned
    /// for plotting (min/max decimation keeps every peak); the errors are scored at
    /// up to 50 000 reference epochs against the full-rate solution.
    Report(report_cmd::ReportArgs),
    /// GNSS-only single point positioning of a RINEX observation file with broadcast
    /// ephemerides (or SP3 orbits and clocks): GPS, GLONASS, Galileo, BeiDou, QZSS with
    /// an inter-system bias per system, single or dual frequency; position, receiver
    /// clock, satellites used and DOP per epoch, as an RTKLIB .pos file with --out, to
    /// compare with RTKLIB's rnx2rtkp directly.
    Spp(spp_cmd::SppArgs),
    /// Score a solution against a reference trajectory.
    ///
    /// SOLUTION and TRUTH may each be a KF-GINS .nav file (11 columns; week 0 = seconds
    /// of week only), navfuse's solution.csv / smoothed.csv, an RTKLIB .pos file (GPST,
    /// lat/lon/height) or a KF-GINS GNSS text file (7 or 13 columns), recognised by
    /// their content, not by the file name (--solution-format / --truth-format choose).
    /// .nav and CSV are IMU-centre states with velocity and attitude; .pos and KF-GINS
    /// GNSS are antenna positions (with velocity in their 24- / 13-column forms) and no
    /// attitude: use --lever-arm to move the solution to the antenna. Prints RMS, max
    /// and mean of N/E/D, horizontal, vertical, 3D, along-track and cross-track
    /// position, velocity (when both files have it) and attitude errors (the rotation
    /// between the attitudes: roll/pitch/yaw components and the total angle; only when
    /// both files have attitude), the P50/P68/P95/P99 of the horizontal and 3D error
    /// (CEP = P50, R95 = P95 horizontal); with --gaps also each outage's maximum error
    /// and the RMS of those maxima; --errors writes every epoch's errors.
    Eval {
        /// The solution: .nav, navfuse CSV, RTKLIB .pos or KF-GINS GNSS (by content).
        solution: PathBuf,
        /// The reference: .nav, navfuse CSV, RTKLIB .pos, KF-GINS GNSS or a PX4 ULog
        /// (EKF2's estimate) (by content).
        truth: PathBuf,
        /// The solution's format: auto (by content), nav, csv, pos, kfgins-gnss or ulog.
        #[arg(long, value_name = "FORMAT", default_value = "auto",
              value_parser = ["auto", "nav", "csv", "pos", "kfgins-gnss", "ulog"])]
        solution_format: String,
        /// The reference's format: auto (by content), nav, csv, pos, kfgins-gnss or ulog.
        #[arg(long, value_name = "FORMAT", default_value = "auto",
              value_parser = ["auto", "nav", "csv", "pos", "kfgins-gnss", "ulog"])]
        truth_format: String,
        /// Outage windows: comma-separated `a:b` and `L/P@T[..U]` (see `run --outages`).
        #[arg(long, value_name = "SPEC")]
        gaps: Option<String>,
        /// Body-frame point [m] (F,R,D) to move the solution to before comparing, e.g.
        /// the antenna lever arm when TRUTH is an antenna track.
        #[arg(long, value_name = "X,Y,Z", allow_hyphen_values = true)]
        lever_arm: Option<String>,
        /// For an RTKLIB .pos truth: solution qualities to score against (default 1 = fix;
        /// a .pos solution keeps every epoch).
        #[arg(long, value_name = "Q,...", default_value = "1")]
        quality: String,
        /// Only score reference epochs in [start, end] (seconds, same time base).
        #[arg(long, value_name = "START:END")]
        window: Option<String>,
        /// Write the per-epoch errors as CSV: t, position N E D, horizontal,
        /// along-track, cross-track [m], velocity N E D [m/s], roll pitch yaw and total
        /// attitude error [deg].
        #[arg(long, value_name = "FILE.csv")]
        errors: Option<PathBuf>,
        /// Machine-readable output.
        #[arg(long)]
        json: bool,
    },
    /// Simulate a scenario (docs/SIMULATOR.md): truth, IMU, odometer, GNSS raw
    /// measurements (RINEX 3), receiver fixes, dual-antenna heading, DGPS corrections,
    /// barometer.
    ///
    /// Writes into DIR: truth.nav, truth.kml (the truth as a map, at most 10 Hz), imu.txt
    /// (or imu.csv), truth_imu_err.txt, and as the
    /// scenario asks odometer.txt, gnss.txt, heading.txt, obs.rnx, nav.rnx, dgps.csv,
    /// gnss_errors.csv, events.csv, baro.txt, baro_truth.txt; plus run.toml (a navfuse run configuration for these
    /// files), scenario.toml (a copy) and sim_summary.json. Same scenario and seed give
    /// byte-identical files.
    Sim {
        /// Scenario file (TOML), e.g. scenarios/seed002_car.toml.
        scenario: PathBuf,
        /// Output directory (created if missing).
        #[arg(long, value_name = "DIR")]
        out: PathBuf,
        /// Override the scenario's seed.
        #[arg(long)]
        seed: Option<u64>,
        /// No summary line.
        #[arg(long, short)]
        quiet: bool,
    },
    /// Many runs in one process on a pool of threads: the cases of a manifest (a
    /// list of run configurations, or one simulator scenario over many seeds;
    /// docs/CONFIG.md "Batch manifest"), a folder per case and one table.
    ///
    /// Writes DIR/NAME/ per case (exactly what `navfuse run --out DIR/NAME` writes;
    /// no progress bar, the warnings in its events.log; a Monte Carlo case's
    /// simulated data in DIR/NAME/sim), and DIR/batch.csv and DIR/batch.json (one row
    /// per case in manifest order: index, name, seed, status, epochs, the figures
    /// against the truth (horizontal / vertical / 3D position RMS and max, P95
    /// horizontal, velocity and attitude RMS, per-gap maxima with gaps) and the GNSS
    /// updates used / rejected, error; numbers in shortest round-trip form, the same
    /// bytes whatever --jobs) and DIR/batch_timing.csv (each case's wall time).
    /// Prints a line per finished case on stderr (unless -q) and the total wall time
    /// and cases/s at the end. A failing case does not stop the others: its row says
    /// failed with the error, and the exit status is 1 once the tables are written (3
    /// when none failed but some ran with status "unreliable", as `navfuse run`).
    /// Ctrl-C / SIGTERM: no more cases are started, those under way finish, the tables
    /// are written (the others "not run"), exit status 130 / 143.
    Batch {
        /// The manifest (TOML; paths in it relative to its folder).
        manifest: PathBuf,
        /// Output folder (created if missing).
        #[arg(long, value_name = "DIR", default_value = batch_cmd::DEFAULT_OUT)]
        out: PathBuf,
        /// Cases run at once (threads). Default: the number of CPUs.
        #[arg(long, value_name = "N")]
        jobs: Option<usize>,
        /// Write only the three tables into DIR, no case folders: the runs' output
        /// stays in memory and a Monte Carlo case's simulated data go to a temporary
        /// folder, removed after the case (the same rows).
        #[arg(long)]
        tables_only: bool,
        /// No line per finished case (the final line stays).
        #[arg(long, short)]
        quiet: bool,
    },
    /// Reproduce a paper's experiment on the simulator (SYSTEM.md §7): seed000 (tight
    /// coupling, DGPS), seed001 (heading from GNSS), seed001_outages (seed 001's drive
    /// with seed 002's 30 s and 60 s GNSS outages), seed002 (NHC with GNSS outages),
    /// seed004 (INS + odometer, no GNSS; with --attack, spoofing detection).
    ///
    /// Simulates the experiment's scenario for each seed, runs every navigator variant
    /// on the same data, scores it against the truth and prints mean [min, max] over the
    /// seeds beside the paper's figures (tables at most 100 columns wide, a legend of
    /// the columns under them), with the improvement (base - variant) / base (the
    /// formula of seed 002 eq. 18; the footer says what it means for each experiment),
    /// its 95 % bootstrap interval over the seeds and the range of the seeds' own
    /// improvements.
    ///
    /// seed004 only: --attack, --jump-runs and --clean-hours replace the plain
    /// experiment by the spoofing ones (any combination; each is printed in turn, or
    /// together under --json). Their runs use two threads.
    Reproduce {
        /// Experiment: seed000, seed001, seed001_outages, seed002 or seed004.
        experiment: String,
        /// Number of random seeds.
        #[arg(long, default_value_t = 4)]
        seeds: u64,
        /// First seed (seeds are consecutive).
        #[arg(long, default_value_t = 1)]
        first_seed: u64,
        /// Machine-readable output.
        #[arg(long)]
        json: bool,
        /// Keep the simulated data and the solutions (the files of `navfuse run`) in
        /// DIR. Default: the simulated data go to a temporary directory, removed at
        /// the end, and the solutions are scored in memory, not written.
        #[arg(long, value_name = "DIR")]
        keep: Option<PathBuf>,
        /// No per-run progress lines on stderr.
        #[arg(long, short)]
        quiet: bool,
        /// seed004: the spoofing experiment (SYSTEM.md §5): scenarios/seed004_attack.toml
        /// (built in; two laps of the loop, drift attack at 2 m/s from 150 s to 450 s)
        /// with the variants no_monitor, monitor ([spoofing] defaults), monitor_R
        /// (distance R = 10 m alone); seed 004's own system (6-state fusion, GNSS tested
        /// against the free dead reckoning): odo_dr_R (INS/odometer/NHC, R alone),
        /// ins_only_R (INS only, R alone), ins_only_chi2 (INS only, chi-square alone);
        /// dead_reckoning (GNSS removed over the attack), six_state_monitor (6-state
        /// fusion + defaults against its prediction), six_state_dead_reckoning (6-state
        /// fusion, GNSS removed over the attack); prints alarms
        /// before the attack, detection delay and detector, maximum horizontal and 3D
        /// errors during the attack and in the 60 s after it, and the 3D RMSE, over
        /// --seeds seeds, beside the paper's statements.
        #[arg(long)]
        attack: bool,
        /// seed004: N jump attacks on scenarios/seed004_loop.toml (one lap) with the
        /// `monitor` variant: random seed, direction uniform on the sphere, 20-200 m,
        /// start uniform in [70, 330] s while moving, 30 s long, drawn from
        /// --first-seed; prints the fraction detected within 1 s of the attack start,
        /// the delays, detectors and alarms before the attack.
        #[arg(long, value_name = "N", default_value_t = 0)]
        jump_runs: usize,
        /// seed004: false alarms over H hours of clean driving (1-hour drives of the
        /// loop with a stop each lap, seeds from --first-seed): ADIS16405 MEMS IMU at
        /// 50 Hz + odometer + NHC + GNSS, [spoofing] defaults; transitions out of
        /// trusted and entries to spoofed, per 10 h.
        #[arg(long, value_name = "H", default_value_t = 0.0)]
        clean_hours: f64,
    },
    /// Allan deviation of an IMU file: the overlapping Allan deviation (IEEE 952) of the
    /// three gyro and three accelerometer axes, with the angle / velocity random walk
    /// (ARW, VRW: the -1/2 slope line fitted to the white-noise part, at tau = 1 s)
    /// and the bias instability (the minimum / 0.664).
    ///
    /// Reads the file as `navfuse run` does: a KF-GINS IMU text file (increments) by
    /// default, the CSV IMU layout with --format csv (t, gyro x y z, accel x y z; units
    /// and quantity as below), or with --config a run configuration's [imu] input with
    /// all its settings (any format, columns, units, axes). Prints a table per sensor
    /// (gyro: deg/sqrt(h), deg/h; accel: m/s/sqrt(h), mGal); --out writes the curves
    /// and the read-offs as CSV, --svg DIR plots them (docs/FORMATS.md "Allan
    /// deviation"). Record the IMU at rest; an hour or more shows the bias instability.
    Allan(allan_cmd::AllanArgs),
    /// Estimate the noise model from the run's own data: the IMU's angle and velocity
    /// random walk, bias and scale-factor instabilities, each aiding source's
    /// measurement noise (GNSS position / velocity std scales, NHC, odometer, ZUPT,
    /// pseudorange and range-rate sigma scales, barometer), and whether the GNSS
    /// fixes' errors are white or time-correlated (with the correlation time).
    ///
    /// Maximum likelihood by expectation-maximisation over the RTS smoother: each pass
    /// runs the filter forward and smooths it, then sets every noise to the mean
    /// expected square of its noise under the smoothed estimate; the innovation
    /// likelihood of each pass is printed and the configuration of highest likelihood
    /// kept; the fix-error model is chosen by the likelihood among white and three
    /// correlation times (docs/ALGORITHMS.md "Noise identification"). Without
    /// [imu_noise] in the configuration the IMU model starts from the white noise read
    /// from the data. Prints the estimates (given, start, estimate, relative standard
    /// error) and the likelihood per pass; writes the tuned configuration (the input
    /// with the estimates in it; paths absolute) to DIR/tuned.toml, the estimation to
    /// DIR/tuning.json and DIR/tuning.txt, and the tuned configuration's run (what
    /// `navfuse run DIR/tuned.toml --out DIR` writes, so `navfuse report DIR` shows
    /// the estimation beside it).
    Tune {
        /// navfuse TOML configuration (docs/CONFIG.md); a .yaml file is read as KF-GINS.
        config: PathBuf,
        /// Output directory (created if missing).
        #[arg(long, value_name = "DIR", default_value = "out/tune")]
        out: PathBuf,
        /// Most expectation-maximisation passes.
        #[arg(long, value_name = "N", default_value_t = 8)]
        iterations: usize,
        /// Start the IMU noise from the data even where the configuration gives it.
        #[arg(long)]
        from_data: bool,
        /// Keep the configuration's GNSS fix-error model (do not choose between white
        /// and time-correlated errors).
        #[arg(long)]
        keep_fix_error_model: bool,
        /// Only the estimation: no tuned run into DIR.
        #[arg(long)]
        no_run: bool,
        /// No progress on stderr.
        #[arg(long, short)]
        quiet: bool,
    },
    /// Measure speed and memory: the core filter loop without I/O (samples/s) and a full
    /// run writing KF-GINS's three output files (wall time, peak memory); with --tight,
    /// tight coupling with 10 satellites on simulated data (required: 500x real time).
    ///
    /// Default: loose coupling on the KF-GINS stand-in in ../shared/data. With --tight:
    /// tight coupling (pseudoranges + TDCP) with 10 GPS satellites at 1 Hz and a 200 Hz
    /// IMU on a simulated car drive (scenarios/bench_tight_10sat.toml, built in; needs no
    /// data): the scenario is simulated into a temporary directory (not timed), then a
    /// full `navfuse run` (read imu.txt + RINEX, write solution.nav at the IMU rate) and
    /// the core loop in memory are timed; prints the satellites per epoch (min / mean /
    /// max), IMU samples, seconds of data, wall time, the real-time factor and PASS/FAIL
    /// against the required 500x. The verdict does not set the exit status; fewer than
    /// 10 satellites per epoch on average is an error.
    ///
    /// With --smooth: the smoother on one simulated hour at 200 Hz (scenarios/
    /// hour_200hz.toml, built in, with a barometer and receiver fixes) with every
    /// vehicle state (odometer scale, mounting with the NHC, fix errors, barometer
    /// bias, time offset and rate; ZUPT/ZARU at the standstills), output at the IMU
    /// rate: wall time and peak memory of `navfuse run` without and with `--smooth`;
    /// PASS/FAIL against forward + backward <= 2.5x forward alone and peak memory <=
    /// 300 MiB; also the time offset found (none is simulated) and the share of
    /// odometer records refused.
    ///
    /// With --report: `navfuse report` on that hour (run with --smooth, not timed)
    /// against its 200 Hz truth: wall time and peak memory of reading, thinning,
    /// scoring, drawing and writing the page.
    ///
    /// With --tdcp-sweep: not a speed measurement but the accuracy sweep of tight
    /// coupling with TDCP against Doppler over random sites and start times (issue
    /// 30): a table per drive and latitude band, PASS/FAIL (the exit status).
    Bench {
        /// KF-GINS YAML for the full run (default: ../shared/data/kf-gins/synthetic/kf-gins.yaml).
        #[arg(long, value_name = "FILE.yaml", conflicts_with = "tight")]
        kf_gins: Option<PathBuf>,
        /// Benchmark tight coupling on simulated data instead (10 satellites, 1 Hz GNSS,
        /// 200 Hz IMU; requirement: at least 500x faster than real time).
        #[arg(long)]
        tight: bool,
        /// Benchmark the smoother instead (one simulated hour at 200 Hz).
        #[arg(long, conflicts_with_all = ["tight", "kf_gins"])]
        smooth: bool,
        /// Benchmark `navfuse report` instead (the same hour, smoothed, against its
        /// truth).
        #[arg(long, conflicts_with_all = ["tight", "kf_gins", "smooth"])]
        report: bool,
        /// The TDCP sweep instead (issue 30): --runs simulated car drives at random
        /// sites (every 20 deg latitude band from 80 S to 80 N in turn, any
        /// longitude) and start times (GPS week, time of week), each navigated with
        /// tight coupling with TDCP and with Doppler, without and with one GNSS outage
        /// of 60-600 s. PASS: no horizontal error above 50 m from 30 s after the start
        /// or after GNSS returns, and TDCP's velocity RMS at or below Doppler's in
        /// every drive; exit status 1 on FAIL.
        #[arg(long, conflicts_with_all = ["tight", "kf_gins", "smooth", "report"])]
        tdcp_sweep: bool,
        /// With --tdcp-sweep: the number of drives.
        #[arg(long, value_name = "N", requires = "tdcp_sweep", default_value_t = navfuse_experiments::BENCH_TDCP_SWEEP_DEFAULT_RUNS)]
        runs: usize,
        /// With --tdcp-sweep: the sweep's seed (sites, start times, outages and the
        /// simulator's seeds follow from it).
        #[arg(long, value_name = "S", requires = "tdcp_sweep", default_value_t = 1)]
        seed: u64,
        /// With --tight: seconds of data to simulate and navigate (at most the
        /// scenario's length, 1880 s for the built-in one).
        #[arg(long, value_name = "N", requires = "tight", default_value_t = navfuse_experiments::BENCH_TIGHT_DEFAULT_DURATION_S)]
        duration_s: f64,
        /// With --tight: another scenario file (with raw GNSS) in place of the
        /// built-in one.
        #[arg(long, value_name = "FILE.toml", requires = "tight")]
        scenario: Option<PathBuf>,
        /// Noise identification instead (`navfuse tune` against the hand-tuned runs,
        /// from configurations with every noise key at its default): simulated cars
        /// with white and correlated fix errors, with and without an odometer, over
        /// N seeds each; with ../shared the KF-GINS stand-in and the real drive.
        /// Prints each case's verdicts (PASS / FAIL; informational, the exit status
        /// does not follow them).
        #[arg(long, value_name = "SEEDS", conflicts_with_all = ["tight", "kf_gins", "smooth", "report"])]
        tune: Option<usize>,
        /// With --tune: the simulated cases only.
        #[arg(long, requires = "tune")]
        sim_only: bool,
        /// Repetitions of each measurement (the best is reported).
        #[arg(long, default_value_t = 3)]
        repeat: usize,
        /// Machine-readable output.
        #[arg(long)]
        json: bool,
    },
}

fn export_main(dir: &std::path::Path, formats: &str, smoothed: bool) -> anyhow::Result<()> {
    let list = navfuse_io::export::ExportFormat::parse_list(formats)
        .map_err(|e| anyhow::anyhow!("--formats: {e}"))?;
    if list.is_empty() {
        anyhow::bail!("--formats: no format given (pos, nmea, kml, geojson, gpx)");
    }
    let stem = if smoothed { "smoothed" } else { "solution" };
    for f in navfuse_app::export_run(dir, stem, &list)? {
        eprintln!("navfuse: wrote {}", f.display());
    }
    Ok(())
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Run {
            config,
            kf_gins,
            out,
            outages,
            smooth,
            smooth_mode,
            formats,
            time_snap,
            quiet,
        } => run_cmd::main(
            config,
            kf_gins,
            out,
            outages,
            (smooth, smooth_mode, formats),
            time_snap,
            quiet,
        ),
        Command::Export {
            run_dir,
            formats,
            smoothed,
        } => export_main(&run_dir, &formats, smoothed),
        Command::Report(a) => report_cmd::main(a),
        Command::Spp(a) => spp_cmd::main(&a),
        Command::Eval {
            solution,
            truth,
            solution_format,
            truth_format,
            gaps,
            lever_arm,
            quality,
            window,
            errors,
            json,
        } => eval_cmd::main(
            &eval_cmd::EvalInputs {
                solution: &solution,
                truth: &truth,
                solution_format: &solution_format,
                truth_format: &truth_format,
                quality: &quality,
            },
            gaps,
            lever_arm,
            window,
            errors.as_deref(),
            json,
        ),
        Command::Sim {
            scenario,
            out,
            seed,
            quiet,
        } => sim_cmd::main(&scenario, &out, seed, quiet),
        Command::Reproduce {
            experiment,
            seeds,
            first_seed,
            json,
            keep,
            quiet,
            attack,
            jump_runs,
            clean_hours,
        } => navfuse_experiments::reproduce(&navfuse_experiments::ReproduceArgs {
            experiment,
            seeds,
            first_seed,
            json,
            keep,
            quiet,
            attack,
            jump_runs,
            clean_hours,
        }),
        Command::Batch {
            manifest,
            out,
            jobs,
            tables_only,
            quiet,
        } => batch_cmd::main(&manifest, &out, jobs, tables_only, quiet),
        Command::Allan(args) => allan_cmd::main(&args),
        Command::Tune {
            config,
            out,
            iterations,
            from_data,
            keep_fix_error_model,
            no_run,
            quiet,
        } => tune_cmd::main(&tune_cmd::TuneArgs {
            config,
            out,
            options: navfuse_app::tune::TuneOptions {
                max_iterations: iterations,
                from_data,
                fix_error_model: !keep_fix_error_model,
                ..Default::default()
            },
            run: !no_run,
            quiet,
        }),
        Command::Bench {
            kf_gins,
            tight,
            smooth,
            report,
            tdcp_sweep,
            runs,
            seed,
            duration_s,
            scenario,
            tune,
            sim_only,
            repeat,
            json,
        } => navfuse_experiments::bench(&navfuse_experiments::BenchArgs {
            kf_gins,
            tight,
            smooth,
            report,
            tdcp_sweep,
            runs,
            seed,
            duration_s,
            scenario,
            repeat,
            json,
            tune_seeds: tune.unwrap_or(0),
            tune_sim_only: sim_only,
        }),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("navfuse: error: {e:#}");
            let interrupted = e
                .downcast_ref::<navfuse_app::Error>()
                .and_then(navfuse_app::Error::interrupted);
            match interrupted {
                Some(i) => ExitCode::from(i.exit_status()),
                None if e.downcast_ref::<navfuse_app::Unreliable>().is_some() => {
                    ExitCode::from(navfuse_app::EXIT_UNRELIABLE)
                }
                None => ExitCode::FAILURE,
            }
        }
    }
}
