//! Round trip of the multi-system writers (issue 19 item 6): a mixed RINEX 3.05
//! observation file (GPS C1C..S1C, Galileo C1C..S1C, BeiDou C2I..S2I with LLI and
//! SSI digits, blank fields) and a mixed navigation file with GPS, Galileo and BeiDou
//! records read back equal to the formats' precision (F14.3; D19.12: 13 significant
//! digits).

use nalgebra::Vector3;
use navfuse_gnss::constellation::{
    glonass_records, nominal_beidou27, nominal_galileo24, nominal_gps24,
};
use navfuse_gnss::ephemeris::kepler::KeplerOrbit;
use navfuse_gnss::ephemeris::Ephemeris;
use navfuse_gnss::obs::{MultiObsEpoch, ObsValue, SatSignals};
use navfuse_gnss::signal::ObsCode;
use navfuse_gnss::{GpsTime, SatId, System};
use navfuse_io::rinex_nav::{read_rinex_nav, write_rinex3_nav_dated, RinexNav};
use navfuse_io::rinex_obs::{read_rinex_obs_all, ObsHeader, RinexMultiObsWriter};
use std::path::PathBuf;

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("navfuse_write_multi_{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d.join(name)
}

fn codes(names: &[&str]) -> Vec<ObsCode> {
    names.iter().map(|n| ObsCode::parse(n).unwrap()).collect()
}

#[test]
fn mixed_observations_round_trip() {
    let types = vec![
        (System::Gps, codes(&["C1C", "L1C", "D1C", "S1C"])),
        (System::Galileo, codes(&["C1C", "L1C", "D1C", "S1C"])),
        (System::BeiDou, codes(&["C2I", "L2I", "D2I", "S2I"])),
    ];
    let t0 = GpsTime::new(2381, 345_600.0);
    let hdr = ObsHeader {
        marker_name: "RT".into(),
        approx_pos_ecef_m: Vector3::new(4_000_000.0, 500_000.0, 4_900_000.0),
        antenna_delta_hen_m: Vector3::zeros(),
        interval_s: Some(1.0),
        first_obs: t0,
        receiver: ["1".into(), "SIM".into(), "0".into()],
        antenna: ["1".into(), "SIM".into()],
        program: "test".into(),
        date: Some("20260101 000000 UTC".into()),
    };
    let mut epochs = Vec::new();
    for k in 0..5 {
        let mut sats = Vec::new();
        for (j, (sys, list)) in types.iter().enumerate() {
            for prn in [3u8, 11, 24] {
                let base = 2.0e7 + 1e5 * f64::from(prn) + 1234.5678 * f64::from(k) + j as f64;
                let signals = list
                    .iter()
                    .enumerate()
                    // A blank field: no Doppler for PRN 11 at odd epochs.
                    .filter(|(i, _)| !(*i == 2 && prn == 11 && k % 2 == 1))
                    .map(|(i, c)| {
                        let v = match i {
                            0 => base,
                            1 => base / 0.19 + 0.123456,
                            2 => -1234.5678 - f64::from(prn),
                            _ => 44.25,
                        };
                        let lli = (i == 1 && k == 2).then_some(1);
                        (
                            *c,
                            ObsValue {
                                value: Some(v),
                                lli,
                                ssi: Some(7),
                            },
                        )
                    })
                    .collect();
                sats.push(SatSignals {
                    sat: SatId::new(*sys, prn),
                    signals,
                });
            }
        }
        epochs.push(MultiObsEpoch {
            t: t0.add_s(f64::from(k)),
            flag: 0,
            rx_clock_offset_s: None,
            sats,
        });
    }
    let p = tmp("mixed.rnx");
    let f = std::io::BufWriter::new(std::fs::File::create(&p).unwrap());
    let mut w = RinexMultiObsWriter::new(f, &hdr, &types, &[]).unwrap();
    for e in &epochs {
        w.write_epoch(e).unwrap();
    }
    w.finish().unwrap();
    let text = std::fs::read_to_string(&p).unwrap();
    assert!(text.starts_with("     3.05           OBSERVATION DATA    M: Mixed"));
    let back = read_rinex_obs_all(&p).unwrap();
    assert_eq!(back.header.types, types);
    assert_eq!(back.epochs.len(), epochs.len());
    for (a, b) in epochs.iter().zip(&back.epochs) {
        assert_eq!(a.t, b.t);
        assert_eq!(a.sats.len(), b.sats.len());
        for (sa, sb) in a.sats.iter().zip(&b.sats) {
            assert_eq!(sa.sat, sb.sat);
            assert_eq!(sa.signals.len(), sb.signals.len(), "{}", sa.sat);
            for ((ca, va), (cb, vb)) in sa.signals.iter().zip(&sb.signals) {
                assert_eq!(ca, cb);
                let (x, y) = (va.value.unwrap(), vb.value.unwrap());
                assert!((x - y).abs() <= 5e-4 + 1e-9, "{} {ca}: {x} {y}", sa.sat);
                assert_eq!((va.lli, va.ssi), (vb.lli, vb.ssi), "{} {ca}", sa.sat);
            }
        }
    }
}

/// Realistic non-zero values in every field of a Keplerian orbit.
fn perturbed(o: &KeplerOrbit, k: f64) -> KeplerOrbit {
    KeplerOrbit {
        e: 1.234_567_890_123e-3 * k,
        omega_rad: -1.987_654_321 + 0.01 * k,
        delta_n_rad_per_s: 3.456_789_012_3e-9,
        idot_rad_per_s: -2.345_678_901_2e-10,
        cuc_rad: 1.234_5e-6,
        cus_rad: -7.654_3e-6,
        crc_m: 234.567_8,
        crs_m: -45.678_9,
        cic_rad: 3.2e-8,
        cis_rad: -1.1e-7,
        ..*o
    }
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-12 * a.abs().max(b.abs())
}

#[test]
fn mixed_navigation_round_trip() {
    let t = GpsTime::new(2381, 345_600.0);
    let mut gal = nominal_galileo24(t);
    for (k, e) in gal.iter_mut().enumerate() {
        e.orbit = perturbed(&e.orbit, k as f64 + 1.0);
        e.transmission_time = Some(t.add_s(-600.0));
        e.af2_s_per_s2 = 1.5e-19;
    }
    let tb = navfuse_gnss::ephemeris::beidou::gpst_to_bdt(t);
    let tb = GpsTime::new(tb.week, 345_600.0);
    let mut bds = nominal_beidou27(tb);
    for (k, e) in bds.iter_mut().enumerate() {
        e.orbit = perturbed(&e.orbit, k as f64 + 1.0);
        e.transmission_time = Some(tb.add_s(-600.0));
        e.aode = k as u16;
        e.aodc = 200 - k as u16;
    }
    let mut glo = glonass_records(t, t.add_s(3_600.0), 18.0);
    for (k, e) in glo.iter_mut().enumerate() {
        e.acc_mps2 = Vector3::new(1.5e-6, -2.25e-6, 3.0e-7 * k as f64);
    }
    let nav = RinexNav {
        gps: nominal_gps24(t),
        galileo: gal.clone(),
        beidou: bds.clone(),
        glonass: glo.clone(),
        iono_alpha: Some([1.1176e-8, 7.4506e-9, -5.9605e-8, -5.9605e-8]),
        iono_beta: Some([9.0112e4, 3.2768e4, -1.9661e5, -6.5536e4]),
        leap_seconds: Some(18),
        ..RinexNav::default()
    };
    let p = tmp("mixed_nav.rnx");
    let mut w = std::io::BufWriter::new(std::fs::File::create(&p).unwrap());
    write_rinex3_nav_dated(&mut w, &nav, "test", "20260101 000000 UTC").unwrap();
    drop(w);
    let text = std::fs::read_to_string(&p).unwrap();
    assert!(text.lines().next().unwrap().contains("M: MIXED"));
    let back = read_rinex_nav(&p).unwrap();
    assert_eq!(back.gps.len(), 24);
    assert_eq!(back.galileo.len(), gal.len());
    assert_eq!(back.beidou.len(), bds.len());
    let orbit_eq = |a: &KeplerOrbit, b: &KeplerOrbit| {
        let fa = [
            a.sqrt_a_sqrt_m,
            a.e,
            a.i0_rad,
            a.omega0_rad,
            a.omega_rad,
            a.m0_rad,
            a.delta_n_rad_per_s,
            a.omega_dot_rad_per_s,
            a.idot_rad_per_s,
            a.cuc_rad,
            a.cus_rad,
            a.crc_m,
            a.crs_m,
            a.cic_rad,
            a.cis_rad,
            a.toe_sow_s,
        ];
        let fb = [
            b.sqrt_a_sqrt_m,
            b.e,
            b.i0_rad,
            b.omega0_rad,
            b.omega_rad,
            b.m0_rad,
            b.delta_n_rad_per_s,
            b.omega_dot_rad_per_s,
            b.idot_rad_per_s,
            b.cuc_rad,
            b.cus_rad,
            b.crc_m,
            b.crs_m,
            b.cic_rad,
            b.cis_rad,
            b.toe_sow_s,
        ];
        fa.iter().zip(&fb).all(|(x, y)| close(*x, *y))
    };
    for (a, b) in gal.iter().zip(&back.galileo) {
        assert!(orbit_eq(&a.orbit, &b.orbit), "E{:02}", a.prn);
        assert_eq!(
            (a.prn, a.toe, a.toc, a.iodnav),
            (b.prn, b.toe, b.toc, b.iodnav)
        );
        assert_eq!(
            (a.data_sources, a.health, a.transmission_time),
            (b.data_sources, b.health, b.transmission_time)
        );
        for (x, y) in [
            (a.af0_s, b.af0_s),
            (a.af1_s_per_s, b.af1_s_per_s),
            (a.af2_s_per_s2, b.af2_s_per_s2),
            (a.sisa_m, b.sisa_m),
            (a.bgd_e1_e5a_s, b.bgd_e1_e5a_s),
            (a.bgd_e1_e5b_s, b.bgd_e1_e5b_s),
        ] {
            assert!(close(x, y), "E{:02}: {x} {y}", a.prn);
        }
    }
    for (a, b) in bds.iter().zip(&back.beidou) {
        assert!(orbit_eq(&a.orbit, &b.orbit), "C{:02}", a.prn);
        assert_eq!(
            (a.prn, a.toe, a.toc, a.aode, a.aodc),
            (b.prn, b.toe, b.toc, b.aode, b.aodc)
        );
        assert_eq!(
            (a.sat_h1, a.transmission_time),
            (b.sat_h1, b.transmission_time)
        );
        for (x, y) in [
            (a.af0_s, b.af0_s),
            (a.af1_s_per_s, b.af1_s_per_s),
            (a.sv_accuracy_m, b.sv_accuracy_m),
            (a.tgd1_s, b.tgd1_s),
            (a.tgd2_s, b.tgd2_s),
        ] {
            assert!(close(x, y), "C{:02}: {x} {y}", a.prn);
        }
    }
    assert_eq!(back.glonass.len(), glo.len());
    for (a, b) in glo.iter().zip(&back.glonass) {
        assert_eq!(
            (a.slot, a.tb, a.health, a.freq_channel),
            (b.slot, b.tb, b.health, b.freq_channel)
        );
        assert_eq!(a.tb_utc_sod_s, b.tb_utc_sod_s);
        for (x, y) in [
            (a.tau_n_s, b.tau_n_s),
            (a.gamma_n, b.gamma_n),
            (a.frame_time_s, b.frame_time_s),
            (a.age_days, b.age_days),
        ] {
            assert!(close(x, y), "R{:02}: {x} {y}", a.slot);
        }
        for (x, y) in [
            (a.pos_m, b.pos_m),
            (a.vel_mps, b.vel_mps),
            (a.acc_mps2, b.acc_mps2),
        ] {
            for i in 0..3 {
                assert!(close(x[i], y[i]), "R{:02}: {x} {y}", a.slot);
            }
        }
    }
    // Each record read back gives the state of the one written, 10 min after toe,
    // to well below a millimetre.
    let written = gal
        .iter()
        .map(|e| Ephemeris::Galileo(e.clone()))
        .chain(bds.iter().map(|e| Ephemeris::BeiDou(e.clone())))
        .chain(glo.iter().map(|e| Ephemeris::Glonass(e.clone())));
    let read = back
        .galileo
        .iter()
        .map(|e| Ephemeris::Galileo(e.clone()))
        .chain(back.beidou.iter().map(|e| Ephemeris::BeiDou(e.clone())))
        .chain(back.glonass.iter().map(|e| Ephemeris::Glonass(e.clone())));
    let mut worst = 0.0f64;
    for (a, b) in written.zip(read) {
        let tt = a.toe_gpst().add_s(600.0);
        let (sa, sb) = (a.sat_state(tt), b.sat_state(tt));
        worst = worst.max((sa.pos_ecef_m - sb.pos_ecef_m).norm());
        worst = worst.max(299_792_458.0 * (sa.clock_bias_s - sb.clock_bias_s).abs());
    }
    assert!(worst < 1e-4, "{worst} m");
}
