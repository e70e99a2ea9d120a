//! Static Allan-deviation checks of the IMU grades (docs/SIM_IMU.md).
//!
//! Each grade is simulated at rest (zero true increments) at 100 Hz. The white-noise
//! coefficients (ARW/VRW) are read from the first 2 h at full rate; the bias
//! instability from a 24 h record (integral kept every 1 s), because a 2 h record
//! holds only 72 correlation times of a 100 s Gauss-Markov bias: its Allan peak then
//! scatters by about 10 % (1 sigma) between realisations, too much for a 10 % check per
//! axis. The 2 h bias-instability figures are printed for comparison.

use std::time::Instant;

use nalgebra::Vector3;
use navfuse_core::allan::{
    allan_deviation_integrated, bias_instability_from_minimum, bias_instability_gm_floor,
    log_slope, log_spaced_clusters, white_noise_coefficient,
};
use navfuse_sim::imu_model::{preset, ImuErrorModel, ImuGrade};

const RATE_HZ: f64 = 100.0;
const DT: f64 = 1.0 / RATE_HZ;
const SHORT_S: f64 = 7200.0;
const DECIM: usize = 100; // long record: integral every 1 s
const TOL: f64 = 0.10;

/// Integrated outputs: 6 channels (gyro x y z, accel x y z).
struct Record {
    short: Vec<Vec<f64>>,
    long: Vec<Vec<f64>>,
}

fn simulate(grade: &ImuGrade, seed: u64, hours: f64) -> Record {
    let n = (hours * 3600.0 * RATE_HZ).round() as usize;
    let n_short = (SHORT_S * RATE_HZ) as usize;
    let mut model = ImuErrorModel::new(grade, seed);
    let mut short: Vec<Vec<f64>> = (0..6).map(|_| Vec::with_capacity(n_short + 1)).collect();
    let mut long: Vec<Vec<f64>> = (0..6).map(|_| Vec::with_capacity(n / DECIM + 1)).collect();
    let mut acc = [0.0f64; 6];
    for ch in 0..6 {
        short[ch].push(0.0);
        long[ch].push(0.0);
    }
    let zero = Vector3::zeros();
    for k in 1..=n {
        let (dth, dv) = model.apply(DT, &zero, &zero);
        for i in 0..3 {
            acc[i] += dth[i];
            acc[3 + i] += dv[i];
        }
        if k <= n_short {
            for ch in 0..6 {
                short[ch].push(acc[ch]);
            }
        }
        if k % DECIM == 0 {
            for ch in 0..6 {
                long[ch].push(acc[ch]);
            }
        }
    }
    Record { short, long }
}

struct Figures {
    white: f64,
    slope: f64,
    bi_short: Option<f64>,
    bi_long: Option<(f64, f64)>,
    min_long: Option<f64>,
}

fn analyse(rec: &Record, ch: usize, with_long: bool) -> Figures {
    let x = &rec.short[ch];
    let curve = allan_deviation_integrated(x, DT, &log_spaced_clusters(x.len() - 1, 10));
    // White region: 0.01-0.1 s (below every grade's bias-instability rise).
    let white = white_noise_coefficient(&curve, 0.009, 0.11).unwrap();
    let slope = log_slope(&curve, 0.009, 0.11).unwrap();
    let short_cut: Vec<(f64, f64)> = curve
        .iter()
        .copied()
        .filter(|(t, _)| *t <= SHORT_S / 10.0)
        .collect();
    let bi_short = bias_instability_gm_floor(&short_cut, white).map(|p| p.1);
    let (bi_long, min_long) = if with_long {
        let xl = &rec.long[ch];
        let dtl = DT * DECIM as f64;
        let cl: Vec<(f64, f64)> =
            allan_deviation_integrated(xl, dtl, &log_spaced_clusters(xl.len() - 1, 10))
                .into_iter()
                .filter(|(t, _)| *t <= xl.len() as f64 * dtl / 10.0)
                .collect();
        (
            bias_instability_gm_floor(&cl, white),
            bias_instability_from_minimum(&cl).map(|p| p.1),
        )
    } else {
        (None, None)
    };
    Figures {
        white,
        slope,
        bi_short,
        bi_long,
        min_long,
    }
}

fn check_grade(name: &str, seed: u64, hours: f64, check_bi: bool) {
    let grade = preset(name).unwrap();
    let t0 = Instant::now();
    let rec = simulate(&grade, seed, hours);
    let t_sim = t0.elapsed().as_secs_f64();
    let mut failures = Vec::new();
    for ch in 0..6 {
        let (label, e, unit_white, unit_bi, sw, sb) = if ch < 3 {
            let d = std::f64::consts::PI / 180.0;
            (
                "gyro",
                &grade.gyro,
                "deg/sqrt(h)",
                "deg/h",
                d / 60.0,
                d / 3600.0,
            )
        } else {
            (
                "accel",
                &grade.accel,
                "m/s/sqrt(h)",
                "mg",
                1.0 / 60.0,
                9.806_65e-3,
            )
        };
        let axis = ["x", "y", "z"][ch % 3];
        let f = analyse(&rec, ch, check_bi);
        let w_ratio = f.white / e.white_noise_density;
        println!(
            "{name} {label}.{axis}: white {:.5} vs {:.5} {unit_white} ({:+.2} %), slope {:.3}",
            f.white / sw,
            e.white_noise_density / sw,
            (w_ratio - 1.0) * 100.0,
            f.slope
        );
        if (w_ratio - 1.0).abs() > TOL {
            failures.push(format!("{label}.{axis} white ratio {w_ratio:.4}"));
        }
        if (f.slope + 0.5).abs() > 0.05 {
            failures.push(format!("{label}.{axis} white slope {:.3}", f.slope));
        }
        if check_bi {
            let b = e.bias_instability;
            let (tau, bl) = f.bi_long.expect("no bias-instability bump found");
            println!(
                "{name} {label}.{axis}: B 24 h {:.5} (peak at {:.0} s), 2 h {:.5}, \
                 24 h min/0.664 {:.5}, configured {:.5} {unit_bi} ({:+.2} %)",
                bl / sb,
                tau,
                f.bi_short.unwrap_or(f64::NAN) / sb,
                f.min_long.unwrap_or(f64::NAN) / sb,
                b / sb,
                (bl / b - 1.0) * 100.0
            );
            if (bl / b - 1.0).abs() > TOL {
                failures.push(format!(
                    "{label}.{axis} bias instability ratio {:.4}",
                    bl / b
                ));
            }
        }
    }
    println!(
        "{name}: {hours} h at {RATE_HZ} Hz simulated in {t_sim:.2} s, total {:.2} s",
        t0.elapsed().as_secs_f64()
    );
    assert!(failures.is_empty(), "{name}: {failures:?}");
}

#[test]
fn adis16405_static_allan() {
    check_grade("adis16405", 2024, 24.0, true);
}

#[test]
fn imu500_static_allan() {
    check_grade("imu500", 2025, 24.0, true);
}

#[test]
fn hg1700_static_white_noise() {
    // No bias instability in the preset (one "bias" figure on the spec sheet).
    check_grade("hg1700", 2026, 2.0, false);
}

#[test]
fn one_hour_at_200_hz_is_fast() {
    let grade = preset("adis16405").unwrap();
    let mut model = ImuErrorModel::new(&grade, 1);
    let th = Vector3::new(1e-4, -2e-4, 5e-5);
    let dv = Vector3::new(1e-3, 0.0, -0.049);
    let t0 = Instant::now();
    let mut sink = Vector3::zeros();
    for _ in 0..720_000 {
        let (a, b) = model.apply(0.005, &th, &dv);
        sink += a + b;
    }
    let t = t0.elapsed().as_secs_f64();
    println!("720 000 samples in {t:.3} s ({sink:?})");
    if !cfg!(debug_assertions) {
        assert!(t < 1.0, "720 000 samples took {t:.3} s");
    }
}
