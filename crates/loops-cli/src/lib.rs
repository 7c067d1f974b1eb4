//! `loops`: inexact-loop components of trajectories, on the command line.
//!
//! `main` parses, dispatches to the command's module and maps errors: one line on stderr and
//! exit code 2 on error, 0 on success or a closed pipe (`loops run` also exits 1 when a log
//! failed, 130 on Ctrl-C). Each command is a thin adapter over `loops-core` and `loops-io`:
//! it converts its flags ([`args`] holds the groups several share), calls, and prints.

mod args;
mod components;
mod demo;
mod guard;
mod info;
mod out_dir;
mod progress;
mod report;
mod run;
mod sample;
mod synth;

use std::process::ExitCode;

use anyhow::Result;
use clap::{Parser, Subcommand};

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
    Synth(synth::SynthArgs),
}

fn main() -> ExitCode {
    match run(Cli::parse()) {
        Ok(code) => code,
        Err(error) if is_broken_pipe(&error) => ExitCode::SUCCESS,
        Err(error) => {
            eprintln!("loops: error: {error:#}");
            ExitCode::from(2)
        }
    }
}

fn run(cli: Cli) -> Result<ExitCode> {
    guard::install()?;
    let done = match cli.command {
        Command::Components(args) => components::components(args),
        Command::Sample(args) => sample::sample(args),
        Command::Info(args) => info::info(args),
        Command::Demo(args) => demo::demo(args),
        Command::Run(args) => return run::run(args),
        Command::Synth(args) => synth::synth(args),
    };
    done.map(|()| ExitCode::SUCCESS)
}

fn is_broken_pipe(error: &anyhow::Error) -> bool {
    error.chain().any(|cause| {
        cause.downcast_ref::<std::io::Error>().is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
    })
}
