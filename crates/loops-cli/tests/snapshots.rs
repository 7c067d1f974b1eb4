//! Snapshots of what each subcommand prints on fixed inputs (stdout and stderr, exit code), so
//! that a change to the terminal output is a reviewed change. Timings are masked; everything
//! else (numbers, layout, wording) must match. Update with `INSTA_UPDATE=always cargo test`
//! and review the diff.

use std::path::Path;
use std::process::Command;

mod support;
use support::TempDir;

/// A fresh folder holding two synthetic drives (5 min, seeds 0 and 1; MCAP and TUM) and a
/// hand-written out-and-back TUM file; commands run inside it so paths print short.
fn workspace(name: &str) -> TempDir {
    let dir = TempDir::at(std::env::temp_dir().join(format!("loops-snapshots-{name}-{}", std::process::id())));
    let mut text = String::from("# timestamp tx ty tz qx qy qz qw\n");
    for i in 0..=40 {
        let x = if i <= 20 { i } else { 40 - i };
        text += &format!("{i}.0 {x}.0 0.0 0.0 0 0 0 1\n");
    }
    std::fs::write(dir.join("out-and-back.tum"), text).expect("write");
    for (seed, file) in [(0, "drive-a.mcap"), (1, "drive-b.tum")] {
        let status = Command::new(env!("CARGO_BIN_EXE_loops"))
            .args(["synth", file, "--duration-s", "300", "--seed", &seed.to_string()])
            .current_dir(&dir)
            .output()
            .expect("loops synth runs");
        assert!(status.status.success(), "{}", String::from_utf8_lossy(&status.stderr));
    }
    dir
}

/// The command's exit code, stdout and stderr as one text.
fn transcript(dir: &Path, args: &[&str]) -> String {
    let output = Command::new(env!("CARGO_BIN_EXE_loops"))
        .args(args)
        .current_dir(dir)
        .env("NO_COLOR", "1")
        .output()
        .expect("the loops binary runs");
    format!(
        "$ loops {}\nexit: {}\n--- stdout\n{}--- stderr\n{}",
        args.join(" "),
        output.status.code().map_or("signal".to_owned(), |c| c.to_string()),
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr)
    )
}

macro_rules! snapshot {
    ($name:expr, $text:expr) => {
        insta::with_settings!({
            filters => vec![
                // Seconds spent: "; 0.003 s" (components), ", 0.25 s" (run lines), "in 1.20 s;".
                (r"([;,] )\d+\.\d+ s\n", "$1[time] s\n"),
                (r"in \d+\.\d+ s;", "in [time] s;"),
                // The time column of the run table.
                (r"(\d+/\d+) +\d+\.\d+\n", "$1  [time]\n"),
            ],
            prepend_module_to_snapshot => false,
        }, {
            insta::assert_snapshot!($name, $text);
        });
    };
}

#[test]
fn components() {
    let dir = workspace("components");
    snapshot!("components_out_and_back", transcript(&dir, &["components", "out-and-back.tum", "--gamma", "1.5"]));
    snapshot!("components_mcap", transcript(&dir, &["components", "drive-a.mcap", "--gamma", "40", "--limit", "3"]));
    snapshot!(
        "components_se3",
        transcript(
            &dir,
            &["components", "drive-b.tum", "--gamma", "40", "--metric", "se3(rotation_weight_m_per_rad=20)"]
        )
    );
    snapshot!("components_bad_gamma", transcript(&dir, &["components", "drive-b.tum", "--gamma", "-1"]));
    snapshot!("components_missing", transcript(&dir, &["components", "nowhere.tum", "--gamma", "1"]));
    // Usage errors are one line, as every other error: the option, the value, where the help is.
    snapshot!("components_gamma_not_a_number", transcript(&dir, &["components", "drive-b.tum", "--gamma", "abc"]));
    snapshot!("components_without_gamma", transcript(&dir, &["components", "drive-b.tum"]));
}

#[test]
fn sample() {
    let dir = workspace("sample");
    snapshot!("sample_rho", transcript(&dir, &["sample", "drive-a.mcap", "--gamma", "40", "--budget", "50"]));
    snapshot!(
        "sample_lio_sam",
        transcript(&dir, &["sample", "drive-b.tum", "--gamma", "40", "--sampler", "lio-sam", "--budget", "20"])
    );
    snapshot!("sample_unknown", transcript(&dir, &["sample", "drive-b.tum", "--gamma", "40", "--sampler", "sigma"]));
}

#[test]
fn info() {
    let dir = workspace("info");
    snapshot!("info_mcap", transcript(&dir, &["info", "drive-a.mcap"]));
    snapshot!("info_tum", transcript(&dir, &["info", "drive-b.tum"]));
}

#[test]
fn demo() {
    let dir = workspace("demo");
    snapshot!("demo_short", transcript(&dir, &["demo", "--duration-s", "600", "--limit", "5"]));
}

#[test]
fn synth() {
    let dir = workspace("synth");
    snapshot!("synth_count", transcript(&dir, &["synth", "more", "--count", "2", "--duration-s", "60"]));
    snapshot!("synth_exists", transcript(&dir, &["synth", "drive-a.mcap"]));
}

#[test]
fn run() {
    let dir = workspace("run");
    std::fs::write(dir.join("broken.mcap"), b"\x89MCAP0\r\nnot really").expect("write");
    let args = ["run", "drive-a.mcap", "broken.mcap", "drive-b.tum", "--gamma", "40", "--budget", "100"];
    snapshot!("run_batch", transcript(&dir, &[&args[..], &["--out", "results", "--threads", "1"]].concat()));
    snapshot!("run_exists", transcript(&dir, &["run", "drive-a.mcap", "--gamma", "40", "--out", "results"]));
    snapshot!("run_quiet", transcript(&dir, &["run", "drive-a.mcap", "--gamma", "40", "--out", "quiet", "--quiet"]));
}

#[test]
fn fleet() {
    let dir = workspace("fleet");
    let synth = ["synth", "cars", "--vehicles", "2", "--days", "2", "--duration-s", "300"];
    snapshot!("fleet_synth", transcript(&dir, &synth));
    let sessions = ["cars/car0-day0.mcap", "cars/car1-day0.mcap", "cars/car0-day1.mcap", "cars/car1-day1.mcap"];
    let args = ["--gamma", "40", "--budget", "100", "--out", "fleet-results", "--threads", "1"];
    snapshot!("fleet_run", transcript(&dir, &[&["fleet"][..], &sessions, &args].concat()));
    snapshot!(
        "fleet_duplicate",
        transcript(&dir, &["fleet", "out-and-back.tum", "./out-and-back.tum", "--gamma", "1", "--out", "x"])
    );
}

#[test]
fn help() {
    let dir = std::env::temp_dir();
    for command in ["components", "sample", "info", "demo", "run", "fleet", "synth", "replay"] {
        snapshot!(format!("help_{command}"), transcript(&dir, &[command, "--help"]));
    }
    snapshot!("help", transcript(&dir, &["--help"]));
}
