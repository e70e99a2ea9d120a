//! Checks shared by the sections: finite, positive, non-negative numbers, vectors of
//! three, standard deviations, innovation-test probabilities, optional values with
//! defaults. Each returns the key with its message.

use nalgebra::Vector3;

use super::error::{kerr, KResult};
use super::units::{vec3, Unit};
use super::values::{Gate, Num3};
use crate::error::{check_finite_si, check_scale};

/// A satellite system by its RINEX letter (`G`, `R`, `E`, `C`, `J`, `S`, `I`).
pub(super) fn system_letter(key: &str, letter: &str) -> KResult<navfuse_core::sat::System> {
    use navfuse_core::sat::System;
    let mut chars = letter.trim().chars();
    match (chars.next(), chars.next()) {
        (Some(c), None) if c != ' ' => System::from_letter(c.to_ascii_uppercase()),
        _ => System::ALL
            .iter()
            .copied()
            .find(|s| s.name().eq_ignore_ascii_case(letter.trim())),
    }
    .ok_or_else(|| {
        let all: Vec<String> = System::ALL
            .iter()
            .map(|s| format!("{} ({})", s.letter(), s.name()))
            .collect();
        kerr(
            key,
            format!(
                "expected a system letter or name, one of {}, got \"{letter}\"",
                all.join(", ")
            ),
        )
    })
}

pub(super) fn finite(key: &str, v: f64) -> KResult<f64> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(kerr(key, format!("expected a finite number, got {v}")))
    }
}

/// A std, variance, rate, scale or duration: > 0, square finite and non-zero
/// (`check_scale`).
pub(super) fn positive(key: &str, v: f64) -> KResult<f64> {
    positive_si(key, v, v)
}

/// `v` (file units) that is `si` in SI units, checked as [`positive`] after conversion.
pub(super) fn positive_si(key: &str, v: f64, si: f64) -> KResult<f64> {
    check_scale("the value", v, si).map_err(|m| kerr(key, format!("expected a number > 0: {m}")))
}

/// The SI values of a 3-vector std (`std3`), each checked after conversion.
pub(super) fn std3_si(key: &str, v: [f64; 3], unit: Unit) -> KResult<Vector3<f64>> {
    let mut out = [0.0; 3];
    for (i, (o, x)) in out.iter_mut().zip(v).enumerate() {
        *o = check_scale("a standard deviation", x, (unit.to_si)(x))
            .map_err(|m| kerr(key, format!("element {i}: {m}")))?;
    }
    Ok(vec3(out))
}

pub(super) fn non_negative(key: &str, v: f64) -> KResult<f64> {
    if v.is_finite() && v >= 0.0 {
        Ok(v)
    } else {
        Err(kerr(key, format!("expected a number >= 0, got {v}")))
    }
}

/// Exactly three finite numbers.
pub(super) fn v3(key: &str, v: &[f64]) -> KResult<[f64; 3]> {
    if v.len() != 3 {
        return Err(kerr(
            key,
            format!("expected an array of 3 numbers, got {} element(s)", v.len()),
        ));
    }
    for (i, x) in v.iter().enumerate() {
        if !x.is_finite() {
            return Err(kerr(
                key,
                format!("element {i}: expected a finite number, got {x}"),
            ));
        }
    }
    Ok([v[0], v[1], v[2]])
}

pub(super) fn n3(key: &str, v: &Num3) -> KResult<[f64; 3]> {
    match v {
        Num3::Scalar(x) => Ok([finite(key, *x)?; 3]),
        Num3::List(l) => v3(key, l),
    }
}

/// A std: scalar or 3-vector, every element > 0 with a finite non-zero square
/// (`check_scale`; [`std3_si`] checks again after conversion).
pub(super) fn std3(key: &str, v: &Num3) -> KResult<[f64; 3]> {
    let a = n3(key, v)?;
    for (i, x) in a.iter().enumerate() {
        if let Err(m) = check_scale("a standard deviation", *x, *x) {
            let what = if matches!(v, Num3::Scalar(_)) {
                String::new()
            } else {
                format!("element {i}: ")
            };
            return Err(kerr(key, format!("{what}{m}")));
        }
    }
    Ok(a)
}

/// An innovation-test key of the vehicle and heading aiding: a probability in
/// [1e-15, 0.5), `false` (None, no test), or absent (`default`).
pub(super) fn gate(key: &str, g: Option<Gate>, default: Option<f64>) -> KResult<Option<f64>> {
    match g {
        None => Ok(default),
        Some(Gate::Off) => Ok(None),
        Some(Gate::Probability(p)) => probability(key, p)
            .map(Some)
            .map_err(|_| {
                kerr(
                    key,
                    format!("expected a probability in [1e-15, 0.5), e.g. 1e-4, or false for no test, got {p}"),
                )
            }),
    }
}

/// An optional value checked by `check`, or the default (SI) when absent.
pub(super) fn opt_or(
    key: &str,
    v: Option<f64>,
    check: fn(&str, f64) -> KResult<f64>,
    unit: Unit,
    default: f64,
) -> KResult<f64> {
    match v {
        Some(x) => {
            let si = (unit.to_si)(check(key, x)?);
            check_finite_si(x, si).map_err(|m| kerr(key, m))?;
            // The same check on the SI value (a positive std must stay a usable one).
            check(key, si).map_err(|e| {
                kerr(
                    key,
                    format!("{x} is {si:e} in SI units, out of range: {}", e.msg),
                )
            })
        }
        None => Ok(default),
    }
}

/// A std: > 0.
pub(super) fn std_pos(key: &str, v: f64) -> KResult<f64> {
    check_scale("a standard deviation", v, v).map_err(|m| kerr(key, m))
}

pub(super) fn probability(key: &str, p: f64) -> KResult<f64> {
    if (1e-15..0.5).contains(&p) {
        Ok(p)
    } else {
        Err(kerr(
            key,
            format!("expected a probability in [1e-15, 0.5), got {p}"),
        ))
    }
}
