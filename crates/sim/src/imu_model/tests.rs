//! Tests of the IMU grades and the error model.

use super::error_model::quantize;
use super::*;
use nalgebra::Vector3;

#[test]
fn quantisation_residual_carry_keeps_the_sum() {
    let lsb = 1e-3;
    let mut res = Vector3::zeros();
    let v = Vector3::new(0.2e-3, -0.37e-3, 1.26e-3);
    let (mut sum_in, mut sum_out) = (Vector3::zeros(), Vector3::zeros());
    for _ in 0..10_000 {
        let q = quantize(&v, lsb, &mut res);
        for i in 0..3 {
            let steps = q[i] / lsb;
            assert!((steps - steps.round()).abs() < 1e-9);
        }
        sum_in += v;
        sum_out += q;
        // |carried residual| <= lsb/2; 1e-9 covers the f64 rounding of the sums.
        assert!(res.amax() <= 0.5 * lsb * (1.0 + 1e-9));
        assert!((sum_in - sum_out).amax() <= 0.5 * lsb + 1e-9);
    }
    // Without the carry, 0.2e-3 would always round to 0: the mean would be lost.
    assert!((sum_out[0] / 10_000.0 - 0.2e-3).abs() < 1e-7);
    assert!((sum_out[1] / 10_000.0 + 0.37e-3).abs() < 1e-7);
}

#[test]
fn quantised_model_output_is_on_the_grid_and_unbiased() {
    let spec = ImuSpec {
        grade: "custom".into(),
        gyro_quantization_rad: Some(1e-6),
        accel_quantization_mps: Some(1e-4),
        ..Default::default()
    };
    let mut m = ImuErrorModel::new(&spec.to_grade().unwrap(), 1);
    let true_dth = Vector3::new(3.3e-7, 0.0, -1.7e-6);
    let true_dv = Vector3::new(0.098, 0.0, -2.5e-5);
    let (mut s_th, mut s_v) = (Vector3::zeros(), Vector3::zeros());
    for _ in 0..1000 {
        let (dth, dv) = m.apply(0.01, &true_dth, &true_dv);
        assert!(dth
            .iter()
            .all(|x| ((x / 1e-6) - (x / 1e-6).round()).abs() < 1e-6));
        assert!(dv
            .iter()
            .all(|x| ((x / 1e-4) - (x / 1e-4).round()).abs() < 1e-6));
        s_th += dth;
        s_v += dv;
    }
    assert!((s_th - true_dth * 1000.0).amax() <= 0.5e-6 + 1e-15);
    assert!((s_v - true_dv * 1000.0).amax() <= 0.5e-4 + 1e-12);
}

#[test]
fn perfect_grade_is_identity() {
    let grade = ImuSpec::default().to_grade().unwrap();
    let mut m = ImuErrorModel::new(&grade, 7);
    let th = Vector3::new(1e-3, -2e-3, 3e-3);
    let v = Vector3::new(0.1, 0.2, -0.098);
    for _ in 0..100 {
        assert_eq!(m.apply(0.005, &th, &v), (th, v));
    }
    assert_eq!(m.current_errors(), TrueImuErrors::default());
}

#[test]
fn deterministic_and_scale_misalignment_applied() {
    let spec = ImuSpec {
        grade: "consumer".into(),
        ..Default::default()
    };
    let grade = spec.to_grade().unwrap();
    let mut a = ImuErrorModel::new(&grade, 42);
    let mut b = ImuErrorModel::new(&grade, 42);
    let c = ImuErrorModel::new(&grade, 43);
    let th = Vector3::new(0.01, 0.0, 0.0);
    let v = Vector3::new(0.0, 0.0, -0.098);
    for _ in 0..100 {
        assert_eq!(a.apply(0.01, &th, &v), b.apply(0.01, &th, &v));
    }
    assert_ne!(a.gyro_matrix(), c.gyro_matrix());
    let m = a.gyro_matrix();
    let e = a.current_errors();
    for i in 0..3 {
        assert!((m[(i, i)] - 1.0 - e.gyro_scale[i]).abs() < 1e-15);
    }
    assert!(m[(0, 1)] != 0.0 && m[(2, 0)] != 0.0);
}

#[test]
fn turn_on_bias_statistics() {
    // Across seeds, the turn-on gyro bias has the configured sigma (HG1700 1 deg/h).
    let grade = preset("hg1700").unwrap();
    let n = 4000;
    let mut s2 = 0.0;
    for seed in 0..n {
        let b = ImuErrorModel::new(&grade, seed)
            .current_errors()
            .gyro_bias_rad_s;
        s2 += b.norm_squared() / 3.0;
    }
    let sigma = (s2 / n as f64).sqrt();
    // 12 000 draws: 0.65 % standard error.
    assert!(
        (sigma / DEGPH - 1.0).abs() < 0.03,
        "sigma {} deg/h",
        sigma / DEGPH
    );
}

#[test]
fn kf_gins_units() {
    let e = TrueImuErrors {
        gyro_bias_rad_s: Vector3::new(DEGPH, 0.0, 0.0),
        accel_bias_mps2: Vector3::new(0.0, 1e-5, 0.0),
        gyro_scale: Vector3::new(0.0, 0.0, 1e-6),
        accel_scale: Vector3::new(2e-6, 0.0, 0.0),
    };
    let c = e.kf_gins_columns();
    assert!((c[0] - 1.0).abs() < 1e-12);
    assert!((c[4] - 1.0).abs() < 1e-9);
    assert!((c[8] - 1.0).abs() < 1e-9);
    assert!((c[9] - 2.0).abs() < 1e-9);
    assert_eq!(e.to_core().gyro_bias, e.gyro_bias_rad_s);
}

#[test]
fn spec_parses_and_converts_units() {
    let spec: ImuSpec = toml::from_str(
        "grade = \"imu500\"\nrate_hz = 100\noutput = \"rates\"\n\
         arw_deg_sqrth = 0.6\nvrw_ug_sqrthz = 50\ngyro_scale_ppm = 300\n\
         accel_bias_mg = 2\ngyro_misalignment_mrad = 0.5\ngyro_corr_time_s = inf",
    )
    .unwrap();
    assert_eq!(spec.output, ImuOutput::Rates);
    let g = spec.to_grade().unwrap();
    assert!((g.gyro.white_noise_density - 0.6 * DEG / 60.0).abs() < 1e-15);
    assert!((g.accel.white_noise_density - 50e-6 * G0_MPS2).abs() < 1e-15);
    assert!((g.gyro.scale_sigma - 300e-6).abs() < 1e-15);
    assert!((g.accel.turn_on_bias_sigma - 2.0 * MG).abs() < 1e-15);
    assert!((g.gyro.misalignment_sigma_rad - 5e-4).abs() < 1e-15);
    assert!(g.gyro.bias_corr_time_s.is_infinite());
    // Untouched preset values stay.
    assert!((g.gyro.bias_instability - 0.1 * DEGPH).abs() < 1e-18);
    let d: ImuSpec = toml::from_str("").unwrap();
    assert_eq!(d, ImuSpec::default());
    assert_eq!(d.rate_hz, 200.0);
    assert_eq!(d.output, ImuOutput::Increments);
}

#[test]
fn spec_errors_name_the_key() {
    let bad = |s: &str| ImuSpec {
        grade: s.to_string(),
        ..Default::default()
    };
    let e = bad("hg1800").to_grade().unwrap_err();
    assert!(e.contains("imu.grade") && e.contains("hg1700"), "{e}");
    let e = ImuSpec {
        arw_deg_sqrth: Some(-0.1),
        ..Default::default()
    }
    .to_grade()
    .unwrap_err();
    assert!(e.contains("imu.arw_deg_sqrth") && e.contains(">= 0"), "{e}");
    let e = ImuSpec {
        accel_bias_mg: Some(f64::NAN),
        ..Default::default()
    }
    .to_grade()
    .unwrap_err();
    assert!(
        e.contains("imu.accel_bias_mg") && e.contains("finite"),
        "{e}"
    );
    let e = ImuSpec {
        accel_bias_instability_mg: Some(f64::INFINITY),
        ..Default::default()
    }
    .to_grade()
    .unwrap_err();
    assert!(e.contains("imu.accel_bias_instability_mg"), "{e}");
    let e = ImuSpec {
        gyro_corr_time_s: Some(0.0),
        ..Default::default()
    }
    .to_grade()
    .unwrap_err();
    assert!(
        e.contains("imu.gyro_corr_time_s") && e.contains("> 0"),
        "{e}"
    );
    let e = ImuSpec {
        rate_hz: 0.0,
        ..Default::default()
    }
    .to_grade()
    .unwrap_err();
    assert!(e.contains("imu.rate_hz"), "{e}");
    let e = ImuSpec {
        vrw_mps_sqrth: Some(0.1),
        vrw_ug_sqrthz: Some(20.0),
        ..Default::default()
    }
    .to_grade()
    .unwrap_err();
    assert!(
        e.contains("vrw_mps_sqrth") && e.contains("vrw_ug_sqrthz"),
        "{e}"
    );
    // Unknown keys are rejected by serde (the loader adds file/line).
    let r: Result<ImuSpec, _> = toml::from_str("grade = \"perfect\"\narw = 1.0");
    assert!(r.unwrap_err().to_string().contains("arw"));
}

#[test]
fn every_preset_converts() {
    for name in PRESET_NAMES {
        let g = ImuSpec {
            grade: name.to_string(),
            ..Default::default()
        }
        .to_grade()
        .unwrap();
        assert_eq!(g.name, name);
    }
}
