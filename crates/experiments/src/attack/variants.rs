//! The navigator configurations of the spoofing experiments.

use navfuse_core::config::NhcMode;
use navfuse_core::integrity::{IntegrityOptions, IntegrityReference};
use navfuse_core::outage::Window;
use navfuse_io::config::RunConfig;
use navfuse_sim::gnss_sim::EventSpec;
use navfuse_sim::scenario::Scenario;

use crate::reproduce::setup::{seed004_odometer, seed004_start};
use crate::reproduce::Variant;

/// Seed 004's start (surveyed position, static levelling + gyrocompassing, ZUPT while
/// static) with the GNSS fixes kept.
pub(super) fn attack_start(cfg: &mut RunConfig, sc: &Scenario) {
    let gnss = cfg.gnss.take();
    seed004_start(cfg, sc);
    cfg.gnss = gnss;
}

/// The INS/odometer reference: seed 004's odometer and the NHC at every epoch.
pub(super) fn odometer_nhc(cfg: &mut RunConfig, sc: &Scenario) {
    seed004_odometer(cfg, sc);
    cfg.nav.nhc.mode = NhcMode::Always;
}

/// `[spoofing]` with its defaults (the thresholds under test), and the fix error's
/// correlation time, which the simulator sets (`[gnss.fix] corr_time_s = 30`).
pub(super) fn monitor_defaults(cfg: &mut RunConfig) {
    cfg.nav.integrity = IntegrityOptions {
        enabled: true,
        gnss_corr_time_s: 30.0,
        ..IntegrityOptions::default()
    };
}

/// Seed 004's architecture: the 6-state fusion (every fix) of GNSS with a dead
/// reckoning that GNSS never corrects, and the monitor testing the GNSS against that
/// dead reckoning (r_INS/OD) with its own covariance.
pub(super) fn seed004_architecture(cfg: &mut RunConfig) {
    six_state_fusion(cfg);
    // With no GNSS to calibrate them, the dead reckoning's biases wander as the
    // grade's in-run Gauss-Markov process (IMU500: 100 s), not the slow 1 h process
    // that a GNSS-aided filter uses to keep what it has learnt.
    cfg.nav.imu_noise.corr_time_s = 100.0;
    cfg.nav.integrity.reference = IntegrityReference::DeadReckoning;
}

/// Seed 004's 6-state fusion of every fix (`[gnss] fusion = "six_state"`).
pub(super) fn six_state_fusion(cfg: &mut RunConfig) {
    cfg.nav.gnss.fusion = navfuse_core::config::GnssFusion::SixState {
        every: std::num::NonZeroU32::MIN,
    };
}

/// Seed 004's detector alone: distance R = 10 m, the statistical tests off.
/// (Every statistical detector of `IntegrityOptions` must be switched off here.)
pub(super) fn distance_only(cfg: &mut RunConfig) {
    monitor_defaults(cfg);
    let i = &mut cfg.nav.integrity;
    i.distance_m = Some(10.0);
    i.chi2_probability = None;
    i.window_epochs = 0;
}

/// The per-epoch chi-square test alone (distance and window off).
pub(super) fn chi2_only(cfg: &mut RunConfig) {
    monitor_defaults(cfg);
    let i = &mut cfg.nav.integrity;
    i.distance_m = None;
    i.window_epochs = 0;
}

/// The attack's window (start, end) from the scenario's spoof event [s from the start].
pub(super) fn attack_window_rel(sc: &Scenario) -> Option<(f64, f64)> {
    sc.file.gnss.as_ref()?.events.iter().find_map(|e| match e {
        EventSpec::Spoof { start_s, end_s, .. } => Some((*start_s, *end_s)),
        _ => None,
    })
}

pub(super) fn variants() -> Vec<Variant> {
    vec![
        Variant {
            name: "no_monitor",
            label: "IMU + odometer + NHC (always) + GNSS, no monitor",
            apply: |c, sc| {
                attack_start(c, sc);
                odometer_nhc(c, sc);
            },
        },
        Variant {
            name: "monitor",
            label:
                "same + [spoofing] defaults (R 10 m, chi-square, window), INS/odometer reference",
            apply: |c, sc| {
                attack_start(c, sc);
                odometer_nhc(c, sc);
                monitor_defaults(c);
            },
        },
        Variant {
            name: "monitor_R",
            label: "same, seed 004's detector alone: distance R = 10 m (chi-square, window off)",
            apply: |c, sc| {
                attack_start(c, sc);
                odometer_nhc(c, sc);
                distance_only(c);
            },
        },
        Variant {
            name: "odo_dr_R",
            label: "seed 004's system: 6-state fusion, the free INS/odometer/NHC dead reckoning as the reference, R = 10 m alone",
            apply: |c, sc| {
                attack_start(c, sc);
                odometer_nhc(c, sc);
                distance_only(c);
                seed004_architecture(c);
            },
        },
        Variant {
            name: "ins_only_R",
            label: "same with a free INS-only dead reckoning (no odometer, no NHC), R = 10 m alone",
            apply: |c, sc| {
                attack_start(c, sc);
                distance_only(c);
                seed004_architecture(c);
            },
        },
        Variant {
            name: "ins_only_chi2",
            label: "free INS-only dead reckoning, chi-square with its own covariance alone",
            apply: |c, sc| {
                attack_start(c, sc);
                chi2_only(c);
                seed004_architecture(c);
            },
        },
        Variant {
            name: "dead_reckoning",
            label: "IMU + odometer + NHC, GNSS removed over the attack (INS/odometer drift bound)",
            apply: |c, sc| {
                attack_start(c, sc);
                odometer_nhc(c, sc);
                withhold_gnss_over_attack(c, sc);
            },
        },
        // seed 004's 6-state fusion (`[gnss] fusion = "six_state"`, every fix):
        // GNSS fused with the INS/odometer/NHC dead reckoning by X = [r^n, v^n].
        Variant {
            name: "six_state_monitor",
            label: "seed 004's 6-state fusion of GNSS with INS/odometer/NHC + [spoofing] defaults (against its prediction)",
            apply: |c, sc| {
                attack_start(c, sc);
                odometer_nhc(c, sc);
                monitor_defaults(c);
                six_state_fusion(c);
            },
        },
        Variant {
            name: "six_state_dead_reckoning",
            label: "the same 6-state fusion, GNSS removed over the attack (its drift bound)",
            apply: |c, sc| {
                attack_start(c, sc);
                odometer_nhc(c, sc);
                six_state_fusion(c);
                withhold_gnss_over_attack(c, sc);
            },
        },
    ]
}

/// An outage over the attack: epochs strictly inside are withheld, so the last fix used
/// is the one before the attack (the first spoofed one, at its start, already carries
/// the false velocity) and the next the true one at its end.
pub(super) fn withhold_gnss_over_attack(c: &mut RunConfig, sc: &Scenario) {
    // Fused as under the monitor (white fixes, no gate), so that the bound is the
    // monitored filter's own.
    c.nav.gnss.gate_probability = None;
    c.nav.gnss.fix_error = navfuse_core::config::FixErrorOptions::white();
    if let Some((a, b)) = attack_window_rel(sc) {
        let t0 = sc.file.start.time_s;
        c.nav.gnss.outages.windows.push(Window {
            start: t0 + a - 0.5,
            end: t0 + b,
        });
    }
}
