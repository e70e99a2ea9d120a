//! The RINEX keys of `[gnss]` (`gnss.format = "rinex"`): navigation file, coupling,
//! range rate, elevation mask, fault exclusion, signals, dual frequency, orbits (SP3
//! and clock files), DGPS (input::RinexGnss), and the `[gnss.tight]` table
//! (tight.rs).

use std::path::Path;

use navfuse_core::config::TightOptions;

use super::error::{kerr, KResult};
use super::gnss::TGnss;
use super::paths::{file_key, PathWriter};
use super::tight;
use super::units::{DEG, SAME};
use super::validate::{opt_or, positive, system_letter, v3};
use super::values::Strings;
use crate::input::{Coupling, DgpsKind, DgpsSource, Orbits, RinexGnss};

/// Default `gnss.elevation_mask_deg`.
pub const DEFAULT_ELEVATION_MASK_DEG: f64 = 10.0;
/// Default `gnss.cn0_reference_dbhz` (RTKLIB demo5's `stats-snrmax`).
pub const DEFAULT_CN0_REFERENCE_DBHZ: f64 = 52.0;
/// Default `gnss.dgps_max_age_s`.
pub const DEFAULT_DGPS_MAX_AGE_S: f64 = 30.0;

/// `gnss.format = "rinex"`: navigation file, coupling, DGPS and `[gnss.tight]`.
pub(super) fn convert(g: &TGnss, base: &Path) -> KResult<(RinexGnss, TightOptions)> {
    let nav = g.nav.as_deref().ok_or_else(|| {
        kerr(
            "gnss.nav",
            "gnss.format = \"rinex\" needs nav = \"RINEX navigation file\"",
        )
    })?;
    let nav_path = file_key(base, "gnss.nav", nav)?;
    convert_with_nav(g, base, nav_path)
}

/// The RINEX keys with the navigation file `nav_path` already resolved (ubx.rs
/// passes an optional one).
pub(super) fn convert_with_nav(
    g: &TGnss,
    base: &Path,
    nav_path: std::path::PathBuf,
) -> KResult<(RinexGnss, TightOptions)> {
    // Tight coupling unless asked otherwise: raw observations are what it is for.
    let coupling = g.coupling.unwrap_or(Coupling::Tight);
    let elevation_mask_deg = g.elevation_mask_deg.unwrap_or(DEFAULT_ELEVATION_MASK_DEG);
    if !(0.0..90.0).contains(&elevation_mask_deg) {
        return Err(kerr(
            "gnss.elevation_mask_deg",
            format!("expected 0 <= mask < 90 deg, got {elevation_mask_deg}"),
        ));
    }
    let max_age_s = opt_or(
        "gnss.dgps_max_age_s",
        g.dgps_max_age_s,
        positive,
        SAME,
        DEFAULT_DGPS_MAX_AGE_S,
    )?;
    let dgps =
        match (
            g.dgps.unwrap_or(false),
            &g.dgps_corrections,
            &g.dgps_reference_obs,
        ) {
            (false, _, _) => None,
            (true, Some(_), Some(_)) => {
                return Err(kerr(
                    "gnss.dgps_corrections",
                    "give either dgps_corrections or dgps_reference_obs, not both",
                ))
            }
            (true, Some(f), None) => Some(DgpsKind::Corrections(file_key(
                base,
                "gnss.dgps_corrections",
                f,
            )?)),
            (true, None, Some(f)) => {
                let key = "gnss.dgps_reference_position_deg_m";
                let p = g.dgps_reference_position_deg_m.as_deref().ok_or_else(|| {
                    kerr(
                        key,
                        "dgps_reference_obs needs the station's [lat_deg, lon_deg, h_m]",
                    )
                })?;
                let p = v3(key, p)?;
                Some(DgpsKind::ReferenceStation {
                    obs_path: file_key(base, "gnss.dgps_reference_obs", f)?,
                    position_lla: [DEG.si(p[0]), DEG.si(p[1]), p[2]],
                })
            }
            (true, None, None) => return Err(kerr(
                "gnss.dgps",
                "dgps = true needs dgps_corrections = \"FILE\" or dgps_reference_obs = \"FILE\"",
            )),
        }
        .map(|kind| DgpsSource { kind, max_age_s });
    let signals = match &g.signals {
        None => Vec::new(),
        Some(m) => {
            let text: Vec<String> = m
                .iter()
                .map(|(sys, codes)| {
                    let sys = system_letter("gnss.signals", sys)?;
                    Ok(format!("{}:{}", sys.letter(), codes.0.join("+")))
                })
                .collect::<KResult<_>>()?;
            navfuse_gnss::signal_plan::parse_codes(&text.join(",")).map_err(|e| {
                kerr(
                    "gnss.signals",
                    format!("{e} (e.g. signals = {{ R = [\"C1P\", \"C1C\"] }})"),
                )
            })?
        }
    };
    let paths = |key: &str, v: &Option<Vec<String>>| -> KResult<Vec<std::path::PathBuf>> {
        v.iter().flatten().map(|f| file_key(base, key, f)).collect()
    };
    let orbits = match g.orbits.as_deref().unwrap_or("broadcast") {
        "broadcast" => {
            if g.sp3.is_some() || g.clk.is_some() {
                return Err(kerr(
                    "gnss.sp3",
                    "sp3 / clk files are given but orbits = \"broadcast\": set orbits = \"sp3\"",
                ));
            }
            Orbits::Broadcast
        }
        "sp3" => {
            let sp3 = paths("gnss.sp3", &g.sp3)?;
            if sp3.is_empty() {
                return Err(kerr(
                    "gnss.orbits",
                    "orbits = \"sp3\" needs sp3 = [\"FILE.sp3\", ...]",
                ));
            }
            Orbits::Sp3 {
                sp3,
                clk: paths("gnss.clk", &g.clk)?,
            }
        }
        other => {
            return Err(kerr(
                "gnss.orbits",
                format!("expected \"broadcast\" or \"sp3\", got \"{other}\""),
            ))
        }
    };
    let cn0_weighting = match (g.cn0_sigma_m, g.cn0_reference_dbhz) {
        (None, None) => None,
        (None, Some(_)) => {
            return Err(kerr(
                "gnss.cn0_reference_dbhz",
                "cn0_reference_dbhz needs cn0_sigma_m (the C/N0 weighting's sigma)",
            ))
        }
        (Some(s), r) => {
            let s = positive("gnss.cn0_sigma_m", s)?;
            let r = r.unwrap_or(DEFAULT_CN0_REFERENCE_DBHZ);
            if !(r.is_finite() && (10.0..=70.0).contains(&r)) {
                return Err(kerr(
                    "gnss.cn0_reference_dbhz",
                    format!("expected 10-70 dB-Hz, got {r}"),
                ));
            }
            Some((s, r))
        }
    };
    let mut t = TightOptions {
        enabled: coupling == Coupling::Tight,
        range_rate: g.range_rate.unwrap_or(TightOptions::default().range_rate),
        ..TightOptions::default()
    };
    if let Some(x) = &g.tight {
        tight::convert(x, &mut t)?;
    }
    Ok((
        RinexGnss {
            nav_path,
            coupling,
            elevation_mask_deg,
            fde: g.fde.unwrap_or(true),
            dgps,
            signals,
            dual_frequency: g.dual_frequency.unwrap_or(false),
            orbits,
            cn0_weighting,
        },
        t,
    ))
}

/// The RINEX keys of `t` from `r` and `tight`.
pub(super) fn to_toml(r: &RinexGnss, tight: &TightOptions, t: &mut TGnss, w: &PathWriter) {
    t.nav = Some(w.path(&r.nav_path));
    t.coupling = Some(r.coupling);
    t.range_rate = Some(tight.range_rate);
    t.elevation_mask_deg = Some(r.elevation_mask_deg);
    t.fde = Some(r.fde);
    if !r.signals.is_empty() {
        t.signals = Some(
            r.signals
                .iter()
                .map(|(s, c)| {
                    (
                        s.letter().to_string(),
                        Strings(c.iter().map(|x| x.to_string()).collect()),
                    )
                })
                .collect(),
        );
    }
    t.dual_frequency = Some(r.dual_frequency);
    match &r.orbits {
        Orbits::Broadcast => t.orbits = Some("broadcast".into()),
        Orbits::Sp3 { sp3, clk } => {
            t.orbits = Some("sp3".into());
            t.sp3 = Some(sp3.iter().map(|p| w.path(p)).collect());
            if !clk.is_empty() {
                t.clk = Some(clk.iter().map(|p| w.path(p)).collect());
            }
        }
    }
    if let Some((sigma, reference)) = r.cn0_weighting {
        t.cn0_sigma_m = Some(sigma);
        t.cn0_reference_dbhz = Some(reference);
    }
    t.dgps = Some(r.dgps.is_some());
    if let Some(d) = &r.dgps {
        t.dgps_max_age_s = Some(d.max_age_s);
        match &d.kind {
            DgpsKind::Corrections(p) => t.dgps_corrections = Some(w.path(p)),
            DgpsKind::ReferenceStation {
                obs_path,
                position_lla,
            } => {
                t.dgps_reference_obs = Some(w.path(obs_path));
                t.dgps_reference_position_deg_m = Some(vec![
                    DEG.user(position_lla[0]),
                    DEG.user(position_lla[1]),
                    position_lla[2],
                ]);
            }
        }
    }
    t.tight = Some(tight::to_toml(tight));
}
