//! Tests of the trajectory compiler and the truth generator.

use super::*;
use navfuse_core::earth::{gravity_normal, lla_diff_ned};

fn start(speed: f64) -> Start {
    Start {
        t0: 100_000.0,
        lla: Vector3::new(30f64.to_radians(), 114f64.to_radians(), 20.0),
        heading_rad: 0.3,
        speed_mps: speed,
    }
}

fn run(traj: &Trajectory, rate: f64) -> Vec<TruthSample> {
    let mut g = TruthGenerator::new(traj, Rig::default(), rate);
    let mut out = vec![g.current()];
    while let Some((_, s)) = g.step() {
        out.push(s);
    }
    out
}

#[test]
fn static_imu_senses_gravity_and_earth_rate() {
    let traj = Trajectory::new(start(0.0), &[Segment::Static { duration_s: 1.0 }]).unwrap();
    let mut g = TruthGenerator::new(&traj, Rig::default(), 100.0);
    let (imu, s) = g.step().unwrap();
    let gn = gravity_normal(30f64.to_radians(), 20.0);
    // Level, heading 0.3: f^b = (0, 0, -g); |w_ib| = earth rate.
    assert!((imu.dvel.z / imu.dt + gn).abs() < 1e-12);
    assert!(imu.dvel.xy().norm() < 1e-14);
    assert!((imu.dtheta.norm() / imu.dt - navfuse_core::earth::OMEGA_IE).abs() < 1e-15);
    assert!(lla_diff_ned(&s.lla, &traj.start.lla).norm() < 1e-9);
}

#[test]
fn accelerate_reaches_speed_and_distance() {
    let segs = [
        Segment::Accelerate {
            accel_mps2: 2.0,
            to_speed_mps: Some(20.0),
            duration_s: None,
            ramp_s: 1.0,
        },
        Segment::Hold { duration_s: 10.0 },
    ];
    let traj = Trajectory::new(start(0.0), &segs).unwrap();
    // 20 m/s at 2 m/s² with 1 s ramps: 1 + 9 + 1 s; distance = 20*11/2 = 110 m + 200 m.
    assert!((traj.duration() - 21.0).abs() < 1e-12);
    let out = run(&traj, 200.0);
    let last = out.last().unwrap();
    assert!((last.speed - 20.0).abs() < 1e-9);
    let d = lla_diff_ned(&last.lla, &traj.start.lla).norm();
    assert!((d - 310.0).abs() < 1e-3, "{d}");
}

#[test]
fn turn_changes_heading_by_angle() {
    let segs = [Segment::Turn {
        rate_dps: 10.0,
        angle_deg: 90.0,
        ramp_s: 2.0,
    }];
    let traj = Trajectory::new(start(10.0), &segs).unwrap();
    assert!((traj.duration() - 11.0).abs() < 1e-12);
    let out = run(&traj, 100.0);
    let d = out.last().unwrap().euler().z - 0.3;
    assert!((d - PI / 2.0).abs() < 1e-9, "{d}");
}

#[test]
fn coordinated_turn_and_climb_end_where_configured() {
    let segs = [
        Segment::CoordinatedTurn {
            rate_dps: 3.0,
            angle_deg: 180.0,
            roll_s: 4.0,
        },
        Segment::Climb {
            vertical_speed_mps: 3.0,
            height_m: 100.0,
            transition_s: 5.0,
        },
        // The run ends at the last whole IMU interval: hold so the climb completes.
        Segment::Hold { duration_s: 1.0 },
    ];
    let traj = Trajectory::new(start(30.0), &segs).unwrap();
    let out = run(&traj, 100.0);
    let last = out.last().unwrap();
    let dyaw = navfuse_core::attitude::wrap_pi(last.euler().z - 0.3 - PI);
    assert!(dyaw.abs() < 1e-6, "{dyaw}");
    assert!(last.euler().x.abs() < 1e-9 && last.euler().y.abs() < 1e-9);
    assert!((last.lla.z - 120.0).abs() < 1e-3, "{}", last.lla.z);
}

#[test]
fn lane_change_offsets_sideways() {
    let segs = [Segment::LaneChange {
        width_m: 3.5,
        duration_s: 5.0,
    }];
    let mut st = start(20.0);
    st.heading_rad = 0.0;
    let traj = Trajectory::new(st, &segs).unwrap();
    let out = run(&traj, 200.0);
    let last = out.last().unwrap();
    let d = lla_diff_ned(&last.lla, &st.lla);
    assert!((d.y - 3.5).abs() < 1e-3, "{d}");
    assert!(last.euler().z.abs() < 1e-9);
}

#[test]
fn bad_segments_are_rejected() {
    let e = Trajectory::new(
        start(0.0),
        &[Segment::Turn {
            rate_dps: 5.0,
            angle_deg: 90.0,
            ramp_s: 0.0,
        }],
    );
    assert!(e.unwrap_err().message.contains("moving"));
    let e = Trajectory::new(start(5.0), &[Segment::Static { duration_s: 1.0 }]);
    assert!(e.is_err());
}
