//! RTKLIB's `rnx2rtkp` as the oracle of the SPP tests: run it in single mode with
//! navfuse's settings and read its solution back.

use nalgebra::Vector3;
use navfuse_gnss::GpsTime;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

pub fn have_rnx2rtkp() -> bool {
    match Command::new("rnx2rtkp")
        .arg("-?")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
    {
        Ok(_) => true,
        Err(e) => {
            eprintln!("skipped: rnx2rtkp not runnable ({e}); install the Debian package rtklib");
            false
        }
    }
}

pub fn tmp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("navfuse-spp-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// One rnx2rtkp epoch.
pub struct RtkEpoch {
    pub t: GpsTime,
    pub pos_ecef_m: Vector3<f64>,
    pub q: u8,
    pub ns: usize,
    /// Doppler velocity east, north, up from the `-y 1` status file ($VELACC) [m/s].
    pub vel_enu_mps: Option<Vector3<f64>>,
}

/// Run rnx2rtkp in single mode with our settings, GPS only; ECEF output, GPST
/// week/tow.
pub fn run_rnx2rtkp(
    dir: &Path,
    name: &str,
    obs: &Path,
    nav: &Path,
    iono: &str,
    raim: bool,
) -> Vec<RtkEpoch> {
    run_rnx2rtkp_systems(dir, name, obs, nav, iono, raim, 1)
}

/// RTKLIB's `pos1-navsys` bits: GPS 1, SBAS 2, GLONASS 4, Galileo 8, QZSS 16,
/// BeiDou 32.
pub fn navsys(letters: &str) -> u32 {
    letters
        .chars()
        .map(|c| match c {
            'G' => 1,
            'S' => 2,
            'R' => 4,
            'E' => 8,
            'J' => 16,
            'C' => 32,
            _ => 0,
        })
        .sum()
}

/// The systems rnx2rtkp writes in its `% navi sys` header line for `navsys`.
fn navsys_names(navsys: u32) -> String {
    [
        (1, "gps"),
        (4, "glonass"),
        (8, "galileo"),
        (16, "qzss"),
        (32, "bds"),
    ]
    .iter()
    .filter(|(b, _)| navsys & b != 0)
    .map(|(_, n)| *n)
    .collect::<Vec<_>>()
    .join(" ")
}

/// The same with the systems of `navsys` ([`navsys`]).
#[allow(clippy::too_many_arguments)]
pub fn run_rnx2rtkp_systems(
    dir: &Path,
    name: &str,
    obs: &Path,
    nav: &Path,
    iono: &str,
    raim: bool,
    navsys_bits: u32,
) -> Vec<RtkEpoch> {
    let conf = dir.join(format!("{name}.conf"));
    let out = dir.join(format!("{name}.pos"));
    // Option names of RTKLIB 2.4.3 (rtkpost/rnx2rtkp option files). stats-* are the
    // defaults, written out because they set the weights (code sigma 100 x 0.003 m).
    let text = format!(
        "pos1-posmode       =single\n\
         pos1-frequency     =l1\n\
         pos1-soltype       =forward\n\
         pos1-elmask        =10\n\
         pos1-snrmask_r     =off\n\
         pos1-dynamics      =off\n\
         pos1-tidecorr      =off\n\
         pos1-ionoopt       ={iono}\n\
         pos1-tropopt       =saas\n\
         pos1-sateph        =brdc\n\
         pos1-posopt5       ={raim}\n\
         pos1-navsys        ={navsys_bits}\n\
         stats-eratio1      =100\n\
         stats-errphase     =0.003\n\
         stats-errphaseel   =0.003\n\
         out-solformat      =xyz\n\
         out-outhead        =on\n\
         out-outopt         =on\n\
         out-timesys        =gpst\n\
         out-timeform       =tow\n\
         out-timendec       =3\n",
        raim = if raim { "on" } else { "off" }
    );
    std::fs::write(&conf, text).unwrap();
    let status = Command::new("rnx2rtkp")
        .arg("-k")
        .arg(&conf)
        .args(["-p", "0", "-m", "10", "-e", "-y", "1", "-o"])
        .arg(&out)
        .arg(obs)
        .arg(nav)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .expect("run rnx2rtkp");
    assert!(status.success(), "rnx2rtkp failed: {status}");
    let text = std::fs::read_to_string(&out).expect("rnx2rtkp output");
    let sys_line = text
        .lines()
        .find(|l| l.starts_with("% navi sys"))
        .map(|l| l.trim_end().to_string());
    let want = navsys_names(navsys_bits);
    assert!(
        sys_line
            .as_deref()
            .is_none_or(|l| l.to_lowercase().trim_end().ends_with(&want)),
        "rnx2rtkp did not take {want}: {sys_line:?}"
    );
    // $VELACC,week,tow,stat,ve,vn,vu,... (RTKLIB's estvel: Doppler, after estpos).
    let stat = std::fs::read_to_string(dir.join(format!("{name}.pos.stat"))).unwrap_or_default();
    let vel: std::collections::HashMap<i64, Vector3<f64>> = stat
        .lines()
        .filter(|l| l.starts_with("$VELACC"))
        .filter_map(|l| {
            let f: Vec<f64> = l
                .split(',')
                .skip(1)
                .map(|x| x.parse().unwrap_or(f64::NAN))
                .collect();
            (f.len() >= 6 && f[2] == 5.0)
                .then(|| ((f[1] * 1e3).round() as i64, Vector3::new(f[3], f[4], f[5])))
        })
        .collect();
    text.lines()
        .filter(|l| !l.starts_with('%') && !l.trim().is_empty())
        .map(|l| {
            let f: Vec<&str> = l.split_whitespace().collect();
            let num = |k: usize| -> f64 { f[k].parse().unwrap_or_else(|_| panic!("{l}")) };
            RtkEpoch {
                t: GpsTime::new(num(0) as i32, num(1)),
                pos_ecef_m: Vector3::new(num(2), num(3), num(4)),
                q: num(5) as u8,
                ns: num(6) as usize,
                vel_enu_mps: vel.get(&((num(1) * 1e3).round() as i64)).copied(),
            }
        })
        .collect()
}
