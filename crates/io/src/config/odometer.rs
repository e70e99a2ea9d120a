//! `[odometer]`: the odometer input and its error model (input::OdometerSource,
//! core::config::OdometerOptions).

use std::path::Path;

use navfuse_core::config::OdometerOptions;
use serde::{Deserialize, Serialize};

use super::error::{kerr, KResult};
use super::paths::{file_key, PathWriter};
use super::units::{PPM, PPM_SQRTH_PSD, SAME};
use super::validate::{finite, gate, non_negative, opt_or, positive, std_pos};
use super::values::Gate;
use crate::input::{OdometerFormat, OdometerSource, UbxOdometer};

/// `odometer.format`. A raw type: `OdometerFormat`'s variants carry
/// `meters_per_pulse` / `speed_is_mean`, which are keys of their own.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq)]
pub(super) enum TOdoFormat {
    #[serde(rename = "speed")]
    Speed,
    #[serde(rename = "pulses")]
    Pulses,
    #[serde(rename = "navfuse")]
    Navfuse,
    #[serde(rename = "navfuse_speed")]
    NavfuseSpeed,
    #[serde(rename = "ubx")]
    Ubx,
}

/// `odometer.ubx_measurement` (`format = "ubx"`).
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub(super) enum TUbxOdo {
    Ticks,
    Speed,
}

#[derive(Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(super) struct TOdometer {
    pub(super) file: String,
    pub(super) format: TOdoFormat,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) meters_per_pulse: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) speed_is_mean: Option<bool>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) skip_lines: Option<usize>,
    pub(super) ubx_measurement: Option<TUbxOdo>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) std_mps: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) scale_ppm: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) scale_std_ppm: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) scale_random_walk_ppm_per_sqrth: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) with_nhc: Option<bool>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) std_speed_fraction: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) calibration_min_speed_mps: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) gate_probability: Option<Gate>,
}

pub(super) fn convert(o: &TOdometer, base: &Path) -> KResult<(OdometerSource, OdometerOptions)> {
    let d = OdometerOptions::default();
    let path = file_key(base, "odometer.file", &o.file)?;
    if o.format == TOdoFormat::Ubx && o.skip_lines.is_some() {
        return Err(kerr(
            "odometer.skip_lines",
            "applies only to text files, not to odometer.format = \"ubx\"",
        ));
    }
    if o.format != TOdoFormat::Ubx && o.ubx_measurement.is_some() {
        return Err(kerr(
            "odometer.ubx_measurement",
            "applies only to odometer.format = \"ubx\"",
        ));
    }
    let format = match o.format {
        TOdoFormat::Ubx => {
            if o.speed_is_mean.is_some() {
                return Err(kerr(
                    "odometer.speed_is_mean",
                    "applies only to odometer.format = \"speed\" (a UBX speed is instantaneous, wheel ticks give the mean over the interval)",
                ));
            }
            match (o.ubx_measurement.unwrap_or(TUbxOdo::Ticks), o.meters_per_pulse) {
                (TUbxOdo::Speed, Some(_)) => {
                    return Err(kerr(
                        "odometer.meters_per_pulse",
                        "applies only to wheel ticks (odometer.ubx_measurement = \"ticks\"), not to the UBX speed",
                    ))
                }
                (TUbxOdo::Speed, None) => OdometerFormat::Ubx(UbxOdometer::Speed),
                (TUbxOdo::Ticks, None) => {
                    return Err(kerr(
                        "odometer.meters_per_pulse",
                        "missing: the distance per wheel tick [m] is required for UBX wheel ticks (or set odometer.ubx_measurement = \"speed\")",
                    ))
                }
                (TUbxOdo::Ticks, Some(k)) => OdometerFormat::Ubx(UbxOdometer::Ticks {
                    meters_per_pulse: positive("odometer.meters_per_pulse", k)?,
                }),
            }
        }
        TOdoFormat::Speed | TOdoFormat::NavfuseSpeed => {
            if o.meters_per_pulse.is_some() {
                return Err(kerr(
                    "odometer.meters_per_pulse",
                    "applies only to odometer.format = \"pulses\", \"navfuse\" or \"ubx\"",
                ));
            }
            if o.format == TOdoFormat::NavfuseSpeed {
                if o.speed_is_mean.is_some() {
                    return Err(kerr(
                        "odometer.speed_is_mean",
                        "applies only to odometer.format = \"speed\" (the simulator's speed column is the mean over the interval)",
                    ));
                }
                OdometerFormat::NavfuseSpeed
            } else {
                OdometerFormat::Speed {
                    speed_is_mean: o.speed_is_mean.unwrap_or(true),
                }
            }
        }
        TOdoFormat::Pulses | TOdoFormat::Navfuse => {
            if o.speed_is_mean.is_some() {
                return Err(kerr(
                    "odometer.speed_is_mean",
                    "applies only to odometer.format = \"speed\" (pulse counts always give the mean speed over the interval)",
                ));
            }
            let k = o.meters_per_pulse.ok_or_else(|| {
                kerr(
                    "odometer.meters_per_pulse",
                    "missing: the distance per pulse [m] is required for pulse counts",
                )
            })?;
            let meters_per_pulse = positive("odometer.meters_per_pulse", k)?;
            if o.format == TOdoFormat::Pulses {
                OdometerFormat::Pulses { meters_per_pulse }
            } else {
                OdometerFormat::Navfuse { meters_per_pulse }
            }
        }
    };
    let ppm_finite = |key: &str, v: Option<f64>, default: f64| -> KResult<f64> {
        opt_or(key, v, finite, PPM, default)
    };
    let opts = OdometerOptions {
        enabled: true,
        std_mps: opt_or("odometer.std_mps", o.std_mps, std_pos, SAME, d.std_mps)?,
        scale_initial: ppm_finite("odometer.scale_ppm", o.scale_ppm, d.scale_initial)?,
        scale_std: opt_or(
            "odometer.scale_std_ppm",
            o.scale_std_ppm,
            non_negative,
            PPM,
            d.scale_std,
        )?,
        scale_random_walk: opt_or(
            "odometer.scale_random_walk_ppm_per_sqrth",
            o.scale_random_walk_ppm_per_sqrth,
            non_negative,
            PPM_SQRTH_PSD,
            d.scale_random_walk,
        )?,
        with_nhc: o.with_nhc.unwrap_or(d.with_nhc),
        std_speed_fraction: opt_or(
            "odometer.std_speed_fraction",
            o.std_speed_fraction,
            non_negative,
            SAME,
            d.std_speed_fraction,
        )?,
        calibration_min_speed_mps: opt_or(
            "odometer.calibration_min_speed_mps",
            o.calibration_min_speed_mps,
            non_negative,
            SAME,
            d.calibration_min_speed_mps,
        )?,
        gate_probability: gate(
            "odometer.gate_probability",
            o.gate_probability,
            d.gate_probability,
        )?,
    };
    let src = OdometerSource {
        path,
        format,
        skip_lines: o.skip_lines,
    };
    Ok((src, opts))
}

/// An odometer is configured by its file; options without one cannot be written.
pub(super) fn to_toml(
    src: Option<&OdometerSource>,
    od: &OdometerOptions,
    w: &PathWriter,
) -> Option<TOdometer> {
    let src = src?;
    let mut ubx_measurement = None;
    let (format, meters_per_pulse, speed_is_mean) = match src.format {
        OdometerFormat::Speed { speed_is_mean } => (TOdoFormat::Speed, None, Some(speed_is_mean)),
        OdometerFormat::NavfuseSpeed => (TOdoFormat::NavfuseSpeed, None, None),
        OdometerFormat::Ubx(UbxOdometer::Speed) => {
            ubx_measurement = Some(TUbxOdo::Speed);
            (TOdoFormat::Ubx, None, None)
        }
        OdometerFormat::Ubx(UbxOdometer::Ticks { meters_per_pulse }) => {
            ubx_measurement = Some(TUbxOdo::Ticks);
            (TOdoFormat::Ubx, Some(meters_per_pulse), None)
        }
        OdometerFormat::Pulses { meters_per_pulse } => {
            (TOdoFormat::Pulses, Some(meters_per_pulse), None)
        }
        OdometerFormat::Navfuse { meters_per_pulse } => {
            (TOdoFormat::Navfuse, Some(meters_per_pulse), None)
        }
    };
    Some(TOdometer {
        file: w.path(&src.path),
        format,
        meters_per_pulse,
        speed_is_mean,
        skip_lines: src.skip_lines,
        ubx_measurement,
        std_mps: Some(od.std_mps),
        scale_ppm: Some(PPM.user(od.scale_initial)),
        scale_std_ppm: Some(PPM.user(od.scale_std)),
        scale_random_walk_ppm_per_sqrth: Some(PPM_SQRTH_PSD.user(od.scale_random_walk)),
        with_nhc: Some(od.with_nhc),
        std_speed_fraction: Some(od.std_speed_fraction),
        calibration_min_speed_mps: Some(od.calibration_min_speed_mps),
        gate_probability: Some(Gate::from_option(od.gate_probability)),
    })
}
