//! One pass over a scenario: truth, IMU, odometer and GNSS are produced in time order
//! and streamed to files (memory stays flat for any duration). The files are listed
//! in docs/SIMULATOR.md.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::time::Instant;

use nalgebra::{UnitQuaternion, Vector3};
use navfuse_core::sat::System;
use navfuse_core::types::{ImuErrors, NavState};
use navfuse_gnss::constellation::{
    beidou_toe_near, galileo_toe_near, glonass_records, nominal_beidou27, nominal_galileo24,
    nominal_gps24, reissued, reissued_beidou, reissued_galileo, seed000_table3,
};
use navfuse_gnss::ephemeris::GpsEphemeris;
use navfuse_gnss::obs::{MultiObsEpoch, ObsValue, SatSignals};
use navfuse_gnss::signal::ObsCode;
use navfuse_gnss::time::GpsTime;
use navfuse_io::error::InputError;
use navfuse_io::export::ExportFormat;
use navfuse_io::fmt::push_fixed9;
use navfuse_io::nav::{ImuErrWriter, NavWriter, RecordWriter, SolutionRecord};
use navfuse_io::rinex_nav::{read_rinex_nav, write_rinex3_nav_dated, RinexNav};
use navfuse_io::rinex_obs::{ssi_from_cn0, ObsHeader, RinexMultiObsWriter, RinexObsWriter};

use crate::baro_sim::BaroSim;
use crate::gnss_sim::{systems_of, EventSpec, GnssSim, SatEpoch};
use crate::imu_model::{ImuErrorModel, ImuOutput};
use crate::random::Stream;
use crate::run_config::run_config_text;
use crate::scenario::Scenario;
use crate::trajectory::{TruthGenerator, TruthSample};

/// What a run produced (also written as sim_summary.json by the CLI).
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct SimSummary {
    pub scenario: String,
    pub seed: u64,
    pub gps_week: u32,
    pub t_start: f64,
    pub t_end: f64,
    pub imu_samples: u64,
    pub imu_rate_hz: f64,
    pub imu_grade: String,
    pub truth_epochs: u64,
    pub gnss_epochs: u64,
    pub gnss_fixes: u64,
    pub satellites_min: usize,
    pub satellites_max: usize,
    pub odometer_epochs: u64,
    pub dgps_corrections: u64,
    pub distance_m: f64,
    pub files: Vec<String>,
    pub elapsed_s: f64,
}

/// A buffered output file.
struct Out {
    path: PathBuf,
    w: BufWriter<File>,
}

impl Out {
    fn create(dir: &Path, name: &str, files: &mut Vec<String>) -> Result<Out, InputError> {
        let path = dir.join(name);
        let f = File::create(&path).map_err(|e| InputError::create(&path, &e))?;
        files.push(name.to_string());
        Ok(Out {
            path,
            w: BufWriter::with_capacity(1 << 20, f),
        })
    }

    fn put(&mut self, bytes: &[u8]) -> Result<(), InputError> {
        self.w
            .write_all(bytes)
            .map_err(|e| InputError::write(&self.path, &e))
    }

    fn finish(mut self) -> Result<(), InputError> {
        self.w
            .flush()
            .map_err(|e| InputError::write(&self.path, &e))
    }
}

/// GPS - UTC \[s\] written to nav.rnx (`LEAP SECONDS`) and used for the GLONASS
/// records' UTC epochs.
const NAV_LEAP_SECONDS: i32 = 18;

/// The obs.rnx writer: GPS-only RINEX 3.04, or mixed RINEX 3.05.
enum ObsOut {
    Gps(RinexObsWriter<BufWriter<File>>),
    Multi(RinexMultiObsWriter<BufWriter<File>>),
}

/// "G05", "E11" for an event's satellite (validated).
fn sat_label(r: &crate::gnss_sim::SatRef) -> String {
    r.sat().map_or_else(|| r.to_string(), |s| s.to_string())
}

fn io_err(path: &Path) -> impl Fn(std::io::Error) -> InputError + '_ {
    move |e| InputError::write(path, &e)
}

/// The constellation of every system a scenario asks for: GPS as
/// [`gps_constellation`]; Galileo, BeiDou and GLONASS the bundled ones (Galileo and
/// BeiDou re-issued hourly with SISA / URA the simulated signal-in-space error,
/// GLONASS every 30 min), or those of `rinex_nav` with `constellation = "rinex"`.
/// Only the systems simulated are built or kept.
fn constellation(sc: &Scenario) -> Result<RinexNav, InputError> {
    let g = sc.file.gnss.as_ref().expect("called with [gnss]");
    let systems = systems_of(g);
    let (mut gps, iono) = gps_constellation(sc)?;
    let start = GpsTime::new(sc.file.start.gps_week as i32, sc.file.start.time_s);
    let end = start.add_s(sc.trajectory.duration());
    let e = &g.errors;
    let ura_m = (e.orbit_m.powi(2) + e.sat_clock_m.powi(2) + e.sa_m.powi(2)).sqrt();
    let has = |s: System| systems.contains(&s);
    if !has(System::Gps) {
        gps.clear();
    }
    let mut nav = RinexNav {
        gps,
        iono_alpha: iono.map(|i| i.0),
        iono_beta: iono.map(|i| i.1),
        ..RinexNav::default()
    };
    if systems == [System::Gps] {
        return Ok(nav);
    }
    if g.constellation == "rinex" {
        let p = sc
            .base_dir()
            .join(g.rinex_nav.as_deref().unwrap_or_default());
        let file = read_rinex_nav(&p)?;
        (nav.galileo, nav.beidou, nav.glonass) = (file.galileo, file.beidou, file.glonass);
    } else {
        if has(System::Galileo) {
            let gal = nominal_galileo24(galileo_toe_near(start));
            nav.galileo = reissued_galileo(&gal, start, end, 3_600.0);
            nav.galileo.iter_mut().for_each(|e| e.sisa_m = ura_m);
        }
        if has(System::BeiDou) {
            let bds = nominal_beidou27(beidou_toe_near(start));
            nav.beidou = reissued_beidou(&bds, start, end, 3_600.0);
            nav.beidou.iter_mut().for_each(|e| e.sv_accuracy_m = ura_m);
        }
        if has(System::Glonass) {
            // GPS - UTC as written to nav.rnx's LEAP SECONDS.
            nav.glonass = glonass_records(start, end, f64::from(NAV_LEAP_SECONDS));
        }
    }
    if !has(System::Galileo) {
        nav.galileo.clear();
    }
    if !has(System::BeiDou) {
        nav.beidou.clear();
    }
    if !has(System::Glonass) {
        nav.glonass.clear();
    }
    Ok(nav)
}

/// The signals written for each system: code, phase, Doppler, strength of GPS L1
/// C/A, Galileo E1, GLONASS L1OF (C1C...) and BeiDou B1I (C2I...).
fn obs_types(system: System) -> Vec<ObsCode> {
    let names: [&[u8; 3]; 4] = match system {
        System::BeiDou => [b"C2I", b"L2I", b"D2I", b"S2I"],
        _ => [b"C1C", b"L1C", b"D1C", b"S1C"],
    };
    names.iter().map(|n| ObsCode(**n)).collect()
}

/// One simulated satellite as a RINEX 3 record: its system's four signals, LLI on
/// the phase when set, the SSI of the C/N0 on each value.
fn sat_signals(s: &SatEpoch) -> SatSignals {
    let ssi = s.obs.cn0_dbhz.map(ssi_from_cn0).filter(|d| *d > 0);
    let vals = [
        s.obs.pseudorange_m,
        s.obs.carrier_cycles,
        s.obs.doppler_hz,
        s.obs.cn0_dbhz,
    ];
    let signals = obs_types(s.sat.system)
        .into_iter()
        .zip(vals)
        .enumerate()
        .filter_map(|(k, (code, v))| {
            let lli = (k == 1 && s.obs.lli != 0).then_some(s.obs.lli & 7);
            v.map(|v| {
                (
                    code,
                    ObsValue {
                        value: Some(v),
                        lli,
                        ssi,
                    },
                )
            })
        })
        .collect();
    SatSignals {
        sat: s.sat,
        signals,
    }
}

/// The GPS constellation and Klobuchar coefficients a scenario asks for.
#[allow(clippy::type_complexity)]
fn gps_constellation(
    sc: &Scenario,
) -> Result<(Vec<GpsEphemeris>, Option<([f64; 4], [f64; 4])>), InputError> {
    let g = sc.file.gnss.as_ref().expect("called with [gnss]");
    let week = sc.file.start.gps_week as i32;
    // Nominal ephemerides referenced to the start (the nearest even hour).
    let toe_sow = (sc.file.start.time_s / 7200.0).round() * 7200.0;
    // Synthetic ephemerides broadcast the URA of the simulated signal-in-space error
    // (orbit, satellite clock, SA), as the control segment would: a receiver weights
    // its pseudoranges by it. A RINEX file keeps its own values.
    let e = &g.errors;
    let ura_m = (e.orbit_m.powi(2) + e.sat_clock_m.powi(2) + e.sa_m.powi(2)).sqrt();
    let with_ura = |mut ephs: Vec<GpsEphemeris>| {
        for eph in ephs.iter_mut() {
            eph.sv_accuracy_m = ura_m;
        }
        ephs
    };
    // Re-issued every 2 h (as the control segment uploads) so that a scenario of any
    // length has valid ephemerides throughout.
    let start = GpsTime::new(week, sc.file.start.time_s);
    let end = start.add_s(sc.trajectory.duration());
    let refresh = |ephs: Vec<GpsEphemeris>| reissued(&ephs, start, end, 7_200.0);
    match g.constellation.as_str() {
        "nominal24" => Ok((
            with_ura(refresh(nominal_gps24(GpsTime::new(week, toe_sow)))),
            None,
        )),
        "seed000" => Ok((with_ura(refresh(seed000_table3(week))), None)),
        _ => {
            let p = sc
                .base_dir()
                .join(g.rinex_nav.as_deref().unwrap_or_default());
            let nav = read_rinex_nav(&p)?;
            let iono = nav.iono_alpha.zip(nav.iono_beta);
            Ok((nav.gps, iono))
        }
    }
}

/// Run the scenario and write everything into `out_dir` (created if needed).
pub fn generate(sc: &Scenario, out_dir: &Path) -> Result<SimSummary, InputError> {
    let started = Instant::now();
    std::fs::create_dir_all(out_dir).map_err(|e| InputError::create(out_dir, &e))?;
    let mut files = Vec::new();
    let week = sc.file.start.gps_week;
    let seed = sc.file.seed;
    let traj = &sc.trajectory;
    let imu_rate = sc.imu.rate_hz;
    let mut gen = TruthGenerator::new(traj, sc.rig, imu_rate);
    let mut imu_model = ImuErrorModel::new(&sc.imu_grade, seed);
    let vibration = sc
        .file
        .vibration
        .as_ref()
        .map(|v| crate::vibration::Vibration::new(v, seed));

    // Scenario copy, for provenance.
    {
        let mut o = Out::create(out_dir, "scenario.toml", &mut files)?;
        o.put(sc.text.as_bytes())?;
        o.finish()?;
    }

    let (imu_name, imu_header) = match sc.imu.output {
        ImuOutput::Increments => ("imu.txt", None),
        ImuOutput::Rates => (
            "imu.csv",
            Some("t_s,gyro_x_radps,gyro_y_radps,gyro_z_radps,acc_x_mps2,acc_y_mps2,acc_z_mps2\n"),
        ),
    };
    let mut imu_out = Out::create(out_dir, imu_name, &mut files)?;
    if let Some(h) = imu_header {
        imu_out.put(h.as_bytes())?;
    }
    let truth_path = out_dir.join("truth.nav");
    let mut truth_out = NavWriter::create(&truth_path)?;
    files.push("truth.nav".into());
    // The truth as a map (KML, at most 10 Hz: io export.rs).
    let mut truth_kml = ExportFormat::Kml.create(&out_dir.join("truth.kml"))?;
    files.push("truth.kml".into());
    let mut err_out = if sc.file.output.truth_imu_errors {
        files.push("truth_imu_err.txt".into());
        Some(ImuErrWriter::create(&out_dir.join("truth_imu_err.txt"))?)
    } else {
        None
    };

    // The IMU clock: the IMU, odometer and barometer files are tagged this much later
    // than GPS time (`[gnss] time_offset_s`, the GNSS-IMU time offset tau: a GNSS epoch
    // tagged t was taken at IMU time t + tau); GNSS, heading and truth stay on GPS time.
    let imu_clock_s = sc.file.gnss.as_ref().map_or(0.0, |g| g.time_offset_s);

    // Odometer.
    let odo = sc.file.odometer.clone();
    let mut odo_out = match &odo {
        Some(_) => {
            let mut o = Out::create(out_dir, "odometer.txt", &mut files)?;
            o.put(
                b"# t [s of GPS week], pulses (cumulative), pulses in the interval, speed [m/s]\n",
            )?;
            Some(o)
        }
        None => None,
    };
    let odo_every = odo
        .as_ref()
        .map(|o| (imu_rate / o.rate_hz).round().max(1.0) as u64);
    let mut odo_rng = Stream::new(seed, "odometer");
    let mut distance = 0.0_f64;
    let mut odo_pulses_prev: i64 = 0;
    let mut odo_t_prev = traj.t_start();

    // Barometer (baro_sim.rs): pressure readings and the true bias beside them.
    let mut baro = match &sc.file.baro {
        Some(b) => {
            let mut o = Out::create(out_dir, "baro.txt", &mut files)?;
            o.put(b"# t [s of GPS week], pressure [Pa]\n")?;
            let mut tr = Out::create(out_dir, "baro_truth.txt", &mut files)?;
            tr.put(b"# t [s of GPS week, time of validity], barometer error without its white noise [m]\n")?;
            let every = (imu_rate / b.rate_hz).round().max(1.0) as u64;
            Some((BaroSim::new(b, seed, traj.t_start()), every, o, tr))
        }
        None => None,
    };

    // GNSS.
    let gspec = sc.file.gnss.clone();
    let mut gnss = None;
    let mut gnss_every = 0u64;
    let mut obs_w = None;
    let mut fix_out = None;
    let mut head_out = None;
    let mut dgps_out = None;
    let mut err_csv = None;
    if let Some(g) = &gspec {
        let cons = constellation(sc)?;
        let systems = systems_of(g);
        let sim = GnssSim::new(
            g,
            cons.store(),
            cons.iono_alpha.zip(cons.iono_beta),
            seed,
            week,
            traj.t_start(),
            &traj_start_lla(sc),
        );
        gnss_every = (imu_rate / g.rate_hz).round().max(1.0) as u64;
        if g.raw {
            // File date = the scenario start (UTC ~ GPST - 18 s ignored): output depends
            // only on the scenario, never on the wall clock.
            let stamp = {
                let c = GpsTime::new(week as i32, traj.t_start()).to_calendar();
                format!(
                    "{:04}{:02}{:02} {:02}{:02}{:02} UTC",
                    c.year, c.month, c.day, c.hour, c.minute, c.second as u32
                )
            };
            let (alpha, beta) = sim.iono_coefficients();
            let nav = RinexNav {
                gps: cons.gps.clone(),
                galileo: cons.galileo.clone(),
                beidou: cons.beidou.clone(),
                glonass: cons.glonass.clone(),
                iono_alpha: Some(alpha),
                iono_beta: Some(beta),
                leap_seconds: Some(NAV_LEAP_SECONDS),
                skipped_records: 0,
                warnings: Vec::new(),
                ..RinexNav::default()
            };
            let p = out_dir.join("nav.rnx");
            let mut w = BufWriter::new(File::create(&p).map_err(|e| InputError::create(&p, &e))?);
            write_rinex3_nav_dated(&mut w, &nav, "navfuse sim", &stamp).map_err(io_err(&p))?;
            w.flush().map_err(io_err(&p))?;
            files.push("nav.rnx".into());
            let p = out_dir.join("obs.rnx");
            let f = File::create(&p).map_err(|e| InputError::create(&p, &e))?;
            let s0 = gen.current();
            let hdr = ObsHeader {
                marker_name: "NAVFUSE_SIM".into(),
                approx_pos_ecef_m: navfuse_core::earth::lla_to_ecef(&s0.lla),
                antenna_delta_hen_m: Vector3::zeros(),
                interval_s: Some(1.0 / g.rate_hz),
                first_obs: GpsTime::new(week as i32, traj.t_start()),
                receiver: [
                    "SIM".into(),
                    "navfuse sim".into(),
                    env!("CARGO_PKG_VERSION").into(),
                ],
                antenna: ["SIM".into(), "SIM".into()],
                program: "navfuse sim".into(),
                date: Some(stamp.clone()),
            };
            let bw = BufWriter::with_capacity(1 << 20, f);
            // GPS only: the RINEX 3.04 GPS file as always; else RINEX 3.05 mixed.
            let w = if systems == [System::Gps] {
                ObsOut::Gps(RinexObsWriter::new(bw, &hdr).map_err(io_err(&p))?)
            } else {
                let types: Vec<_> = systems.iter().map(|s| (*s, obs_types(*s))).collect();
                let mut channels: Vec<(u8, i8)> = cons
                    .glonass
                    .iter()
                    .map(|e| (e.slot, e.freq_channel))
                    .collect();
                channels.sort_unstable();
                channels.dedup();
                ObsOut::Multi(
                    RinexMultiObsWriter::new(bw, &hdr, &types, &channels).map_err(io_err(&p))?,
                )
            };
            obs_w = Some((w, p));
            files.push("obs.rnx".into());
        }
        if g.fix.is_some() {
            let mut o = Out::create(out_dir, "gnss.txt", &mut files)?;
            o.put(b"# t [s of GPS week], lat lon [deg], h [m], std N E D [m], vN vE vD [m/s], std vN vE vD [m/s]; antenna\n")?;
            fix_out = Some(o);
        }
        if g.heading.is_some() {
            let mut o = Out::create(out_dir, "heading.txt", &mut files)?;
            o.put(b"# t [s of GPS week], heading of the antenna baseline [deg, 0..360 from north], std [deg]\n")?;
            head_out = Some(o);
        }
        if g.dgps.is_some() {
            let mut o = Out::create(out_dir, "dgps.csv", &mut files)?;
            let r = sim.reference_lla().expect("dgps on");
            let line = format!(
                "# navfuse DGPS corrections v1; reference station lat {:.9} deg lon {:.9} deg h {:.3} m; corrected P = P + prc_m + rrc_mps (t - t_s)\nt_s,prn,prc_m,rrc_mps,iode\n",
                r.x.to_degrees(),
                r.y.to_degrees(),
                r.z
            );
            o.put(line.as_bytes())?;
            dgps_out = Some(o);
        }
        let mut o = Out::create(out_dir, "gnss_errors.csv", &mut files)?;
        o.put(b"t_s,prn,el_deg,az_deg,iono_m,tropo_m,sat_clock_m,orbit_m,multipath_m,noise_m,rx_clock_m,sa_m,total_m,dgps_age_s,dgps_iono_m,dgps_tropo_m,dgps_sat_clock_m,dgps_orbit_m,dgps_multipath_m,dgps_noise_m,dgps_sa_m,spoof_range_m\n")?;
        err_csv = Some(o);
        gnss = Some(sim);
    }

    let mut summary = SimSummary {
        scenario: sc.path.display().to_string(),
        seed,
        gps_week: week,
        t_start: traj.t_start(),
        imu_rate_hz: imu_rate,
        imu_grade: sc.imu_grade.name.clone(),
        satellites_min: usize::MAX,
        ..Default::default()
    };
    let mut line = Vec::with_capacity(256);
    let mut k: u64 = 0;
    let mut cur = gen.current();
    let write_truth = |s: &TruthSample,
                       e: &ImuErrors,
                       tw: &mut NavWriter,
                       kw: &mut Box<dyn RecordWriter>,
                       ew: &mut Option<ImuErrWriter>|
     -> Result<(), InputError> {
        let rec = SolutionRecord {
            gps_week: week,
            nav: NavState {
                t: s.t,
                lla: s.lla,
                v_n: s.v_n,
                q_bn: UnitQuaternion::from_matrix(&s.c_bn),
            },
            imu_errors: *e,
            std: None,
            gnss_integrity: None,
            state: None,
        };
        tw.write(&rec)?;
        kw.write_record(&rec)?;
        if let Some(w) = ew {
            w.write(&rec)?;
        }
        Ok(())
    };
    write_truth(
        &cur,
        &imu_model.current_errors().to_core(),
        &mut truth_out,
        &mut truth_kml,
        &mut err_out,
    )?;
    summary.truth_epochs += 1;
    loop {
        // GNSS at the current sample time.
        if let Some(sim) = gnss.as_mut() {
            if k.is_multiple_of(gnss_every) {
                let ep = sim.epoch(&cur);
                summary.gnss_epochs += 1;
                if !ep.outage {
                    summary.satellites_min = summary.satellites_min.min(ep.sats.len());
                    summary.satellites_max = summary.satellites_max.max(ep.sats.len());
                }
                if let Some((w, p)) = obs_w.as_mut() {
                    if !ep.sats.is_empty() {
                        let t = GpsTime::new(week as i32, ep.t);
                        match w {
                            ObsOut::Gps(w) => {
                                let obs: Vec<_> = ep.sats.iter().map(|s| s.obs.clone()).collect();
                                w.write_epoch(t, &obs).map_err(io_err(p))?;
                            }
                            ObsOut::Multi(w) => {
                                let m = MultiObsEpoch {
                                    t,
                                    flag: 0,
                                    rx_clock_offset_s: None,
                                    sats: ep.sats.iter().map(sat_signals).collect(),
                                };
                                w.write_epoch(&m).map_err(io_err(p))?;
                            }
                        }
                    }
                }
                if let (Some(o), Some(f)) = (fix_out.as_mut(), ep.fix) {
                    line.clear();
                    push_fixed9(&mut line, f.t);
                    for v in [f.lla.x.to_degrees(), f.lla.y.to_degrees()] {
                        line.push(b' ');
                        push_fixed9(&mut line, v);
                    }
                    for v in [
                        f.lla.z,
                        f.std_ned.x,
                        f.std_ned.y,
                        f.std_ned.z,
                        f.vel_ned.x,
                        f.vel_ned.y,
                        f.vel_ned.z,
                        f.vel_std,
                        f.vel_std,
                        f.vel_std,
                    ] {
                        line.push(b' ');
                        push_fixed9(&mut line, v);
                    }
                    line.push(b'\n');
                    o.put(&line)?;
                    summary.gnss_fixes += 1;
                }
                if let (Some(o), Some((psi, std))) = (head_out.as_mut(), ep.heading) {
                    line.clear();
                    push_fixed9(&mut line, ep.t);
                    line.push(b' ');
                    push_fixed9(&mut line, psi.to_degrees());
                    line.push(b' ');
                    push_fixed9(&mut line, std.to_degrees());
                    line.push(b'\n');
                    o.put(&line)?;
                }
                if let Some(o) = dgps_out.as_mut() {
                    for c in &ep.corrections {
                        let s = format!(
                            "{:.3},{},{:.4},{:.6},{}\n",
                            c.t, c.prn, c.prc_m, c.rrc_mps, c.iode
                        );
                        o.put(s.as_bytes())?;
                        summary.dgps_corrections += 1;
                    }
                }
                if let Some(o) = err_csv.as_mut() {
                    use std::fmt::Write as _;
                    let mut s = String::new();
                    for sat in &ep.sats {
                        let e = &sat.errors;
                        let _ = write!(
                            s,
                            "{:.3},{},{:.4},{:.4},{:.4},{:.4},{:.4},{:.4},{:.4},{:.4},{:.4},{:.4},{:.4},",
                            ep.t,
                            // GPS: the PRN; other systems: "E11", "C23".
                            if sat.sat.system == System::Gps {
                                sat.obs.prn.to_string()
                            } else {
                                sat.sat.to_string()
                            },
                            sat.el_rad.to_degrees(),
                            sat.az_rad.to_degrees(),
                            e.iono,
                            e.tropo,
                            e.sat_clock,
                            e.orbit,
                            e.multipath,
                            e.noise,
                            e.rx_clock,
                            e.sa,
                            e.total()
                        );
                        match (&sat.dgps_residual, sat.dgps_age_s) {
                            (Some(r), Some(age)) => {
                                let _ = write!(
                                    s,
                                    "{:.3},{:.4},{:.4},{:.4},{:.4},{:.4},{:.4},{:.4},",
                                    age,
                                    r.iono,
                                    r.tropo,
                                    r.sat_clock,
                                    r.orbit,
                                    r.multipath,
                                    r.noise,
                                    r.sa
                                );
                            }
                            _ => s.push_str(",,,,,,,,"),
                        }
                        let _ = writeln!(s, "{:.4}", sat.spoof_range_m);
                    }
                    o.put(s.as_bytes())?;
                }
            }
        }

        let Some((imu_true, next)) = gen.step() else {
            break;
        };
        k += 1;
        // Odometer distance of the vehicle reference point (trapezoid at the IMU rate).
        distance += 0.5 * (cur.speed + next.speed) * imu_true.dt;
        let (dth, dv) = match &vibration {
            // Engine vibration: zero-mean, exact over the interval (not in the truth).
            Some(v)
                if v.when == crate::vibration::VibrationWhen::Always
                    || cur.speed.abs().max(next.speed.abs()) < 0.01 =>
            {
                let a = imu_true.t - imu_true.dt - traj.t_start();
                let (vth, vv) = v.increments(a, a + imu_true.dt);
                imu_model.apply(imu_true.dt, &(imu_true.dtheta + vth), &(imu_true.dvel + vv))
            }
            _ => imu_model.apply(imu_true.dt, &imu_true.dtheta, &imu_true.dvel),
        };
        line.clear();
        push_fixed9(&mut line, imu_true.t + imu_clock_s);
        // Shortest round-trip decimal of each value: a fixed 9 decimals would round a
        // static 3.6e-7 rad increment by the same amount every sample, a gyro bias of
        // up to 20 deg/h at 200 Hz.
        let sep = match sc.imu.output {
            ImuOutput::Increments => b' ',
            ImuOutput::Rates => b',',
        };
        let k_rate = match sc.imu.output {
            ImuOutput::Increments => 1.0,
            ImuOutput::Rates => 1.0 / imu_true.dt,
        };
        for v in dth.iter().chain(dv.iter()) {
            line.push(sep);
            let _ = write!(line, "{:e}", *v * k_rate);
        }
        line.push(b'\n');
        imu_out.put(&line)?;
        summary.imu_samples += 1;
        cur = next;
        if k.is_multiple_of(sc.truth_every) {
            write_truth(
                &cur,
                &imu_model.current_errors().to_core(),
                &mut truth_out,
                &mut truth_kml,
                &mut err_out,
            )?;
            summary.truth_epochs += 1;
        }
        if let Some((sim, every, o, tr)) = baro.as_mut() {
            if k.is_multiple_of(*every) {
                let r = sim.sample(cur.t, cur.lla.z);
                o.put(format!("{:.9} {:.4}\n", r.t_tag + imu_clock_s, r.pressure_pa).as_bytes())?;
                tr.put(format!("{:.9} {:.6}\n", cur.t, r.bias_m).as_bytes())?;
            }
        }
        if let (Some(o), Some(every), Some(spec)) = (odo_out.as_mut(), odo_every, odo.as_ref()) {
            if k.is_multiple_of(every) {
                // SYSTEM.md §4b: true distance = (1 + dk) K_OD N.
                let per_pulse = spec.meters_per_pulse * (1.0 + spec.scale_error_ppm * 1e-6);
                let pulses = (distance / per_pulse).floor() as i64;
                let dt = cur.t - odo_t_prev;
                let speed = (pulses - odo_pulses_prev) as f64 * spec.meters_per_pulse / dt
                    + spec.speed_noise_mps * odo_rng.normal();
                let s = format!(
                    "{:.9} {} {} {:.6}\n",
                    cur.t + imu_clock_s,
                    pulses,
                    pulses - odo_pulses_prev,
                    speed
                );
                o.put(s.as_bytes())?;
                odo_pulses_prev = pulses;
                odo_t_prev = cur.t;
                summary.odometer_epochs += 1;
            }
        }
    }
    summary.t_end = cur.t;
    summary.distance_m = distance;
    if summary.satellites_min == usize::MAX {
        summary.satellites_min = 0;
    }

    imu_out.finish()?;
    truth_out.finish()?;
    truth_kml.finish_boxed()?;
    if let Some(w) = err_out {
        w.finish()?;
    }
    let (baro_out, baro_truth) = match baro {
        Some((_, _, o, tr)) => (Some(o), Some(tr)),
        None => (None, None),
    };
    for o in [
        odo_out, fix_out, head_out, dgps_out, err_csv, baro_out, baro_truth,
    ]
    .into_iter()
    .flatten()
    {
        o.finish()?;
    }
    if let Some((w, p)) = obs_w {
        let mut inner = match w {
            ObsOut::Gps(w) => w.finish(),
            ObsOut::Multi(w) => w.finish(),
        }
        .map_err(io_err(&p))?;
        inner.flush().map_err(io_err(&p))?;
    }
    write_events(sc, out_dir, &mut files)?;
    write_run_config(sc, out_dir, &mut files)?;
    summary.files = files;
    summary.elapsed_s = started.elapsed().as_secs_f64();
    Ok(summary)
}

fn traj_start_lla(sc: &Scenario) -> Vector3<f64> {
    let p = sc.file.start.position_deg_m;
    Vector3::new(p[0].to_radians(), p[1].to_radians(), p[2])
}

/// events.csv: every configured GNSS event in absolute GPS time (the truth labels
/// an evaluator needs, e.g. for spoofing detection).
fn write_events(sc: &Scenario, dir: &Path, files: &mut Vec<String>) -> Result<(), InputError> {
    let Some(g) = &sc.file.gnss else {
        return Ok(());
    };
    let t0 = sc.trajectory.t_start();
    let t_end = sc.trajectory.t_end();
    let mut o = Out::create(dir, "events.csv", files)?;
    o.put(b"type,start_s,end_s,details\n")?;
    for ev in &g.events {
        let line = match ev {
            EventSpec::Outage { start_s, end_s } => {
                format!("outage,{:.3},{:.3},\n", t0 + start_s, t0 + end_s)
            }
            EventSpec::OutageEvery {
                length_s,
                period_s,
                from_s,
                until_s,
            } => {
                let mut s = String::new();
                let mut a = t0 + from_s;
                let until = until_s.map_or(t_end, |u| t0 + u);
                while a < until && a < t_end {
                    s.push_str(&format!("outage,{:.3},{:.3},periodic\n", a, a + length_s));
                    a += period_s;
                }
                s
            }
            EventSpec::Blockage {
                start_s,
                end_s,
                keep,
                prns,
            } => format!(
                "blockage,{:.3},{:.3},{}\n",
                t0 + start_s,
                t0 + end_s,
                match (keep, prns) {
                    (Some(k), _) => format!("keep {k}"),
                    (_, Some(p)) => format!(
                        "prns [{}]",
                        p.iter()
                            .map(|r| r.to_string())
                            .collect::<Vec<_>>()
                            .join(" ")
                    ),
                    _ => String::new(),
                }
            ),
            EventSpec::Spoof {
                mode,
                start_s,
                end_s,
                offset_m,
                velocity_mps,
                delay_s,
            } => format!(
                "spoof,{:.3},{:.3},{:?} offset_m {:?} velocity_mps {:?} delay_s {}\n",
                t0 + start_s,
                t0 + end_s,
                mode,
                offset_m,
                velocity_mps,
                delay_s
            )
            .replace(", ", " "),
            EventSpec::CycleSlip { prn, at_s, cycles } => {
                format!(
                    "cycle_slip,{:.3},{:.3},{} {cycles} cycles\n",
                    t0 + at_s,
                    t0 + at_s,
                    sat_label(prn)
                )
            }
            EventSpec::LossOfLock {
                prn,
                start_s,
                end_s,
            } => {
                format!(
                    "loss_of_lock,{:.3},{:.3},{}\n",
                    t0 + start_s,
                    t0 + end_s,
                    sat_label(prn)
                )
            }
        };
        o.put(line.as_bytes())?;
    }
    o.finish()
}

/// run.toml: [`run_config_text`].
fn write_run_config(sc: &Scenario, dir: &Path, files: &mut Vec<String>) -> Result<(), InputError> {
    let mut o = Out::create(dir, "run.toml", files)?;
    o.put(run_config_text(sc, dir).as_bytes())?;
    o.finish()
}
