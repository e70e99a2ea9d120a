//! The barometer reader and `[baro]` (docs/FORMATS.md "Barometer", CONFIG.md).

use navfuse_core::aiding::baro::{pressure_at_altitude_pa, ISA_P0_PA};
use navfuse_io::baro::{read_baro, BaroQuantity, BaroSource};
use navfuse_io::config::{load, parse_toml_str};
use std::path::PathBuf;

fn tmp(name: &str, text: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("navfuse-baro-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    let p = d.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

fn src(path: PathBuf, quantity: BaroQuantity, delay_s: f64) -> BaroSource {
    BaroSource {
        path,
        quantity,
        reference_pressure_pa: ISA_P0_PA,
        delay_s,
        format: Default::default(),
        skip_lines: None,
    }
}

#[test]
fn pressures_become_heights_with_the_delay_removed() {
    let p1 = pressure_at_altitude_pa(120.0, ISA_P0_PA);
    let p2 = pressure_at_altitude_pa(121.5, ISA_P0_PA);
    let text = format!("time pressure\n# a comment\n100.0 {p1:.4}\n100.1, {p2:.4}\n");
    let mut w = Vec::new();
    let out = read_baro(
        &src(tmp("ok.txt", &text), BaroQuantity::PressurePa, 0.05),
        &mut w,
    )
    .unwrap();
    assert!(w.is_empty());
    assert_eq!(out.len(), 2);
    assert!((out[0].t - 99.95).abs() < 1e-12 && (out[1].t - 100.05).abs() < 1e-12);
    assert!(
        (out[0].height_m - 120.0).abs() < 1e-3,
        "{}",
        out[0].height_m
    );
    assert!((out[1].height_m - 121.5).abs() < 1e-3);
    // hPa and heights.
    let text = format!("1 {:.6}\n2 {:.6}\n", p1 / 100.0, p2 / 100.0);
    let out = read_baro(
        &src(tmp("hpa.txt", &text), BaroQuantity::PressureHpa, 0.0),
        &mut w,
    )
    .unwrap();
    assert!((out[1].height_m - 121.5).abs() < 1e-2);
    let out = read_baro(
        &src(tmp("h.txt", "1 10.5\n2 11\n"), BaroQuantity::HeightM, 0.0),
        &mut w,
    )
    .unwrap();
    assert_eq!(out[1].height_m, 11.0);
}

#[test]
fn bad_records_name_file_line_and_field() {
    let mut w = Vec::new();
    // hPa given as Pa: the message names the likely mistake.
    let p = tmp("unit.txt", "1 1013.2\n2 1013.1\n");
    let e = read_baro(&src(p.clone(), BaroQuantity::PressurePa, 0.0), &mut w)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("unit.txt:1") && e.contains("value") && e.contains("hPa"),
        "{e}"
    );
    let e = read_baro(
        &src(
            tmp("cols.txt", "1 101000 3\n"),
            BaroQuantity::PressurePa,
            0.0,
        ),
        &mut w,
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("cols.txt:1") && e.contains("2"), "{e}");
    let e = read_baro(
        &src(
            tmp("back.txt", "2 101000\n1 101000\n"),
            BaroQuantity::PressurePa,
            0.0,
        ),
        &mut w,
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("back.txt:2"), "{e}");
    // kPa, and a pressure file read as heights.
    let e = read_baro(
        &src(tmp("kpa.txt", "1 101.3\n"), BaroQuantity::PressurePa, 0.0),
        &mut w,
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("kPa"), "{e}");
    let e = read_baro(
        &src(tmp("ph.txt", "1 101300\n"), BaroQuantity::HeightM, 0.0),
        &mut w,
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("ph.txt:1") && e.contains("pressure_pa"), "{e}");
    // A last line cut mid-write is dropped with a warning.
    let out = read_baro(
        &src(
            tmp("cut.txt", "1 101000\n2 1010"),
            BaroQuantity::PressurePa,
            0.0,
        ),
        &mut w,
    )
    .unwrap();
    assert_eq!(out.len(), 1);
    assert_eq!(w.len(), 1, "{w:?}");
}

#[test]
fn the_section_converts_and_round_trips() {
    let baro = tmp("b.txt", "1 101000\n");
    let imu = tmp("imu.txt", "");
    let text = format!(
        "[imu]\nfile = {imu:?}\nformat = \"kf-gins\"\nrate_hz = 100\n\n[initial]\nposition_deg_m = [21, 105, 10]\nattitude_deg = [0, 0, 0]\nposition_std_m = 1\nvelocity_std_mps = 0.1\nattitude_std_deg = 1\n\n\
         [imu_noise]\narw_deg_sqrth = 0.1\nvrw_mps_sqrth = 0.1\ngyro_bias_std_degph = 10\naccel_bias_std_mgal = 1000\n\
         gyro_scale_std_ppm = 100\naccel_scale_std_ppm = 100\ncorr_time_h = 1\n\n\
         [baro]\nfile = {baro:?}\nquantity = \"pressure_hpa\"\nstd_m = 0.8\nbias_drift_m_per_sqrth = 2\ndelay_s = 0.02\n"
    );
    let path = tmp("run.toml", &text);
    let c = parse_toml_str(&text, &path).unwrap();
    let b = c.baro.as_ref().unwrap();
    assert_eq!(b.quantity, BaroQuantity::PressureHpa);
    assert_eq!(b.delay_s, 0.02);
    assert!(c.nav.baro.enabled);
    assert_eq!(c.nav.baro.std_m, 0.8);
    assert!((c.nav.baro.bias_random_walk - 2.0 / 60.0).abs() < 1e-15);
    let back = load(&tmp("rt.toml", &c.to_toml_string())).unwrap();
    assert_eq!(back.baro, c.baro);
    assert_eq!(back.nav.baro, c.nav.baro);
    // A bad key names the section.
    let bad = text.replace("std_m = 0.8", "std_m = -1");
    let e = parse_toml_str(&bad, &path).unwrap_err().to_string();
    assert!(e.contains("baro.std_m"), "{e}");
}
