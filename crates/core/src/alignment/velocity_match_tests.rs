use super::*;
use crate::alignment::synth::{generate, random_motion, Sensors};
use crate::attitude::c_bn_from_euler;
use crate::types::GnssFix;

fn epochs_of(fixes: &[GnssFix], t0: f64, t1: f64) -> Vec<VelEpoch> {
    fixes
        .iter()
        .filter(|f| f.t >= t0 - 1e-9 && f.t <= t1 + 1e-9)
        .map(|f| VelEpoch {
            t: f.t,
            v_n: f.vel_ned.unwrap(),
            var_n: f.vel_std_ned.unwrap().map(|x| x * x),
        })
        .collect()
}

/// Roll, pitch and yaw errors \[deg\] of `c` against `truth` (the rotation between
/// them, resolved in NED: north/east = tilt, down = yaw).
fn errors_deg(c: &Matrix3<f64>, truth: &Matrix3<f64>) -> (f64, f64) {
    let e = Rotation3::from_matrix(&(c * truth.transpose())).scaled_axis();
    (e.xy().norm().to_degrees(), e.z.abs().to_degrees())
}

fn quiet(imu_hz: f64, gnss_hz: f64) -> Sensors {
    Sensors {
        imu_rate_hz: imu_hz,
        gnss_rate_hz: gnss_hz,
        gyro_bias: Vector3::zeros(),
        accel_bias: Vector3::zeros(),
        gyro_scale: Vector3::zeros(),
        arw: 0.0,
        vrw: 0.0,
        vib_accel: 0.0,
        vib_gyro: 0.0,
        lever_arm_b: Vector3::new(0.3, -0.2, -0.8),
        vel_std: 0.0,
        pos_std: 0.0,
        outliers: 0.0,
    }
}

fn setup<'a>(
    imu: &'a [ImuSample],
    ep: &'a [VelEpoch],
    s: &Sensors,
    lla: Vector3<f64>,
    bias_std: f64,
) -> FitSetup<'a> {
    FitSetup {
        samples: imu,
        epochs: ep,
        lla,
        lever_arm_b: s.lever_arm_b,
        vrw: s.vrw.max(1e-4),
        gyro_bias_std: Vector3::repeat(bias_std),
        accel_bias_std: Vector3::repeat(if bias_std > 0.0 { 0.05 } else { 0.0 }),
        gyro_scale_std: Vector3::repeat(if bias_std > 0.0 { 0.005 } else { 0.0 }),
        course: None,
    }
}

#[test]
fn wahba_recovers_a_rotation() {
    let c = c_bn_from_euler(&Vector3::new(2.5, -0.7, -2.0));
    let us = [
        Vector3::new(1.0, 0.2, -9.0),
        Vector3::new(-0.5, 1.0, -9.5),
        Vector3::new(0.3, -2.0, -10.0),
    ];
    let r = wahba(us.iter().map(|u| (1.0, c * u, *u)));
    assert!((r - c).norm() < 1e-12, "{r}");
}

/// Exact data, a flying body turning and accelerating: the attitude at the window
/// start is found to 0.01 deg whatever the IMU and GNSS rates.
#[test]
fn noiseless_motion_gives_the_attitude() {
    for (seed, imu_hz, gnss_hz) in [
        (1, 100.0, 1.0),
        (2, 200.0, 5.0),
        (3, 50.0, 10.0),
        (4, 400.0, 2.0),
    ] {
        let m = random_motion(seed, true, true);
        let s = quiet(imu_hz, gnss_hz);
        let (imu, fixes) = generate(&m, &s, 12.0, seed);
        let ep = epochs_of(&fixes, m.t0 + 1.0, m.t0 + 11.0);
        let f = fit(&setup(&imu, &ep, &s, m.lla0, 0.0)).expect("fit");
        let (tilt, yaw) = errors_deg(&f.c_bn, &m.c_bn(ep[0].t));
        assert!(
            tilt < 0.01 && yaw < 0.02,
            "seed {seed}: tilt {tilt} yaw {yaw} deg"
        );
        assert_eq!(f.inliers, f.epochs);
    }
}

/// Sweep over random geometry (attitudes, sites, headings, a car or a UAV), seeds,
/// IMU and GNSS rates, with MEMS gyro biases of 0.3 deg/s and scale errors of 0.5 %
/// (estimated), accelerometer biases, white noise, engine vibration and 10 % gross
/// GNSS outliers: roll and pitch
/// within 1 deg; where the fit claims yaw 1-sigma below 1 deg, yaw within 2 deg, and
/// the claimed sigmas cover the errors (4 sigma plus the accelerometer-bias tilt).
#[test]
fn sweep_random_geometry_rates_bias_and_outliers() {
    let mut worst = (0.0f64, 0.0f64);
    let mut yaw_found = 0;
    let rates = [
        (100.0, 1.0),
        (200.0, 10.0),
        (50.0, 5.0),
        (400.0, 2.0),
        (125.0, 4.0),
    ];
    for seed in 0..30u64 {
        let uav = seed % 2 == 1;
        let m = random_motion(seed, uav, true);
        let (imu_hz, gnss_hz) = rates[seed as usize % rates.len()];
        let bias = 0.3f64.to_radians();
        let s = Sensors {
            gyro_bias: Vector3::new(bias, -0.6 * bias, 0.8 * bias),
            accel_bias: Vector3::new(0.02, -0.03, 0.04),
            gyro_scale: Vector3::new(0.004, -0.003, 0.005),
            arw: 0.2f64.to_radians() / 60.0,
            vrw: 0.1 / 60.0,
            vib_accel: 0.1,
            vib_gyro: 1.5f64.to_radians(),
            vel_std: 0.05,
            pos_std: 0.5,
            outliers: 0.1,
            ..quiet(imu_hz, gnss_hz)
        };
        let (imu, fixes) = generate(&m, &s, 22.0, 100 + seed);
        let ep = epochs_of(&fixes, m.t0 + 1.0, m.t0 + 21.0);
        let f = fit(&setup(&imu, &ep, &s, m.lla0, 0.5f64.to_radians())).expect("fit");
        let (tilt, yaw) = errors_deg(&f.c_bn, &m.c_bn(ep[0].t));
        eprintln!("seed {seed} uav {uav} {imu_hz}/{gnss_hz} Hz: tilt {tilt:.3} (sd {:.3}) yaw {yaw:.3} (sd {:.3}) scale {:.2} inl {}/{} bias {:?}", f.tilt_std().to_degrees(), f.yaw_std().to_degrees(), f.scale, f.inliers, f.epochs, (f.gyro_bias - s.gyro_bias).map(|x| x.to_degrees()));
        let ba_tilt = (0.05f64 / 9.8).to_degrees();
        assert!(tilt < 1.0, "seed {seed}: tilt {tilt:.3} deg, fit {f:?}");
        assert!(
            tilt < 4.0 * f.tilt_std().to_degrees() + ba_tilt,
            "seed {seed}: tilt {tilt:.3} deg against 1-sigma {:.3}",
            f.tilt_std().to_degrees()
        );
        if f.yaw_std() < 1f64.to_radians() {
            yaw_found += 1;
            assert!(
                yaw < 2.0,
                "seed {seed}: yaw {yaw:.3} deg, sigma {:.3}",
                f.yaw_std().to_degrees()
            );
            worst.1 = worst.1.max(yaw);
        }
        worst.0 = worst.0.max(tilt);
        let b_err = (f.gyro_bias - s.gyro_bias).xy().norm().to_degrees();
        assert!(
            b_err < 0.1,
            "seed {seed}: horizontal gyro bias off by {b_err:.3} deg/s"
        );
    }
    eprintln!("30 windows: worst tilt {:.3} deg, worst yaw {:.3} deg ({yaw_found} with yaw sigma < 1 deg)", worst.0, worst.1);
    assert!(
        yaw_found >= 15,
        "yaw determined in only {yaw_found} of 30 windows"
    );
}

/// Without the reweighting a gross GNSS velocity error tilts the fit; with it the
/// bad interval is dropped.
#[test]
fn a_gross_velocity_error_is_rejected() {
    let m = random_motion(7, false, true);
    let s = Sensors {
        vel_std: 0.03,
        ..quiet(100.0, 2.0)
    };
    let (imu, fixes) = generate(&m, &s, 12.0, 7);
    let mut ep = epochs_of(&fixes, m.t0 + 1.0, m.t0 + 11.0);
    ep[8].v_n += Vector3::new(6.0, -4.0, 3.0);
    let f = fit(&setup(&imu, &ep, &s, m.lla0, 0.0)).expect("fit");
    let (tilt, _) = errors_deg(&f.c_bn, &m.c_bn(ep[0].t));
    assert!(tilt < 0.2, "tilt {tilt}");
    assert_eq!(f.inliers, f.epochs - 1, "{f:?}");
}

/// A car with a known mounting: held to the course, the yaw is the course plus the
/// mounting yaw even on a straight stretch where the fit alone cannot see it.
#[test]
fn course_hold_gives_the_yaw_of_a_car() {
    let mut m = random_motion(12, false, true);
    m.vel[0].terms.clear();
    m.vel[1].terms.clear();
    m.vel[2].terms.clear();
    let mount = m.yaw_course_offset.unwrap();
    let s = Sensors {
        vel_std: 0.05,
        vrw: 0.1 / 60.0,
        ..quiet(100.0, 5.0)
    };
    let (imu, fixes) = generate(&m, &s, 8.0, 12);
    let ep = epochs_of(&fixes, m.t0 + 1.0, m.t0 + 7.0);
    let mut st = setup(&imu, &ep, &s, m.lla0, 0.0);
    let free = fit(&st).expect("fit");
    assert!(free.yaw_std() > 5f64.to_radians(), "{free:?}");
    st.course = Some(CourseHold {
        c_bm: c_bn_from_euler(&Vector3::new(0.0, 0.0, mount)),
        min_speed_mps: 3.0,
        std_rad: 1f64.to_radians(),
        turn_lever_m: 2.0,
    });
    let f = fit(&st).expect("fit");
    let (tilt, yaw) = errors_deg(&f.c_bn, &m.c_bn(ep[0].t));
    eprintln!(
        "course: tilt {tilt} sd {} yaw {yaw} sd {}; free: {:?}",
        f.tilt_std().to_degrees(),
        f.yaw_std().to_degrees(),
        errors_deg(&free.c_bn, &m.c_bn(ep[0].t))
    );
    assert!(tilt < 0.1 && yaw < 0.5, "tilt {tilt} yaw {yaw}");
    assert_eq!(f.courses, ep.len());
}
