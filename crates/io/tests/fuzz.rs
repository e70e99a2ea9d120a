//! Fuzz suite: every reader and both config formats on mutated real seed files
//! (tests/data/fuzz, tests/data, examples). Each case runs under `catch_unwind` in a
//! worker thread watched for hangs; every accepted output is checked (numbers
//! finite, stds in range, times increasing; configs round-trip through
//! `to_toml_string`). Normal `cargo test`: a few thousand cases per reader.
//!
//! Long mode: `NAVFUSE_FUZZ_CASES=1000000 cargo test --release -p navfuse-io --test
//! fuzz -- --nocapture` (cases per reader); `NAVFUSE_FUZZ_SEED` sets the base seed,
//! `NAVFUSE_FUZZ_ONLY=name` runs one target. A failure prints its target and seed.

mod fuzz_support;

use fuzz_support::{mutate, Rng};
use navfuse_gnss::GpsTime;
use navfuse_io::config::{load, parse_toml_str, RunConfig};
use navfuse_io::input::*;
use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::time::{Duration, Instant};

const DEFAULT_CASES: u64 = 1500;
const DEFAULT_SEED: u64 = 0x6E61_7666_7573_6531;
/// A case taking longer than this is a hang.
const HANG: Duration = Duration::from_secs(10);

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn seed(rel: &str) -> Vec<u8> {
    std::fs::read(root().join(rel)).unwrap_or_else(|e| panic!("seed {rel}: {e}"))
}

type Check = fn(&Path) -> Result<(), String>;

struct Target {
    name: &'static str,
    ext: &'static str,
    seeds: Vec<Vec<u8>>,
    check: Check,
}

fn finite(what: &str, v: f64) -> Result<(), String> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(format!("accepted a non-finite {what}: {v}"))
    }
}

/// A usable std: its square finite and non-zero.
fn std_ok(what: &str, v: f64) -> Result<(), String> {
    let sq = v * v;
    if v > 0.0 && sq.is_finite() && sq > 0.0 {
        Ok(())
    } else {
        Err(format!("accepted an unusable {what}: {v}"))
    }
}

fn increasing(what: &str, prev: &mut Option<f64>, t: f64) -> Result<(), String> {
    finite(what, t)?;
    if let Some(p) = *prev {
        if t <= p {
            return Err(format!("{what} not increasing: {t} after {p}"));
        }
    }
    *prev = Some(t);
    Ok(())
}

fn imu_src(path: &Path, format: ImuFormat, rate_hz: f64) -> ImuSource {
    ImuSource {
        path: path.to_path_buf(),
        format,
        rate_hz,
        sensor_to_body_rpy_deg: [180.0, 0.0, 180.0],
        time_offset_s: 0.0,
        gap_policy: GapPolicy::default(),
    }
}

fn check_imu(src: &ImuSource) -> Result<(), String> {
    let Ok(mut r) = navfuse_io::imu::open_imu(src) else {
        return Ok(());
    };
    let mut prev = None;
    for s in r.by_ref() {
        let Ok(s) = s else { return Ok(()) };
        increasing("IMU time", &mut prev, s.t)?;
        std_ok("IMU dt", s.dt)?;
        for v in s.dtheta.iter().chain(s.dvel.iter()) {
            finite("IMU increment", *v)?;
        }
    }
    r.report().to_string();
    Ok(())
}

fn kfgins_imu(p: &Path) -> Result<(), String> {
    check_imu(&imu_src(p, ImuFormat::KfGins, 200.0))
}

fn csv_imu(p: &Path) -> Result<(), String> {
    let o = CsvImuOptions {
        skip_lines: 2,
        gyro_cols: [4, 5, 6],
        accel_cols: [1, 2, 3],
        gyro_unit: GyroUnit::Deg,
        accel_unit: AccelUnit::G,
        ..Default::default()
    };
    check_imu(&imu_src(p, ImuFormat::Csv(o), 100.0))
}

/// An IMU in three CSV files (`[imu] files`): the case is the three files' texts
/// separated by NUL bytes (mutations cross files, remove or add separators); the
/// gyro file is joined row by row, the accelerometer file on its time column.
fn imu_files(p: &Path) -> Result<(), String> {
    check_imu(&imu_files_source(p)?)
}

/// The case file `p` split into the three files of an `[imu] files` source.
fn imu_files_source(p: &Path) -> Result<ImuSource, String> {
    let data = std::fs::read(p).map_err(|e| e.to_string())?;
    let mut parts = data.split(|&b| b == 0);
    let dir = p.with_extension("parts");
    std::fs::create_dir_all(&dir).map_err(|e| e.to_string())?;
    let mut paths = Vec::new();
    for name in ["time.csv", "gyro.csv", "accel.csv"] {
        let q = dir.join(name);
        std::fs::write(&q, parts.next().unwrap_or_default()).map_err(|e| e.to_string())?;
        paths.push(q);
    }
    let files = CsvImuFiles {
        time_path: paths[0].clone(),
        time_col: 0,
        gyro: CsvImuPart {
            path: paths[1].clone(),
            time_col: None,
            cols: [0, 1, 2],
        },
        accel: CsvImuPart {
            path: paths[2].clone(),
            time_col: Some(0),
            cols: [1, 2, 3],
        },
        skip_lines: None,
        tolerance_s: 1e-4,
        csv: CsvImuOptions::default(),
    };
    Ok(imu_src(p, ImuFormat::CsvFiles(Box::new(files)), 100.0))
}

/// The `imu_files` seed is a valid input (the cases start from a read that works):
/// four rows, the first starting the intervals.
#[test]
fn imu_files_seed_reads() {
    let dir = std::env::temp_dir().join(format!("navfuse-fuzz-seed-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let t = targets()
        .into_iter()
        .find(|t| t.name == "imu_files")
        .unwrap();
    let p = dir.join("seed.bin");
    std::fs::write(&p, &t.seeds[0]).unwrap();
    let r = navfuse_io::imu::open_imu(&imu_files_source(&p).unwrap()).unwrap();
    let n = r.collect::<Result<Vec<_>, _>>().unwrap().len();
    assert_eq!(n, 3);
    let _ = std::fs::remove_dir_all(&dir);
}

fn check_gnss(p: &Path, format: GnssFormat) -> Result<(), String> {
    let src = GnssSource {
        path: p.to_path_buf(),
        format,
        decimate_s: None,
        time_offset_s: 0.0,
        skip_lines: None,
    };
    let Ok(d) = navfuse_io::gnss::read_gnss(&src) else {
        return Ok(());
    };
    let mut prev = None;
    for f in &d.fixes {
        increasing("GNSS time", &mut prev, f.t)?;
        for v in f.lla.iter().chain(f.vel_ned.iter().flatten()) {
            finite("GNSS value", *v)?;
        }
        for v in f.std_ned.iter().chain(f.vel_std_ned.iter().flatten()) {
            std_ok("GNSS std", *v)?;
        }
        if f.lla.x.abs() > std::f64::consts::FRAC_PI_2 + 1e-12 {
            return Err(format!("latitude {} rad accepted", f.lla.x));
        }
    }
    Ok(())
}

fn gnss_kfgins(p: &Path) -> Result<(), String> {
    check_gnss(p, GnssFormat::KfGins)
}

fn gnss_pos(p: &Path) -> Result<(), String> {
    check_gnss(p, GnssFormat::RtklibPos { quality: vec![] })
}

fn gnss_nmea(p: &Path) -> Result<(), String> {
    let o = navfuse_io::nmea::NmeaOptions::default();
    if let Ok(d) = navfuse_io::nmea::read_nmea(p, &o) {
        let mut prev = None;
        for h in &d.heading {
            increasing("NMEA heading time", &mut prev, h.t)?;
            finite("NMEA heading", h.heading_rad)?;
        }
    }
    check_gnss(p, GnssFormat::Nmea(o))
}

fn gnss_csv(p: &Path) -> Result<(), String> {
    use navfuse_io::gnss_csv::{CsvGnssOptions, CsvTimeScale};
    let mut o = CsvGnssOptions::lla(0, [1, 2, 3]);
    o.time_scale = CsvTimeScale::IsoUtc;
    o.pos_std_cols = Some([4, 5, 6]);
    o.vel_cols = Some([7, 8, 9]);
    o.velocity_std_mps = Some([0.1, 0.1, 0.3]);
    check_gnss(p, GnssFormat::Csv(o.clone()))?;
    // The same file read as plain numbers (a non-ISO time column is a header or an
    // error) with ECEF columns.
    o.time_scale = CsvTimeScale::GpstUnix;
    o.position = navfuse_io::gnss_csv::CsvPosition::Ecef([1, 2, 3]);
    check_gnss(p, GnssFormat::Csv(o))
}

fn heading(p: &Path) -> Result<(), String> {
    let Ok(h) = navfuse_io::heading::read_heading(p) else {
        return Ok(());
    };
    let mut prev = None;
    for o in &h {
        increasing("heading time", &mut prev, o.t)?;
        finite("heading", o.heading_rad)?;
        std_ok("heading std", o.std_rad)?;
    }
    Ok(())
}

fn check_odometer(p: &Path, format: OdometerFormat) -> Result<(), String> {
    let src = OdometerSource {
        path: p.to_path_buf(),
        format,
        skip_lines: None,
    };
    let Ok(o) = navfuse_io::odometer::read_odometer(&src) else {
        return Ok(());
    };
    let mut prev = None;
    for s in &o {
        increasing("odometer time", &mut prev, s.t)?;
        finite("odometer speed", s.speed_mps)?;
        finite("odometer interval", s.interval_s)?;
        if s.interval_s < 0.0 {
            return Err(format!("negative interval {}", s.interval_s));
        }
    }
    Ok(())
}

fn odometer_speed(p: &Path) -> Result<(), String> {
    check_odometer(
        p,
        OdometerFormat::Speed {
            speed_is_mean: true,
        },
    )
}

fn odometer_navfuse(p: &Path) -> Result<(), String> {
    check_odometer(
        p,
        OdometerFormat::Navfuse {
            meters_per_pulse: 0.01,
        },
    )
}

fn dgps(p: &Path) -> Result<(), String> {
    let Ok(f) = navfuse_io::dgps::read_dgps_file(p) else {
        return Ok(());
    };
    let mut prev: Option<f64> = None;
    for c in &f.corrections {
        for v in [c.t_s, c.prc_m, c.rrc_mps] {
            finite("DGPS value", v)?;
        }
        if prev.is_some_and(|p| c.t_s < p) {
            return Err(format!("DGPS time {} goes backwards", c.t_s));
        }
        prev = Some(c.t_s);
    }
    for v in f.reference_lla.iter().flatten() {
        finite("station position", *v)?;
    }
    Ok(())
}

/// A ULog through every reader that takes one: IMU, GNSS, barometer, EKF2 track.
fn ulog(p: &Path) -> Result<(), String> {
    check_imu(&imu_src(p, ImuFormat::Ulog { multi_id: 0 }, 100.0))?;
    check_gnss(p, GnssFormat::Ulog { multi_id: 0 })?;
    let src = navfuse_io::baro::BaroSource {
        path: p.to_path_buf(),
        quantity: navfuse_io::baro::BaroQuantity::PressurePa,
        reference_pressure_pa: 101_325.0,
        delay_s: 0.0,
        format: navfuse_io::baro::BaroFormat::Ulog { multi_id: 0 },
        skip_lines: None,
    };
    if let Ok(b) = navfuse_io::baro::read_baro(&src, &mut Vec::new()) {
        for s in &b {
            finite("baro time", s.t)?;
            finite("baro height", s.height_m)?;
        }
    }
    let f = Some(navfuse_io::trajectory::TrajFormat::Ulog);
    if let Ok(t) = navfuse_io::trajectory::read_trajectory(p, f, &[]) {
        let mut prev = None;
        for q in &t.points {
            increasing("track time", &mut prev, q.t)?;
            for v in q
                .lla
                .iter()
                .chain(q.v_n.iter().flatten())
                .chain(q.rpy.iter().flatten())
            {
                finite("track value", *v)?;
            }
        }
    }
    Ok(())
}

fn nav(p: &Path) -> Result<(), String> {
    let Ok(n) = navfuse_io::nav::read_nav(p) else {
        return Ok(());
    };
    let mut prev = None;
    for (w, s) in &n {
        increasing("nav time", &mut prev, f64::from(*w) * 604_800.0 + s.t)?;
        for v in s.lla.iter().chain(s.v_n.iter()).chain(s.q_bn.coords.iter()) {
            finite("nav value", *v)?;
        }
    }
    Ok(())
}

fn rinex_nav(p: &Path) -> Result<(), String> {
    let Ok(n) = navfuse_io::rinex_nav::read_rinex_nav(p) else {
        return Ok(());
    };
    for e in &n.gps {
        for dt in [-7200.0, 0.0, 3600.0] {
            let t: GpsTime = e.toe.add_s(dt);
            let s = e.sat_state(t);
            for v in s.pos_ecef_m.iter().chain(s.vel_ecef_mps.iter()) {
                finite(&format!("satellite state of PRN {}", e.prn), *v)?;
            }
            finite("satellite clock", s.clock_bias_s)?;
            finite("satellite clock drift", s.clock_drift_s_per_s)?;
        }
    }
    Ok(())
}

/// Every system and signal (plain or Compact RINEX): times non-decreasing, values finite.
fn rinex_obs_all(p: &Path) -> Result<(), String> {
    let Ok(r) = navfuse_io::rinex_obs::read_rinex_obs_all(p) else {
        return Ok(());
    };
    for w in r.epochs.windows(2) {
        if w[1].t.diff_s(&w[0].t) < 0.0 {
            return Err(format!(
                "epoch time goes backwards: {:?} after {:?}",
                w[1].t, w[0].t
            ));
        }
    }
    let values = r
        .epochs
        .iter()
        .flat_map(|e| &e.sats)
        .flat_map(|s| &s.signals);
    for (code, v) in values {
        if let Some(x) = v.value {
            finite(code.as_str(), x)?;
        }
    }
    Ok(())
}

fn rinex_obs(p: &Path) -> Result<(), String> {
    let Ok(r) = navfuse_io::rinex_obs::read_rinex_obs_report(p) else {
        return Ok(());
    };
    let mut prev: Option<GpsTime> = None;
    for e in &r.epochs {
        finite("epoch time", e.t.sow)?;
        if let Some(p) = prev {
            if e.t.diff_s(&p) < 0.0 {
                return Err(format!("epoch time goes backwards: {:?} after {p:?}", e.t));
            }
        }
        prev = Some(e.t);
        for s in &e.sats {
            let vals = [s.pseudorange_m, s.carrier_cycles, s.doppler_hz, s.cn0_dbhz];
            for v in vals.iter().flatten() {
                finite("observation", *v)?;
            }
        }
    }
    Ok(())
}

/// An accepted config: no NaN/inf in it (except the open start time) and a fixpoint
/// of `to_toml_string` after one round trip.
fn check_config(cfg: &RunConfig, path: &Path) -> Result<(), String> {
    let dbg = format!("{:?}", cfg.nav).replace("start_time: -inf", "");
    if dbg.contains("NaN") || dbg.contains("inf") {
        return Err(format!("config holds NaN/inf: {dbg}"));
    }
    let i = &cfg.imu;
    let mut vals = vec![i.rate_hz, i.time_offset_s];
    vals.extend(i.sensor_to_body_rpy_deg);
    if let Some(g) = &cfg.gnss {
        vals.push(g.time_offset_s);
        vals.extend(g.decimate_s);
    }
    for v in vals {
        finite("config source value", v)?;
    }
    round_trip(cfg, path)
}

/// load(to_toml_string(cfg)) loads, and writing it again gives the same text.
pub fn round_trip(cfg: &RunConfig, path: &Path) -> Result<(), String> {
    let body = |s: &str| {
        let v: Vec<&str> = s.lines().skip_while(|l| l.starts_with('#')).collect();
        v.join("\n")
    };
    let s1 = cfg.to_toml_string();
    let c2 = parse_toml_str(&s1, path)
        .map_err(|e| format!("to_toml_string output does not load: {e}\n{s1}"))?;
    let s2 = c2.to_toml_string();
    if body(&s1) != body(&s2) {
        let diff: Vec<String> = s1
            .lines()
            .zip(s2.lines())
            .filter(|(a, b)| a != b)
            .map(|(a, b)| format!("{a}  ->  {b}"))
            .collect();
        return Err(format!(
            "round trip changes the config: {}",
            diff.join("; ")
        ));
    }
    Ok(())
}

fn config(p: &Path) -> Result<(), String> {
    match load(p) {
        Ok(c) => check_config(&c, p),
        Err(_) => Ok(()),
    }
}

/// UBX: never an error but for an unreadable file; every accepted value finite,
/// epochs in time order, ephemerides giving finite satellite states, fixes usable.
fn ubx(p: &Path) -> Result<(), String> {
    let Ok(log) = navfuse_io::ubx::read_ubx(p) else {
        return Ok(());
    };
    for w in log.epochs.windows(2) {
        if w[1].t.diff_s(&w[0].t) <= 0.0 {
            return Err(format!("RAWX epoch {:?} after {:?}", w[1].t, w[0].t));
        }
    }
    for e in &log.epochs {
        finite("RAWX time", e.t.sow)?;
        for (code, v) in e.sats.iter().flat_map(|s| &s.signals) {
            if let Some(x) = v.value {
                finite(code.as_str(), x)?;
            }
        }
    }
    // Every decoded record of every system gives a finite satellite state.
    let mut states = Vec::new();
    for e in log.nav.gps.iter().chain(&log.nav.qzss) {
        states.push((format!("G/J{:02}", e.prn), e.sat_state(e.toe)));
    }
    for e in &log.nav.galileo {
        states.push((format!("E{:02}", e.prn), e.sat_state(e.toe)));
    }
    for e in &log.nav.beidou {
        let t = navfuse_gnss::ephemeris::beidou::bdt_to_gpst(e.toe);
        states.push((format!("C{:02}", e.prn), e.sat_state(t)));
    }
    for e in &log.nav.glonass {
        states.push((format!("R{:02}", e.slot), e.sat_state(e.tb.add_s(300.0))));
    }
    for (sat, s) in &states {
        for v in s.pos_ecef_m.iter().chain(s.vel_ecef_mps.iter()) {
            finite(&format!("satellite state of {sat}"), *v)?;
        }
        finite(&format!("clock of {sat}"), s.clock_bias_s)?;
    }
    let mut prev = None;
    for f in &log.fixes {
        increasing("NAV-PVT time", &mut prev, f.t)?;
        for v in f.lla.iter() {
            finite("NAV-PVT position", *v)?;
        }
        for v in f.std_ned.iter().chain(f.vel_std_ned.iter().flatten()) {
            std_ok("NAV-PVT std", *v)?;
        }
    }
    Ok(())
}

/// `data` with the checksum of every frame-like run (`B5 62`, class, id, length
/// that fits) recomputed: mutated payloads then reach the message decoders.
fn repair_ubx_checksums(data: &[u8]) -> Vec<u8> {
    let mut d = data.to_vec();
    let mut i = 0;
    while i + 8 <= d.len() {
        if d[i] != 0xB5 || d[i + 1] != 0x62 {
            i += 1;
            continue;
        }
        let len = usize::from(u16::from_le_bytes([d[i + 4], d[i + 5]]));
        let end = i + 6 + len + 2;
        if end > d.len() {
            i += 1;
            continue;
        }
        let (a, b) = navfuse_io::ubx::frame::checksum(&d[i + 2..i + 6 + len]);
        d[end - 2] = a;
        d[end - 1] = b;
        i = end;
    }
    d
}

/// ESF-RAW / ESF-MEAS / NAV-RELPOSNED of a UBX log, as read and with the checksums
/// repaired: the IMU through `open_imu`, the odometer (ticks and speed) and the
/// headings: values finite, stds usable, times increasing; never a panic.
fn ubx_esf(p: &Path) -> Result<(), String> {
    let Ok(data) = std::fs::read(p) else {
        return Ok(());
    };
    let fixed = p.with_extension("fixed.ubx");
    std::fs::write(&fixed, repair_ubx_checksums(&data)).map_err(|e| e.to_string())?;
    for f in [p, fixed.as_path()] {
        check_imu(&imu_src(f, ImuFormat::Ubx, 50.0))?;
        let Ok(log) = navfuse_io::ubx::read_ubx(f) else {
            continue;
        };
        for how in [
            UbxOdometer::Ticks {
                meters_per_pulse: 0.02,
            },
            UbxOdometer::Speed,
        ] {
            if let Ok(o) = navfuse_io::ubx::aiding::odometer(f, &log, how, &mut Vec::new()) {
                let mut prev = None;
                for s in &o {
                    increasing("odometer time", &mut prev, s.t)?;
                    finite("odometer speed", s.speed_mps)?;
                    finite("odometer interval", s.interval_s)?;
                }
            }
        }
        for float_ok in [false, true] {
            let how = UbxHeading { float_ok };
            if let Ok(h) = navfuse_io::ubx::aiding::headings(f, &log, how, &mut Vec::new()) {
                let mut prev = None;
                for x in &h {
                    increasing("heading time", &mut prev, x.t)?;
                    finite("heading", x.heading_rad)?;
                    std_ok("heading std", x.std_rad)?;
                }
            }
        }
        let _ = log.summary();
    }
    Ok(())
}

fn targets() -> Vec<Target> {
    let t = |name, ext, seeds: &[&str], check| Target {
        name,
        ext,
        seeds: seeds.iter().map(|s| seed(s)).collect(),
        check,
    };
    let inline = |name, ext, text: &str, check| Target {
        name,
        ext,
        seeds: vec![text.as_bytes().to_vec()],
        check,
    };
    let f = "crates/io/tests/data/fuzz/";
    vec![
        t("kfgins_imu", "txt", &[&format!("{f}kfgins_imu.txt")], kfgins_imu as Check),
        t("csv_imu", "csv", &[&format!("{f}demo_imu.csv")], csv_imu),
        inline(
            "imu_files",
            "bin",
            "t_s\n100.00\n100.01\n100.02\n100.03\n\0gx,gy,gz\n0.01,0,-0.02\n0.01,0.001,-0.02\n\
             0.011,0,-0.02\n0.01,0,-0.021\n\0t,ax,ay,az\n100.00,0.1,0,-9.8\n100.01,0.1,0,-9.81\n\
             100.02,0.11,0,-9.8\n100.03,0.1,0.01,-9.8\n",
            imu_files,
        ),
        t("gnss_kfgins", "txt", &[&format!("{f}kfgins_gnss.txt")], gnss_kfgins),
        t("gnss_pos", "pos", &[&format!("{f}demo.pos")], gnss_pos),
        t("gnss_nmea", "nmea", &[&format!("{f}gnss.nmea")], gnss_nmea),
        t("gnss_csv", "csv", &[&format!("{f}gnss.csv")], gnss_csv),
        inline(
            "heading",
            "txt",
            "# t heading std\n100.0 10.5 0.2\n100.2 350.0 0.2\n100.4 -179.0 0.5\n101 0 1e-3\n",
            heading,
        ),
        inline(
            "odometer_speed",
            "txt",
            "# t speed\n10.00 1.5\n10.10 1.6\n10.20,1.7\n10.35 0\n",
            odometer_speed,
        ),
        inline(
            "odometer_navfuse",
            "txt",
            "10.0 1000 0 5.0\n10.1 1050 50 5.0\n10.2 1100 50 5.0\n10.3 1151 51 5.1\n",
            odometer_navfuse,
        ),
        inline(
            "dgps",
            "csv",
            "# reference station lat 40.0 deg lon -105.0 deg h 1600.0 m\nt_s,prn,prc_m,rrc_mps,iode\n\
             345600.0,5,-2.5,0.01,77\n345600.0,12,1.25,-0.002,\n345601.0,5,-2.49,0.01,77\n\
             604799.0,7,3.0,0.0,12\n1.0,7,3.1,0.0,12\n",
            dgps,
        ),
        t("nav", "nav", &[&format!("{f}truth.nav")], nav),
        // The shared logs are 1.5 and 4 MB: a synthetic 2 s log (every message type).
        Target {
            name: "ulog",
            ext: "ulg",
            seeds: vec![
                navfuse_io::ulog::synth::synthetic_ulog(2),
                navfuse_io::ulog::synth::synthetic_ulog_separate_imu(2),
            ],
            check: ulog,
        },
        t("rinex_nav", "nav", &[&format!("{f}walk_0827.nav")], rinex_nav),
        t(
            "rinex_obs",
            "obs",
            &[
                "crates/io/tests/data/hand_v211.obs",
                "crates/io/tests/data/walk_0827_3ep_v211.obs",
                "crates/io/tests/data/walk_0827_3ep_v304.obs",
            ],
            rinex_obs,
        ),
        t(
            "rinex_crx",
            "crx",
            &["crates/io/tests/data/esbc_3ep.crx"],
            rinex_obs_all,
        ),
        t(
            "config_toml",
            "toml",
            &[
                "examples/demo/drive_excerpt.toml",
                "examples/drive_0708.toml",
                "examples/drive_0708_nhc.toml",
                "examples/kfgins-synthetic.toml",
                "examples/kfgins-synthetic-outages.toml",
                "examples/walk_0827_tight.toml",
            ],
            config,
        ),
        t("config_yaml", "yaml", &[&format!("{f}kfgins.yaml")], config),
        t(
            "ubx",
            "ubx",
            &[
                &format!("{f}walk_0827_cut.ubx"),
                &format!("{f}walk_0827_sfrbx.ubx"),
            ],
            ubx,
        ),
        // No real ESF / RELPOSNED log: a synthetic 3 s one (ubx::synth).
        Target {
            name: "ubx_esf",
            ext: "ubx",
            seeds: vec![navfuse_io::ubx::synth::synthetic_esf_log(3)],
            check: ubx_esf,
        },
    ]
}

fn env_u64(key: &str) -> Option<u64> {
    let v = std::env::var(key).ok()?;
    let v = v.trim();
    match v.strip_prefix("0x") {
        Some(h) => u64::from_str_radix(h, 16).ok(),
        None => v.parse().ok(),
    }
}

struct Outcome {
    cases: u64,
    failures: Vec<String>,
    elapsed: Duration,
}

/// Run `cases` mutated cases of one target in a worker thread; a case that does not
/// finish within [`HANG`] fails the run.
fn run_target(t: Target, cases: u64, base: u64, dir: PathBuf) -> Outcome {
    let (tx, rx) = mpsc::channel::<(u64, Option<String>)>();
    let name = t.name;
    let worker = std::thread::spawn(move || {
        let file = dir.join(format!("{}.{}", t.name, t.ext));
        for k in 0..cases {
            let case_seed = base ^ k.wrapping_mul(0x9E37_79B9_7F4A_7C15);
            let mut rng = Rng::new(case_seed);
            let s = &t.seeds[rng.below(t.seeds.len())];
            let data = mutate(s, &mut rng);
            if std::fs::write(&file, &data).is_err() {
                let _ = tx.send((case_seed, Some("cannot write the case file".into())));
                return;
            }
            let check = t.check;
            let r = std::panic::catch_unwind(|| check(&file));
            let fail = match r {
                Ok(Ok(())) => None,
                Ok(Err(m)) => Some(m),
                Err(p) => Some(format!(
                    "PANIC: {}",
                    p.downcast_ref::<String>()
                        .cloned()
                        .or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string()))
                        .unwrap_or_default()
                )),
            };
            if fail.is_some() {
                let _ = std::fs::write(dir.join(format!("fail-{}-{case_seed:x}", t.name)), &data);
            }
            if tx.send((case_seed, fail)).is_err() {
                return;
            }
        }
    });
    let start = Instant::now();
    let mut out = Outcome {
        cases: 0,
        failures: Vec::new(),
        elapsed: Duration::ZERO,
    };
    while out.cases < cases {
        match rx.recv_timeout(HANG) {
            Ok((case_seed, fail)) => {
                out.cases += 1;
                if let Some(m) = fail {
                    let m: String = m.chars().take(600).collect();
                    out.failures
                        .push(format!("{name} case seed 0x{case_seed:x}: {m}"));
                }
            }
            Err(mpsc::RecvTimeoutError::Timeout) => {
                out.failures.push(format!(
                    "{name}: HANG, a case ran over {HANG:?} after {} cases",
                    out.cases
                ));
                out.elapsed = start.elapsed();
                return out; // the worker is left behind; the test fails
            }
            Err(mpsc::RecvTimeoutError::Disconnected) => break,
        }
    }
    let _ = worker.join();
    out.elapsed = start.elapsed();
    out
}

#[test]
fn fuzz_every_reader_and_config() {
    let cases = env_u64("NAVFUSE_FUZZ_CASES").unwrap_or(DEFAULT_CASES);
    let base = env_u64("NAVFUSE_FUZZ_SEED").unwrap_or(DEFAULT_SEED);
    let only = std::env::var("NAVFUSE_FUZZ_ONLY").ok();
    let dir = std::env::temp_dir().join(format!("navfuse-fuzz-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // Panics are caught and reported per case; keep their default messages quiet.
    std::panic::set_hook(Box::new(|_| {}));
    let mut failures = Vec::new();
    let mut handles = Vec::new();
    for (i, t) in targets().into_iter().enumerate() {
        if only.as_deref().is_some_and(|o| o != t.name) {
            continue;
        }
        let (d, b) = (dir.clone(), base.wrapping_add((i as u64) << 40));
        let name = t.name;
        handles.push((name, std::thread::spawn(move || run_target(t, cases, b, d))));
        // Two cores: at most two targets at a time.
        if handles.len() == 2 {
            for (name, h) in handles.drain(..) {
                report(name, h.join().unwrap(), &mut failures);
            }
        }
    }
    for (name, h) in handles.drain(..) {
        report(name, h.join().unwrap(), &mut failures);
    }
    let _ = std::panic::take_hook();
    assert!(
        failures.is_empty(),
        "{} failures (base seed 0x{base:x}, inputs saved in {}):\n{}",
        failures.len(),
        dir.display(),
        failures.join("\n")
    );
    let _ = std::fs::remove_dir_all(&dir);
}

fn report(name: &str, o: Outcome, failures: &mut Vec<String>) {
    let rate = o.cases as f64 / o.elapsed.as_secs_f64().max(1e-9);
    println!(
        "fuzz {name}: {} cases in {:.1} s ({rate:.0} cases/s), {} failures",
        o.cases,
        o.elapsed.as_secs_f64(),
        o.failures.len()
    );
    failures.extend(o.failures);
}
