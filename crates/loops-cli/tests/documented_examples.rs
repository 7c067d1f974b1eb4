//! The commands the README, the documentation site (`docs/**/*.md`) and `--help` show run as
//! shown. Every example that names a file of `../shared/data` (`kitti_odometry/00.txt`,
//! `tum_rgbd/fr2_desk_groundtruth.txt`, ...) runs through `sh`, in a folder that holds the data
//! under those names, and must succeed; the output shown under it must be in what it prints
//! (a line `...` stands for any lines, and `...` within a line for any text). Skipped, saying
//! so, when the data is absent. The fleet example of the documentation's getting-started page
//! needs no data (it writes its own logs): it always runs. `tests/test_docs.py` runs every
//! example of the documentation in order, page by page; this test runs the command line's own
//! examples against the binary built here.

use std::path::{Path, PathBuf};
use std::process::Command;

mod support;
use support::TempDir;

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

/// A documented command, where it is documented, and the output shown under it (not for `--help`).
#[derive(Debug)]
struct Example {
    command: String,
    source: String,
    shown: Vec<String>,
}

/// The Markdown files whose console blocks are examples: the README, then the site's pages.
fn documented_files() -> Vec<PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let mut files = vec![root.join("README.md")];
    let mut folders = vec![root.join("docs")];
    let mut pages = Vec::new();
    while let Some(folder) = folders.pop() {
        for entry in std::fs::read_dir(&folder).expect("docs folder") {
            let path = entry.expect("entry").path();
            if path.is_dir() {
                folders.push(path);
            } else if path.extension().is_some_and(|e| e == "md") {
                pages.push(path);
            }
        }
    }
    pages.sort();
    files.extend(pages);
    files
}

/// The `$ ...` lines of the console blocks of `text` (from `name`), with the lines shown under
/// each.
fn console_examples(text: &str, name: &str) -> Vec<Example> {
    let mut examples: Vec<Example> = Vec::new();
    let mut in_console = false;
    for (index, line) in text.lines().enumerate() {
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
                source: format!("{name} line {}", index + 1),
                shown: Vec::new(),
            });
        } else if let Some(example) = examples.last_mut() {
            example.shown.push(line.to_owned());
        }
    }
    examples
}

/// The console examples of the README and of every page of the documentation site.
fn readme_examples() -> Vec<Example> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    documented_files()
        .iter()
        .flat_map(|path| {
            let text = std::fs::read_to_string(path).expect("documentation page");
            let name = path.strip_prefix(&root).unwrap_or(path).display().to_string();
            console_examples(&text, &name)
        })
        .collect()
}

/// The commands of the getting-started page for fleets, section "One machine, command line"
/// (its console blocks, in order), with the lines shown under each: a sequence that runs in one
/// folder.
fn fleet_examples() -> Vec<Example> {
    let page = "docs/getting-started/fleet.md";
    let text = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../..").join(page))
        .expect("the fleet page");
    let section = text
        .split("\n## ")
        .find(|s| s.starts_with("One machine, command line"))
        .expect("the section \"One machine, command line\"");
    console_examples(section, page)
}

/// The documented fleet example (synthetic logs, no shared data) runs as shown: its commands in
/// order in one folder, each succeeding and printing every line shown under it but `...`.
#[test]
fn the_fleet_example_runs_as_shown() {
    let examples = fleet_examples();
    assert!(examples.iter().any(|e| e.command.starts_with("loops synth")), "{examples:#?}");
    assert!(examples.iter().any(|e| e.command.starts_with("loops fleet")), "{examples:#?}");
    let dir = TempDir::at(std::env::temp_dir().join(format!("loops-documented-fleet-{}", std::process::id())));
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
        .filter(|line| !printed.lines().any(|printed_line| shown_as(line, printed_line)))
        .map(|line| {
            format!(
                "{} ({}): the documentation shows {line:?}, which it does not print:\n{printed}",
                example.command, example.source
            )
        })
        .collect();
    (output.status, failures)
}

/// Whether `printed` is the line `shown`, where `...` in `shown` stands for any text (and a
/// line that is only `...` for any line).
fn shown_as(shown: &str, printed: &str) -> bool {
    if shown.trim() == "..." {
        return true;
    }
    let parts: Vec<&str> = shown.split("...").collect();
    let (first, last) = (parts[0], parts[parts.len() - 1]);
    if parts.len() == 1 {
        return printed == shown;
    }
    if !printed.starts_with(first) || printed.len() < first.len() + last.len() || !printed.ends_with(last) {
        return false;
    }
    let mut rest = &printed[first.len()..printed.len() - last.len()];
    for part in &parts[1..parts.len() - 1] {
        match rest.find(part) {
            Some(at) => rest = &rest[at + part.len()..],
            None => return false,
        }
    }
    true
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
    // The documentation's KITTI, fr2_desk, Corridor and pose graph commands, and the help's.
    let from_docs = examples.iter().filter(|e| !e.source.starts_with("loops ")).count();
    let from_help = examples.len() - from_docs;
    assert!(from_docs >= 8 && from_help >= 5, "{from_docs} documented and {from_help} help examples: {examples:#?}");
}

#[test]
fn the_examples_are_found() {
    // The extraction itself: a documented example and a help example that do name data files,
    // and the wildcard of shown output.
    let entries = vec!["kitti_odometry".to_owned(), "tuc".to_owned()];
    assert!(uses_data("loops components kitti_odometry/00.txt --axes 0,2 --gamma 6", &entries));
    assert!(uses_data("loops sample x.tum --detections 'tuc/SLAM/Corridor_Input.txt'", &entries));
    assert!(!uses_data("loops components drive.tum --gamma 40", &entries));
    assert!(!uses_data("loops run logs/*.mcap --gamma 40 --out results", &entries));
    let readme = readme_examples();
    assert!(readme.iter().any(|e| e.command.starts_with("loops components kitti_odometry/00.txt")), "{readme:#?}");
    let help = help_examples();
    assert!(help.iter().any(|e| e.command.starts_with("loops sample tuc/SLAM/Corridor_GT.txt")), "{help:#?}");
    assert!(shown_as("a ... c", "a b c") && shown_as("...", "x") && shown_as("a b", "a b"));
    assert!(!shown_as("a ... c", "a b d") && !shown_as("a ... c ... e", "a e c") && !shown_as("a b", "a b c"));
    assert!(help.iter().all(|e| !e.command.contains("--format tum --axes")), "{help:#?}");
}
