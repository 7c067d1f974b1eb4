//! Reads the poses of an MCAP file (or several) and prints how fast: the speed check of the MCAP
//! reader (not a timed test).
//!
//! ```text
//! cargo run --release -p loops-io --example read_mcap -- drive.mcap [more.mcap ...] [--topic /pose] [--repeat 5]
//! ```
//!
//! A file to try it on, with 10⁶ `PoseStamped` messages, and the Python reader on the same file:
//!
//! ```text
//! python3 crates/loops-io/tests/make_mcap_fixtures.py --bench 1e6 /tmp/poses.mcap
//! cargo run --release -p loops-io --example read_mcap -- /tmp/poses.mcap --repeat 5
//! python3 crates/loops-io/tests/make_mcap_fixtures.py --read /tmp/poses.mcap
//! ```

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use loops_io::{McapOptions, list_topics, read_mcap_files};

fn main() -> ExitCode {
    let mut files = Vec::new();
    let mut options = McapOptions::default();
    let mut repeat = 3usize;
    let mut args = std::env::args().skip(1);
    while let Some(arg) = args.next() {
        match arg.as_str() {
            "--topic" => match args.next() {
                Some(topic) => options = options.topic(topic),
                None => return usage("--topic needs a topic"),
            },
            "--repeat" => match args.next().and_then(|n| n.parse().ok()) {
                Some(n) if n > 0 => repeat = n,
                _ => return usage("--repeat needs a positive count"),
            },
            _ => files.push(PathBuf::from(arg)),
        }
    }
    if files.is_empty() {
        return usage("no file given");
    }
    for file in &files {
        match list_topics(file) {
            Ok(topics) => {
                let bytes = std::fs::metadata(file).map(|m| m.len()).unwrap_or(0);
                println!("{} ({:.1} MB):", file.display(), bytes as f64 / 1e6);
                for topic in topics {
                    println!("  {topic}");
                }
            }
            Err(error) => {
                eprintln!("{error}");
                return ExitCode::from(1);
            }
        }
    }
    let mut best_s = f64::INFINITY;
    let mut poses = 0;
    for run in 0..repeat {
        let start = Instant::now();
        let table = match read_mcap_files(&files, &options) {
            Ok(table) => table,
            Err(error) => {
                eprintln!("{error}");
                return ExitCode::from(1);
            }
        };
        let seconds = start.elapsed().as_secs_f64();
        poses = table.len();
        best_s = best_s.min(seconds);
        println!("run {}: {poses} poses in {seconds:.3} s ({:.0} poses/s)", run + 1, poses as f64 / seconds);
    }
    println!("best of {repeat}: {poses} poses in {best_s:.3} s ({:.0} poses/s)", poses as f64 / best_s);
    ExitCode::SUCCESS
}

fn usage(problem: &str) -> ExitCode {
    eprintln!("{problem}\nusage: read_mcap FILE.mcap [FILE.mcap ...] [--topic TOPIC] [--repeat N]");
    ExitCode::from(2)
}
