//! Byte layouts of what the smoother keeps in its scratch files (spill.rs); little
//! endian f64 / u64, symmetric matrices as their upper triangle, the transition
//! matrix as its entries that differ from the identity.

use nalgebra::{DMatrix, DVector, Matrix3, Quaternion, UnitQuaternion, Vector3};
use navfuse_core::smoother::{Nominal, RtsRecord, SmoothedRecord};
use navfuse_core::{ImuErrors, ImuSample, NavState};

#[derive(Default)]
pub(crate) struct Enc(pub Vec<u8>);

impl Enc {
    pub fn clear(&mut self) {
        self.0.clear();
    }
    pub fn f(&mut self, v: f64) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    pub fn u(&mut self, v: u64) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn u32(&mut self, v: usize) {
        self.0.extend_from_slice(&(v as u32).to_le_bytes());
    }
    pub fn fs<'a>(&mut self, v: impl IntoIterator<Item = &'a f64>) {
        for x in v {
            self.f(*x);
        }
    }
    fn sym(&mut self, m: &DMatrix<f64>) {
        let n = m.nrows();
        for j in 0..n {
            for i in 0..=j {
                self.f(m[(i, j)]);
            }
        }
    }
}

pub(crate) struct Dec<'a> {
    b: &'a [u8],
}

/// A scratch entry shorter than its layout.
fn short() -> std::io::Error {
    std::io::Error::other("smoother scratch entry truncated")
}

impl<'a> Dec<'a> {
    pub fn new(b: &'a [u8]) -> Self {
        Dec { b }
    }
    fn take(&mut self) -> std::io::Result<[u8; 8]> {
        if self.b.len() < 8 {
            return Err(short());
        }
        let (h, t) = self.b.split_at(8);
        self.b = t;
        Ok(h.try_into().unwrap())
    }
    pub fn f(&mut self) -> std::io::Result<f64> {
        Ok(f64::from_le_bytes(self.take()?))
    }
    pub fn u(&mut self) -> std::io::Result<u64> {
        Ok(u64::from_le_bytes(self.take()?))
    }
    fn u32(&mut self) -> std::io::Result<usize> {
        if self.b.len() < 4 {
            return Err(short());
        }
        let (h, t) = self.b.split_at(4);
        self.b = t;
        Ok(u32::from_le_bytes(h.try_into().unwrap()) as usize)
    }
    fn v3(&mut self) -> std::io::Result<Vector3<f64>> {
        Ok(Vector3::new(self.f()?, self.f()?, self.f()?))
    }
    pub fn vec(&mut self, n: usize) -> std::io::Result<DVector<f64>> {
        let mut v = DVector::zeros(n);
        for i in 0..n {
            v[i] = self.f()?;
        }
        Ok(v)
    }
    fn sym(&mut self, n: usize) -> std::io::Result<DMatrix<f64>> {
        let mut m = DMatrix::zeros(n, n);
        for j in 0..n {
            for i in 0..=j {
                let v = self.f()?;
                m[(i, j)] = v;
                m[(j, i)] = v;
            }
        }
        Ok(m)
    }
}

pub(crate) fn put_record(e: &mut Enc, r: &RtsRecord) {
    let n = r.dim();
    e.f(r.t);
    e.u(n as u64);
    e.u(u64::from(r.phi.is_some())
        | u64::from(r.q.is_some()) << 1
        | u64::from(r.propagated_only) << 2);
    if let Some(phi) = &r.phi {
        let nz: Vec<(usize, f64)> = phi
            .as_slice()
            .iter()
            .enumerate()
            .filter(|(k, v)| **v != if k % (n + 1) == 0 { 1.0 } else { 0.0 })
            .map(|(k, v)| (k, *v))
            .collect();
        e.u(nz.len() as u64);
        for (k, v) in nz {
            e.u32(k);
            e.f(v);
        }
    }
    if let Some(q) = &r.q {
        // Upper triangle, entries that are not zero.
        let nz: Vec<(usize, f64)> = (0..n)
            .flat_map(|j| (0..=j).map(move |i| (i, j)))
            .filter(|&(i, j)| q[(i, j)] != 0.0)
            .map(|(i, j)| (i + j * n, q[(i, j)]))
            .collect();
        e.u(nz.len() as u64);
        for (k, v) in nz {
            e.u32(k);
            e.f(v);
        }
    }
    e.sym(&r.p_post);
    e.fs(r.dx.iter());
}

pub(crate) fn get_record(b: &[u8]) -> std::io::Result<RtsRecord> {
    let mut d = Dec::new(b);
    let t = d.f()?;
    let n = d.u()? as usize;
    let flags = d.u()?;
    let phi = if flags & 1 != 0 {
        let mut phi = DMatrix::identity(n, n);
        let nz = d.u()? as usize;
        for _ in 0..nz {
            let k = d.u32()?;
            let v = d.f()?;
            *phi.as_mut_slice().get_mut(k).ok_or_else(short)? = v;
        }
        Some(phi)
    } else {
        None
    };
    let q = if flags & 2 != 0 {
        let mut q = DMatrix::zeros(n, n);
        let nz = d.u()? as usize;
        for _ in 0..nz {
            let k = d.u32()?;
            let v = d.f()?;
            if k >= n * n {
                return Err(short());
            }
            q[(k % n, k / n)] = v;
            q[(k / n, k % n)] = v;
        }
        Some(q)
    } else {
        None
    };
    Ok(RtsRecord {
        t,
        phi,
        q,
        p_post: d.sym(n)?,
        dx: d.vec(n)?,
        propagated_only: flags & 4 != 0,
    })
}

/// The nominal values; `extra` only at `source_idx`.
pub(crate) fn put_nominal(e: &mut Enc, m: &Nominal, source_idx: &[usize]) {
    let nav = &m.nav;
    e.f(nav.t);
    e.fs(nav.lla.iter());
    e.fs(nav.v_n.iter());
    e.fs(nav.q_bn.coords.iter());
    let ie = &m.imu_errors;
    for v in [ie.gyro_bias, ie.accel_bias, ie.gyro_scale, ie.accel_scale] {
        e.fs(v.iter());
    }
    e.f(m.time_offset_s);
    e.f(m.time_offset_rate);
    e.f(m.odometer_scale);
    e.fs(m.c_bm.iter());
    for &i in source_idx {
        e.f(m.extra[i]);
    }
}

pub(crate) fn get_nominal(d: &mut Dec, n: usize, source_idx: &[usize]) -> std::io::Result<Nominal> {
    let t = d.f()?;
    let lla = d.v3()?;
    let v_n = d.v3()?;
    let c = [d.f()?, d.f()?, d.f()?, d.f()?];
    let q_bn = UnitQuaternion::new_unchecked(Quaternion::new(c[3], c[0], c[1], c[2]));
    let imu_errors = ImuErrors {
        gyro_bias: d.v3()?,
        accel_bias: d.v3()?,
        gyro_scale: d.v3()?,
        accel_scale: d.v3()?,
    };
    let time_offset_s = d.f()?;
    let time_offset_rate = d.f()?;
    let odometer_scale = d.f()?;
    let mut c_bm = Matrix3::zeros();
    for v in c_bm.iter_mut() {
        *v = d.f()?;
    }
    let mut extra = DVector::zeros(n);
    for &i in source_idx {
        extra[i] = d.f()?;
    }
    Ok(Nominal {
        nav: NavState { t, lla, v_n, q_bn },
        imu_errors,
        time_offset_s,
        time_offset_rate,
        odometer_scale,
        c_bm,
        extra,
    })
}

pub(crate) fn put_smoothed(e: &mut Enc, s: &SmoothedRecord, var_fwd: &DVector<f64>) {
    e.f(s.t);
    e.u(s.var.len() as u64);
    e.fs(s.s_post.iter());
    e.fs(s.s_prior.iter());
    e.fs(s.var.iter());
    e.fs(var_fwd.iter());
}

/// A smoothed record with the forward variances of its epoch.
pub(crate) fn get_smoothed(b: &[u8]) -> std::io::Result<(SmoothedRecord, DVector<f64>)> {
    let mut d = Dec::new(b);
    let t = d.f()?;
    let n = d.u()? as usize;
    let s = SmoothedRecord {
        t,
        s_post: d.vec(n)?,
        s_prior: d.vec(n)?,
        var: d.vec(n)?,
    };
    Ok((s, d.vec(n)?))
}

pub(crate) fn put_imu(e: &mut Enc, s: &ImuSample) {
    e.f(s.t);
    e.f(s.dt);
    e.fs(s.dtheta.iter());
    e.fs(s.dvel.iter());
}

pub(crate) fn get_imu(b: &[u8]) -> std::io::Result<ImuSample> {
    let mut d = Dec::new(b);
    Ok(ImuSample {
        t: d.f()?,
        dt: d.f()?,
        dtheta: d.v3()?,
        dvel: d.v3()?,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn record_round_trip() {
        let n = 4;
        let mut phi = DMatrix::identity(n, n);
        phi[(0, 1)] = 0.25;
        phi[(3, 3)] = 0.9;
        let p = DMatrix::from_fn(n, n, |i, j| 1.0 / (1.0 + i as f64 + j as f64));
        let r = RtsRecord {
            t: 12.5,
            phi: Some(phi),
            q: Some(&p * 2.0),
            p_post: p,
            dx: DVector::from_vec(vec![1.0, -2.0, 3.0, 0.5]),
            propagated_only: true,
        };
        let mut e = Enc::default();
        put_record(&mut e, &r);
        assert_eq!(get_record(&e.0).unwrap(), r);
        let r2 = RtsRecord {
            phi: None,
            q: None,
            propagated_only: false,
            ..r
        };
        e.clear();
        put_record(&mut e, &r2);
        assert_eq!(get_record(&e.0).unwrap(), r2);
        assert!(get_record(&e.0[..e.0.len() - 3]).is_err());
    }
}
