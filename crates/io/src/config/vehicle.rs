//! `[vehicle]`: how the IMU sits in the vehicle (core::config::VehicleOptions).

use navfuse_core::config::VehicleOptions;
use serde::{Deserialize, Serialize};

use super::error::{kerr, KResult};
use super::units::{arr3, map3, vec3, DEG};
use super::validate::{non_negative, opt_or, v3};

#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(super) struct TVehicle {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) mounting_rpy_deg: Option<Vec<f64>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) lever_arm_m: Option<Vec<f64>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) mounting_std_deg: Option<f64>,
}

pub(super) fn convert(v: &TVehicle) -> KResult<VehicleOptions> {
    let d = VehicleOptions::default();
    let mounting_rpy = match &v.mounting_rpy_deg {
        Some(m) => {
            let m = v3("vehicle.mounting_rpy_deg", m)?;
            if !(-90.0..=90.0).contains(&m[1]) {
                return Err(kerr(
                    "vehicle.mounting_rpy_deg",
                    format!("pitch (element 1) must be in [-90, 90] deg, got {}", m[1]),
                ));
            }
            vec3(map3(m, DEG.to_si))
        }
        None => d.mounting_rpy,
    };
    let lever_arm_b = match &v.lever_arm_m {
        Some(l) => vec3(v3("vehicle.lever_arm_m", l)?),
        None => d.lever_arm_b,
    };
    let mounting_std = opt_or(
        "vehicle.mounting_std_deg",
        v.mounting_std_deg,
        non_negative,
        DEG,
        d.mounting_std,
    )?;
    Ok(VehicleOptions {
        mounting_rpy,
        lever_arm_b,
        mounting_std,
    })
}

pub(super) fn to_toml(v: &VehicleOptions) -> TVehicle {
    TVehicle {
        mounting_rpy_deg: Some(map3(arr3(&v.mounting_rpy), |x| DEG.user(x)).to_vec()),
        lever_arm_m: Some(arr3(&v.lever_arm_b).to_vec()),
        mounting_std_deg: Some(DEG.user(v.mounting_std)),
    }
}
