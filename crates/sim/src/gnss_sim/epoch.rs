//! One simulated epoch: visibility and events, raw measurements with their errors,
//! the receiver fix and heading, and the reference station's DGPS corrections.

use nalgebra::Vector3;
use navfuse_core::earth::{c_ne, ecef_to_lla, lla_to_ecef};
use navfuse_core::sat::{SatId, System};
use navfuse_gnss::atmosphere::{klobuchar_l1_delay_m, saastamoinen_slant_m, tropo_mapping};
use navfuse_gnss::ephemeris::SPEED_OF_LIGHT_MPS;
use navfuse_gnss::geometry::{az_el, signal_path};
use navfuse_gnss::time::GpsTime;
use navfuse_io::rinex_obs::SatObs;

use super::{
    elevation_scale, iono_obliquity, sim_carrier_hz, DgpsCorrection, DgpsSpec, ErrorParts,
    EventSpec, Fix, GnssEpoch, GnssSim, SatEpoch, L1_HZ,
};
use crate::trajectory::TruthSample;

impl GnssSim {
    /// Simulate the epoch at the truth sample `truth` (time truth.t).
    pub fn epoch(&mut self, truth: &TruthSample) -> GnssEpoch {
        let t = truth.t;
        let rel = t - self.t0;
        let dt = self.last_t.map_or(0.0, |lt| t - lt);
        self.last_t = Some(t);
        let e = self.spec.errors.clone();
        // Advance the processes (also through outages: the errors keep evolving).
        if dt > 0.0 {
            self.tropo_common.step(dt, &mut self.rng_tropo);
            self.tropo_diff.step(dt, &mut self.rng_tropo);
            self.rx_clock.step(dt, &mut self.rng_rx);
            let q = e.isb_walk_m_per_sqrth * (dt / 3_600.0).sqrt();
            for (v, rng) in self.isb_walk.values_mut() {
                *v += q * rng.normal();
            }
            for p in self.procs.values_mut() {
                let r = &mut p.rng;
                p.iono_common.step(dt, r);
                p.iono_diff.step(dt, r);
                p.sat_clock.step(dt, r);
                p.orbit_common.step(dt, r);
                p.orbit_diff.step(dt, r);
                p.sa.step(dt, r);
                p.multipath.step(dt, r);
                p.phase_multipath.step(dt, r);
                p.ref_multipath.step(dt, r);
            }
            for g in self.fix_err.iter_mut() {
                g.step(dt, &mut self.rng_fix);
            }
        }
        let gt = GpsTime::new(self.week, t);
        let ant_lla = {
            let d = truth.c_bn * self.lever_b;
            ecef_to_lla(&(lla_to_ecef(&truth.lla) + c_ne(truth.lla.x, truth.lla.y) * d))
        };
        let ant_vel = truth.velocity_at(&self.lever_b);
        self.history.push_back((t, ant_lla, ant_vel));
        let max_delay = self
            .spec
            .events
            .iter()
            .map(|e| match e {
                EventSpec::Spoof { delay_s, .. } => *delay_s,
                _ => 0.0,
            })
            .fold(0.0, f64::max);
        while self
            .history
            .front()
            .is_some_and(|h| h.0 < t - max_delay - 2.0)
        {
            self.history.pop_front();
        }

        // DGPS: the reference station's corrections at this epoch (before the rover
        // uses them, so latency 0 means "this epoch's corrections").
        let mut out = GnssEpoch {
            t,
            rx_clock_m: self.rx_clock.value(),
            ..Default::default()
        };
        if let (Some(d), Some(ref_lla)) = (self.spec.dgps.clone(), self.ref_lla) {
            if t - self.last_dgps_t >= d.interval_s - 1e-6 {
                self.last_dgps_t = t;
                let corr = self.reference_corrections(gt, &ref_lla, &d);
                out.corrections = corr.clone();
                self.pending.extend(corr);
            }
            while self
                .pending
                .front()
                .is_some_and(|c| c.t + d.latency_s <= t + 1e-9)
            {
                let c = self.pending.pop_front().expect("checked");
                self.latest[c.prn as usize] = Some(c);
            }
        }

        out.outage = self.in_outage(rel);
        if out.outage {
            for p in self.procs.values_mut() {
                if p.tracked {
                    p.lli_pending = true;
                }
                p.tracked = false;
            }
            return out;
        }
        let (rx_lla, rx_vel_ned, spoof) = self.antenna_track(rel, ant_lla, ant_vel);
        out.spoof_offset_ned = spoof;
        let rx_ecef = lla_to_ecef(&rx_lla);
        let rx_vel_ecef = c_ne(rx_lla.x, rx_lla.y) * rx_vel_ned;
        // Geometry is that of the (possibly false) position: the spoofer synthesises
        // consistent signals. The true antenna sees the spoofer's signals only.
        let true_ecef = lla_to_ecef(&ant_lla);
        let mask = self.spec.elevation_mask_deg.to_radians();
        let mut paths = Vec::new();
        for sat in self.ephs.sats() {
            let Some(eph) = self.ephs.select(sat, gt) else {
                continue;
            };
            let path = signal_path(eph, &rx_ecef, &rx_vel_ecef, gt);
            let (az, el) = az_el(&rx_lla, &path.los_unit);
            if el < mask {
                continue;
            }
            if self.blocked(rel, sat) {
                continue;
            }
            let lost = self.spec.events.iter().any(|e| matches!(e, EventSpec::LossOfLock { prn: p, start_s, end_s } if p.sat() == Some(sat) && rel > *start_s && rel < *end_s));
            if lost {
                continue;
            }
            let f_hz = sim_carrier_hz(eph);
            paths.push((sat, (eph.group_delay_s(), eph.iod(), f_hz), path, az, el));
        }
        // Blockage by count: keep the highest satellites.
        if let Some(keep) = self.blockage_keep(rel) {
            paths.sort_by(|a, b| b.4.total_cmp(&a.4));
            paths.truncate(keep);
            paths.sort_by_key(|p| p.0);
        }
        let tracked: Vec<SatId> = paths.iter().map(|p| p.0).collect();
        for (sat, p) in self.procs.iter_mut() {
            let now = tracked.contains(sat);
            if !now && p.tracked {
                // Lost: a new ambiguity on reacquisition.
                p.ambiguity = (p.rng.uniform_range(-1e5, 1e5)).round() as i64;
            }
            if now && !p.tracked {
                p.lli_pending = true;
            }
            p.tracked = now;
        }
        for (sat, (tgd_s, iode, f_hz), path, az, el) in paths {
            let Some(p) = self.procs.get_mut(&sat) else {
                continue;
            };
            let prn = sat.prn;
            // The system's signal: wavelength, ionosphere scaling (f_L1/f)^2 of the
            // L1-referred delays, receiver inter-system bias.
            let wavelength_m = SPEED_OF_LIGHT_MPS / f_hz;
            let iono_scale = (L1_HZ / f_hz).powi(2);
            let isb_m = e.isb_of(sat.system) + self.isb_walk.get(&sat.system).map_or(0.0, |w| w.0);
            for ev in &self.spec.events {
                if let EventSpec::CycleSlip {
                    prn: sp,
                    at_s,
                    cycles,
                } = ev
                {
                    let (at_s, cycles) = (*at_s, *cycles);
                    if sp.sat() == Some(sat) && at_s > rel - dt && at_s <= rel {
                        p.ambiguity += cycles;
                        p.lli_pending = true;
                    }
                }
            }
            let obl = iono_obliquity(el);
            let mt = tropo_mapping(el);
            let sc = elevation_scale(el);
            let noise = e.noise_m * sc * p.rng.normal();
            // The receiver clock as this system's signals see it: + ISB (GPS: none).
            let rx_clock = if isb_m == 0.0 {
                self.rx_clock.value()
            } else {
                self.rx_clock.value() + isb_m
            };
            let parts = ErrorParts {
                iono: iono_scale * (obl * (p.iono_common.value() + p.iono_diff.value())),
                tropo: mt * (self.tropo_common.value() + self.tropo_diff.value()),
                sat_clock: p.sat_clock.value(),
                orbit: p.orbit_common.value() + p.orbit_diff.value(),
                multipath: sc * p.multipath.value(),
                noise,
                rx_clock,
                sa: p.sa.value(),
            };
            let rates = iono_scale * (obl * (p.iono_common.rate() + p.iono_diff.rate()));
            let tropo_rate = mt * (self.tropo_common.rate() + self.tropo_diff.rate());
            let common_rate = tropo_rate
                + p.sat_clock.rate()
                + p.orbit_common.rate()
                + p.orbit_diff.rate()
                + p.sa.rate()
                + self.rx_clock.rate();
            let (model_iono, model_tropo) = if e.model_delays {
                (
                    iono_scale
                        * klobuchar_l1_delay_m(
                            &self.iono_alpha,
                            &self.iono_beta,
                            rx_lla.x,
                            rx_lla.y,
                            az,
                            el,
                            t,
                        ),
                    saastamoinen_slant_m(rx_lla.x, rx_lla.z, el),
                )
            } else {
                (0.0, 0.0)
            };
            // Satellite clock as a single-frequency user applies it: minus TGD (GPS L1
            // C/A, IS-GPS-200 20.3.3.3.3.2), BGD (Galileo E1), TGD1 (BeiDou B1I).
            let dts_m = (path.sat_clock_bias_s - tgd_s) * SPEED_OF_LIGHT_MPS;
            let dts_rate = path.sat_clock_drift_s_per_s * SPEED_OF_LIGHT_MPS;
            let range = path.geometric_range_m;
            let pr = range - dts_m + model_iono + model_tropo + parts.total();
            let nondisp = parts.tropo + parts.sat_clock + parts.orbit + parts.rx_clock + parts.sa;
            let phase_m = range - dts_m - model_iono + model_tropo - parts.iono
                + nondisp
                + sc * p.phase_multipath.value()
                + e.phase_noise_m * sc * p.rng.normal();
            let carrier = phase_m / wavelength_m + p.ambiguity as f64;
            let range_rate = path.range_rate_mps - dts_rate + common_rate - rates;
            let doppler = -(range_rate + e.doppler_noise_mps * sc * p.rng.normal()) / wavelength_m;
            let cn0 = e.cn0_zenith_dbhz - 20.0 * sc.log10() + 0.5 * p.rng.normal();
            let lli = if p.lli_pending { 1 } else { 0 };
            p.lli_pending = false;
            let spoof_range_m = if spoof.is_some() {
                range - (path.sat_pos_ecef_m - true_ecef).norm()
            } else {
                0.0
            };
            let latest = match sat.system {
                System::Gps => self.latest[prn as usize],
                _ => None,
            };
            let (dgps_residual, dgps_age_s) = match latest {
                Some(c) if c.iode == iode => {
                    let age = t - c.t;
                    let r = |rover: f64, refv: f64, rate: f64| rover - refv - rate * age;
                    let (a, b) = (c.parts, c.parts_rate);
                    (
                        Some(ErrorParts {
                            iono: r(parts.iono, a.iono, b.iono),
                            tropo: r(parts.tropo, a.tropo, b.tropo),
                            sat_clock: r(parts.sat_clock, a.sat_clock, b.sat_clock),
                            orbit: r(parts.orbit, a.orbit, b.orbit),
                            multipath: r(parts.multipath, a.multipath, b.multipath),
                            noise: r(parts.noise, a.noise, b.noise),
                            rx_clock: parts.rx_clock,
                            sa: r(parts.sa, a.sa, b.sa),
                        }),
                        Some(age),
                    )
                }
                _ => (None, None),
            };
            out.sats.push(SatEpoch {
                sat,
                obs: SatObs {
                    prn,
                    pseudorange_m: Some(pr),
                    carrier_cycles: Some(carrier),
                    doppler_hz: Some(doppler),
                    cn0_dbhz: Some(cn0),
                    lli,
                },
                el_rad: el,
                az_rad: az,
                errors: parts,
                dgps_residual,
                dgps_age_s,
                spoof_range_m,
            });
        }

        // Receiver fix from the noise model (at the reported, possibly false, position).
        if let Some(f) = &self.spec.fix {
            if out.sats.len() >= f.min_satellites {
                let err = Vector3::new(
                    self.fix_err[0].value(),
                    self.fix_err[1].value(),
                    self.fix_err[2].value(),
                );
                let lla = ecef_to_lla(&(rx_ecef + c_ne(rx_lla.x, rx_lla.y) * err));
                let vn = Vector3::new(
                    self.rng_fix.normal(),
                    self.rng_fix.normal(),
                    self.rng_fix.normal(),
                ) * f.velocity_std_mps;
                out.fix = Some(Fix {
                    t,
                    lla,
                    std_ned: Vector3::new(f.horizontal_std_m, f.horizontal_std_m, f.vertical_std_m),
                    vel_ned: rx_vel_ned + vn,
                    vel_std: f.velocity_std_mps,
                    spoofed: spoof.is_some(),
                });
            }
        }
        // Dual-antenna heading (SYSTEM.md §3c): azimuth of the baseline in NED.
        if let Some(h) = &self.spec.heading {
            if out.sats.len() >= 4 {
                let b = Vector3::from(h.baseline_m);
                let std = h.std_deg.unwrap_or(0.3 * 1.2 / b.norm()).to_radians();
                let b_n = truth.c_bn * b;
                let psi = b_n.y.atan2(b_n.x) + std * self.rng_heading.normal();
                out.heading = Some((navfuse_core::attitude::wrap_2pi(psi), std));
            }
        }
        out
    }

    fn blockage_keep(&self, rel: f64) -> Option<usize> {
        self.spec.events.iter().find_map(|e| match e {
            EventSpec::Blockage {
                start_s,
                end_s,
                keep: Some(k),
                ..
            } if rel > *start_s && rel < *end_s => Some(*k),
            _ => None,
        })
    }

    /// Blockage by satellite list.
    fn blocked(&self, rel: f64, sat: SatId) -> bool {
        self.spec.events.iter().any(|e| match e {
            EventSpec::Blockage {
                start_s,
                end_s,
                prns: Some(list),
                ..
            } => rel > *start_s && rel < *end_s && !list.iter().any(|r| r.sat() == Some(sat)),
            _ => false,
        })
    }

    /// Corrections from the reference station at `gt` (RTCM convention: the station
    /// removes its own clock, so PRC = -(common errors + model delays + own noise)).
    fn reference_corrections(
        &mut self,
        gt: GpsTime,
        ref_lla: &Vector3<f64>,
        d: &DgpsSpec,
    ) -> Vec<DgpsCorrection> {
        let e = &self.spec.errors;
        let ref_ecef = lla_to_ecef(ref_lla);
        let mask = self.spec.elevation_mask_deg.to_radians();
        let mut out = Vec::new();
        // GPS only: dgps.csv carries GPS PRNs (RTCM 1/9 style).
        for sat in self.ephs.sats() {
            if sat.system != System::Gps {
                continue;
            }
            let prn = sat.prn;
            let Some(eph) = self.ephs.select(sat, gt) else {
                continue;
            };
            let Some(p) = self.procs.get_mut(&sat) else {
                continue;
            };
            let path = signal_path(eph, &ref_ecef, &Vector3::zeros(), gt);
            let (az, el) = az_el(ref_lla, &path.los_unit);
            if el < mask {
                continue;
            }
            let obl = iono_obliquity(el);
            let mt = tropo_mapping(el);
            let sc = elevation_scale(el);
            let parts = ErrorParts {
                iono: obl * p.iono_common.value(),
                tropo: mt * self.tropo_common.value(),
                sat_clock: p.sat_clock.value(),
                orbit: p.orbit_common.value(),
                multipath: sc * p.ref_multipath.value(),
                noise: d.ref_noise_m * sc * p.rng.normal(),
                rx_clock: 0.0,
                sa: p.sa.value(),
            };
            let rates = ErrorParts {
                iono: obl * p.iono_common.rate(),
                tropo: mt * self.tropo_common.rate(),
                sat_clock: p.sat_clock.rate(),
                orbit: p.orbit_common.rate(),
                multipath: 0.0,
                noise: 0.0,
                rx_clock: 0.0,
                sa: p.sa.rate(),
            };
            let (mi, mtr) = if e.model_delays {
                (
                    klobuchar_l1_delay_m(
                        &self.iono_alpha,
                        &self.iono_beta,
                        ref_lla.x,
                        ref_lla.y,
                        az,
                        el,
                        gt.sow,
                    ),
                    saastamoinen_slant_m(ref_lla.x, ref_lla.z, el),
                )
            } else {
                (0.0, 0.0)
            };
            out.push(DgpsCorrection {
                t: gt.sow,
                prn,
                prc_m: -(parts.total() + mi + mtr),
                rrc_mps: -(rates.total()),
                iode: eph.iod(),
                parts,
                parts_rate: rates,
            });
        }
        out
    }
}
