//! Velocity and receiver clock drift from Doppler on the satellites of a fit.

use super::solve::{true_rx_time, Candidate, Fit};
use crate::ephemeris::SPEED_OF_LIGHT_MPS;
use crate::geometry::signal_path;
use crate::time::GpsTime;
use nalgebra::{Matrix3, Matrix4, Vector3, Vector4};
use navfuse_core::earth::c_ne;

/// A Doppler velocity solution.
pub(super) struct Velocity {
    pub(super) vel_ecef_mps: Vector3<f64>,
    pub(super) clock_drift_mps: f64,
    pub(super) std_ned_mps: Vector3<f64>,
    /// Post-fit range-rate residual per pseudorange row (None without Doppler) [m/s].
    pub(super) range_rate_residuals_mps: Vec<Option<f64>>,
}

/// Velocity and clock drift from Doppler on the used satellites (one drift for all
/// systems: their clocks differ by a near-constant bias): range rate
/// -lambda D = los . (v_sat - v_rx) + c (d(dt_rx)/dt - d(dt_sv)/dt) (SYSTEM.md §3b
/// eq. 16-18 with the clock drifts). Needs 4 satellites with Doppler.
pub(super) fn solve_velocity(
    cands: &[Candidate<'_>],
    fit: &Fit,
    t_rx: GpsTime,
    doppler_sigma_hz: f64,
    lla: &Vector3<f64>,
) -> Option<Velocity> {
    let with_doppler: Vec<(usize, f64)> = fit
        .rows
        .iter()
        .enumerate()
        .filter_map(|(k, r)| {
            cands[r.idx]
                .doppler_hz
                .filter(|d| d.is_finite())
                .map(|d| (k, d))
        })
        .collect();
    if with_doppler.len() < 4 {
        return None;
    }
    let t_true = true_rx_time(t_rx, fit.clock_bias_m);
    let mut vel = Vector3::zeros();
    let mut drift = 0.0;
    let mut n_inv = Matrix4::zeros();
    let mut res = vec![0.0; with_doppler.len()];
    // Linear in (v, drift) up to the light-time factor (~1e-6): a second pass settles it.
    for _ in 0..3 {
        let mut n = Matrix4::zeros();
        let mut b = Vector4::zeros();
        let mut rows = Vec::with_capacity(with_doppler.len());
        for &(k, d_hz) in &with_doppler {
            let c = &cands[fit.rows[k].idx];
            let sp = signal_path(&c.orbit, &fit.pos_ecef_m, &vel, t_true);
            let measured = -c.wavelength_m * d_hz;
            let modelled =
                sp.range_rate_mps + drift - SPEED_OF_LIGHT_MPS * sp.sat_clock_drift_s_per_s;
            let h = Vector4::new(-sp.los_unit.x, -sp.los_unit.y, -sp.los_unit.z, 1.0);
            let v = measured - modelled;
            n += h * h.transpose();
            b += h * v;
            rows.push((h, v));
        }
        let chol = n.cholesky()?;
        let dx = chol.solve(&b);
        if !dx.iter().all(|x| x.is_finite()) {
            return None;
        }
        vel += dx.fixed_rows::<3>(0);
        drift += dx[3];
        n_inv = chol.inverse();
        for (r, (h, v)) in res.iter_mut().zip(&rows) {
            *r = v - h.dot(&dx);
        }
        if dx.norm() < 1e-6 {
            break;
        }
    }
    let sigma_mps = doppler_sigma_hz * super::GPS_L1_WAVELENGTH_M;
    let c = c_ne(lla.x, lla.y);
    let p_ned: Matrix3<f64> =
        c.transpose() * n_inv.fixed_view::<3, 3>(0, 0) * c * (sigma_mps * sigma_mps);
    let std_ned = p_ned.diagonal().map(|x| x.max(0.0).sqrt());
    let mut per_row = vec![None; fit.rows.len()];
    for (&(k, _), r) in with_doppler.iter().zip(&res) {
        per_row[k] = Some(*r);
    }
    Some(Velocity {
        vel_ecef_mps: vel,
        clock_drift_mps: drift,
        std_ned_mps: std_ned,
        range_rate_residuals_mps: per_row,
    })
}
