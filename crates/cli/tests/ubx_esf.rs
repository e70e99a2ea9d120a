//! The demo's IMU written as u-blox ESF-RAW (with NAV-PVT epochs for the time
//! mapping, output with receiver-like latencies) against the same IMU from its CSV:
//! `navfuse run` on both, the solutions compared with `navfuse eval`
//! (docs/FORMATS.md "ESF-RAW and ESF-MEAS"). Needs no ../shared.

mod common;

use common::{eval_json, num, repo, run, tmp};
use navfuse_io::ubx::synth::{self, ImuRate, Stream};

const G: f64 = 9.80665;
/// The demo's GPS week (imu.csv header).
const WEEK: i32 = 2374;
/// Receiver-like output: ESF-RAW batches of 10 samples 1 ms after the last,
/// NAV-PVT 40 ms after its epoch.
const BATCH: usize = 10;
const NAV_LATENCY_S: f64 = 0.040;

/// (t, accel [g], gyro [deg/s]) rows of examples/demo/imu.csv.
fn demo_imu() -> Vec<(f64, [f64; 3], [f64; 3])> {
    let text = std::fs::read_to_string(repo().join("examples/demo/imu.csv")).unwrap();
    text.lines()
        .skip(2)
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            let v: Vec<f64> = l.split(',').map(|x| x.trim().parse().unwrap()).collect();
            (v[0], [v[1], v[2], v[3]], [v[4], v[5], v[6]])
        })
        .collect()
}

/// The demo IMU as a UBX log: 1 ms tags counted from the first sample's time, a
/// NAV-PVT at every whole second.
fn demo_as_ubx() -> Vec<u8> {
    let rows = demo_imu();
    let t0 = rows[0].0;
    let tag = |t: f64| 10_000 + ((t - t0) * 1000.0).round() as u32;
    let mut st = Stream::default();
    for chunk in rows.chunks(BATCH) {
        let batch: Vec<ImuRate> = chunk
            .iter()
            .map(|(t, a, g)| ImuRate {
                tag: tag(*t),
                gyro: g.map(f64::to_radians),
                accel: a.map(|x| x * G),
            })
            .collect();
        let last = chunk[chunk.len() - 1].0;
        st.push(last + 0.001, synth::esf_raw(&batch));
    }
    let (first, end) = (rows[0].0.ceil() as u32, rows[rows.len() - 1].0 as u32);
    for s in first..=end {
        st.push(
            f64::from(s) + NAV_LATENCY_S,
            synth::nav_pvt_at(WEEK, s * 1000),
        );
    }
    st.finish()
}

#[test]
fn demo_imu_as_esf_raw_matches_the_csv_run() {
    let dir = tmp("ubx-esf-demo");
    std::fs::create_dir_all(&dir).unwrap();
    let ubx = dir.join("demo_imu.ubx");
    std::fs::write(&ubx, demo_as_ubx()).unwrap();
    let demo = repo().join("examples/demo");
    let base = std::fs::read_to_string(demo.join("drive_excerpt.toml")).unwrap();
    // [imu] + [imu.csv] replaced by the UBX log, the rest of the demo as it is.
    let (head, rest) = base.split_once("[imu]").unwrap();
    let (_, after_imu) = rest.split_once("[gnss]").unwrap();
    let config = |offset_s: f64| {
        format!(
            "{head}[imu]\nfile = {:?}\nformat = \"ubx\"\nrate_hz = 100\nsensor_to_body_rpy_deg = [180.0, 0.0, 180.0]\ntime_offset_s = {offset_s}\n\n[gnss]{}",
            ubx.display().to_string(),
            after_imu.replace("file = \"gnss.pos\"", &format!("file = {:?}", demo.join("gnss.pos").display().to_string()))
        )
    };
    let csv_run = dir.join("csv");
    run(&demo.join("drive_excerpt.toml"), &csv_run);
    // The mapped time of the first sample against its CSV time: the latency bias.
    let src = navfuse_io::input::ImuSource {
        path: ubx.clone(),
        format: navfuse_io::input::ImuFormat::Ubx,
        rate_hz: 100.0,
        sensor_to_body_rpy_deg: [0.0; 3],
        time_offset_s: 0.0,
        gap_policy: Default::default(),
    };
    let mut r = navfuse_io::imu::open_imu(&src).unwrap();
    assert_eq!(r.gps_week(), Some(WEEK as u32));
    let rows = demo_imu();
    let bias: Vec<f64> = r
        .by_ref()
        .zip(rows.iter().skip(1))
        .map(|(s, row)| s.unwrap().t - row.0)
        .collect();
    let mean = bias.iter().sum::<f64>() / bias.len() as f64;
    let spread = bias.iter().fold(0f64, |m, b| m.max((b - mean).abs()));
    println!("{}", r.report());
    println!(
        "ESF-RAW times - CSV times: mean {:.2} ms, max deviation from the mean {:.3} ms",
        mean * 1e3,
        spread * 1e3
    );
    // The latency bias (10-sample batches at 100 Hz, 40 ms navigation latency):
    // seen 14.03 ms, constant to the 1 ms tag rounding (0.53 ms).
    assert!(
        mean > 0.0 && mean < NAV_LATENCY_S && spread < 0.001,
        "{mean} {spread}"
    );
    let mut figures = Vec::new();
    for (name, offset) in [("as read", 0.0), ("bias removed", -mean)] {
        let cfg = dir.join(format!("ubx_{}.toml", figures.len()));
        std::fs::write(&cfg, config(offset)).unwrap();
        let out = dir.join(format!("ubx_{}", figures.len()));
        run(&cfg, &out);
        let v = eval_json(
            &out.join("solution.nav"),
            &csv_run.join("solution.nav"),
            &[],
        );
        let h = (
            num(&v, &["position_m", "horizontal", "rms"]),
            num(&v, &["position_m", "horizontal", "max"]),
        );
        let vv = num(&v, &["position_m", "vertical", "max"]);
        let att = num(&v, &["attitude_deg", "total", "max"]);
        let att_rms = num(&v, &["attitude_deg", "total", "rms"]);
        let vel = num(&v, &["velocity_mps", "3d", "max"]);
        println!(
            "UBX ({name}, imu.time_offset_s = {offset:.4}) vs CSV run: horizontal RMS {:.4} max {:.4} m, vertical max {vv:.4} m, velocity max {vel:.4} m/s, attitude RMS {att_rms:.4} max {att:.4} deg",
            h.0, h.1
        );
        figures.push((h, vv, (att_rms, att), vel));
    }
    // Seen (2026-12): as read 1.9 / 16.4 mm horizontal RMS / max, attitude 0.107 /
    // 0.437 deg; bias removed 1.6 / 17.6 mm, 0.112 / 0.442 deg. The inputs then agree to
    // the 1 ms tags and the ESF quanta, and the runs differ as much as the CSV run
    // does from itself with its times rounded to 1 ms (1.4 cm, yaw 0.14 deg max):
    // the yaw of the 35 s standstill at the start is unobservable and wanders.
    for ((h_rms, h_max), vv, (att_rms, att_max), vel) in &figures {
        assert!(
            *h_rms < 0.01 && *h_max < 0.05 && *vv < 0.05 && *vel < 0.05,
            "{figures:?}"
        );
        assert!(*att_rms < 0.3 && *att_max < 1.0, "{figures:?}");
    }
}

/// `rows` of a simulator text file (comment lines skipped), as numbers.
fn table(path: &std::path::Path) -> Vec<Vec<f64>> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
        .map(|l| l.split_whitespace().map(|x| x.parse().unwrap()).collect())
        .collect()
}

/// The simulator's odometer (cumulative pulses, 10 Hz) as ESF-MEAS single ticks
/// (type 10) and its dual-antenna heading as NAV-RELPOSNED v1, with a NAV-PVT each
/// second for the time map: `[odometer]` / `[heading]` `format = "ubx"` give the
/// same runs as the text files.
#[test]
fn simulated_odometer_and_heading_as_ubx_match_the_text_inputs() {
    let dir = tmp("ubx-esf-sim");
    let week = 2381; // both scenarios
    let runs = [("calib_20min", "odometer"), ("seed001_car", "heading")];
    for (scenario, what) in runs {
        let sim = dir.join(scenario);
        common::simulate(&repo().join(format!("scenarios/{scenario}.toml")), &sim);
        let rows = table(&sim.join(format!("{what}.txt")));
        let ms = |t: f64| (t * 1000.0).round() as u32;
        let mut st = Stream::default();
        let (t_first, t_last) = (rows[0][0], rows[rows.len() - 1][0]);
        for r in &rows {
            if what == "odometer" {
                let tag = ms(r[0]) - ms(t_first) + 5000;
                let f = synth::tick_field(r[1] as u64, false);
                st.push(r[0] + 0.002, synth::esf_meas(tag, &[(10, f)]));
            } else {
                st.push(
                    r[0] + 0.041,
                    synth::relposned_v1(ms(r[0]), r[1], r[2], synth::RELPOS_OK),
                );
            }
        }
        for s in t_first.ceil() as u32..=t_last as u32 {
            st.push(f64::from(s) + 0.040, synth::nav_pvt_at(week, s * 1000));
        }
        let ubx = sim.join(format!("{what}.ubx"));
        std::fs::write(&ubx, st.finish()).unwrap();
        let text = std::fs::read_to_string(sim.join("run.toml")).unwrap();
        let changed = if what == "odometer" {
            text.replace(
                "file = \"odometer.txt\"\nformat = \"navfuse\"",
                "file = \"odometer.ubx\"\nformat = \"ubx\"",
            )
        } else {
            text.replace(
                "file = \"heading.txt\"",
                "file = \"heading.ubx\"\nformat = \"ubx\"",
            )
        };
        assert_ne!(
            changed, text,
            "{scenario}: the run.toml section was not found"
        );
        let cfg = sim.join("run_ubx.toml");
        std::fs::write(&cfg, changed).unwrap();
        let (a, b) = (sim.join("out_text"), sim.join("out_ubx"));
        run(&sim.join("run.toml"), &a);
        run(&cfg, &b);
        let v = eval_json(&b.join("solution.nav"), &a.join("solution.nav"), &[]);
        let h = num(&v, &["position_m", "3d", "max"]);
        let att = num(&v, &["attitude_deg", "total", "max"]);
        println!(
            "{scenario}: {what} from UBX vs text: position 3D max {h:.2e} m, attitude max {att:.2e} deg"
        );
        // Odometer: the same pulses at the same times (the map has no bias here:
        // the last ESF-MEAS before each epoch's NAV-PVT is the epoch's own);
        // heading: 1e-5 deg quanta. Seen: odometer 4.0e-9 m / 3.3e-6 deg, heading
        // 1.1e-4 m / 2.9e-6 deg.
        assert!(h < 1e-3 && att < 1e-3, "{scenario}: {h} m, {att} deg");
    }
}
