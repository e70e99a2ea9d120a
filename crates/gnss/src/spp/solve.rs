//! The SPP solver: weighted least squares on the pseudoranges of every system (one
//! clock per clock group, [`clock_group`]), DOPs, the residual chi-square test with
//! fault detection and exclusion, and the solution assembly.

use super::velocity::solve_velocity;
use super::{
    clock_group, Dops, SppConfig, SppError, SppMeasurement, SppSatellite, SppSolution,
    FDE_MIN_REDUNDANCY, GPS_L1_HZ, NEAR_SURFACE_MIN_H_M,
};
use crate::ephemeris::SPEED_OF_LIGHT_MPS;
use crate::geometry::{az_el, signal_path, SignalPath};
use crate::orbit_source::{OrbitSource, SelectedOrbit};
use crate::time::GpsTime;
use nalgebra::{Matrix4, SMatrix, SVector, Vector3, Vector4};
use navfuse_core::chi2::chi2_quantile;
use navfuse_core::earth::{c_ne, ecef_to_lla};
use navfuse_core::sat::{SatId, System};

/// The clock groups, in order of preference for the reference clock.
pub(super) const CLOCKS: [System; 5] = [
    System::Gps,
    System::Galileo,
    System::BeiDou,
    System::Glonass,
    System::Navic,
];
/// Unknowns: position and one clock per group.
const NX: usize = 3 + CLOCKS.len();
type VecX = SVector<f64, NX>;
type MatX = SMatrix<f64, NX, NX>;

fn clock_index(system: System) -> Option<usize> {
    let g = clock_group(system);
    CLOCKS.iter().position(|&c| c == g)
}

/// A measurement with its orbit.
pub(super) struct Candidate<'a> {
    pub(super) sat: SatId,
    /// Index into `CLOCKS`.
    clock: usize,
    /// Measured pseudorange, plus the DGPS correction when `dgps` [m].
    pseudorange_m: f64,
    dgps: bool,
    iono_free: bool,
    /// Group delay of the code (`RecordRef::group_delay_s`) [s].
    group_delay_s: f64,
    /// (f_L1 / f)^2: the L1 ionospheric delay on this signal.
    iono_scale: f64,
    pub(super) doppler_hz: Option<f64>,
    /// The C/N0 variance term (`SppErrorModel::cn0_variance_m2`) [m^2].
    cn0_var_m2: f64,
    pub(super) wavelength_m: f64,
    pub(super) orbit: SelectedOrbit<'a>,
}

/// One pseudorange row of the linearised system.
pub(super) struct Row {
    /// Index into the candidates.
    pub(super) idx: usize,
    /// Design row d(P)/d(x, y, z, clocks): the reference clock and, for another
    /// group, its inter-system bias.
    h: VecX,
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
    /// Reference clock [m].
    pub(super) clock_bias_m: f64,
    /// Index into `CLOCKS` of the reference clock.
    reference: usize,
    /// Inter-system bias of each group to the reference (0 when absent) [m].
    isb_m: [f64; CLOCKS.len()],
    pub(super) rows: Vec<Row>,
    /// Post-fit residuals, one per row [m].
    post_m: Vec<f64>,
    /// (H^T W H)^-1 over all unknowns (unit rows for those not estimated).
    cov_full: MatX,
    /// Groups with a row.
    present: [bool; CLOCKS.len()],
    masked: Vec<SatId>,
    iterations: usize,
}

impl Fit {
    /// Unknowns estimated: 3 + the clock groups present.
    fn unknowns(&self) -> usize {
        3 + self.present.iter().filter(|p| **p).count()
    }

    /// Covariance of (x, y, z, reference clock).
    fn cov4(&self) -> Matrix4<f64> {
        let mut c = Matrix4::zeros();
        let k = [0, 1, 2, 3 + self.reference];
        for i in 0..4 {
            for j in 0..4 {
                c[(i, j)] = self.cov_full[(k[i], k[j])];
            }
        }
        c
    }
}

/// True reception time: the receiver tag corrected by the clock estimate.
pub(super) fn true_rx_time(t_rx: GpsTime, clock_bias_m: f64) -> GpsTime {
    t_rx.add_s(-clock_bias_m / SPEED_OF_LIGHT_MPS)
}

/// The state being iterated: position, reference clock, inter-system biases.
#[derive(Clone, Copy)]
struct Estimate {
    pos: Vector3<f64>,
    clock_m: f64,
    isb_m: [f64; CLOCKS.len()],
}

/// Build the pseudorange rows at `x` for the active candidates; `reference` is set
/// to the first clock group present.
fn build_rows(
    cands: &[Candidate<'_>],
    active: &[bool],
    cfg: &SppConfig,
    t_rx: GpsTime,
    x: &Estimate,
    masked: &mut Vec<SatId>,
) -> (Vec<Row>, usize) {
    let lla = ecef_to_lla(&x.pos);
    let near_surface = lla.z > NEAR_SURFACE_MIN_H_M;
    let t_true = true_rx_time(t_rx, x.clock_m);
    masked.clear();
    let mut rows = Vec::with_capacity(cands.len());
    for (idx, c) in cands.iter().enumerate() {
        if !active[idx] {
            continue;
        }
        let sp: SignalPath = signal_path(&c.orbit, &x.pos, &Vector3::zeros(), t_true);
        if !(sp.geometric_range_m.is_finite() && sp.sat_clock_bias_s.is_finite()) {
            masked.push(c.sat);
            continue;
        }
        // Far from the surface (the Earth-centre start) elevations mean nothing:
        // every satellite is taken, without atmospheric corrections.
        let (az, el) = if near_surface {
            az_el(&lla, &sp.los_unit)
        } else {
            (0.0, std::f64::consts::FRAC_PI_2)
        };
        if near_surface && el < cfg.elevation_mask_rad {
            masked.push(c.sat);
            continue;
        }
        // A DGPS-corrected pseudorange already has the atmosphere removed.
        let (iono_l1_m, tropo_m) = if near_surface && !c.dgps {
            cfg.atmosphere_m(&lla, az, el, t_rx.sow)
        } else {
            (0.0, 0.0)
        };
        let iono_m = if c.iono_free {
            0.0
        } else {
            iono_l1_m * c.iono_scale
        };
        // IS-GPS-200 20.3.3.3.3.2: the single-frequency user's clock is dt_sv - TGD.
        let sat_clock_m = SPEED_OF_LIGHT_MPS * (sp.sat_clock_bias_s - c.group_delay_s);
        let modelled =
            sp.geometric_range_m + x.clock_m + x.isb_m[c.clock] - sat_clock_m + iono_m + tropo_m;
        let var_m2 = cfg.pseudorange_variance_m2(
            c.sat.system,
            &c.orbit.accuracy,
            el,
            iono_m,
            c.dgps,
            c.iono_free,
        ) + c.cn0_var_m2;
        let los = sp.los_unit;
        let mut h = VecX::zeros();
        h[0] = -los.x;
        h[1] = -los.y;
        h[2] = -los.z;
        rows.push(Row {
            idx,
            h,
            v_m: c.pseudorange_m - modelled,
            var_m2,
            az_rad: az,
            el_rad: el,
            iono_m,
            tropo_m,
            los_unit: los,
        });
    }
    let reference = (0..CLOCKS.len())
        .find(|&k| rows.iter().any(|r| cands[r.idx].clock == k))
        .unwrap_or(0);
    for r in &mut rows {
        let k = cands[r.idx].clock;
        r.h[3 + reference] = 1.0;
        if k != reference {
            r.h[3 + k] = 1.0;
        }
    }
    (rows, reference)
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
    let mut x = Estimate {
        pos: start_pos_ecef_m,
        clock_m: start_clock_bias_m,
        isb_m: [0.0; CLOCKS.len()],
    };
    let mut masked = Vec::new();
    let mut last_step = f64::INFINITY;
    let max_iter = cfg.max_iterations.max(1);
    let mut last_reference = None;
    for it in 0..max_iter {
        let (rows, reference) = build_rows(cands, active, cfg, t_rx, &x, &mut masked);
        if last_reference.is_some_and(|r| r != reference) {
            // The reference group changed (its satellites masked): its clock is
            // now the old clock plus that group's bias.
            let shift = x.isb_m[reference];
            x.clock_m += shift;
            x.isb_m.iter_mut().for_each(|b| *b -= shift);
        }
        last_reference = Some(reference);
        let mut present = [false; CLOCKS.len()];
        rows.iter().for_each(|r| present[cands[r.idx].clock] = true);
        let n_clocks = present.iter().filter(|p| **p).count().max(1);
        let required = cfg.min_satellites.max(3 + n_clocks);
        if rows.len() < required {
            return Err(SppError::TooFewSatellites {
                available: rows.len(),
                required,
            });
        }
        let mut n = MatX::zeros();
        let mut b = VecX::zeros();
        for r in &rows {
            let w = 1.0 / r.var_m2;
            n += r.h * r.h.transpose() * w;
            b += r.h * (r.v_m * w);
        }
        // Column 3 + reference is the reference clock, 3 + k the bias of group k;
        // a group without satellites gets a unit row that keeps its bias at zero.
        for k in 0..CLOCKS.len() {
            if !present[k] {
                n[(3 + k, 3 + k)] += 1.0;
            }
        }
        let chol = n.cholesky().ok_or(SppError::SingularGeometry)?;
        let dx = chol.solve(&b);
        if !dx.iter().all(|v| v.is_finite()) {
            return Err(SppError::SingularGeometry);
        }
        x.pos += dx.fixed_rows::<3>(0);
        x.clock_m += dx[3 + reference];
        for k in 0..CLOCKS.len() {
            if k != reference {
                x.isb_m[k] += dx[3 + k];
            }
        }
        last_step = dx.norm();
        if last_step < cfg.convergence_m {
            // Post-fit residuals of the linearised system at the converged state.
            let post_m = rows.iter().map(|r| r.v_m - r.h.dot(&dx)).collect();
            return Ok(Fit {
                pos_ecef_m: x.pos,
                clock_bias_m: x.clock_m,
                reference,
                isb_m: x.isb_m,
                rows,
                post_m,
                cov_full: chol.inverse(),
                present,
                masked,
                iterations: it + 1,
            });
        }
        if !x.pos.iter().all(|v| v.is_finite()) || x.pos.norm() > 1e9 {
            break;
        }
    }
    Err(SppError::NotConverged {
        iterations: max_iter,
        last_step_m: last_step,
    })
}

/// DOPs from the used lines of sight (unit weights, one common clock as the usual
/// definition), in NED at `lla`.
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
    orbits: &(impl OrbitSource + ?Sized),
    t_rx: GpsTime,
    meas: &[SppMeasurement],
    cfg: &SppConfig,
    start: Option<(Vector3<f64>, f64)>,
) -> Result<SppSolution, SppError> {
    // Candidates: valid pseudorange, a usable orbit, first occurrence of a satellite.
    let mut cands: Vec<Candidate<'_>> = Vec::with_capacity(meas.len());
    let mut unusable = Vec::new();
    for m in meas {
        if cands.iter().any(|c| c.sat == m.sat) {
            continue;
        }
        let pr_ok = m.pseudorange_m.is_finite()
            && m.pseudorange_m > 0.0
            && m.frequency_hz.is_finite()
            && m.frequency_hz > 0.0
            && m.dgps_prc_m.is_none_or(f64::is_finite);
        let clock = clock_index(m.sat.system);
        let orbit = orbits.select(m.sat, t_rx);
        let group_delay = orbit.and_then(|o| {
            o.record
                .group_delay_s(m.sat.system, m.band, m.iono_free_with)
        });
        match (orbit, clock, group_delay) {
            (Some(orbit), Some(clock), Some(group_delay_s)) if pr_ok => cands.push(Candidate {
                sat: m.sat,
                clock,
                pseudorange_m: m.pseudorange_m + m.dgps_prc_m.unwrap_or(0.0),
                dgps: m.dgps_prc_m.is_some(),
                iono_free: m.iono_free_with.is_some(),
                group_delay_s,
                iono_scale: (GPS_L1_HZ / m.frequency_hz).powi(2),
                doppler_hz: m.doppler_hz,
                cn0_var_m2: cfg.errors.cn0_variance_m2(m.cn0_dbhz),
                wavelength_m: m.wavelength_m(),
                orbit,
            }),
            _ => unusable.push(m.sat),
        }
    }
    if cands.is_empty() {
        return Err(SppError::NoEphemeris { sats: unusable });
    }
    let required = cfg.min_satellites.max(4);
    if cands.len() < required {
        return Err(SppError::TooFewSatellites {
            available: cands.len(),
            required,
        });
    }

    let mut active = vec![true; cands.len()];
    let mut excluded: Vec<SatId> = Vec::new();
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
        let unknowns = fitted.unknowns();
        let chi2: f64 = fitted
            .rows
            .iter()
            .zip(&fitted.post_m)
            .map(|(r, v)| v * v / r.var_m2)
            .sum();
        let threshold =
            (n_used > unknowns).then(|| chi2_quantile(n_used - unknowns, cfg.chi2_probability));
        if let (true, Some(thr)) = (cfg.fde, threshold) {
            if chi2 > thr {
                if n_used < unknowns + FDE_MIN_REDUNDANCY {
                    return Err(SppError::ResidualTestFailed {
                        chi2,
                        threshold: thr,
                        n_used,
                        excluded,
                    });
                }
                // Exclude the largest normalised residual |v_i| / sqrt(Q_v,ii),
                // Q_v = R - H (H^T W H)^-1 H^T (Baarda's w-test). A group's only
                // satellite has Q_v = 0 (its bias absorbs it) and is not tested.
                let worst = fitted
                    .rows
                    .iter()
                    .zip(&fitted.post_m)
                    .enumerate()
                    .filter_map(|(k, (r, v))| {
                        let qv = r.var_m2 - (r.h.transpose() * fitted.cov_full * r.h)[0];
                        (qv > 1e-9 * r.var_m2).then(|| (k, v.abs() / qv.sqrt()))
                    })
                    .max_by(|a, b| a.1.total_cmp(&b.1));
                let Some((k, _)) = worst else {
                    return Err(SppError::ResidualTestFailed {
                        chi2,
                        threshold: thr,
                        n_used,
                        excluded,
                    });
                };
                let idx = fitted.rows[k].idx;
                active[idx] = false;
                excluded.push(cands[idx].sat);
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
    excluded: Vec<SatId>,
    unusable: Vec<SatId>,
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
    let cov_m2 = fitted.cov4();
    let c = c_ne(lla.x, lla.y);
    let p_ned = c.transpose() * cov_m2.fixed_view::<3, 3>(0, 0) * c;
    let std_ned_m = p_ned.diagonal().map(|x| x.max(0.0).sqrt());
    let velocity = solve_velocity(cands, &fitted, t_rx, cfg.errors.doppler_sigma_hz, &lla);
    let rr_res = velocity.as_ref().map(|v| &v.range_rate_residuals_mps);
    let satellites: Vec<SppSatellite> = fitted
        .rows
        .iter()
        .zip(&fitted.post_m)
        .enumerate()
        .map(|(k, (r, v))| SppSatellite {
            sat: cands[r.idx].sat,
            az_rad: r.az_rad,
            el_rad: r.el_rad,
            residual_m: *v,
            sigma_m: r.var_m2.sqrt(),
            iono_m: r.iono_m,
            tropo_m: r.tropo_m,
            range_rate_residual_mps: rr_res.and_then(|x| x[k]),
        })
        .collect();
    let isb_m = (0..CLOCKS.len())
        .filter(|&k| fitted.present[k] && k != fitted.reference)
        .map(|k| {
            let var = fitted.cov_full[(3 + k, 3 + k)];
            (CLOCKS[k], fitted.isb_m[k], var.max(0.0).sqrt())
        })
        .collect();
    Ok(SppSolution {
        t: t_rx,
        t_fix: true_rx_time(t_rx, fitted.clock_bias_m),
        pos_ecef_m: fitted.pos_ecef_m,
        lla,
        clock_bias_m: fitted.clock_bias_m,
        reference_system: CLOCKS[fitted.reference],
        isb_m,
        vel_ecef_mps: velocity.as_ref().map(|v| v.vel_ecef_mps),
        clock_drift_mps: velocity.as_ref().map(|v| v.clock_drift_mps),
        n_used: satellites.len(),
        used_sats: satellites.iter().map(|s| s.sat).collect(),
        excluded_sats: excluded,
        masked_sats: fitted.masked,
        unusable_sats: unusable,
        satellites,
        dops,
        cov_m2,
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
        orbits: &(impl OrbitSource + ?Sized),
        t_rx: GpsTime,
        meas: &[SppMeasurement],
    ) -> Result<SppSolution, SppError> {
        let r = solve_epoch(orbits, t_rx, meas, &self.config, self.last);
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
