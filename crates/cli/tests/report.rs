//! Issue 18 (report): `navfuse report RUN_DIR` writes one self-contained HTML page
//! with every figure, and `--svg DIR` the same figures as files; opened in a real
//! headless browser (Debian's chromium) when it is installed.

mod common;

use common::{navfuse_ok, run_demo, sim_and_run, tmp};
use std::path::Path;
use std::process::Command;

/// The `<figure id="fig-NAME">` names of a page.
fn figure_names(html: &str) -> Vec<String> {
    html.split("<figure id=\"fig-")
        .skip(1)
        .map(|s| s[..s.find('"').unwrap()].to_string())
        .collect()
}

/// Self-contained: nothing to fetch (the only URLs are XML namespaces).
fn assert_offline(html: &str) {
    let lower = html.to_lowercase();
    for bad in ["<link", "<img", "<iframe", "src=", "@import", "url("] {
        assert!(!lower.contains(bad), "the page refers out: {bad}");
    }
    let urls = lower.matches("http").count();
    let namespaces = lower.matches("http://www.w3.org/2000/svg").count();
    assert_eq!(urls, namespaces, "only SVG namespace URLs");
}

fn chromium() -> Option<String> {
    ["chromium", "chromium-browser", "google-chrome"]
        .into_iter()
        .find(|b| {
            Command::new(b)
                .arg("--version")
                .output()
                .is_ok_and(|o| o.status.success())
        })
        .map(String::from)
}

/// Open `page` in headless chromium, offline: (the DOM after the scripts ran,
/// the console messages at warning level or above).
fn open_in_browser(browser: &str, page: &Path, shot: Option<&Path>) -> (String, Vec<String>) {
    let profile = page.with_extension("profile");
    let mut cmd = Command::new(browser);
    cmd.args([
        "--headless=new",
        "--no-sandbox",
        "--disable-gpu",
        "--no-first-run",
        "--disable-extensions",
        "--disable-background-networking",
        "--enable-logging=stderr",
        "--v=0",
        "--window-size=1280,2400",
        // Offline: every host resolves nowhere.
        "--host-resolver-rules=MAP * ~NOTFOUND",
    ])
    .arg(format!("--user-data-dir={}", profile.display()));
    match shot {
        Some(s) => cmd.arg(format!("--screenshot={}", s.display())),
        None => cmd.arg("--dump-dom"),
    };
    let out = cmd
        .arg(format!("file://{}", page.canonicalize().unwrap().display()))
        .output()
        .expect("run chromium");
    let _ = std::fs::remove_dir_all(&profile);
    let stderr = String::from_utf8_lossy(&out.stderr);
    let console: Vec<String> = stderr
        .lines()
        .filter(|l| l.contains(":CONSOLE"))
        .map(String::from)
        .collect();
    (String::from_utf8_lossy(&out.stdout).into_owned(), console)
}

/// Check a page in the browser: no console errors, every figure's SVG rendered
/// (the page's script counts them into `data-figures`).
fn check_in_browser(page: &Path, figures: usize) {
    let Some(b) = chromium() else {
        eprintln!("skipped: the browser check (chromium is not installed; .ci/run installs it)");
        return;
    };
    let (dom, console) = open_in_browser(&b, page, None);
    assert!(console.is_empty(), "console messages: {console:?}");
    assert!(
        dom.contains(&format!("data-figures=\"{figures}\"")),
        "the script did not see {figures} figures: {}",
        &dom[..dom.len().min(300)]
    );
    let shot = page.with_extension("png");
    open_in_browser(&b, page, Some(&shot));
    let png = std::fs::read(&shot).expect("screenshot written");
    assert!(
        png.starts_with(b"\x89PNG") && png.len() > 20_000,
        "screenshot of {} bytes",
        png.len()
    );
}

/// `navfuse report RUN_DIR ARGS... -q` into `page`; the page, checked offline, with its
/// figure names, every name in `want` among them.
fn report(run_dir: &Path, page: &Path, args: &[&str], want: &[&str]) -> (String, Vec<String>) {
    let (r, p) = (run_dir.to_str().unwrap(), page.to_str().unwrap());
    let mut all = vec!["report", r, "--out", p, "-q"];
    all.extend_from_slice(args);
    navfuse_ok(&all);
    let html = std::fs::read_to_string(page).unwrap();
    assert_offline(&html);
    let names = figure_names(&html);
    for w in want {
        assert!(
            names.iter().any(|n| n == w),
            "figure {w} missing from {names:?}"
        );
    }
    (html, names)
}

#[test]
fn the_browser_check_catches_a_broken_page() {
    let Some(b) = chromium() else {
        eprintln!("skipped: chromium is not installed");
        return;
    };
    let dir = tmp("report-broken");
    std::fs::create_dir_all(&dir).unwrap();
    let page = dir.join("broken.html");
    std::fs::write(
        &page,
        "<!DOCTYPE html><html><body><script>undefinedFunction();</script></body></html>",
    )
    .unwrap();
    let (_, console) = open_in_browser(&b, &page, None);
    assert!(
        console.iter().any(|l| l.contains("undefinedFunction")),
        "a script error must show: {console:?}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn report_of_the_demo_drive_with_an_outage_and_smoothing() {
    let (dir, out) = run_demo("report-demo", &["--smooth", "--outages", "243350:243380"]);
    let svg = dir.join("svg");
    let page = out.join("report.html");
    let (html, names) = report(
        &out,
        &page,
        &[
            "--truth",
            "examples/demo/gnss.pos",
            "--lever-arm",
            "0,-0.05,0",
            "--svg",
            svg.to_str().unwrap(),
        ],
        &[
            "ground_track",
            "position",
            "velocity",
            "attitude",
            "yaw",
            "error_north",
            "error_east",
            "error_down",
            "error_velocity",
            "error_cdf",
            "outage_drift",
            "nis_gnss_position",
            "nis_gnss_velocity",
            "gyroscope_bias",
            "accelerometer_bias",
            "states_gnss_fix_bias_n_m",
            "solution_state",
            "separation_ratio",
            "separation_position",
        ],
    );
    // A .pos truth has no attitude: no attitude errors.
    assert!(!names.iter().any(|n| n == "error_yaw"), "{names:?}");
    // The ground track is coloured by state: both states of this run are named.
    let track = std::fs::read_to_string(svg.join("ground_track.svg")).unwrap();
    assert!(
        track.contains(">\ngnss\n<") || track.contains(">gnss<"),
        "gnss legend"
    );
    assert!(track.contains("inertial"), "inertial legend");
    // --svg: one standalone file per figure.
    let files: Vec<_> = std::fs::read_dir(&svg)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    assert_eq!(files.len(), names.len());
    for f in &files {
        let s = std::fs::read_to_string(f).unwrap();
        assert!(
            s.starts_with("<svg") && s.trim_end().ends_with("</svg>"),
            "{}",
            f.display()
        );
        assert!(
            !s.contains("NaN") && !s.contains("inf\""),
            "{}",
            f.display()
        );
    }
    // The tables: percentiles and the coasting interval with its drift.
    assert!(html.contains("P68") && html.contains("Coasting intervals"));
    assert!(
        html.contains("config.toml") || html.contains("[imu]"),
        "the configuration"
    );
    check_in_browser(&page, names.len());
    std::fs::remove_dir_all(&dir).ok();
}

/// The full real drive (../shared) with 30 s outages every 90 s, NHC and the
/// smoother, against the receiver's RTK track.
#[test]
fn report_of_the_real_drive_with_outages() {
    let Some(data) = common::shared() else {
        return;
    };
    let dir = tmp("report-drive");
    let out = dir.join("out");
    navfuse_ok(&[
        "run",
        "examples/drive_0708_nhc.toml",
        "--outages",
        "30/90@243381.854",
        "--smooth",
        "--out",
        out.to_str().unwrap(),
        "-q",
    ]);
    let truth = data.join("rtklibexplorer/drive_0708/gnss_1934_sf.pos");
    let page = out.join("report.html");
    let (html, names) = report(
        &out,
        &page,
        &[
            "--truth",
            truth.to_str().unwrap(),
            "--lever-arm",
            "0,-0.05,0",
        ],
        &[
            "ground_track",
            "error_cdf",
            "outage_drift",
            "nis_nhc",
            "solution_state",
            "separation_ratio",
            "states_mounting_yaw_deg",
        ],
    );
    // Five outages in the drive, each a coasting interval (NHC only).
    let table = &html[html.find("Coasting intervals").unwrap()..];
    let table = &table[..table.find("</table>").unwrap()];
    assert_eq!(table.matches("dead_reckoning").count(), 5, "{table}");
    check_in_browser(&page, names.len());
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn report_of_a_simulated_run_with_truth() {
    let (dir, sim, out) = sim_and_run(
        "report-sim",
        "scenarios/seed002_car.toml",
        &["--outages", "30/200@200", "--smooth"],
    );
    let page = dir.join("sim_report.html");
    let truth = sim.join("truth.nav");
    let (html, names) = report(
        &out,
        &page,
        &["--truth", truth.to_str().unwrap()],
        &[
            "error_roll",
            "error_pitch",
            "error_yaw",
            "error_cdf",
            "outage_drift",
            "solution_state",
            "smoothed_errors",
        ],
    );
    assert!(html.contains("Smoothed solution against the truth"));
    // The simulator's run writes std.txt: the errors have their sigma bands.
    assert_eq!(
        html.matches("+-3 sigma (std.txt)").count(),
        6,
        "N, E, D, roll, pitch, yaw"
    );
    // No solution.csv in this run: the state comes from innovations.csv, and says so.
    assert!(!out.join("solution.csv").exists());
    assert!(html.contains("derived from innovations.csv"));
    check_in_browser(&page, names.len());
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn report_errors_name_the_file() {
    let dir = tmp("report-errors");
    std::fs::create_dir_all(&dir).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_navfuse"))
        .args(["report", dir.join("nothing").to_str().unwrap()])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let e = String::from_utf8_lossy(&out.stderr);
    assert!(e.contains("nothing") && e.contains("navfuse run"), "{e}");
    // A damaged innovations.csv: the file and line.
    let (rdir, run) = run_demo("report-damaged", &[]);
    let p = run.join("innovations.csv");
    let mut text = std::fs::read_to_string(&p).unwrap();
    text.push_str("1.0,gnss_position,3,0,0,0,abc,,applied\n");
    std::fs::write(&p, text).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_navfuse"))
        .args(["report", run.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let e = String::from_utf8_lossy(&out.stderr);
    assert!(e.contains("innovations.csv:") && e.contains("nis"), "{e}");
    std::fs::remove_dir_all(&dir).ok();
    std::fs::remove_dir_all(&rdir).ok();
}
