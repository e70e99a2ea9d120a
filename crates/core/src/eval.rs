//! Scoring a solution against a reference: RMS and maximum of the N/E/D,
//! horizontal, vertical and 3D position errors, velocity and attitude errors, and
//! per-outage maxima with their RMS (the KF-GINS paper's outage statistic).
//!
//! The solution is linearly interpolated to each reference epoch (the attitude by
//! spherical interpolation of the quaternions); reference epochs outside the
//! solution, or where the solution has a hole longer than `max_interp_gap_s`, are
//! skipped and counted.
//!
//! The attitude error is the rotation from the reference attitude to the solution's,
//! C_err = C_b,ref^T C_b,sol, taken as a rotation vector in the reference body frame:
//! its x, y, z components are the roll, pitch and yaw errors (equal to the Euler
//! angle differences when level, and still meaningful near pitch +-90 deg, where
//! Euler differences are not), its norm the total attitude error.

use crate::attitude::{c_bn_from_euler, euler_from_q_bn, q_bn_from_euler, wrap_pi};
use crate::earth::{lla_add_ned, lla_diff_ned};
use crate::outage::Window;
use nalgebra::Vector3;

/// One epoch of a trajectory (solution or reference).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrajPoint {
    pub t: f64,
    /// Latitude \[rad\], longitude \[rad\], height \[m\].
    pub lla: Vector3<f64>,
    /// NED velocity \[m/s\], if known.
    pub v_n: Option<Vector3<f64>>,
    /// Roll, pitch, yaw \[rad\], if known.
    pub rpy: Option<Vector3<f64>>,
}

#[derive(Clone, Debug, PartialEq)]
pub struct EvalOptions {
    /// Outage windows for the per-gap statistic (reference epochs with a < t < b).
    pub gaps: Vec<Window>,
    /// Move the solution from the IMU centre to this body-frame point before
    /// comparing (e.g. the antenna, when the reference is an antenna track) \[m\].
    pub lever_arm_b: Option<Vector3<f64>>,
    /// Do not interpolate across solution holes longer than this \[s\].
    pub max_interp_gap_s: f64,
    /// Keep every scored epoch's errors in [`EvalReport::per_epoch`].
    pub keep_epochs: bool,
}

impl Default for EvalOptions {
    fn default() -> Self {
        EvalOptions {
            gaps: Vec::new(),
            lever_arm_b: None,
            max_interp_gap_s: 1.0,
            keep_epochs: false,
        }
    }
}

/// RMS, maximum absolute value and mean of one error component.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Stat {
    pub rms: f64,
    pub max: f64,
    pub mean: f64,
}

#[derive(Default)]
struct Acc {
    sum: f64,
    sum2: f64,
    max: f64,
    n: usize,
}

impl Acc {
    fn add(&mut self, e: f64) {
        self.sum += e;
        self.sum2 += e * e;
        self.max = self.max.max(e.abs());
        self.n += 1;
    }
    fn stat(&self) -> Stat {
        if self.n == 0 {
            return Stat::default();
        }
        let n = self.n as f64;
        Stat {
            rms: (self.sum2 / n).sqrt(),
            max: self.max,
            mean: self.sum / n,
        }
    }
}

/// Errors of one scored epoch (solution minus reference).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EpochError {
    pub t: f64,
    /// Position N, E, D \[m\].
    pub pos_ned: Vector3<f64>,
    pub horizontal: f64,
    /// Along-track (positive ahead) and cross-track (positive to the right) \[m\], by
    /// the reference's horizontal velocity (or its track between neighbouring
    /// epochs); None below 0.5 m/s.
    pub along_cross: Option<(f64, f64)>,
    /// Velocity N, E, D \[m/s\].
    pub vel_ned: Option<Vector3<f64>>,
    /// Attitude error, body-frame rotation vector (roll, pitch, yaw) \[rad\].
    pub att: Option<Vector3<f64>>,
}

/// Below this horizontal speed the along/cross-track split is not made \[m/s\].
const MIN_TRACK_SPEED_MPS: f64 = 0.5;

/// Maxima inside one outage window.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GapReport {
    pub start: f64,
    pub end: f64,
    pub epochs: usize,
    pub max_horizontal: f64,
    pub max_vertical: f64,
    pub max_3d: f64,
    pub max_roll: f64,
    pub max_pitch: f64,
    pub max_yaw: f64,
}

#[derive(Clone, Debug, Default, PartialEq)]
pub struct EvalReport {
    pub epochs: usize,
    pub skipped: usize,
    pub t_first: f64,
    pub t_last: f64,
    pub north: Stat,
    pub east: Stat,
    pub down: Stat,
    pub horizontal: Stat,
    pub vertical: Stat,
    pub pos_3d: Stat,
    /// Velocity N, E, D and 3D \[m/s\] (when both sides have velocity).
    pub vel: Option<[Stat; 4]>,
    /// Roll, pitch, yaw \[rad\] (when both sides have attitude): body-frame
    /// components of the rotation between the attitudes.
    pub att: Option<[Stat; 3]>,
    /// The angle of that rotation \[rad\].
    pub att_total: Option<Stat>,
    /// Percentiles P50, P68, P95, P99 of the horizontal and of the 3D position error
    /// \[m\] (P50 horizontal = CEP, P95 horizontal = R95).
    pub horizontal_pct: [f64; 4],
    pub pos_3d_pct: [f64; 4],
    pub gaps: Vec<GapReport>,
    /// RMS over gaps of each gap's maximum: horizontal, vertical, 3D \[m\], roll,
    /// pitch, yaw \[rad\]. None without gaps.
    pub gap_rms: Option<[f64; 6]>,
    /// Along-track and cross-track error \[m\] (epochs moving faster than 0.5 m/s).
    pub along_cross: Option<[Stat; 2]>,
    /// Every scored epoch (with `EvalOptions::keep_epochs`).
    pub per_epoch: Vec<EpochError>,
}

fn interpolate(a: &TrajPoint, b: &TrajPoint, t: f64) -> TrajPoint {
    let k = if b.t > a.t {
        (t - a.t) / (b.t - a.t)
    } else {
        0.0
    };
    let mut d = b.lla - a.lla;
    d.y = wrap_pi(d.y); // across the antimeridian
    let mut lla = a.lla + d * k;
    lla.y = wrap_pi(lla.y);
    let v_n = match (a.v_n, b.v_n) {
        (Some(x), Some(y)) => Some(x + (y - x) * k),
        _ => None,
    };
    let rpy = match (a.rpy, b.rpy) {
        (Some(x), Some(y)) => {
            let (qa, qb) = (q_bn_from_euler(&x), q_bn_from_euler(&y));
            Some(euler_from_q_bn(&qa.slerp(&qb, k)))
        }
        _ => None,
    };
    TrajPoint { t, lla, v_n, rpy }
}

/// Score `solution` (time-sorted) against `reference` (time-sorted).
pub fn evaluate(solution: &[TrajPoint], reference: &[TrajPoint], opts: &EvalOptions) -> EvalReport {
    let mut rep = EvalReport::default();
    let (mut n, mut e, mut d, mut hz, mut vt, mut p3) = (
        Acc::default(),
        Acc::default(),
        Acc::default(),
        Acc::default(),
        Acc::default(),
        Acc::default(),
    );
    let mut vel = [
        Acc::default(),
        Acc::default(),
        Acc::default(),
        Acc::default(),
    ];
    let mut att = [Acc::default(), Acc::default(), Acc::default()];
    let mut att_total = Acc::default();
    let (mut along, mut cross) = (Acc::default(), Acc::default());
    let (mut all_h, mut all_3d) = (Vec::new(), Vec::new());
    let mut gaps: Vec<GapReport> = opts
        .gaps
        .iter()
        .map(|w| GapReport {
            start: w.start,
            end: w.end,
            ..Default::default()
        })
        .collect();
    let mut j = 0usize;
    let mut first = true;
    for (ri, r) in reference.iter().enumerate() {
        while j + 1 < solution.len() && solution[j + 1].t < r.t {
            j += 1;
        }
        if j + 1 >= solution.len() || solution[j].t > r.t || solution[j + 1].t < r.t {
            // Exact match on the last sample is still fine.
            if !(solution.get(j).is_some_and(|s| (s.t - r.t).abs() < 1e-9)) {
                rep.skipped += 1;
                continue;
            }
        }
        let (a, b) = (&solution[j], solution.get(j + 1).unwrap_or(&solution[j]));
        if b.t - a.t > opts.max_interp_gap_s {
            rep.skipped += 1;
            continue;
        }
        let mut s = interpolate(a, b, r.t);
        if let (Some(l), Some(rpy)) = (opts.lever_arm_b, s.rpy) {
            s.lla = lla_add_ned(&s.lla, &(c_bn_from_euler(&rpy) * l));
        }
        let dp = lla_diff_ned(&s.lla, &r.lla);
        let h = (dp.x * dp.x + dp.y * dp.y).sqrt();
        n.add(dp.x);
        e.add(dp.y);
        d.add(dp.z);
        hz.add(h);
        vt.add(dp.z);
        p3.add(dp.norm());
        all_h.push(h);
        all_3d.push(dp.norm());
        if let (Some(vs), Some(vr)) = (s.v_n, r.v_n) {
            let dv = vs - vr;
            for k in 0..3 {
                vel[k].add(dv[k]);
            }
            vel[3].add(dv.norm());
        }
        // The track direction: the reference velocity, else its neighbours.
        let track = r.v_n.map(|v| (v.x, v.y)).or_else(|| {
            let (p, q) = (reference.get(ri.checked_sub(1)?)?, reference.get(ri + 1)?);
            let d = lla_diff_ned(&q.lla, &p.lla) / (q.t - p.t).max(1e-9);
            Some((d.x, d.y))
        });
        let ac = track.and_then(|(vn, ve)| {
            let speed = vn.hypot(ve);
            (speed >= MIN_TRACK_SPEED_MPS).then(|| {
                let (un, ue) = (vn / speed, ve / speed);
                (dp.x * un + dp.y * ue, -dp.x * ue + dp.y * un)
            })
        });
        if let Some((a, c)) = ac {
            along.add(a);
            cross.add(c);
        }
        let mut da = None;
        if let (Some(a_s), Some(a_r)) = (s.rpy, r.rpy) {
            // C_err = C_ref^T C_sol as a body-frame rotation vector.
            let (q_s, q_r) = (q_bn_from_euler(&a_s), q_bn_from_euler(&a_r));
            let x = (q_r.inverse() * q_s).scaled_axis();
            for k in 0..3 {
                att[k].add(x[k]);
            }
            att_total.add(x.norm());
            da = Some(x);
        }
        if opts.keep_epochs {
            rep.per_epoch.push(EpochError {
                t: r.t,
                pos_ned: dp,
                horizontal: h,
                along_cross: ac,
                vel_ned: s.v_n.zip(r.v_n).map(|(a, b)| a - b),
                att: da,
            });
        }
        for g in gaps.iter_mut().filter(|g| r.t > g.start && r.t < g.end) {
            g.epochs += 1;
            g.max_horizontal = g.max_horizontal.max(h);
            g.max_vertical = g.max_vertical.max(dp.z.abs());
            g.max_3d = g.max_3d.max(dp.norm());
            if let Some(x) = da {
                g.max_roll = g.max_roll.max(x.x.abs());
                g.max_pitch = g.max_pitch.max(x.y.abs());
                g.max_yaw = g.max_yaw.max(x.z.abs());
            }
        }
        if first {
            rep.t_first = r.t;
            first = false;
        }
        rep.t_last = r.t;
    }
    rep.epochs = n.n;
    rep.north = n.stat();
    rep.east = e.stat();
    rep.down = d.stat();
    rep.horizontal = hz.stat();
    rep.vertical = vt.stat();
    rep.pos_3d = p3.stat();
    if vel[3].n > 0 {
        rep.vel = Some([vel[0].stat(), vel[1].stat(), vel[2].stat(), vel[3].stat()]);
    }
    if att[0].n > 0 {
        rep.att = Some([att[0].stat(), att[1].stat(), att[2].stat()]);
        rep.att_total = Some(att_total.stat());
    }
    if along.n > 0 {
        rep.along_cross = Some([along.stat(), cross.stat()]);
    }
    rep.horizontal_pct = percentiles(&mut all_h);
    rep.pos_3d_pct = percentiles(&mut all_3d);
    gaps.retain(|g| g.epochs > 0);
    if !gaps.is_empty() {
        let m = gaps.len() as f64;
        let rms = |f: &dyn Fn(&GapReport) -> f64| {
            (gaps.iter().map(|g| f(g).powi(2)).sum::<f64>() / m).sqrt()
        };
        rep.gap_rms = Some([
            rms(&|g| g.max_horizontal),
            rms(&|g| g.max_vertical),
            rms(&|g| g.max_3d),
            rms(&|g| g.max_roll),
            rms(&|g| g.max_pitch),
            rms(&|g| g.max_yaw),
        ]);
    }
    rep.gaps = gaps;
    rep
}

/// P50, P68, P95, P99 of `v` (nearest rank; zeros when empty).
fn percentiles(v: &mut [f64]) -> [f64; 4] {
    if v.is_empty() {
        return [0.0; 4];
    }
    v.sort_by(f64::total_cmp);
    [0.50, 0.68, 0.95, 0.99].map(|p| {
        let rank = (p * v.len() as f64).ceil() as usize;
        v[rank.clamp(1, v.len()) - 1]
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pt(t: f64, north_m: f64, yaw_deg: f64) -> TrajPoint {
        let base = Vector3::new(0.5, 1.0, 100.0);
        TrajPoint {
            t,
            lla: lla_add_ned(&base, &Vector3::new(north_m, 0.0, 0.0)),
            v_n: Some(Vector3::new(1.0, 0.0, 0.0)),
            rpy: Some(Vector3::new(0.0, 0.0, yaw_deg.to_radians())),
        }
    }

    #[test]
    fn known_errors_and_gaps() {
        // Solution at 10 Hz runs 0.3 m north of the reference at 1 Hz, yaw 1 deg off
        // across the +-180 wrap; inside the gap (2, 5) the error grows to 1.3 m.
        let sol: Vec<_> = (0..=100)
            .map(|k| {
                let t = k as f64 * 0.1;
                let extra = if t > 2.0 && t < 5.0 {
                    (t - 2.0) / 3.0
                } else {
                    0.0
                };
                pt(t, t + 0.3 + extra, 179.5)
            })
            .collect();
        let reference: Vec<_> = (0..=10).map(|k| pt(k as f64, k as f64, -179.5)).collect();
        let opts = EvalOptions {
            gaps: vec![Window {
                start: 2.0,
                end: 5.0,
            }],
            ..Default::default()
        };
        let r = evaluate(&sol, &reference, &opts);
        assert_eq!(r.epochs, 11);
        assert!(r.horizontal.max > 0.3 && r.horizontal.max < 1.3);
        assert!((r.att.unwrap()[2].rms.to_degrees() + 0.0 - 1.0).abs() < 1e-6);
        assert_eq!(r.gaps.len(), 1);
        assert_eq!(r.gaps[0].epochs, 2); // t = 3, 4
        assert!((r.gaps[0].max_horizontal - (0.3 + 2.0 / 3.0)).abs() < 1e-6);
        assert!((r.gap_rms.unwrap()[0] - r.gaps[0].max_horizontal).abs() < 1e-12);
    }

    /// Near pitch 90 deg the Euler angles of two close attitudes differ wildly; the
    /// rotation between them is small.
    #[test]
    fn attitude_error_is_the_rotation_not_euler_differences() {
        let base = Vector3::new(0.5, 1.0, 100.0);
        let p = |t: f64, rpy: Vector3<f64>| TrajPoint {
            t,
            lla: base,
            v_n: None,
            rpy: Some(rpy),
        };
        // The reference at pitch 89.9 deg; the solution rotated 0.05 deg about the
        // body y axis (pitch 89.95 deg), written with a different roll/yaw split.
        let r_rpy = Vector3::new(0.3, 89.9f64.to_radians(), 1.0);
        let q_r = q_bn_from_euler(&r_rpy);
        let q_s = q_r
            * nalgebra::UnitQuaternion::from_scaled_axis(Vector3::new(
                0.0,
                0.05f64.to_radians(),
                0.0,
            ));
        let s_rpy = euler_from_q_bn(&q_s);
        let sol = vec![p(0.5, s_rpy), p(1.5, s_rpy)];
        let reference = vec![p(1.0, r_rpy)];
        let r = evaluate(&sol, &reference, &EvalOptions::default());
        let total = r.att_total.unwrap().max.to_degrees();
        assert!((total - 0.05).abs() < 1e-6, "{total}");
        let a = r.att.unwrap();
        assert!((a[1].max.to_degrees() - 0.05).abs() < 1e-6);
        assert!(a[0].max.to_degrees() < 1e-6 && a[2].max.to_degrees() < 1e-6);
    }

    #[test]
    fn percentiles_by_nearest_rank() {
        let mut v: Vec<f64> = (1..=100).map(f64::from).collect();
        assert_eq!(percentiles(&mut v), [50.0, 68.0, 95.0, 99.0]);
        assert_eq!(percentiles(&mut []), [0.0; 4]);
        let mut one = [3.0];
        assert_eq!(percentiles(&mut one), [3.0; 4]);
    }

    /// A solution 1 m ahead and 0.5 m to the right of a reference driving east.
    #[test]
    fn along_and_cross_track() {
        let base = Vector3::new(0.5, 1.0, 100.0);
        let east = Vector3::new(0.0, 10.0, 0.0);
        let at = |t: f64, d: Vector3<f64>| TrajPoint {
            t,
            lla: lla_add_ned(&base, &(east * t + d)),
            v_n: Some(east),
            rpy: None,
        };
        // East is ahead; to the right of east is south (-north).
        let sol: Vec<_> = (0..=20)
            .map(|k| at(k as f64 * 0.5, Vector3::new(-0.5, 1.0, 0.0)))
            .collect();
        let reference: Vec<_> = (1..10).map(|k| at(k as f64, Vector3::zeros())).collect();
        let opts = EvalOptions {
            keep_epochs: true,
            ..Default::default()
        };
        let r = evaluate(&sol, &reference, &opts);
        let [a, c] = r.along_cross.unwrap();
        assert!(
            (a.mean - 1.0).abs() < 1e-6 && (c.mean - 0.5).abs() < 1e-6,
            "{a:?} {c:?}"
        );
        assert_eq!(r.per_epoch.len(), 9);
        assert!(r.per_epoch[0].att.is_none() && r.att.is_none());
    }
}
