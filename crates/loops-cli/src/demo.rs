//! `loops demo`: the components of a built-in synthetic urban drive, printed as `loops
//! components` prints them.

use anyhow::{Context, Result};
use clap::Args;
use loops_core::{MetricSpec, Separation, UrbanDrive};

use crate::args::OutputArgs;
use crate::components;

/// Run on a built-in synthetic urban drive (2.1 h, 10 Hz, 1 km² city) and print a summary.
#[derive(Debug, Args)]
#[command(
    allow_negative_numbers = true,
    after_help = "Examples:\n  loops demo\n  loops demo --duration-s 600 --seed 3 --json demo.json"
)]
pub(crate) struct DemoArgs {
    /// Length of the drive, seconds.
    #[arg(long, default_value_t = UrbanDrive::default().duration_s, allow_hyphen_values = true)]
    duration_s: f64,
    /// Seed of the drive.
    #[arg(long, default_value_t = UrbanDrive::default().seed)]
    seed: u64,
    /// The distance threshold γ, metres.
    #[arg(long, value_name = "GAMMA_M", default_value_t = UrbanDrive::DEFAULT_GAMMA_M, allow_hyphen_values = true)]
    gamma: f64,
    /// The paper's S_gamma instead of the revisits at least 4 x gamma apart along the path.
    #[arg(long)]
    no_separation: bool,
    /// Worker threads (default: one per core).
    #[arg(long)]
    threads: Option<usize>,
    #[command(flatten)]
    output: OutputArgs,
}

pub(crate) fn demo(args: DemoArgs) -> Result<()> {
    let spec = UrbanDrive { duration_s: args.duration_s, seed: args.seed, ..UrbanDrive::default() };
    let drive = spec.generate().context("generating the urban drive")?;
    let source = format!("urban drive (seed {}, {:.0} s at {} Hz)", spec.seed, spec.duration_s, spec.rate_hz);
    loops_core::check_gamma(args.gamma)?;
    let separation = if args.no_separation { Separation::NONE } else { Separation::for_gamma(args.gamma) };
    let (loops, seconds) = components::timed(args.threads, || {
        MetricSpec::Euclidean.find_loops_separated(&drive.trajectory, args.gamma, separation)
    })?;
    components::print(&source, "positions x, y, z", &drive.trajectory, &loops, seconds, &args.output)
}
