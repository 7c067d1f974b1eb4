//! `loops synth`: seeded urban drives written as pose logs (MCAP or TUM), for trying the tool
//! and for tests; one drive, several with consecutive seeds (`--count`), or a fleet of vehicles
//! over days in one city (`--vehicles`, [`UrbanFleet`]), a file per session.

use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use clap::Args;
use loops_core::{Districts, SyntheticDrive, UrbanDrive, UrbanFleet};
use rayon::prelude::*;

use crate::guard;

/// Write seeded synthetic urban drives (a vehicle on a Manhattan grid) as MCAP or TUM logs: one,
/// several (--count), or a fleet of vehicles over days in one city (--vehicles, --days).
#[derive(Debug, Args)]
#[command(
    allow_negative_numbers = true,
    after_help = "Examples:\n  loops synth drive.mcap\n  \
    loops synth drive.tum --duration-s 600 --seed 7\n  \
    loops synth logs --count 20 --duration-s 900    # logs/urban-drive-0.mcap ... urban-drive-19.mcap\n  \
    loops synth big.mcap --duration-s 100800 --city-size-m 10000\n  \
    loops synth fleet --vehicles 3 --days 2 --duration-s 900    # fleet/car0-day0.mcap ... car2-day1.mcap\n  \
    loops synth city --vehicles 50 --duration-s 600 --city-size-m 10000 --district-m 1000 --format tum"
)]
pub(crate) struct SynthArgs {
    /// Where to write: a file (.mcap or .tum), or with --count or --vehicles a folder to create.
    #[arg(value_name = "PATH")]
    out: PathBuf,
    /// Length of each drive (each session of a fleet), seconds.
    #[arg(long, default_value_t = UrbanDrive::default().duration_s)]
    duration_s: f64,
    /// Pose rate, Hz.
    #[arg(long, default_value_t = UrbanDrive::default().rate_hz)]
    rate_hz: f64,
    /// Side of the square city, metres.
    #[arg(long, default_value_t = UrbanDrive::default().city_size_m)]
    city_size_m: f64,
    /// Work the city one square district of this side (metres) at a time, in snake order, so
    /// that revisits stay bounded however long the drive (default: roam the whole city).
    #[arg(long)]
    district_m: Option<f64>,
    /// Time in each district, seconds (with --district-m).
    // TODO(core): "a dwell time needs a district side" is checked here by clap and again in
    // loops-py; a core constructor from the two optional values should own it.
    #[arg(long, requires = "district_m", default_value_t = Districts::DEFAULT_DWELL_S)]
    district_dwell_s: f64,
    /// Seed of the (first) drive; of a fleet, the seed every session's own seed, start and first
    /// district are drawn from.
    #[arg(long, default_value_t = UrbanDrive::default().seed)]
    seed: u64,
    /// Write this many drives (seeds SEED, SEED+1, ...) into the folder PATH, named
    /// urban-drive-<seed>.<format>.
    #[arg(long)]
    count: Option<usize>,
    /// Write a fleet into the folder PATH: this many vehicles in one city, each driving once a
    /// day (--days), one file per session named car<V>-day<D>.<format>, with its own seed, start
    /// time and, with --district-m, its own first district (`loops fleet` reads them).
    #[arg(long, conflicts_with = "count")]
    vehicles: Option<usize>,
    /// Days of the fleet (with --vehicles): each session's clock counts from the first day's
    /// midnight.
    #[arg(long, requires = "vehicles", default_value_t = UrbanFleet::default().days)]
    days: usize,
    /// Sessions start at a time drawn uniformly within this many seconds after midnight (with
    /// --vehicles).
    #[arg(long, requires = "vehicles", default_value_t = UrbanFleet::default().start_spread_s)]
    start_spread_s: f64,
    /// File format: mcap (geometry_msgs/msg/PoseStamped, ROS 2 CDR) or tum (default: from PATH's
    /// extension; mcap for a folder).
    #[arg(long)]
    format: Option<String>,
    /// MCAP topic of the poses.
    #[arg(long, default_value_t = loops_io::McapWriteOptions::default().topic)]
    topic: String,
    /// Replace existing files.
    #[arg(long)]
    force: bool,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum SynthFormat {
    Mcap,
    Tum,
}

impl SynthFormat {
    fn extension(self) -> &'static str {
        match self {
            Self::Mcap => "mcap",
            Self::Tum => "tum",
        }
    }
}

pub(crate) fn synth(args: SynthArgs) -> Result<()> {
    let format = match (args.format.as_deref(), args.count) {
        (Some("mcap"), _) => SynthFormat::Mcap,
        (Some("tum"), _) => SynthFormat::Tum,
        (Some(other), _) => bail!("--format {other}: expected mcap or tum"),
        (None, Some(_)) => SynthFormat::Mcap,
        (None, None) if args.vehicles.is_some() => SynthFormat::Mcap,
        (None, None) => match args.out.extension().and_then(|e| e.to_str()) {
            Some("mcap") => SynthFormat::Mcap,
            Some("tum" | "txt") => SynthFormat::Tum,
            _ => bail!("{}: give a .mcap or .tum file name, or --format", args.out.display()),
        },
    };
    if let Some(vehicles) = args.vehicles {
        return synth_fleet(&args, vehicles, format);
    }
    let targets: Vec<(u64, PathBuf)> = match args.count {
        None => vec![(args.seed, args.out.clone())],
        Some(0) => bail!("--count must be at least 1"),
        Some(count) => {
            create_folder(&args.out)?;
            (0..count as u64)
                .map(|k| {
                    let seed = args.seed + k;
                    (seed, args.out.join(format!("urban-drive-{seed}.{}", format.extension())))
                })
                .collect()
        }
    };
    if !args.force
        && let Some((_, existing)) = targets.iter().find(|(_, path)| path.exists())
    {
        bail!("{} exists; pass --force to replace it", existing.display());
    }
    let written: Vec<usize> = targets
        .par_iter()
        .map(|(seed, path)| {
            let spec = UrbanDrive { seed: *seed, ..drive_spec(&args) };
            let drive = spec.generate().context("generating the urban drive")?;
            write_drive(&drive, path, format, &args)?;
            Ok(drive.trajectory.len())
        })
        .collect::<Result<_>>()?;
    let mut stdout = std::io::stdout().lock();
    for ((seed, path), poses) in targets.iter().zip(written) {
        writeln!(stdout, "wrote {} ({poses} poses, seed {seed})", path.display())?;
    }
    Ok(())
}

/// The drive the flags ask for (of every session, for a fleet), with the default seed.
fn drive_spec(args: &SynthArgs) -> UrbanDrive {
    UrbanDrive {
        duration_s: args.duration_s,
        rate_hz: args.rate_hz,
        city_size_m: args.city_size_m,
        seed: args.seed,
        districts: args.district_m.map(|side_m| Districts { side_m, dwell_s: args.district_dwell_s }),
        ..UrbanDrive::default()
    }
}

/// Creates the folder `out` (and its parents) for several files, refusing a file there.
fn create_folder(out: &Path) -> Result<()> {
    if out.exists() && !out.is_dir() {
        bail!("{} exists and is not a folder", out.display());
    }
    guard::with_writes(|writes| writes.create_dir(out))
}

/// `--vehicles`: a fleet ([`UrbanFleet`]), one file per session in the folder `args.out`, each
/// named by its session.
fn synth_fleet(args: &SynthArgs, vehicles: usize, format: SynthFormat) -> Result<()> {
    let spec = UrbanFleet { vehicles, days: args.days, drive: drive_spec(args), start_spread_s: args.start_spread_s };
    // The parameters are the core's to check, before the folder is made.
    let drives = spec.drives().context("generating the fleet")?;
    let targets: Vec<PathBuf> =
        drives.iter().map(|(name, _)| args.out.join(format!("{name}.{}", format.extension()))).collect();
    if !args.force
        && let Some(existing) = targets.iter().find(|path| path.exists())
    {
        bail!("{} exists; pass --force to replace it", existing.display());
    }
    create_folder(&args.out)?;
    drives.par_iter().zip(&targets).try_for_each(|((_, drive), path)| write_drive(drive, path, format, args))?;
    let mut stdout = std::io::stdout().lock();
    for ((name, drive), path) in drives.iter().zip(&targets) {
        let t = drive.trajectory.timestamps_s();
        writeln!(
            stdout,
            "wrote {} ({} poses, session {name} from {:.1} s to {:.1} s)",
            path.display(),
            t.len(),
            t[0],
            t[t.len() - 1]
        )?;
    }
    Ok(())
}

/// The drive as a pose table: positions, yaw quaternions, nanosecond stamps.
fn pose_table(drive: &SyntheticDrive, path: &Path) -> loops_io::PoseTable {
    let traj = &drive.trajectory;
    let positions: Vec<[f64; 3]> =
        (0..traj.len()).map(|i| <[f64; 3]>::try_from(traj.point(i)).unwrap_or_default()).collect();
    let orientations = drive.yaw_rad.iter().map(|yaw| [0.0, 0.0, (0.5 * yaw).sin(), (0.5 * yaw).cos()]).collect();
    let timestamps_ns: Vec<i64> = traj.timestamps_s().iter().map(|t| (t * 1e9).round() as i64).collect();
    loops_io::PoseTable {
        path: path.to_path_buf(),
        timestamps_s: timestamps_ns.iter().map(|&ns| loops_io::seconds_of_ns(ns)).collect(),
        timestamps_ns: Some(timestamps_ns),
        positions,
        orientations_xyzw: Some(orientations),
        dim: 3,
        source_lines: Vec::new(),
        messages: None,
    }
}

fn write_drive(drive: &SyntheticDrive, path: &Path, format: SynthFormat, args: &SynthArgs) -> Result<()> {
    let table = pose_table(drive, path);
    guard::with_writes(|_| match format {
        SynthFormat::Mcap => {
            let options = loops_io::McapWriteOptions::default().topic(args.topic.clone());
            loops_io::write_mcap(path, &table, &options, args.force)
        }
        SynthFormat::Tum => loops_io::write_tum(path, &table, args.force),
    })
    .with_context(|| format!("writing {}", path.display()))
}
