//! The start of `mode = "auto"` on synthetic data (alignment::synth): in motion it
//! starts at the first GNSS epoch of its window with the GNSS state there and
//! navigates every IMU sample after it; an idling engine's vibration is static, a
//! creeping vehicle is not.

use super::start::find_start;
use super::tests::cfg;
use crate::alignment::synth::{generate, random_motion, Motion, Sensors, Wave};
use crate::attitude::c_bn_from_euler;
use crate::config::{AttitudeInit, NavConfig};
use crate::earth::lla_diff_ned;
use crate::nav::navigator::NavError;
use crate::types::{ImuSample, Measurement};
use nalgebra::{Rotation3, Vector3};

fn sensors(imu_hz: f64, gnss_hz: f64) -> Sensors {
    Sensors {
        imu_rate_hz: imu_hz,
        gnss_rate_hz: gnss_hz,
        gyro_bias: Vector3::new(0.001, -0.0015, 0.002),
        accel_bias: Vector3::new(0.01, -0.02, 0.015),
        gyro_scale: Vector3::zeros(),
        arw: 0.3f64.to_radians() / 60.0,
        vrw: 0.05 / 60.0,
        vib_accel: 0.1,
        vib_gyro: 1.5f64.to_radians(),
        lever_arm_b: Vector3::new(0.4, 0.0, -1.1),
        vel_std: 0.05,
        pos_std: 0.5,
        outliers: 0.0,
    }
}

fn auto_cfg(s: &Sensors) -> NavConfig {
    let mut c = cfg();
    c.initial.lla = None;
    c.initial.attitude = AttitudeInit::default();
    c.initial.att_std = Vector3::new(1.0, 1.0, 5.0).map(f64::to_radians);
    c.initial.imu_errors_std.gyro_bias = Vector3::repeat(0.003);
    c.initial.imu_errors_std.accel_bias = Vector3::repeat(0.03);
    c.gnss.lever_arm_b = s.lever_arm_b;
    c
}

/// Tilt and yaw error \[deg\] of rpy against C_b^n `truth`.
fn att_err(rpy: &Vector3<f64>, truth: &nalgebra::Matrix3<f64>) -> (f64, f64) {
    let e = Rotation3::from_matrix(&(c_bn_from_euler(rpy) * truth.transpose())).scaled_axis();
    (e.xy().norm().to_degrees(), e.z.abs().to_degrees())
}

/// Today's `auto` read a 10 s levelling window, found motion, and started at the
/// first pair of fixes with an empty replay: the rest of the window was lost and the
/// output began seconds late, the vehicle far from its start position. Now: the
/// start is the first GNSS epoch of the aligning window (here the first fix), the
/// state is the GNSS state there, and every later IMU sample is navigated. Sweep
/// over seeds (sites, headings, car or UAV) and IMU / GNSS rates.
#[test]
fn auto_in_motion_starts_at_its_window_and_loses_no_samples() {
    let rates = [(100.0, 10.0), (200.0, 5.0), (50.0, 1.0), (400.0, 2.0)];
    for seed in 0..8u64 {
        let (imu_hz, gnss_hz) = rates[seed as usize % rates.len()];
        let m = random_motion(seed, seed % 2 == 1, true);
        let s = sensors(imu_hz, gnss_hz);
        let (imu, fixes) = generate(&m, &s, 40.0, seed);
        let mut c = auto_cfg(&s);
        // A car's IMU mounting yaw is configured (the course is the car's heading).
        c.vehicle.mounting_rpy.z = m.yaw_course_offset.unwrap_or(0.0);
        let meas: Vec<Measurement> = fixes.iter().map(|f| Measurement::Gnss(*f)).collect();
        let mut it = imu[1..].iter().map(|x| Ok::<ImuSample, NavError>(*x));
        let start = find_start(&c, imu[0], &mut it, &meas).unwrap().unwrap();
        let rest = it.count();
        // Everything after the start is navigated.
        let k0 = imu.iter().position(|x| x.t >= start.t0 - 1e-9).unwrap();
        assert_eq!(start.replay.len() + rest, imu.len() - k0 - 1, "seed {seed}");
        assert!(
            start.method.starts_with("in motion"),
            "seed {seed}: {}",
            start.method
        );
        // The window starts at the first fix (the first IMU epoch at or after it).
        assert!(
            start.t0 - fixes[0].t < 1.0 / imu_hz + 1e-9,
            "seed {seed}: {}",
            start.t0
        );
        let (tilt, yaw) = att_err(&start.rpy, &m.c_bn(start.t0));
        let dp = lla_diff_ned(&start.lla, &m.lla(start.t0)).norm();
        let dv = (start.v_n - m.v_n(start.t0)).norm();
        assert!(
            tilt < 1.0 && yaw < 2.0,
            "seed {seed}: tilt {tilt:.2} yaw {yaw:.2} deg; {}",
            start.reason
        );
        // The first fix's own error (white, 3 sigma of the 3-D vector).
        let p_bound = 3.0 * 3f64.sqrt() * s.pos_std;
        assert!(
            dp < p_bound && dv < 0.3,
            "seed {seed}: {dp:.2} m {dv:.3} m/s"
        );
    }
}

/// A parked vehicle whose engine shakes the IMU by 0.17 m/s² and 2.6 deg/s (RMS of the
/// vector), the GNSS at rest: static (levelling), although the configured ZUPT
/// thresholds (0.05 m/s², 0.5 deg/s) are far below the vibration. The same vibration
/// on a vehicle creeping at 0.6 m/s is not static.
#[test]
fn idling_engine_is_static_and_creeping_is_not() {
    for seed in 0..4u64 {
        let parked = random_motion(seed, false, false);
        let creeping = Motion {
            vel: [
                Wave::constant(0.6 * 0.3f64.cos()),
                Wave::constant(0.6 * 0.3f64.sin()),
                Wave::constant(0.0),
            ],
            ..parked.clone()
        };
        let s = sensors(100.0, 5.0);
        for (m, moving) in [(&parked, false), (&creeping, true)] {
            let (imu, fixes) = generate(m, &s, 15.0, seed);
            let c = auto_cfg(&s);
            let meas: Vec<Measurement> = fixes.iter().map(|f| Measurement::Gnss(*f)).collect();
            let mut it = imu[1..].iter().map(|x| Ok::<ImuSample, NavError>(*x));
            let start = find_start(&c, imu[0], &mut it, &meas);
            if moving {
                // Never fast enough for a course and no acceleration: no attitude,
                // and the message says the first window moved.
                let e = start.err().expect("creeping must not align static");
                assert!(e.0.contains("moved (GNSS speed up to 0."), "{}", e.0);
            } else {
                let st = start.unwrap().unwrap();
                assert!(st.method.starts_with("static levelling"), "{}", st.method);
                assert!(st.reason.contains("window 10.0 s static"), "{}", st.reason);
                // Levelling errs by the horizontal accelerometer bias over g.
                let (tilt, _) = att_err(&st.rpy, &m.c_bn(st.t0));
                let bound = (s.accel_bias.xy().norm() / 9.8).to_degrees() + 0.1;
                assert!(tilt < bound, "seed {seed}: tilt {tilt:.3} > {bound:.3} deg");
                // The whole window is navigated.
                assert_eq!(st.t0, imu[0].t);
            }
        }
    }
}
