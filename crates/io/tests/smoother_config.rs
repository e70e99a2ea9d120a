//! `[smoother]` (docs/CONFIG.md): defaults, values, round trip, errors naming the key.

use navfuse_io::config::{load, parse_toml_str};
use navfuse_io::input::{SmootherMode, SmootherSpec};
use std::path::PathBuf;

fn tmp(name: &str, text: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("navfuse-smoothcfg-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    let p = d.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

fn base() -> String {
    let imu = tmp("imu.txt", "");
    format!(
        "[imu]\nfile = {imu:?}\nformat = \"kf-gins\"\nrate_hz = 100\n\n[initial]\nposition_deg_m = [21, 105, 10]\nattitude_deg = [0, 0, 0]\nposition_std_m = 1\nvelocity_std_mps = 0.1\nattitude_std_deg = 1\n\n\
         [imu_noise]\narw_deg_sqrth = 0.1\nvrw_mps_sqrth = 0.1\ngyro_bias_std_degph = 10\naccel_bias_std_mgal = 1000\n\
         gyro_scale_std_ppm = 100\naccel_scale_std_ppm = 100\ncorr_time_h = 1\n"
    )
}

#[test]
fn smoother_section_converts_and_round_trips() {
    let path = tmp("run.toml", "");
    let c = parse_toml_str(&base(), &path).unwrap();
    assert_eq!(c.smoother, SmootherSpec::default());
    assert!(!c.smoother.enabled);
    // A mode alone turns it on.
    let text = base()
        + "\n[smoother]\nmode = \"combined\"\nseparation_sigma = 4\nseparation_period_s = 0\n";
    let c = parse_toml_str(&text, &path).unwrap();
    assert!(c.smoother.enabled);
    assert_eq!(c.smoother.mode, SmootherMode::Combined);
    assert_eq!(c.smoother.separation_sigma, 4.0);
    assert_eq!(c.smoother.separation_period_s, 0.0);
    let back = load(&tmp("rt.toml", &c.to_toml_string())).unwrap();
    assert_eq!(back.smoother, c.smoother);
    let off = base() + "\n[smoother]\nenabled = false\nmode = \"rts\"\n";
    assert!(!parse_toml_str(&off, &path).unwrap().smoother.enabled);
    // Errors name the key and the line.
    let e = parse_toml_str(&(base() + "\n[smoother]\nmode = \"fast\"\n"), &path)
        .unwrap_err()
        .to_string();
    assert!(e.contains("mode") && e.contains("rts"), "{e}");
    let e = parse_toml_str(&(base() + "\n[smoother]\nseparation_sigma = -1\n"), &path)
        .unwrap_err()
        .to_string();
    assert!(e.contains("smoother.separation_sigma"), "{e}");
    let e = parse_toml_str(&(base() + "\n[smoother]\nenable = true\n"), &path)
        .unwrap_err()
        .to_string();
    assert!(e.contains("enable"), "{e}");
}

#[test]
fn output_formats_convert_and_round_trip() {
    let path = tmp("run_fmt.toml", "");
    let text = base() + "\n[output]\nformats = [\"kml\", \"pos\"]\n";
    let c = parse_toml_str(&text, &path).unwrap();
    use navfuse_io::export::ExportFormat;
    assert_eq!(c.output.formats, vec![ExportFormat::Kml, ExportFormat::Pos]);
    let back = load(&tmp("rt_fmt.toml", &c.to_toml_string())).unwrap();
    assert_eq!(back.output.formats, c.output.formats);
    let e = parse_toml_str(&(base() + "\n[output]\nformats = [\"shp\"]\n"), &path)
        .unwrap_err()
        .to_string();
    assert!(e.contains("shp") || e.contains("formats"), "{e}");
}
