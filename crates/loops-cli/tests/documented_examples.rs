//! The commands the README and `--help` show run as shown. Every example that names a file of
//! `../shared/data` (`kitti_odometry/00.txt`, `tum_rgbd/fr2_desk_groundtruth.txt`, ...) runs
//! through `sh`, in a folder that holds the data under those names, and must succeed; the
//! output the README shows under it (every line but `...`) must be in what it prints. Skipped,
//! saying so, when the data is absent. The fleet example needs no data (it writes its own
//! logs): it always runs.

use std::path::{Path, PathBuf};
use std::process::Command;

/// `../shared/data` beside the checkout, or `None` (with a message) when it is absent.
fn real_data_dir() -> Option<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data");
    if dir.is_dir() {
        Some(dir)
    } else {
        eprintln!(
            "skipping the documented examples: no real data at {} (it lives beside the checkout in CI)",
            dir.display()
        );
        None
    }
}

/// A documented command, where it is documented, and the output shown under it (README only).
#[derive(Debug)]
struct Example {
    command: String,
    source: String,
    shown: Vec<String>,
}

/// The `$ ...` lines of the README's console blocks, with the lines shown under each.
fn readme_examples() -> Vec<Example> {
    let readme =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../../README.md")).expect("README");
    let mut examples: Vec<Example> = Vec::new();
    let mut in_console = false;
    for (index, line) in readme.lines().enumerate() {
        if line.starts_with("```") {
            in_console = line == "```console";
            continue;
        }
        if !in_console {
            continue;
        }
        if let Some(command) = line.strip_prefix("$ ") {
            examples.push(Example {
                command: command.to_owned(),
                source: format!("README.md line {}", index + 1),
                shown: Vec::new(),
            });
        } else if let Some(example) = examples.last_mut() {
            example.shown.push(line.to_owned());
        }
    }
    examples
}

/// The commands of the README's "Fleets" section, "### Command line" (its console blocks, in
/// order), with the lines shown under each: a sequence that runs in one folder.
fn fleet_examples() -> Vec<Example> {
    let readme =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../../README.md")).expect("README");
    let (mut in_fleets, mut in_command_line, mut in_console) = (false, false, false);
    let mut examples: Vec<Example> = Vec::new();
    for (index, line) in readme.lines().enumerate() {
        if line.starts_with("## ") {
            in_fleets = line == "## Fleets";
            in_command_line = false;
        } else if line.starts_with("### ") {
            in_command_line = in_fleets && line == "### Command line";
        }
        if line.starts_with("```") {
            in_console = in_command_line && line == "```console";
            continue;
        }
        if !in_console {
            continue;
        }
        if let Some(command) = line.strip_prefix("$ ") {
            let source = format!("README.md line {}", index + 1);
            examples.push(Example { command: command.to_owned(), source, shown: Vec::new() });
        } else if let Some(example) = examples.last_mut() {
            example.shown.push(line.to_owned());
        }
    }
    examples
}

/// The README's fleet example (synthetic logs, no shared data) runs as shown: its commands in
/// order in one folder, each succeeding and printing every line shown under it but `...`.
#[test]
fn the_fleet_example_runs_as_shown() {
    let examples = fleet_examples();
    assert!(examples.iter().any(|e| e.command.starts_with("loops synth")), "{examples:#?}");
    assert!(examples.iter().any(|e| e.command.starts_with("loops fleet")), "{examples:#?}");
    let dir = std::env::temp_dir().join(format!("loops-documented-fleet-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    let mut failures = Vec::new();
    for example in &examples {
        failures.extend(run_example(example, &dir).1);
    }
    let _ = std::fs::remove_dir_all(&dir);
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}

/// Runs `example` in `dir` with the `loops` binary first on the path: its exit status, and what
/// failed (it failed, or it does not print a line shown under it, `...` aside).
fn run_example(example: &Example, dir: &Path) -> (std::process::ExitStatus, Vec<String>) {
    let bin = PathBuf::from(env!("CARGO_BIN_EXE_loops"));
    let path = format!("{}:{}", bin.parent().expect("bin folder").display(), std::env::var("PATH").unwrap_or_default());
    let output = Command::new("sh")
        .arg("-c")
        .arg(&example.command)
        .current_dir(dir)
        .env("PATH", &path)
        .env("NO_COLOR", "1")
        .output()
        .expect("sh runs");
    let printed = format!("{}{}", String::from_utf8_lossy(&output.stdout), String::from_utf8_lossy(&output.stderr));
    if !output.status.success() {
        let failure = format!("{} ({}): {}\n{printed}", example.command, example.source, output.status);
        return (output.status, vec![failure]);
    }
    let failures = example
        .shown
        .iter()
        .filter(|line| line.trim() != "..." && !printed.lines().any(|printed_line| printed_line == *line))
        .map(|line| {
            format!(
                "{} ({}): the README shows {line:?}, which it does not print:\n{printed}",
                example.command, example.source
            )
        })
        .collect();
    (output.status, failures)
}

/// The lines after `Examples:` in `loops --help` and each command's `--help`.
fn help_examples() -> Vec<Example> {
    let mut examples = Vec::new();
    for command in ["", "components", "sample", "info", "demo", "run", "fleet", "synth", "replay"] {
        let args: Vec<&str> = [command, "--help"].into_iter().filter(|a| !a.is_empty()).collect();
        let output = Command::new(env!("CARGO_BIN_EXE_loops")).args(&args).output().expect("loops runs");
        assert!(output.status.success());
        let help = String::from_utf8(output.stdout).expect("UTF-8 help");
        let Some((_, tail)) = help.split_once("\nExamples:\n") else { continue };
        for line in tail.lines().take_while(|line| !line.trim().is_empty()) {
            if let Some(command_line) = line.trim().strip_prefix("loops ") {
                examples.push(Example {
                    command: format!("loops {command_line}"),
                    source: format!("loops {} --help", command).replace("  ", " "),
                    shown: Vec::new(),
                });
            }
        }
    }
    examples
}

/// Whether `command` names a file of the data folder (`folder/...` with `folder` one of its
/// entries).
fn uses_data(command: &str, entries: &[String]) -> bool {
    command.split_whitespace().map(|word| word.trim_matches(['\'', '"'])).any(|word| {
        word.split_once('/').is_some_and(|(first, rest)| !rest.is_empty() && entries.iter().any(|e| e == first))
    })
}

#[test]
fn every_documented_command_on_the_shared_data_runs() {
    let Some(data) = real_data_dir() else { return };
    let data = data.canonicalize().expect("data folder");
    let entries: Vec<String> = std::fs::read_dir(&data)
        .expect("data folder")
        .map(|entry| entry.expect("entry").file_name().to_string_lossy().into_owned())
        .collect();
    // Each example in a folder of its own (examples are independent: two that write
    // `--out results` are two ways to run, not a sequence), holding the data under the names
    // the examples use; outputs land there.
    let root = std::env::temp_dir().join(format!("loops-documented-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&root);
    let folder = |index: usize| {
        let dir = root.join(index.to_string());
        std::fs::create_dir_all(&dir).expect("temp dir");
        for entry in &entries {
            std::os::unix::fs::symlink(data.join(entry), dir.join(entry)).expect("symlink");
        }
        dir
    };
    // The CLI's own commands (`loops-eval` and other Python console scripts are tested in
    // tests/python).
    let examples: Vec<Example> = readme_examples()
        .into_iter()
        .chain(help_examples())
        .filter(|e| e.command.starts_with("loops ") && uses_data(&e.command, &entries))
        .collect();
    let mut failures = Vec::new();
    for (index, example) in examples.iter().enumerate() {
        let (status, failed) = run_example(example, &folder(index));
        eprintln!("{} ({}): {status}", example.command, example.source);
        failures.extend(failed);
    }
    let _ = std::fs::remove_dir_all(&root);
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
    // The README's KITTI 00, fr2_desk, Corridor and pose graph commands, and the help's.
    let from_readme = examples.iter().filter(|e| e.source.starts_with("README")).count();
    let from_help = examples.len() - from_readme;
    assert!(from_readme >= 4 && from_help >= 5, "{from_readme} README and {from_help} help examples: {examples:#?}");
}

#[test]
fn the_examples_are_found() {
    // The extraction itself: a README example and a help example that do name data files.
    let entries = vec!["kitti_odometry".to_owned(), "tuc".to_owned()];
    assert!(uses_data("loops components kitti_odometry/00.txt --axes 0,2 --gamma 6", &entries));
    assert!(uses_data("loops sample x.tum --detections 'tuc/SLAM/Corridor_Input.txt'", &entries));
    assert!(!uses_data("loops components drive.tum --gamma 40", &entries));
    assert!(!uses_data("loops run logs/*.mcap --gamma 40 --out results", &entries));
    let readme = readme_examples();
    assert!(readme.iter().any(|e| e.command.starts_with("loops components kitti_odometry/00.txt")), "{readme:#?}");
    let help = help_examples();
    assert!(help.iter().any(|e| e.command.starts_with("loops sample tuc/SLAM/Corridor_GT.txt")), "{help:#?}");
    assert!(help.iter().all(|e| !e.command.contains("--format tum --axes")), "{help:#?}");
}
