//! The NMEA and CSV GNSS readers: navfuse's own NMEA export read back, a GNSS CSV
//! written from a known track read back, and line-numbered errors.

use nalgebra::{UnitQuaternion, Vector3};
use navfuse_core::NavState;
use navfuse_io::export::ExportFormat;
use navfuse_io::gnss::read_gnss;
use navfuse_io::gnss_csv::{CsvGnssOptions, CsvPosition, CsvTimeScale};
use navfuse_io::input::{GnssFormat, GnssSource};
use navfuse_io::nav::SolutionRecord;
use navfuse_io::nmea::{read_nmea, NmeaOptions};
use std::path::PathBuf;

fn dir() -> PathBuf {
    let d = std::env::temp_dir().join(format!("navfuse-nmea-csv-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A known track: a turn at 10 m/s near 30.5 N 114.4 E crossing midnight UTC on a
/// Saturday (so the GPS week and the UTC date both change), 10 Hz, week 2374.
fn track(k: usize) -> SolutionRecord {
    let t = 604_800.0 - 18.0 - 30.0 + k as f64 * 0.1;
    let a = k as f64 * 0.002;
    let yaw = 0.3 + a;
    SolutionRecord {
        gps_week: 2374,
        nav: NavState {
            t,
            lla: Vector3::new(
                30.5f64.to_radians() + 1e-6 * a.sin(),
                114.4f64.to_radians() + 1e-6 * (1.0 - a.cos()),
                20.0 + 0.37 * a,
            ),
            v_n: Vector3::new(10.0 * yaw.cos(), 10.0 * yaw.sin(), 0.0),
            q_bn: UnitQuaternion::from_euler_angles(0.0, 0.0, yaw),
        },
        imu_errors: Default::default(),
        std: None,
        gnss_integrity: None,
        state: None,
    }
}

#[test]
fn nmea_export_reads_back_to_its_precision() {
    let p = dir().join("track.nmea");
    let mut w = ExportFormat::Nmea.create(&p).unwrap();
    let n = 600;
    for k in 0..n {
        w.write_record(&track(k)).unwrap();
    }
    w.finish_boxed().unwrap();
    let d = read_nmea(&p, &NmeaOptions::default()).unwrap();
    assert_eq!(d.rejected, 0);
    assert_eq!(d.fixes.len(), n);
    assert_eq!(d.heading.len(), n);
    assert_eq!(d.gps_week, Some(2374));
    let (mut dt, mut dpos, mut dh, mut dv, mut dyaw) = (0f64, 0f64, 0f64, 0f64, 0f64);
    for (k, f) in d.fixes.iter().enumerate() {
        let r = track(k);
        dt = dt.max((f.t - r.nav.t).abs());
        let dlat = (f.lla.x - r.nav.lla.x) * 6.378e6;
        let dlon = (f.lla.y - r.nav.lla.y) * 6.378e6 * r.nav.lla.x.cos();
        dpos = dpos.max(dlat.hypot(dlon));
        dh = dh.max((f.lla.z - r.nav.lla.z).abs());
        let v = f.vel_ned.unwrap();
        dv = dv.max((v - r.nav.v_n).xy().norm());
        let yaw = r
            .nav
            .q_bn
            .euler_angles()
            .2
            .rem_euclid(std::f64::consts::TAU);
        dyaw = dyaw.max((d.heading[k].heading_rad - yaw).abs());
        assert_eq!(d.heading[k].t, f.t);
    }
    println!(
        "NMEA round trip over {n} epochs: time {dt:.1e} s, horizontal {dpos:.1e} m, height {dh:.1e} m, \
         velocity {dv:.1e} m/s, heading {:.1e} deg",
        dyaw.to_degrees()
    );
    // The export's precision: 0.01 s, 1e-6 arc minute (1.9 mm), 1 mm, 0.001 kn and
    // 0.01 deg of course (1.7 mm/s at 10 m/s), 0.001 deg of heading.
    assert!(dt < 1e-6, "{dt}");
    assert!(dpos < 2.0e-3, "{dpos}");
    assert!(dh <= 0.5e-3 + 1e-9, "{dh}");
    assert!(dv < 2.5e-3, "{dv}");
    assert!(dyaw.to_degrees() <= 0.5e-3 + 1e-9, "{dyaw}");
    // Through read_gnss, the whole continues past the week (no wrap).
    let g = read_gnss(&GnssSource {
        path: p,
        format: GnssFormat::Nmea(NmeaOptions::default()),
        decimate_s: Some(1.0),
        time_offset_s: 0.0,
        skip_lines: None,
    })
    .unwrap();
    assert_eq!(g.fixes.len(), 60);
    assert!(g.fixes.last().unwrap().t > 604_800.0);
}

#[test]
fn nmea_line_numbers_of_malformed_sentences() {
    let p = dir().join("malformed.nmea");
    let text = "$GPRMC,120000.00,A,3030.0000,N,11424.0000,E,0.0,,080725,,,A*79\n\
                $GPGGA,120000.00,3030.0000,N,11424.0000,E,1,08,1.0,20.0,M,-10.0,M,,*7A\n\
                $GPGGA,120001.00,3030.0000,N,11424.0000,E,1,08,1.0,20.0,M,-10.0,M,,*7A\n\
                garbage\n\
                $GPGGA,120002.00,3030.0000,Q,11424.0000,E,1,08,1.0,20.0,M,-10.0,M,,*67\n\
                $GPGGA,120003.00,3030.0000,N,11424.0000,E,1,08,1.0,20.0,M,-10.0,M,,*79\n\
                $GPGGA,120004.00,3030.0000,N,11424.0000,E,1,08,1.0,20.0,M,-10.0,M,,*7E\n";
    std::fs::write(&p, text).unwrap();
    let d = read_nmea(&p, &NmeaOptions::default()).unwrap();
    let w = d.warnings.join("\n");
    println!("{w}");
    assert_eq!(d.rejected, 2, "{w}");
    assert!(w.contains("malformed.nmea:3: checksum mismatch"), "{w}");
    // A line with no sentence in it is skipped and counted, not a rejected sentence.
    assert_eq!(d.non_nmea_lines, 1);
    assert!(w.contains("1 lines without an NMEA sentence"), "{w}");
    assert!(
        w.contains("malformed.nmea:5: field 'GGA hemisphere'"),
        "{w}"
    );
    assert_eq!(d.fixes.len(), 3);
    // 20.0 m above the geoid, geoid 10 m below the ellipsoid: 10 m ellipsoidal.
    assert_eq!(d.fixes[0].lla.z, 10.0);
    // GGA quality 6 (dead reckoning) is no GNSS fix; a file with no sentence at all
    // is an error.
    let dr = text.replace(
        "E,1,08,1.0,20.0,M,-10.0,M,,*79",
        "E,6,08,1.0,20.0,M,-10.0,M,,*7E",
    );
    std::fs::write(&p, &dr).unwrap();
    let d = read_nmea(&p, &NmeaOptions::default()).unwrap();
    assert_eq!((d.fixes.len(), d.no_fix), (2, 1));
    std::fs::write(&p, "t lat lon\n100 30 114\n").unwrap();
    let e = read_nmea(&p, &NmeaOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("no NMEA sentence in 2 lines"), "{e}");
}

fn write_csv(name: &str, header: &str, rows: impl Fn(usize) -> String, n: usize) -> PathBuf {
    let p = dir().join(name);
    let mut s = String::from(header);
    for k in 0..n {
        s.push_str(&rows(k));
    }
    std::fs::write(&p, s).unwrap();
    p
}

#[test]
fn csv_lla_with_header_and_iso_utc() {
    // ISO UTC times; lat;lon;h in degrees and feet; std columns; ';' delimiter.
    let p = write_csv(
        "g.csv",
        "time;lat;lon;h_ft;sn;se;sd;vn;ve;vd\n",
        |k| {
            format!(
                "2025-07-08T12:00:{:02}.5Z;30.{k};114.4;100;0.5;0.5;1;1;2;-0.5\n",
                k
            )
        },
        5,
    );
    let mut o = CsvGnssOptions::lla(0, [1, 2, 3]);
    o.delimiter = Some(b';');
    o.time_scale = CsvTimeScale::IsoUtc;
    o.height_unit = navfuse_io::gnss_csv::LengthUnit::Foot;
    o.pos_std_cols = Some([4, 5, 6]);
    o.vel_cols = Some([7, 8, 9]);
    o.velocity_std_mps = Some([0.1, 0.1, 0.2]);
    let g = read_gnss(&GnssSource {
        path: p,
        format: GnssFormat::Csv(o.clone()),
        decimate_s: None,
        time_offset_s: 0.0,
        skip_lines: None,
    })
    .unwrap();
    assert_eq!(g.gps_week, Some(2374));
    assert_eq!(g.fixes.len(), 5);
    let f = &g.fixes[1];
    assert!((f.t - (2.0 * 86400.0 + 12.0 * 3600.0 + 1.5 + 18.0)).abs() < 1e-9);
    assert!((f.lla.x - 30.1f64.to_radians()).abs() < 1e-15);
    assert!((f.lla.z - 30.48).abs() < 1e-12);
    assert_eq!(f.vel_ned, Some(Vector3::new(1.0, 2.0, -0.5)));
    assert_eq!(f.std_ned, Vector3::new(0.5, 0.5, 1.0));

    // A bad value: file, line and column (1-based) named.
    let p = write_csv(
        "bad.csv",
        "time;lat;lon;h_ft;sn;se;sd;vn;ve;vd\n",
        |k| {
            let lat = if k == 3 {
                "x".into()
            } else {
                format!("30.{k}")
            };
            format!("2025-07-08T12:00:{k:02}Z;{lat};114.4;100;0.5;0.5;1;1;2;-0.5\n")
        },
        5,
    );
    let e = read_gnss(&GnssSource {
        path: p,
        format: GnssFormat::Csv(o),
        decimate_s: None,
        time_offset_s: 0.0,
        skip_lines: None,
    })
    .unwrap_err()
    .to_string();
    println!("{e}");
    assert!(e.contains("bad.csv:5: field 'lat (column 2)'"), "{e}");
}

/// A declared delimiter is the only separator: a decimal-comma export with `;` is an
/// error naming the field and the likely mistake (not lat 30, lon 5), and ISO times
/// with a space read with `delimiter = ","`.
#[test]
fn csv_declared_delimiter_is_the_only_separator() {
    let src = |p: PathBuf, o: CsvGnssOptions| GnssSource {
        path: p,
        format: GnssFormat::Csv(o),
        decimate_s: None,
        time_offset_s: 0.0,
        skip_lines: None,
    };
    let p = write_csv(
        "comma.csv",
        "t;lat;lon;h\n",
        |k| format!("{}.0;30,5;114,4;8,2\n", 100 + k),
        3,
    );
    let mut o = CsvGnssOptions::lla(0, [1, 2, 3]);
    o.delimiter = Some(b';');
    o.position_std_m = Some([1.0, 1.0, 2.0]);
    let e = read_gnss(&src(p, o.clone())).unwrap_err().to_string();
    assert!(
        e.contains("comma.csv:2: field 'lat (column 2)'") && e.contains("decimal comma"),
        "{e}"
    );
    let p = write_csv(
        "iso_space.csv",
        "time,lat,lon,h\n",
        |k| format!("2025-07-08 12:00:0{k}.5 , 30.5, 114.4, 8.2\n"),
        3,
    );
    o.delimiter = Some(b',');
    o.time_scale = CsvTimeScale::IsoGpst;
    let g = read_gnss(&src(p, o)).unwrap();
    assert_eq!(g.fixes.len(), 3);
    assert!(
        (g.fixes[2].t - (2.0 * 86400.0 + 12.0 * 3600.0 + 2.5)).abs() < 1e-9,
        "{}",
        g.fixes[2].t
    );
    assert!((g.fixes[0].lla.z - 8.2).abs() < 1e-12);
}

#[test]
fn csv_ecef_week_sow_skip_lines() {
    let lla = Vector3::new(30.5f64.to_radians(), 114.4f64.to_radians(), 20.0);
    let r = navfuse_core::earth::lla_to_ecef(&lla);
    let p = write_csv(
        "ecef.csv",
        "# receiver dump\nweek,sow,x,y,z\n",
        |k| format!("2374,{},{:.4},{:.4},{:.4}\n", 1000 + k, r.x, r.y, r.z),
        3,
    );
    let mut o = CsvGnssOptions::lla(1, [0, 0, 0]);
    o.position = CsvPosition::Ecef([2, 3, 4]);
    o.week_col = Some(0);
    o.skip_lines = Some(2);
    o.position_std_m = Some([2.0, 2.0, 4.0]);
    let mut w = Vec::new();
    let (fixes, week) = navfuse_io::gnss_csv::read_csv_gnss(&p, &o, &mut w).unwrap();
    assert_eq!(week, Some(2374));
    assert_eq!(fixes.len(), 3);
    assert_eq!(fixes[2].t, 1002.0);
    assert!((fixes[0].lla - lla).xy().norm() < 1e-9 && (fixes[0].lla.z - 20.0).abs() < 1e-3);
    assert_eq!(fixes[0].std_ned, Vector3::new(2.0, 2.0, 4.0));
    // Without skip_lines the header is detected, but "# receiver dump" is a comment
    // and "week,sow,..." the first line read: the same.
    o.skip_lines = None;
    let (again, _) = navfuse_io::gnss_csv::read_csv_gnss(&p, &o, &mut w).unwrap();
    assert_eq!(again, fixes);
    // Time going back: line named.
    let p = write_csv(
        "back.csv",
        "",
        |k| format!("2374,{},{:.4},{:.4},{:.4}\n", [5, 6, 4][k], r.x, r.y, r.z),
        3,
    );
    let e = navfuse_io::gnss_csv::read_csv_gnss(&p, &o, &mut w)
        .unwrap_err()
        .to_string();
    assert!(e.contains("back.csv:3: field 'time (column 2)'"), "{e}");
}

#[test]
fn column_name_headers_are_skipped_with_the_file_line_numbers() {
    use navfuse_io::input::{OdometerFormat, OdometerSource};
    let d = dir();
    // KF-GINS GNSS text with a header; the error on the 3rd line still says 3.
    let p = d.join("h_gnss.txt");
    std::fs::write(
        &p,
        "t lat lon h sn se sd\n100 30 114 20 0.1 0.1 0.2\n101 30 114 20 0.1 x 0.2\n",
    )
    .unwrap();
    let src = GnssSource {
        path: p,
        format: GnssFormat::KfGins,
        decimate_s: None,
        time_offset_s: 0.0,
        skip_lines: None,
    };
    let e = read_gnss(&src).unwrap_err().to_string();
    assert!(e.contains("h_gnss.txt:3: field 'std_e'"), "{e}");
    // Heading and odometer with CSV headers.
    let p = d.join("h_heading.csv");
    std::fs::write(&p, "t,heading_deg,std_deg\n100,10,0.5\n101,11,0.5\n").unwrap();
    assert_eq!(navfuse_io::heading::read_heading(&p).unwrap().len(), 2);
    let p = d.join("h_odo.csv");
    std::fs::write(&p, "t,speed_mps\n10.0,1.5\n10.1,1.6\n").unwrap();
    let o = navfuse_io::odometer::read_odometer(&OdometerSource {
        path: p.clone(),
        format: OdometerFormat::Speed {
            speed_is_mean: false,
        },
        skip_lines: None,
    })
    .unwrap();
    assert_eq!(o.len(), 2);
    // Only the first line may be a header: a later word line is an error at its line.
    std::fs::write(&p, "t,speed_mps\n10.0,1.5\nt,speed\n").unwrap();
    let e = navfuse_io::odometer::read_odometer(&OdometerSource {
        path: p,
        format: OdometerFormat::Speed {
            speed_is_mean: false,
        },
        skip_lines: None,
    })
    .unwrap_err()
    .to_string();
    assert!(e.contains("h_odo.csv:3"), "{e}");
}

/// `skip_lines` in `[gnss]` (KF-GINS, .pos), `[heading]`, `[odometer]` and `[baro]`:
/// a preamble whose lines hold numbers (so no header detection could tell) is
/// skipped, line numbers stay the file's, written back, refused where it does not
/// apply.
#[test]
fn skip_lines_for_every_text_reader() {
    let d = dir().join("skip_lines");
    std::fs::create_dir_all(&d).unwrap();
    let pre = "Logger v2.1 exported 2024-03-18\n3 channels, 10 Hz\n";
    let w = |name: &str, body: &str| std::fs::write(d.join(name), format!("{pre}{body}")).unwrap();
    w(
        "gnss.txt",
        "100 30 114 20 0.1 0.1 0.2\n101 30 114 20 0.1 0.1 0.2\n",
    );
    w(
        "fix.pos",
        "2024/03/18 00:00:00.000 30.0 114.0 20.0 1 10 0.01 0.01 0.02 0 0 0 0.0 0.0\n",
    );
    w("heading.txt", "100 10 0.5\n101 11 0.5\n");
    w("odo.txt", "10.0 1.5\n10.1 1.6\n");
    w("baro.txt", "10.0 101000\n10.1 x\n");
    std::fs::write(d.join("imu.txt"), "").unwrap();
    let toml = |gnss: &str| {
        format!(
            "[imu]\nfile = \"imu.txt\"\nformat = \"kf-gins\"\nrate_hz = 100\n\n\
             [initial]\nposition_std_m = 1.0\nvelocity_std_mps = 0.1\nattitude_std_deg = [1, 1, 5]\n\n\
             [imu_noise]\narw_deg_sqrth = 0.2\nvrw_mps_sqrth = 0.05\ngyro_bias_std_degph = 20\naccel_bias_std_mgal = 300\ngyro_scale_std_ppm = 1000\naccel_scale_std_ppm = 1000\ncorr_time_h = 1\n\n\
             [gnss]\n{gnss}\nskip_lines = 2\n\n\
             [heading]\nfile = \"heading.txt\"\nbaseline_m = [1, 0, 0]\nskip_lines = 2\n\n\
             [odometer]\nfile = \"odo.txt\"\nformat = \"speed\"\nspeed_is_mean = false\nskip_lines = 2\n\n\
             [baro]\nfile = \"baro.txt\"\nskip_lines = 2\n"
        )
    };
    let load = |name: &str, text: &str| {
        let p = d.join(name);
        std::fs::write(&p, text).unwrap();
        navfuse_io::config::load(&p)
    };
    let c = load(
        "run.toml",
        &toml("file = \"gnss.txt\"\nformat = \"kf-gins\""),
    )
    .unwrap();
    let g = read_gnss(c.gnss.as_ref().unwrap()).unwrap();
    assert_eq!(g.fixes.len(), 2);
    let h = c.heading.as_ref().unwrap();
    let hv = navfuse_io::heading::read_heading_report(&h.path, h.skip_lines, &mut Vec::new());
    assert_eq!(hv.unwrap().len(), 2);
    let o = navfuse_io::odometer::read_odometer(c.odometer.as_ref().unwrap()).unwrap();
    assert_eq!(o.len(), 2);
    // The barometer's error names the file's own line 4.
    let e = navfuse_io::baro::read_baro(c.baro.as_ref().unwrap(), &mut Vec::new())
        .unwrap_err()
        .to_string();
    assert!(e.contains("baro.txt:4"), "{e}");
    // Without skip_lines the preamble's first line is taken as a header and the
    // second is an error at line 2.
    let src = GnssSource {
        skip_lines: None,
        ..c.gnss.clone().unwrap()
    };
    let e = read_gnss(&src).unwrap_err().to_string();
    assert!(e.contains("gnss.txt:2"), "{e}");
    // Written back.
    let back = c.to_toml_string();
    assert_eq!(back.matches("skip_lines = 2").count(), 4, "{back}");
    // .pos.
    let c = load(
        "run_pos.toml",
        &toml("file = \"fix.pos\"\nformat = \"rtklib-pos\""),
    )
    .unwrap();
    assert_eq!(read_gnss(c.gnss.as_ref().unwrap()).unwrap().fixes.len(), 1);
    // Where it does not apply.
    let e = load(
        "run_nmea.toml",
        &toml("file = \"gnss.txt\"\nformat = \"nmea\"\ndate = \"2024-03-18\""),
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("gnss.skip_lines"), "{e}");
}
