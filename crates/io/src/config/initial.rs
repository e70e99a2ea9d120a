//! `[initial]`: the initial state and its uncertainty (core::config::InitialState),
//! with `[initial.alignment]` in alignment.rs.

use nalgebra::Vector3;
use navfuse_core::config::{AttitudeInit, ImuNoise, InitialState};
use navfuse_core::types::ImuErrors;
use serde::{Deserialize, Serialize};

use super::alignment::{self, TAlignment};
use super::error::{kerr, KResult};
use super::units::{arr3, map3, vec3, Unit, DEG, DEGPH, MGAL, PPM, SAME};
use super::validate::{n3, std3, std3_si, v3};
use super::values::Num3;
use crate::error::SCALE_MAX_SI;

#[derive(Debug, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(super) struct TInitial {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) position_deg_m: Option<Vec<f64>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) velocity_mps: Option<Vec<f64>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) attitude_deg: Option<Vec<f64>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) alignment: Option<TAlignment>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) position_std_m: Option<Num3>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) velocity_std_mps: Option<Num3>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) attitude_std_deg: Option<Num3>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) gyro_bias_degph: Option<Num3>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) accel_bias_mgal: Option<Num3>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) gyro_scale_ppm: Option<Num3>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) accel_scale_ppm: Option<Num3>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) gyro_bias_std_degph: Option<Num3>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) accel_bias_std_mgal: Option<Num3>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) gyro_scale_std_ppm: Option<Num3>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) accel_scale_std_ppm: Option<Num3>,
}

/// Defaults of the initial stds (user units: m, m/s, deg roll pitch yaw): what a
/// start from the first GNSS fix and a coarse alignment can claim. The keys that take
/// them are listed in `RunConfig::defaulted`.
pub const DEFAULT_INITIAL_STD: [(&str, [f64; 3]); 3] = [
    ("initial.position_std_m", [1.0, 1.0, 2.0]),
    ("initial.velocity_std_mps", [0.5, 0.5, 0.5]),
    ("initial.attitude_std_deg", [2.0, 2.0, 10.0]),
];

/// `noise`: the converted `[imu_noise]`, whose stds are the default initial IMU error
/// stds. The initial stds not given are pushed to `defaulted`.
pub(super) fn convert(
    i: &TInitial,
    noise: &ImuNoise,
    defaulted: &mut Vec<&'static str>,
) -> KResult<InitialState> {
    let pos = match &i.position_deg_m {
        Some(p) => Some(v3("initial.position_deg_m", p)?),
        None => None,
    };
    if let Some(pos) = pos {
        if !(-90.0..=90.0).contains(&pos[0]) {
            return Err(kerr(
                "initial.position_deg_m",
                format!(
                    "latitude (element 0) must be in [-90, 90] deg, got {}",
                    pos[0]
                ),
            ));
        }
        if !(-180.0..=360.0).contains(&pos[1]) {
            return Err(kerr(
                "initial.position_deg_m",
                format!(
                    "longitude (element 1) must be in [-180, 360] deg, got {}",
                    pos[1]
                ),
            ));
        }
    }
    let v_n = match &i.velocity_mps {
        Some(v) => vec3(v3("initial.velocity_mps", v)?),
        None => Vector3::zeros(),
    };
    let attitude = match (&i.attitude_deg, &i.alignment) {
        (Some(_), Some(_)) => {
            return Err(kerr(
                "initial.alignment",
                "give either initial.attitude_deg or [initial.alignment], not both",
            ))
        }
        // No attitude in the config: found from the data (static or in motion).
        (None, None) => AttitudeInit::default(),
        (None, Some(al)) => alignment::convert(al)?,
        (Some(att), None) => {
            let att = v3("initial.attitude_deg", att)?;
            if let Some(a) = att.iter().find(|a| a.abs() > 360.0) {
                return Err(kerr(
                    "initial.attitude_deg",
                    format!("expected angles within [-360, 360] deg, got {a}"),
                ));
            }
            if !(-90.0..=90.0).contains(&att[1]) {
                return Err(kerr(
                    "initial.attitude_deg",
                    format!("pitch (element 1) must be in [-90, 90] deg, got {}", att[1]),
                ));
            }
            AttitudeInit::Given(vec3(map3(att, DEG.to_si)))
        }
    };
    // Initial IMU errors: finite, and bounded so that they convert back and forth.
    let err3 = |key: &str, v: &Option<Num3>, unit: Unit, default: Vector3<f64>| {
        let Some(v) = v else {
            return Ok(default);
        };
        let a = n3(key, v)?;
        match a.iter().find(|x| x.abs() > SCALE_MAX_SI) {
            Some(x) => Err(kerr(key, format!("expected |value| <= 1e150, got {x}"))),
            None => Ok(vec3(map3(a, unit.to_si))),
        }
    };
    let d = ImuErrors::default();
    let imu_errors = ImuErrors {
        gyro_bias: err3(
            "initial.gyro_bias_degph",
            &i.gyro_bias_degph,
            DEGPH,
            d.gyro_bias,
        )?,
        accel_bias: err3(
            "initial.accel_bias_mgal",
            &i.accel_bias_mgal,
            MGAL,
            d.accel_bias,
        )?,
        gyro_scale: err3(
            "initial.gyro_scale_ppm",
            &i.gyro_scale_ppm,
            PPM,
            d.gyro_scale,
        )?,
        accel_scale: err3(
            "initial.accel_scale_ppm",
            &i.accel_scale_ppm,
            PPM,
            d.accel_scale,
        )?,
    };
    let std_or = |key: &str, v: &Option<Num3>, unit: Unit, default: Vector3<f64>| match v {
        Some(v) => std3_si(key, std3(key, v)?, unit),
        None => Ok(default),
    };
    let d = noise.error_stds();
    let imu_errors_std = ImuErrors {
        gyro_bias: std_or(
            "initial.gyro_bias_std_degph",
            &i.gyro_bias_std_degph,
            DEGPH,
            d.gyro_bias,
        )?,
        accel_bias: std_or(
            "initial.accel_bias_std_mgal",
            &i.accel_bias_std_mgal,
            MGAL,
            d.accel_bias,
        )?,
        gyro_scale: std_or(
            "initial.gyro_scale_std_ppm",
            &i.gyro_scale_std_ppm,
            PPM,
            d.gyro_scale,
        )?,
        accel_scale: std_or(
            "initial.accel_scale_std_ppm",
            &i.accel_scale_std_ppm,
            PPM,
            d.accel_scale,
        )?,
    };
    let mut required = |k: usize, v: &Option<Num3>, unit: Unit| {
        let (key, default) = DEFAULT_INITIAL_STD[k];
        match v {
            Some(v) => std3_si(key, std3(key, v)?, unit),
            None => {
                defaulted.push(key);
                std3_si(key, default, unit)
            }
        }
    };
    let pos_std = required(0, &i.position_std_m, SAME)?;
    let vel_std = required(1, &i.velocity_std_mps, SAME)?;
    let att_std = required(2, &i.attitude_std_deg, DEG)?;
    Ok(InitialState {
        lla: pos.map(|p| Vector3::new((DEG.to_si)(p[0]), (DEG.to_si)(p[1]), p[2])),
        v_n,
        attitude,
        imu_errors,
        imu_errors_std,
        pos_std,
        vel_std,
        att_std,
    })
}

pub(super) fn to_toml(i: &InitialState) -> TInitial {
    let some3 = |v: &Vector3<f64>, unit: Unit| Some(unit.user3(v));
    TInitial {
        position_deg_m: i.lla.map(|p| vec![DEG.user(p.x), DEG.user(p.y), p.z]),
        velocity_mps: Some(arr3(&i.v_n).to_vec()),
        attitude_deg: match i.attitude {
            AttitudeInit::Given(rpy) => Some(map3(arr3(&rpy), |x| DEG.user(x)).to_vec()),
            _ => None,
        },
        alignment: alignment::to_toml(&i.attitude),
        position_std_m: Some(Num3::from3(arr3(&i.pos_std))),
        velocity_std_mps: Some(Num3::from3(arr3(&i.vel_std))),
        attitude_std_deg: Some(DEG.user3(&i.att_std)),
        gyro_bias_degph: some3(&i.imu_errors.gyro_bias, DEGPH),
        accel_bias_mgal: some3(&i.imu_errors.accel_bias, MGAL),
        gyro_scale_ppm: some3(&i.imu_errors.gyro_scale, PPM),
        accel_scale_ppm: some3(&i.imu_errors.accel_scale, PPM),
        gyro_bias_std_degph: some3(&i.imu_errors_std.gyro_bias, DEGPH),
        accel_bias_std_mgal: some3(&i.imu_errors_std.accel_bias, MGAL),
        gyro_scale_std_ppm: some3(&i.imu_errors_std.gyro_scale, PPM),
        accel_scale_std_ppm: some3(&i.imu_errors_std.accel_scale, PPM),
    }
}
