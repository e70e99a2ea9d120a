//! Single point positioning on real data: the rtklibexplorer walk_0827 u-blox log
//! (RINEX 3.04 from CONVBIN), checked against RTKLIB's `rnx2rtkp` in single mode with
//! the same settings, and scored against the receiver's RTK-fixed track.
//!
//! Settings on both sides (docs/GNSS.md, "Single point positioning"): GPS only, L1
//! C/A (C1C), broadcast ephemeris, elevation mask 10 deg, Saastamoinen troposphere,
//! Klobuchar ionosphere from the navigation header when it has coefficients (this
//! file has none: RTKLIB is then told `ionoopt=off`, since its `brdc` would fall back
//! to built-in coefficients). A second run adds GPSA/GPSB coefficients to a copy of
//! the navigation header so that both sides apply Klobuchar. RTKLIB's RAIM FDE is off
//! (its default); ours is on (it cannot act here: these data have 4 GPS satellites
//! with ephemerides). `rnx2rtkp`'s `-sys G` switch falls through to every system in
//! the Debian 2.4.3 b34 build, so the system is set in the options file instead.
//!
//! Skips with a printed reason when ../shared/data or `rnx2rtkp` is missing.

mod common;

use navfuse_gnss::SatId;

use common::rtklib::{have_rnx2rtkp, run_rnx2rtkp, tmp_dir, RtkEpoch};
use nalgebra::Vector3;
use navfuse_core::earth::{c_ne, ecef_to_lla};
use navfuse_gnss::spp::{IonoModel, SppConfig, SppError, SppSolution};
use navfuse_gnss::{EphemerisSet, GpsTime};
use navfuse_io::gnss::read_gnss;
use navfuse_io::input::{GnssFormat, GnssSource};
use navfuse_io::rinex_nav::read_rinex_nav;
use navfuse_io::rinex_obs::{read_rinex3_obs, ObsEpoch};
use std::path::{Path, PathBuf};

/// Requirement: horizontal agreement with rnx2rtkp at every common epoch [m].
const MAX_HORIZONTAL_DIFF_M: f64 = 1.0;
/// Epoch matching tolerance on the time of validity [s] (epochs are 0.25 s apart;
/// rnx2rtkp prints 3 decimals).
const MATCH_TOL_S: f64 = 0.005;
/// Klobuchar coefficients written into the copied navigation header (a real day's
/// broadcast values, as in crates/gnss/src/atmosphere.rs).
const ALPHA: [f64; 4] = [1.1176e-8, 1.4901e-8, -5.9605e-8, -1.1921e-7];
const BETA: [f64; 4] = [1.1469e5, 8.1920e4, -1.3107e5, -5.2429e5];

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn walk_dir() -> Option<PathBuf> {
    let d = repo().join("../shared/data/rtklibexplorer/walk_0827");
    for f in [
        "derived_rinex/gnss_1730.obs",
        "derived_rinex/gnss_1730.nav",
        "gnss_1730_sf.pos",
    ] {
        if !d.join(f).is_file() {
            eprintln!(
                "skipped: {} not found (tests that need ../shared/data skip)",
                d.join(f).display()
            );
            return None;
        }
    }
    Some(d)
}

/// Our SPP on every epoch; RTKLIB-like settings. `sin_power` 2 is our default
/// elevation weighting b^2 / sin^2 el, 1 is what RTKLIB 2.4.3's code does.
fn run_ours(
    obs: &[ObsEpoch],
    ephs: &EphemerisSet,
    iono: IonoModel,
    sin_power: f64,
) -> Vec<(GpsTime, Result<SppSolution, SppError>)> {
    let mut cfg = SppConfig {
        elevation_mask_rad: 10f64.to_radians(),
        iono,
        tropo_saastamoinen: true,
        fde: true,
        ..SppConfig::default()
    };
    cfg.errors.elevation_sin_power = sin_power;
    navfuse_app::spp::solve_epochs(obs, ephs, cfg)
}

/// Velocity offset [m/s, ECEF] that rnx2rtkp 2.4.3 b34's Doppler solution (`resdop`)
/// has against an exact model: it adds the Earth-rotation (Sagnac) range-rate term
/// We/c (v_s,x r_y + x_s v_r,y - v_s,y r_x - y_s v_r,x) with the opposite sign, so its
/// modelled range rates are short by twice that term, which least squares maps into
/// the velocity as (H^T H)^-1 H^T (2 S_dot), H rows (-los, 1).
fn rtklib_doppler_offset(s: &SppSolution, ephs: &EphemerisSet) -> Vector3<f64> {
    const WE: f64 = 7.292_115_146_7e-5;
    const C: f64 = 299_792_458.0;
    let r = s.pos_ecef_m;
    let v = s.vel_ecef_mps.unwrap_or_default();
    let mut n = nalgebra::Matrix4::<f64>::zeros();
    let mut b = nalgebra::Vector4::<f64>::zeros();
    for sat in &s.used_sats {
        let Some(eph) = ephs.select(sat.prn, s.t) else {
            continue;
        };
        let sp = navfuse_gnss::signal_path(eph, &r, &v, s.t_fix);
        let (xs, vs) = (sp.sat_pos_ecef_m, sp.sat_vel_ecef_mps);
        let s_dot = WE / C * (vs.x * r.y + xs.x * v.y - vs.y * r.x - xs.y * v.x);
        let h = nalgebra::Vector4::new(-sp.los_unit.x, -sp.los_unit.y, -sp.los_unit.z, 1.0);
        n += h * h.transpose();
        b += h * (2.0 * s_dot);
    }
    n.try_inverse().map(|ni| (ni * b).xyz()).unwrap_or_default()
}

/// Horizontal and vertical difference of `a - b` in the local frame at `b` [m].
fn diff_hv(a: &Vector3<f64>, b: &Vector3<f64>) -> (f64, f64) {
    let lla = ecef_to_lla(b);
    let d = c_ne(lla.x, lla.y).transpose() * (a - b);
    (d.x.hypot(d.y), d.z)
}

fn rms(v: &[f64]) -> f64 {
    (v.iter().map(|x| x * x).sum::<f64>() / v.len().max(1) as f64).sqrt()
}

fn max_abs(v: &[f64]) -> f64 {
    v.iter().fold(0.0f64, |m, x| m.max(x.abs()))
}

/// Compare with rnx2rtkp; returns (common epochs, max horizontal diff).
fn compare(
    label: &str,
    ours: &[(GpsTime, Result<SppSolution, SppError>)],
    rtk: &[RtkEpoch],
    ephs: &EphemerisSet,
) -> (usize, f64) {
    let sols: Vec<&SppSolution> = ours.iter().filter_map(|(_, r)| r.as_ref().ok()).collect();
    let mut h = Vec::new();
    let mut v = Vec::new();
    let mut worst = (0.0, GpsTime::new(0, 0.0));
    let mut rtk_only = Vec::new();
    let mut ns_differ = 0;
    let mut dvel = Vec::new();
    let mut dvel_explained = Vec::new();
    let rtk_sols: Vec<&RtkEpoch> = rtk.iter().filter(|r| r.q == 5).collect();
    for r in &rtk_sols {
        let k = sols.partition_point(|s| s.t_fix.diff_s(&r.t) < -MATCH_TOL_S);
        match sols
            .get(k)
            .filter(|s| s.t_fix.diff_s(&r.t).abs() <= MATCH_TOL_S)
        {
            Some(s) => {
                let (dh, dv) = diff_hv(&s.pos_ecef_m, &r.pos_ecef_m);
                if dh > worst.0 {
                    worst = (dh, r.t);
                }
                h.push(dh);
                v.push(dv);
                if s.n_used != r.ns {
                    ns_differ += 1;
                }
                if let (Some(v), Some(rv)) = (s.vel_ecef_mps, r.vel_enu_mps) {
                    let lla = ecef_to_lla(&r.pos_ecef_m);
                    let ned = c_ne(lla.x, lla.y).transpose() * v;
                    let d_enu = Vector3::new(ned.y, ned.x, -ned.z) - rv;
                    dvel.push(d_enu.norm());
                    let lla = ecef_to_lla(&s.pos_ecef_m);
                    let off = c_ne(lla.x, lla.y).transpose() * rtklib_doppler_offset(s, ephs);
                    dvel_explained.push((d_enu + Vector3::new(off.y, off.x, -off.z)).norm());
                }
            }
            None => rtk_only.push(r.t.sow),
        }
    }
    let ours_only = sols.len() - h.len();
    let mut sat_counts: Vec<usize> = sols.iter().map(|s| s.n_used).collect();
    sat_counts.sort_unstable();
    sat_counts.dedup();
    let mut failures: Vec<String> = ours
        .iter()
        .filter_map(|(t, r)| r.as_ref().err().map(|e| format!("{:.3}: {e}", t.sow)))
        .collect();
    failures.truncate(3);
    eprintln!(
        "[{label}] {} epochs; ours {} solutions (satellites used {:?}), rnx2rtkp {} (Q=5); \
         common {}; only rnx2rtkp {}, only ours {}; satellite count differs at {}",
        ours.len(),
        sols.len(),
        sat_counts,
        rtk_sols.len(),
        h.len(),
        rtk_only.len(),
        ours_only,
        ns_differ
    );
    eprintln!(
        "[{label}] ours - rnx2rtkp: horizontal max {:.4} m (at {:.3}) RMS {:.4} m; \
         vertical max {:.4} m RMS {:.4} m",
        worst.0,
        worst.1.sow,
        rms(&h),
        max_abs(&v),
        rms(&v)
    );
    eprintln!(
        "[{label}] Doppler velocity ours - rnx2rtkp ($VELACC): 3D max {:.4} m/s RMS {:.4} m/s \
         ({} epochs); after removing the effect of rnx2rtkp's Earth-rotation sign: \
         max {:.5} m/s RMS {:.5} m/s",
        max_abs(&dvel),
        rms(&dvel),
        dvel.len(),
        max_abs(&dvel_explained),
        rms(&dvel_explained)
    );
    if !failures.is_empty() {
        eprintln!("[{label}] our first failures: {}", failures.join("; "));
    }
    assert_eq!(ns_differ, 0, "[{label}] satellite counts differ");
    assert!(
        rtk_only.is_empty(),
        "[{label}] rnx2rtkp has solutions we lack at {rtk_only:?}"
    );
    assert!(
        dvel.len() + 10 >= h.len() && max_abs(&dvel) < 0.05 && max_abs(&dvel_explained) < 2e-3,
        "[{label}] velocity: {} epochs, max difference {} m/s",
        dvel.len(),
        max_abs(&dvel)
    );
    (h.len(), max_abs(&h))
}

/// Copy of the navigation file with GPSA/GPSB `IONOSPHERIC CORR` header records.
fn nav_with_klobuchar(nav: &Path, out: &Path) {
    let text = std::fs::read_to_string(nav).unwrap();
    let rec = |kind: &str, c: &[f64; 4]| {
        let mut s = format!("{kind} ");
        for v in c {
            s.push_str(&format!("{v:12.4E}"));
        }
        format!("{s:<60}IONOSPHERIC CORR\n")
    };
    let mut copy = String::new();
    for line in text.split_inclusive('\n') {
        if line
            .get(60..)
            .is_some_and(|l| l.starts_with("END OF HEADER"))
        {
            copy.push_str(&rec("GPSA", &ALPHA));
            copy.push_str(&rec("GPSB", &BETA));
        }
        copy.push_str(line);
    }
    std::fs::write(out, copy).unwrap();
}

/// Score SPP against the RTK-fixed track: horizontal / vertical position and
/// horizontal Doppler velocity errors, printed; asserts SPP is better than nothing.
fn score_vs_fixed(
    label: &str,
    ours: &[(GpsTime, Result<SppSolution, SppError>)],
    fixed: &[navfuse_core::GnssFix],
) {
    let sols: Vec<&SppSolution> = ours.iter().filter_map(|(_, r)| r.as_ref().ok()).collect();
    let (mut h, mut v, mut dv_h) = (Vec::new(), Vec::new(), Vec::new());
    for f in fixed {
        let k = sols.partition_point(|s| s.t_fix.sow < f.t - 0.02);
        let Some(s) = sols.get(k).filter(|s| (s.t_fix.sow - f.t).abs() <= 0.02) else {
            continue;
        };
        let d = navfuse_core::earth::lla_diff_ned(&s.lla, &f.lla);
        h.push(d.x.hypot(d.y));
        v.push(d.z);
        if let (Some(vs), Some(vf)) = (s.vel_ecef_mps, f.vel_ned) {
            let vn = c_ne(s.lla.x, s.lla.y).transpose() * vs;
            dv_h.push((vn - vf).xy().norm());
        }
    }
    let mean = |f: &dyn Fn(&SppSolution) -> f64| {
        sols.iter().map(|s| f(s)).sum::<f64>() / sols.len().max(1) as f64
    };
    eprintln!(
        "[{label}] SPP vs RTK-fixed (Q=1) track: {} common epochs; horizontal RMS {:.2} m \
         max {:.2} m; vertical RMS {:.2} m; Doppler velocity horizontal error RMS {:.3} m/s; \
         mean HDOP {:.2} VDOP {:.2}",
        h.len(),
        rms(&h),
        max_abs(&h),
        rms(&v),
        rms(&dv_h),
        mean(&|s| s.dops.hdop),
        mean(&|s| s.dops.vdop),
    );
    assert!(h.len() > 100, "too few epochs matched the RTK track");
    assert!(rms(&h) < 20.0, "SPP horizontal RMS {} m", rms(&h));
    assert!(rms(&dv_h) < 1.0, "velocity RMS {} m/s", rms(&dv_h));
}

#[test]
fn spp_agrees_with_rnx2rtkp_and_beats_nothing() {
    let Some(dir) = walk_dir() else { return };
    let obs_path = dir.join("derived_rinex/gnss_1730.obs");
    let nav_path = dir.join("derived_rinex/gnss_1730.nav");
    let obs = read_rinex3_obs(&obs_path).expect("read obs");
    let nav = read_rinex_nav(&nav_path).expect("read nav");
    let ephs = EphemerisSet::new(nav.gps.clone());
    eprintln!(
        "walk_0827: {} epochs, GPS ephemerides for {:?}, Klobuchar in header: {}",
        obs.len(),
        ephs.prns(),
        nav.iono_alpha.is_some() && nav.iono_beta.is_some()
    );

    // Our SPP as the files are (the header has no Klobuchar coefficients).
    let iono_file = IonoModel::from_broadcast(nav.iono_alpha, nav.iono_beta);
    let file_has_iono = iono_file != IonoModel::None;
    let ours = run_ours(&obs, &ephs, iono_file, 2.0);

    // The same with Klobuchar: coefficients written into a copy of the header.
    let tmp = tmp_dir("walk");
    let nav_k = tmp.join("gnss_1730_klobuchar.nav");
    nav_with_klobuchar(&nav_path, &nav_k);
    let nav2 = read_rinex_nav(&nav_k).expect("read nav copy");
    assert_eq!(nav2.iono_alpha, Some(ALPHA));
    assert_eq!(nav2.iono_beta, Some(BETA));
    let ours_k = run_ours(
        &obs,
        &EphemerisSet::new(nav2.gps.clone()),
        IonoModel::from_broadcast(nav2.iono_alpha, nav2.iono_beta),
        2.0,
    );

    // Score against the RTK-fixed epochs (Q=1) of the receiver's solution.
    let fixed = read_gnss(&GnssSource {
        path: dir.join("gnss_1730_sf.pos"),
        format: GnssFormat::RtklibPos { quality: vec![1] },
        decimate_s: None,
        time_offset_s: 0.0,
        skip_lines: None,
    })
    .expect("read gnss_1730_sf.pos");
    score_vs_fixed("as filed", &ours, &fixed.fixes);
    score_vs_fixed("Klobuchar", &ours_k, &fixed.fixes);

    if !have_rnx2rtkp() {
        let _ = std::fs::remove_dir_all(&tmp);
        return;
    }
    let rtk = run_rnx2rtkp(
        &tmp,
        "file",
        &obs_path,
        &nav_path,
        if file_has_iono { "brdc" } else { "off" },
        false,
    );
    let (n_common, max_h) = compare(
        if file_has_iono {
            "as filed, Klobuchar"
        } else {
            "as filed, no iono coefficients"
        },
        &ours,
        &rtk,
        &ephs,
    );
    assert!(n_common > 400, "only {n_common} common epochs");
    assert!(
        max_h < MAX_HORIZONTAL_DIFF_M,
        "horizontal difference {max_h} m"
    );

    let rtk_k = run_rnx2rtkp(&tmp, "klobuchar", &obs_path, &nav_k, "brdc", false);
    let (n_common, max_h) = compare("Klobuchar on both", &ours_k, &rtk_k, &ephs);
    assert!(n_common > 400, "only {n_common} common epochs");
    assert!(
        max_h < MAX_HORIZONTAL_DIFF_M,
        "horizontal difference {max_h} m"
    );
    let _ = std::fs::remove_dir_all(&tmp);
}

/// xorshift64* uniform in (0, 1) and Box-Muller normals: deterministic noise.
struct Noise(u64);

impl Noise {
    fn uniform(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        let x = self.0.wrapping_mul(0x2545_F491_4F6C_DD1D);
        ((x >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }
    fn normal(&mut self) -> f64 {
        let (u1, u2) = (self.uniform(), self.uniform());
        (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
    }
}

/// More satellites than the walk has: weighting, the elevation mask, the chi-square
/// test and fault exclusion against rnx2rtkp (RAIM FDE on there), on RINEX files
/// written from the nominal 24-satellite constellation for a car near Boulder. Noise
/// 0.5 + 0.5 / sin(el) m, 20 % of the Klobuchar delay left unmodelled, and +100 m on
/// one satellite for 60 s.
#[test]
fn spp_matches_rnx2rtkp_with_many_satellites_and_a_fault() {
    use navfuse_gnss::atmosphere::{klobuchar_l1_delay_m, saastamoinen_slant_m};
    use navfuse_gnss::constellation::nominal_gps24;
    use navfuse_gnss::spp::GPS_L1_WAVELENGTH_M;
    use navfuse_gnss::{az_el, signal_path};
    use navfuse_io::rinex_nav::{write_rinex3_nav_dated, RinexNav};
    use navfuse_io::rinex_obs::{ObsHeader, RinexObsWriter, SatObs};
    const C: f64 = 299_792_458.0;

    if !have_rnx2rtkp() {
        return;
    }
    let tmp = tmp_dir("sim");
    let toe = GpsTime::new(2381, 410_400.0);
    let mut gps = nominal_gps24(toe);
    for (k, e) in gps.iter_mut().enumerate() {
        let k = k as f64;
        e.af0_s = (k - 11.5) * 3e-5;
        e.af1_s_per_s = (k - 7.0) * 1e-12;
        e.tgd_s = (k - 12.0) * 1e-9;
        e.e = 0.002 + 0.0005 * k;
    }
    let nav = RinexNav {
        gps,
        iono_alpha: Some(ALPHA),
        iono_beta: Some(BETA),
        ..RinexNav::default()
    };
    let nav_path = tmp.join("sim.nav");
    let mut buf = Vec::new();
    write_rinex3_nav_dated(&mut buf, &nav, "navfuse test", "20250828 000000 UTC").unwrap();
    std::fs::write(&nav_path, buf).unwrap();
    // Both sides use what the file holds.
    let nav = read_rinex_nav(&nav_path).unwrap();
    let ephs = EphemerisSet::new(nav.gps.clone());

    let lla0 = Vector3::new(
        40.0967f64.to_radians(),
        (-105.1472f64).to_radians(),
        1_601.4,
    );
    let p0 = navfuse_core::earth::lla_to_ecef(&lla0);
    let v_ecef = c_ne(lla0.x, lla0.y) * Vector3::new(8.0, 6.0, 0.2);
    let t0 = toe.add_s(300.0);
    let faulty_prn = 15u8;
    let mut noise = Noise(0x9E37_79B9_7F4A_7C15);
    let hdr = ObsHeader {
        marker_name: "SIM".into(),
        approx_pos_ecef_m: p0,
        antenna_delta_hen_m: Vector3::zeros(),
        interval_s: Some(1.0),
        first_obs: t0,
        receiver: ["1".into(), "SIM".into(), "1".into()],
        antenna: ["1".into(), "SIMANT".into()],
        program: "navfuse test".into(),
        date: Some("20250828 000000 UTC".into()),
    };
    let obs_path = tmp.join("sim.obs");
    let mut w = RinexObsWriter::new(Vec::new(), &hdr).unwrap();
    let mut truth = Vec::new();
    let mut n_visible = Vec::new();
    for k in 0..300 {
        let t_rx = t0.add_s(f64::from(k));
        let dt = f64::from(k);
        let clk_m = 2e-4 * C + 3.0 * dt;
        let t_true = t_rx.add_s(-clk_m / C);
        let pos = p0 + v_ecef * dt;
        let lla = ecef_to_lla(&pos);
        let mut sats = Vec::new();
        for prn in ephs.prns() {
            let eph = ephs.select(prn, t_rx).unwrap();
            let sp = signal_path(eph, &pos, &v_ecef, t_true);
            let (az, el) = az_el(&lla, &sp.los_unit);
            if el < 5f64.to_radians() {
                continue;
            }
            let iono = klobuchar_l1_delay_m(&ALPHA, &BETA, lla.x, lla.y, az, el, t_rx.sow);
            let tropo = saastamoinen_slant_m(lla.x, lla.z, el);
            let fault = if prn == faulty_prn && (100..160).contains(&k) {
                100.0
            } else {
                0.0
            };
            let pr = sp.geometric_range_m + clk_m - C * (sp.sat_clock_bias_s - eph.tgd_s)
                + 1.2 * iono
                + tropo
                + (0.5 + 0.5 / el.sin()) * noise.normal()
                + fault;
            let rr =
                sp.range_rate_mps + 3.0 - C * sp.sat_clock_drift_s_per_s + 0.05 * noise.normal();
            sats.push(SatObs {
                prn,
                pseudorange_m: Some(pr),
                carrier_cycles: None,
                doppler_hz: Some(-rr / GPS_L1_WAVELENGTH_M),
                cn0_dbhz: Some(45.0),
                lli: 0,
            });
        }
        n_visible.push(sats.len());
        w.write_epoch(t_rx, &sats).unwrap();
        truth.push((t_rx, pos));
    }
    std::fs::write(&obs_path, w.finish().unwrap()).unwrap();

    let obs = read_rinex3_obs(&obs_path).unwrap();
    let iono = IonoModel::from_broadcast(nav.iono_alpha, nav.iono_beta);
    let ours = run_ours(&obs, &ephs, iono.clone(), 2.0);
    let rtk = run_rnx2rtkp(&tmp, "sim", &obs_path, &nav_path, "brdc", true);
    let sols: Vec<&SppSolution> = ours.iter().filter_map(|(_, r)| r.as_ref().ok()).collect();
    assert_eq!(sols.len(), 300, "every epoch solved");
    let excluded: Vec<usize> = sols
        .iter()
        .enumerate()
        .filter(|(_, s)| !s.excluded_sats.is_empty())
        .map(|(k, s)| {
            assert_eq!(s.excluded_sats, vec![SatId::gps(faulty_prn)], "epoch {k}");
            k
        })
        .collect();
    let mut used: Vec<usize> = sols.iter().map(|s| s.n_used).collect();
    used.sort_unstable();
    let err_h: Vec<f64> = sols
        .iter()
        .zip(&truth)
        .map(|(s, (_, p))| diff_hv(&s.pos_ecef_m, p).0)
        .collect();
    eprintln!(
        "[simulated] satellites in the file {}-{}, used {}-{}; FDE excluded G{faulty_prn} at \
         {} epochs ({:?}..{:?}); horizontal error vs truth RMS {:.2} m max {:.2} m",
        n_visible.iter().min().unwrap(),
        n_visible.iter().max().unwrap(),
        used[0],
        used[used.len() - 1],
        excluded.len(),
        excluded.first(),
        excluded.last(),
        rms(&err_h),
        max_abs(&err_h)
    );
    assert_eq!(excluded, (100..160).collect::<Vec<_>>());
    let (n_common, max_h) = compare("simulated, RAIM on", &ours, &rtk, &ephs);
    assert_eq!(n_common, 300);
    assert!(
        max_h < MAX_HORIZONTAL_DIFF_M,
        "horizontal difference {max_h} m"
    );
    // With RTKLIB's b^2 / sin el the weights are the same on both sides, and so are
    // the solutions, to the 0.1 mm of rnx2rtkp's output.
    let ours_1 = run_ours(&obs, &ephs, iono, 1.0);
    let (n_common, max_h) = compare("simulated, RAIM on, RTKLIB's weights", &ours_1, &rtk, &ephs);
    assert_eq!(n_common, 300);
    assert!(max_h < 2e-3, "horizontal difference {max_h} m");
    let _ = std::fs::remove_dir_all(&tmp);
}
