//! File units and SI: each unit is one pair of conversions, used by a section's
//! reading (file -> SI) and by its writing (SI -> file), so the two cannot drift
//! apart. Public so that a program that builds a [`RunConfig`](super::RunConfig)
//! from numbers in file units (the simulator does) converts them exactly as loading
//! them from a file would.

use std::f64::consts::PI;

use nalgebra::Vector3;

use super::values::Num3;

pub(super) const D2R: f64 = PI / 180.0;

/// A file unit: how its numbers become SI and back.
#[derive(Clone, Copy)]
pub struct Unit {
    /// File units -> SI (what the loader applies).
    pub(super) to_si: fn(f64) -> f64,
    /// SI -> file units (what the writer applies).
    from_si: fn(f64) -> f64,
}

impl std::fmt::Debug for Unit {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Unit")
    }
}

impl Unit {
    /// `x` in this unit, in SI units: what loading `x` from a file gives.
    pub fn si(&self, x: f64) -> f64 {
        (self.to_si)(x)
    }

    /// An SI value in this unit, as written: the value rounded to 15 significant
    /// digits (`tidy`: 0.027 deg/h, not 0.026999999999999996) when that loads back
    /// to `si` exactly, otherwise the shortest nearby value that does (up to 16
    /// steps of the last bit away), so that writing and loading changes nothing.
    /// When no value loads back exactly, the rounded one.
    pub fn user(&self, si: f64) -> f64 {
        let u = (self.from_si)(si);
        let rounded = tidy(u);
        let exact = |x: f64| (self.to_si)(x) == si;
        if !u.is_finite() || exact(rounded) {
            return rounded;
        }
        let shorter = [format!("{u:.15e}").parse().unwrap_or(u), u];
        if let Some(x) = shorter.into_iter().find(|&x| exact(x)) {
            return x;
        }
        let (mut below, mut above) = (u, u);
        for _ in 0..16 {
            below = below.next_down();
            above = above.next_up();
            if let Some(x) = [below, above].into_iter().find(|&x| exact(x)) {
                return x;
            }
        }
        rounded
    }

    /// A 3-vector in file units, written as one number when the axes agree.
    pub(super) fn user3(&self, v: &Vector3<f64>) -> Num3 {
        Num3::from3([self.user(v.x), self.user(v.y), self.user(v.z)])
    }
}

/// Numbers already in SI units (metres, seconds, m/s, probabilities).
pub const SAME: Unit = Unit {
    to_si: |x| x,
    from_si: |x| x,
};
/// deg -> rad
pub const DEG: Unit = Unit {
    to_si: |x| x * D2R,
    from_si: |x| x / D2R,
};
/// deg/sqrt(h) -> rad/sqrt(s)
pub const ARW: Unit = Unit {
    to_si: |x| x * D2R / 60.0,
    from_si: |x| x * 60.0 / D2R,
};
/// m/s/sqrt(h) -> m/s/sqrt(s)
pub const VRW: Unit = Unit {
    to_si: |x| x / 60.0,
    from_si: |x| x * 60.0,
};
/// deg/h -> rad/s
pub const DEGPH: Unit = Unit {
    to_si: |x| x * D2R / 3600.0,
    from_si: |x| x * 3600.0 / D2R,
};
/// mGal -> m/s²
pub const MGAL: Unit = Unit {
    to_si: |x| x * 1e-5,
    from_si: |x| x * 1e5,
};
/// ppm -> 1
pub const PPM: Unit = Unit {
    to_si: |x| x * 1e-6,
    from_si: |x| x * 1e6,
};
/// h -> s
pub const HOURS: Unit = Unit {
    to_si: |x| x * 3600.0,
    from_si: |x| x / 3600.0,
};
/// Random walk in ppm/sqrt(h) -> PSD \[1/s\]: after T hours the std is q sqrt(T) ppm.
pub const PPM_SQRTH_PSD: Unit = Unit {
    to_si: |q| (q * 1e-6).powi(2) / 3600.0,
    from_si: |psd| (psd * 3600.0).sqrt() * 1e6,
};

pub(super) fn map3(v: [f64; 3], f: fn(f64) -> f64) -> [f64; 3] {
    [f(v[0]), f(v[1]), f(v[2])]
}

pub(super) fn vec3(v: [f64; 3]) -> Vector3<f64> {
    Vector3::new(v[0], v[1], v[2])
}

pub(super) fn arr3(v: &Vector3<f64>) -> [f64; 3] {
    [v.x, v.y, v.z]
}

/// Round to 15 significant digits: hides the last-bit noise of the unit conversions
/// (0.027 deg/h -> rad/s -> 0.026999999999999996 deg/h) when writing user units.
pub(super) fn tidy(x: f64) -> f64 {
    format!("{x:.14e}").parse().unwrap_or(x)
}
