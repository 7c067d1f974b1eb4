//! `loops`: inexact-loop components of trajectories, on the command line.
//!
//! [`main`] parses, dispatches to the command's module and maps errors: one line on stderr and
//! exit code 2 on error, 0 on success or a closed pipe (`loops run` also exits 1 when a log
//! failed, `loops fleet` when a session's folder failed; 130 on Ctrl-C). Each command is a thin
//! adapter over `loops-core` and `loops-io`: it converts its flags (`args` holds the groups
//! several share), calls, and prints.
//!
//! The command is a library so that two front ends run the same code: the `loops` binary of
//! this crate (`cargo install --path crates/loops-cli`) and the `loops` console script of the
//! Python wheel, which calls [`main`] in the Python process through `inexact_loops._core.run_cli`
//! (one build of the workspace gives the library and the command).

mod args;
mod components;
mod demo;
mod fleet;
mod guard;
mod info;
mod out_dir;
mod progress;
mod replay;
mod report;
mod run;
mod sample;
mod serve;
mod store;
mod synth;

use std::ffi::OsString;
use std::io::Write;

use anyhow::Result;
use clap::error::ErrorKind;
use clap::{CommandFactory, Parser, Subcommand};
pub use serve::LiveServer;

/// Find, measure and sample inexact loops (loop closures) in robot trajectories.
#[derive(Debug, Parser)]
#[command(name = "loops", version, about, propagate_version = true)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

/// The commands; each one's help is on its arguments' struct.
#[derive(Debug, Subcommand)]
enum Command {
    Components(components::ComponentsArgs),
    Sample(sample::SampleArgs),
    Info(info::InfoArgs),
    Demo(demo::DemoArgs),
    Run(run::RunArgs),
    Fleet(fleet::FleetArgs),
    Store(store::StoreArgs),
    Synth(synth::SynthArgs),
    Replay(replay::ReplayArgs),
}

/// Runs the `loops` command with `args` (the program name first, as [`std::env::args_os`]
/// gives them) and returns its exit code: 0 on success, a closed stdout, `--help` or
/// `--version`; 1 when `loops run` had a log fail (`loops fleet`: a session's folder); 2 on an
/// error or a usage error; 130 when interrupted (SIGINT or SIGTERM, which exit the process at
/// once after removing unfinished output; `loops replay` stops after its keyframe in progress,
/// prints its figures and returns 130). Nothing else leaves the process: clap's help,
/// version and usage errors are printed and returned as codes, and stdout is flushed before
/// returning.
///
/// It installs the SIGINT/SIGTERM handler once per process: call it from a process that runs
/// the command and nothing else (the binary, a console script).
pub fn main<I, T>(args: I) -> u8
where
    I: IntoIterator<Item = T>,
    T: Into<OsString> + Clone,
{
    let args: Vec<OsString> = args.into_iter().map(Into::into).collect();
    let code = match Cli::try_parse_from(&args) {
        // Help and version go to stdout with code 0, as clap's own `exit` prints them (its
        // broken pipe swallowed too), without leaving the process; a usage error is one line
        // on stderr with code 2, as every other error.
        Err(error) if !error.use_stderr() || error.kind() == ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand => {
            let _ = error.print();
            u8::try_from(error.exit_code()).unwrap_or(2)
        }
        Err(error) => {
            // The command whose help to point at: the subcommand given, if it is one.
            let subcommand =
                args.get(1).and_then(|a| a.to_str()).filter(|a| Cli::command().find_subcommand(a).is_some());
            let command = subcommand.map_or_else(|| "loops".to_owned(), |name| format!("loops {name}"));
            eprintln!("loops: error: {}", usage_error(&error.render().to_string(), &command));
            2
        }
        Ok(cli) => match run(cli) {
            Ok(code) => code,
            Err(error) if is_broken_pipe(&error) => 0,
            Err(error) => {
                eprintln!("loops: error: {error:#}");
                2
            }
        },
    };
    // The binary's runtime flushes stdout at exit; a caller in another runtime (Python) may not.
    let _ = std::io::stdout().flush();
    code
}

fn run(cli: Cli) -> Result<u8> {
    guard::install()?;
    let done = match cli.command {
        Command::Components(args) => components::components(args),
        Command::Sample(args) => sample::sample(args),
        Command::Info(args) => info::info(args),
        Command::Demo(args) => demo::demo(args),
        Command::Run(args) => return run::run(args),
        Command::Fleet(args) => return fleet::fleet(args),
        Command::Store(args) => store::store(args),
        Command::Synth(args) => synth::synth(args),
        Command::Replay(args) => return replay::replay(args),
    };
    done.map(|()| 0)
}

/// clap's usage error of `command` (`rendered`: its text without styles) as one line: the
/// message and its indented details (a missing argument, the valid values, a tip) joined, the
/// usage and "For more information" lines replaced by where the help is
/// (`try 'loops components --help'`).
fn usage_error(rendered: &str, command: &str) -> String {
    let mut parts: Vec<String> = Vec::new();
    // Whether the last part introduced a list ("...were not provided:"), one item a line.
    let mut listing = false;
    for line in rendered.lines().map(str::trim).filter(|line| !line.is_empty()) {
        if line.starts_with("Usage: ") || line.starts_with("For more information") {
            continue;
        }
        let line = line.strip_prefix("error: ").unwrap_or(line);
        match parts.last_mut() {
            Some(last) if listing || line.starts_with('[') => {
                if !last.ends_with(':') && listing {
                    last.push(',');
                }
                last.push(' ');
                last.push_str(line);
            }
            _ => {
                listing = line.ends_with(':');
                parts.push(line.to_owned());
            }
        }
    }
    format!("{} (try '{command} --help')", parts.join("; "))
}

fn is_broken_pipe(error: &anyhow::Error) -> bool {
    error.chain().any(|cause| {
        cause.downcast_ref::<std::io::Error>().is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
    })
}
