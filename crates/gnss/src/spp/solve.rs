//! The SPP solver: weighted least squares on the pseudoranges, DOPs, the residual
//! chi-square test with fault detection and exclusion, and the solution assembly.

use super::velocity::solve_velocity;
use super::{
    Dops, SppConfig, SppError, SppMeasurement, SppSatellite, SppSolution, FDE_MIN_SATELLITES,
    NEAR_SURFACE_MIN_H_M,
};
use crate::ephemeris::{GpsEphemeris, SPEED_OF_LIGHT_MPS};
use crate::ephemeris_set::EphemerisSet;
use crate::geometry::{az_el, signal_path, SignalPath};
use crate::time::GpsTime;
use nalgebra::{Matrix4, Vector3, Vector4};
use navfuse_core::chi2::chi2_quantile;
use navfuse_core::earth::{c_ne, ecef_to_lla};

/// A measurement with its ephemeris.
pub(super) struct Candidate<'a> {
    prn: u8,
    /// Measured pseudorange, plus the DGPS correction when `dgps` [m].
    pseudorange_m: f64,
    dgps: bool,
    pub(super) doppler_hz: Option<f64>,
    pub(super) eph: &'a GpsEphemeris,
}

/// One pseudorange row of the linearised system.
pub(super) struct Row {
    /// Index into the candidates.
    pub(super) idx: usize,
    /// Design row d(P)/d(x, y, z, c dt_rx).
    h: Vector4<f64>,
    /// Pre-fit residual (measured - modelled) [m].
    v_m: f64,
    var_m2: f64,
    az_rad: f64,
    el_rad: f64,
    iono_m: f64,
    tropo_m: f64,
    los_unit: Vector3<f64>,
}

/// A converged fit on one satellite set.
pub(super) struct Fit {
    pub(super) pos_ecef_m: Vector3<f64>,
    pub(super) clock_bias_m: f64,
    pub(super) rows: Vec<Row>,
    /// Post-fit residuals, one per row [m].
    post_m: Vec<f64>,
    /// (H^T W H)^-1.
    cov_m2: Matrix4<f64>,
    masked: Vec<u8>,
    iterations: usize,
}

/// True reception time: the receiver tag corrected by the clock estimate.
pub(super) fn true_rx_time(t_rx: GpsTime, clock_bias_m: f64) -> GpsTime {
    t_rx.add_s(-clock_bias_m / SPEED_OF_LIGHT_MPS)
}

/// Build the pseudorange rows at (pos, clock) for the active candidates.
fn build_rows(
    cands: &[Candidate<'_>],
    active: &[bool],
    cfg: &SppConfig,
    t_rx: GpsTime,
    pos_ecef_m: &Vector3<f64>,
    clock_bias_m: f64,
    masked: &mut Vec<u8>,
) -> Vec<Row> {
    let lla = ecef_to_lla(pos_ecef_m);
    let near_surface = lla.z > NEAR_SURFACE_MIN_H_M;
    let t_true = true_rx_time(t_rx, clock_bias_m);
    masked.clear();
    let mut rows = Vec::with_capacity(cands.len());
    for (idx, c) in cands.iter().enumerate() {
        if !active[idx] {
            continue;
        }
        let sp: SignalPath = signal_path(c.eph, pos_ecef_m, &Vector3::zeros(), t_true);
        // Far from the surface (the Earth-centre start) elevations mean nothing:
        // every satellite is taken, without atmospheric corrections.
        let (az, el) = if near_surface {
            az_el(&lla, &sp.los_unit)
        } else {
            (0.0, std::f64::consts::FRAC_PI_2)
        };
        if near_surface && el < cfg.elevation_mask_rad {
            masked.push(c.prn);
            continue;
        }
        // A DGPS-corrected pseudorange already has the atmosphere removed.
        let (iono_m, tropo_m) = if near_surface && !c.dgps {
            cfg.atmosphere_m(&lla, az, el, t_rx.sow)
        } else {
            (0.0, 0.0)
        };
        // IS-GPS-200 20.3.3.3.3.2: the L1 C/A user's clock is dt_sv - TGD.
        let sat_clock_l1_m = SPEED_OF_LIGHT_MPS * (sp.sat_clock_bias_s - c.eph.tgd_s);
        let modelled = sp.geometric_range_m + clock_bias_m - sat_clock_l1_m + iono_m + tropo_m;
        let var_m2 = cfg.pseudorange_variance_m2(c.eph, el, iono_m, c.dgps);
        let los = sp.los_unit;
        rows.push(Row {
            idx,
            h: Vector4::new(-los.x, -los.y, -los.z, 1.0),
            v_m: c.pseudorange_m - modelled,
            var_m2,
            az_rad: az,
            el_rad: el,
            iono_m,
            tropo_m,
            los_unit: los,
        });
    }
    rows
}

/// Iterated weighted least squares on the active satellites, from (pos, clock).
pub(super) fn fit(
    cands: &[Candidate<'_>],
    active: &[bool],
    cfg: &SppConfig,
    t_rx: GpsTime,
    start_pos_ecef_m: Vector3<f64>,
    start_clock_bias_m: f64,
) -> Result<Fit, SppError> {
    let required = cfg.min_satellites.max(4);
    let mut pos = start_pos_ecef_m;
    let mut clk = start_clock_bias_m;
    let mut masked = Vec::new();
    let mut last_step = f64::INFINITY;
    let max_iter = cfg.max_iterations.max(1);
    for it in 0..max_iter {
        let rows = build_rows(cands, active, cfg, t_rx, &pos, clk, &mut masked);
        if rows.len() < required {
            return Err(SppError::TooFewSatellites {
                available: rows.len(),
                required,
            });
        }
        let mut n = Matrix4::zeros();
        let mut b = Vector4::zeros();
        for r in &rows {
            let w = 1.0 / r.var_m2;
            n += r.h * r.h.transpose() * w;
            b += r.h * (r.v_m * w);
        }
        let chol = n.cholesky().ok_or(SppError::SingularGeometry)?;
        let dx = chol.solve(&b);
        if !dx.iter().all(|x| x.is_finite()) {
            return Err(SppError::SingularGeometry);
        }
        pos += dx.fixed_rows::<3>(0);
        clk += dx[3];
        last_step = dx.norm();
        if last_step < cfg.convergence_m {
            // Post-fit residuals of the linearised system at the converged state.
            let post_m = rows.iter().map(|r| r.v_m - r.h.dot(&dx)).collect();
            return Ok(Fit {
                pos_ecef_m: pos,
                clock_bias_m: clk,
                rows,
                post_m,
                cov_m2: chol.inverse(),
                masked,
                iterations: it + 1,
            });
        }
        if !pos.iter().all(|x| x.is_finite()) || pos.norm() > 1e9 {
            break;
        }
    }
    Err(SppError::NotConverged {
        iterations: max_iter,
        last_step_m: last_step,
    })
}

/// DOPs from the used lines of sight (unit weights), in NED at `lla`.
pub(super) fn dops(rows: &[Row], lla: &Vector3<f64>) -> Option<Dops> {
    let c_en = c_ne(lla.x, lla.y).transpose();
    let mut n = Matrix4::zeros();
    for r in rows {
        let l = c_en * r.los_unit;
        let h = Vector4::new(-l.x, -l.y, -l.z, 1.0);
        n += h * h.transpose();
    }
    let g = n.try_inverse()?;
    let d = g.diagonal();
    if d.iter().any(|x| !x.is_finite() || *x < 0.0) {
        return None;
    }
    Some(Dops {
        gdop: d.sum().sqrt(),
        pdop: (d[0] + d[1] + d[2]).sqrt(),
        hdop: (d[0] + d[1]).sqrt(),
        vdop: d[2].sqrt(),
    })
}

/// Solve one epoch. `start` is the initial (position ECEF \[m\], clock bias \[m\]), e.g.
/// the previous solution; `None` starts at the Earth centre with zero clock. A fit
/// that fails from `start` is retried from the Earth centre.
pub fn solve_epoch(
    ephs: &EphemerisSet,
    t_rx: GpsTime,
    meas: &[SppMeasurement],
    cfg: &SppConfig,
    start: Option<(Vector3<f64>, f64)>,
) -> Result<SppSolution, SppError> {
    // Candidates: valid pseudorange, a usable ephemeris, first occurrence of a PRN.
    let mut cands: Vec<Candidate<'_>> = Vec::with_capacity(meas.len());
    let mut unusable = Vec::new();
    for m in meas {
        if cands.iter().any(|c| c.prn == m.prn) {
            continue;
        }
        let pr_ok = m.pseudorange_m.is_finite()
            && m.pseudorange_m > 0.0
            && m.dgps_prc_m.is_none_or(f64::is_finite);
        match ephs.select(m.prn, t_rx) {
            Some(eph) if pr_ok => cands.push(Candidate {
                prn: m.prn,
                pseudorange_m: m.pseudorange_m + m.dgps_prc_m.unwrap_or(0.0),
                dgps: m.dgps_prc_m.is_some(),
                doppler_hz: m.doppler_hz,
                eph,
            }),
            _ => unusable.push(m.prn),
        }
    }
    if cands.is_empty() {
        return Err(SppError::NoEphemeris { prns: unusable });
    }
    let required = cfg.min_satellites.max(4);
    if cands.len() < required {
        return Err(SppError::TooFewSatellites {
            available: cands.len(),
            required,
        });
    }

    let mut active = vec![true; cands.len()];
    let mut excluded: Vec<u8> = Vec::new();
    let (mut pos0, mut clk0) = start
        .filter(|(p, c)| p.iter().all(|x| x.is_finite()) && c.is_finite())
        .unwrap_or((Vector3::zeros(), 0.0));
    loop {
        let fitted = match fit(&cands, &active, cfg, t_rx, pos0, clk0) {
            // A far-off start (stale or bad previous solution) can mask the wrong
            // satellites or diverge: retry from the Earth centre.
            Err(_) if pos0 != Vector3::zeros() => {
                fit(&cands, &active, cfg, t_rx, Vector3::zeros(), 0.0)
            }
            r => r,
        }?;
        let n_used = fitted.rows.len();
        let chi2: f64 = fitted
            .rows
            .iter()
            .zip(&fitted.post_m)
            .map(|(r, v)| v * v / r.var_m2)
            .sum();
        let threshold = (n_used > 4).then(|| chi2_quantile(n_used - 4, cfg.chi2_probability));
        if let (true, Some(thr)) = (cfg.fde, threshold) {
            if chi2 > thr {
                if n_used < FDE_MIN_SATELLITES {
                    return Err(SppError::ResidualTestFailed {
                        chi2,
                        threshold: thr,
                        n_used,
                        excluded_prns: excluded,
                    });
                }
                // Exclude the largest normalised residual |v_i| / sqrt(Q_v,ii),
                // Q_v = R - H (H^T W H)^-1 H^T (Baarda's w-test).
                let worst = fitted
                    .rows
                    .iter()
                    .zip(&fitted.post_m)
                    .enumerate()
                    .filter_map(|(k, (r, v))| {
                        let qv = r.var_m2 - (r.h.transpose() * fitted.cov_m2 * r.h)[0];
                        (qv > 1e-9 * r.var_m2).then(|| (k, v.abs() / qv.sqrt()))
                    })
                    .max_by(|a, b| a.1.total_cmp(&b.1));
                let Some((k, _)) = worst else {
                    return Err(SppError::ResidualTestFailed {
                        chi2,
                        threshold: thr,
                        n_used,
                        excluded_prns: excluded,
                    });
                };
                let idx = fitted.rows[k].idx;
                active[idx] = false;
                excluded.push(cands[idx].prn);
                pos0 = fitted.pos_ecef_m;
                clk0 = fitted.clock_bias_m;
                continue;
            }
        }
        return finish(
            &cands, fitted, excluded, unusable, cfg, t_rx, chi2, threshold,
        );
    }
}

/// Assemble the solution from an accepted fit.
#[allow(clippy::too_many_arguments)]
fn finish(
    cands: &[Candidate<'_>],
    fitted: Fit,
    excluded: Vec<u8>,
    unusable: Vec<u8>,
    cfg: &SppConfig,
    t_rx: GpsTime,
    chi2: f64,
    chi2_threshold: Option<f64>,
) -> Result<SppSolution, SppError> {
    let lla = ecef_to_lla(&fitted.pos_ecef_m);
    let dops = dops(&fitted.rows, &lla).ok_or(SppError::SingularGeometry)?;
    if dops.gdop.is_nan() || dops.gdop > cfg.max_gdop {
        return Err(SppError::PoorGeometry {
            gdop: dops.gdop,
            max_gdop: cfg.max_gdop,
        });
    }
    let c = c_ne(lla.x, lla.y);
    let p_ned = c.transpose() * fitted.cov_m2.fixed_view::<3, 3>(0, 0) * c;
    let std_ned_m = p_ned.diagonal().map(|x| x.max(0.0).sqrt());
    let velocity = solve_velocity(cands, &fitted, t_rx, cfg.errors.doppler_sigma_hz, &lla);
    let rr_res = velocity.as_ref().map(|v| &v.range_rate_residuals_mps);
    let satellites: Vec<SppSatellite> = fitted
        .rows
        .iter()
        .zip(&fitted.post_m)
        .enumerate()
        .map(|(k, (r, v))| SppSatellite {
            prn: cands[r.idx].prn,
            az_rad: r.az_rad,
            el_rad: r.el_rad,
            residual_m: *v,
            sigma_m: r.var_m2.sqrt(),
            iono_m: r.iono_m,
            tropo_m: r.tropo_m,
            range_rate_residual_mps: rr_res.and_then(|x| x[k]),
        })
        .collect();
    Ok(SppSolution {
        t: t_rx,
        t_fix: true_rx_time(t_rx, fitted.clock_bias_m),
        pos_ecef_m: fitted.pos_ecef_m,
        lla,
        clock_bias_m: fitted.clock_bias_m,
        vel_ecef_mps: velocity.as_ref().map(|v| v.vel_ecef_mps),
        clock_drift_mps: velocity.as_ref().map(|v| v.clock_drift_mps),
        n_used: satellites.len(),
        used_prns: satellites.iter().map(|s| s.prn).collect(),
        excluded_prns: excluded,
        masked_prns: fitted.masked,
        unusable_prns: unusable,
        satellites,
        dops,
        cov_m2: fitted.cov_m2,
        std_ned_m,
        vel_std_ned_mps: velocity.as_ref().map(|v| v.std_ned_mps),
        chi2,
        chi2_threshold,
        iterations: fitted.iterations,
    })
}

/// An SPP solver that starts each epoch from its previous solution.
#[derive(Clone, Debug, Default)]
pub struct SppSolver {
    pub config: SppConfig,
    last: Option<(Vector3<f64>, f64)>,
}

impl SppSolver {
    pub fn new(config: SppConfig) -> Self {
        SppSolver { config, last: None }
    }

    /// Solve one epoch, starting from the last solution (or the Earth centre).
    pub fn solve(
        &mut self,
        ephs: &EphemerisSet,
        t_rx: GpsTime,
        meas: &[SppMeasurement],
    ) -> Result<SppSolution, SppError> {
        let r = solve_epoch(ephs, t_rx, meas, &self.config, self.last);
        if let Ok(s) = &r {
            self.last = Some((s.pos_ecef_m, s.clock_bias_m));
        }
        r
    }

    /// Forget the previous solution.
    pub fn reset(&mut self) {
        self.last = None;
    }
}
