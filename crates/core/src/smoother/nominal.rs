//! The nominal values an error-state correction acts on, and the correction itself
//! (the closed-loop feedback of ins_filter.rs and the smoother's correction of the
//! forward trajectory share it; error conventions in state.rs).

use crate::attitude::quat_from_rotvec;
use crate::earth::lla_add_ned;
use crate::state::{Block, StateLayout, ATT, BA, BG, POS, SA, SG, VEL};
use crate::types::{ImuErrors, NavState};
use nalgebra::{DVector, Matrix3, Vector3};
use std::ops::Range;

/// Everything of the filter's state but the covariance, at one epoch.
#[derive(Clone, Debug, PartialEq)]
pub struct Nominal {
    pub nav: NavState,
    pub imu_errors: ImuErrors,
    /// GNSS-IMU time offset \[s\] and its rate \[s/s\] (0 when not estimated).
    pub time_offset_s: f64,
    pub time_offset_rate: f64,
    /// Odometer scale k (true = (1 + k) measured).
    pub odometer_scale: f64,
    /// C_b^m, IMU to vehicle frame.
    pub c_bm: Matrix3<f64>,
    /// Nominal values of the aiding sources' blocks, by state index (zero at the
    /// other indices).
    pub extra: DVector<f64>,
}

/// Mutable views of the nominal values a correction moves.
pub(crate) struct NominalMut<'a> {
    pub nav: &'a mut NavState,
    pub imu_errors: &'a mut ImuErrors,
    pub time_offset_s: &'a mut f64,
    pub time_offset_rate: &'a mut f64,
    pub odometer_scale: &'a mut f64,
    pub c_bm: &'a mut Matrix3<f64>,
    pub extra: &'a mut DVector<f64>,
}

/// True for the blocks whose nominal value lives in `Nominal::extra` (the aiding
/// sources' blocks: receiver clock, fix error, `Block::Source`).
pub fn is_source_block(b: Block) -> bool {
    !matches!(
        b,
        Block::Position
            | Block::Velocity
            | Block::Attitude
            | Block::GyroBias
            | Block::AccelBias
            | Block::GyroScale
            | Block::AccelScale
            | Block::TimeOffset
            | Block::TimeOffsetRate
            | Block::OdometerScale
            | Block::Mounting
    )
}

/// Index ranges of the source blocks of `layout`.
pub fn source_ranges(layout: &StateLayout) -> impl Iterator<Item = Range<usize>> + '_ {
    layout
        .blocks()
        .filter(|(b, _)| is_source_block(*b))
        .map(|(b, i)| i..i + b.len())
}

/// Remove the error estimate `dx` (state.rs conventions) from the nominal values:
/// position, velocity, attitude and the vehicle states are x_est - x_true, the IMU
/// errors x_true - x_est.
pub(crate) fn correct(
    layout: &StateLayout,
    dx: &DVector<f64>,
    st: NominalMut<'_>,
    sources: impl Iterator<Item = Range<usize>>,
) {
    let d_pos = Vector3::new(dx[POS], dx[POS + 1], dx[POS + 2]);
    let d_vel = Vector3::new(dx[VEL], dx[VEL + 1], dx[VEL + 2]);
    let phi = Vector3::new(dx[ATT], dx[ATT + 1], dx[ATT + 2]);
    st.nav.lla = lla_add_ned(&st.nav.lla, &(-d_pos));
    st.nav.v_n -= d_vel;
    // C_true = (I + phi x) C_est.
    st.nav.q_bn = quat_from_rotvec(&phi) * st.nav.q_bn;
    let e = st.imu_errors;
    for k in 0..3 {
        e.gyro_bias[k] += dx[BG + k];
        e.accel_bias[k] += dx[BA + k];
        e.gyro_scale[k] += dx[SG + k];
        e.accel_scale[k] += dx[SA + k];
    }
    if let Some(i) = layout.index(Block::TimeOffset) {
        *st.time_offset_s -= dx[i];
    }
    if let Some(i) = layout.index(Block::TimeOffsetRate) {
        *st.time_offset_rate -= dx[i];
    }
    if let Some(i) = layout.index(Block::OdometerScale) {
        *st.odometer_scale -= dx[i];
    }
    if let Some(i) = layout.index(Block::Mounting) {
        // C_b^m,true = (I + dalpha x) C_b^m,est, dalpha = (0, pitch, yaw).
        let da = Vector3::new(0.0, dx[i], dx[i + 1]);
        *st.c_bm = quat_from_rotvec(&da).to_rotation_matrix().into_inner() * *st.c_bm;
    }
    // The sources' blocks: x_est - x_true, so the estimate moves by -dx.
    for r in sources {
        for k in r {
            st.extra[k] -= dx[k];
        }
    }
}

impl Nominal {
    /// These values with the error estimate `dx` of `layout` removed.
    pub fn corrected(&self, layout: &StateLayout, dx: &DVector<f64>) -> Nominal {
        let mut out = self.clone();
        let st = NominalMut {
            nav: &mut out.nav,
            imu_errors: &mut out.imu_errors,
            time_offset_s: &mut out.time_offset_s,
            time_offset_rate: &mut out.time_offset_rate,
            odometer_scale: &mut out.odometer_scale,
            c_bm: &mut out.c_bm,
            extra: &mut out.extra,
        };
        correct(layout, dx, st, source_ranges(layout));
        out
    }

    /// The value of each filter state beyond the 21 INS states, in layout order, in
    /// the units of the state (mounting as pitch and yaw of C_b^m \[rad\]).
    pub fn extra_values(&self, layout: &StateLayout) -> Vec<f64> {
        let mut v = Vec::new();
        for (b, i) in layout.blocks() {
            match b {
                Block::TimeOffset => v.push(self.time_offset_s),
                Block::TimeOffsetRate => v.push(self.time_offset_rate),
                Block::OdometerScale => v.push(self.odometer_scale),
                Block::Mounting => {
                    let rpy = crate::attitude::euler_from_c_bn(&self.c_bm);
                    v.extend([rpy.y, rpy.z]);
                }
                b if is_source_block(b) => v.extend(self.extra.rows(i, b.len()).iter()),
                _ => {}
            }
        }
        v
    }
}

/// Names of the states `Nominal::extra_values` lists, with their units.
pub fn extra_names(layout: &StateLayout) -> Vec<String> {
    let mut v = Vec::new();
    for (b, _) in layout.blocks() {
        match b {
            Block::TimeOffset => v.push("time_offset_s".to_string()),
            Block::TimeOffsetRate => v.push("time_offset_rate".to_string()),
            Block::OdometerScale => v.push("odometer_scale".to_string()),
            Block::Mounting => v.extend(["mounting_pitch_rad".into(), "mounting_yaw_rad".into()]),
            Block::ClockBias => v.push("clock_bias_m".to_string()),
            Block::ClockDrift => v.push("clock_drift_mps".to_string()),
            Block::GnssBias => v.extend(["n", "e", "d"].map(|a| format!("gnss_fix_bias_{a}_m"))),
            Block::Source { name, len } => {
                if len == 1 {
                    v.push(name.to_string());
                } else {
                    v.extend((0..len).map(|k| format!("{name}_{k}")));
                }
            }
            _ => {}
        }
    }
    v
}
