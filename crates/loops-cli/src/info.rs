//! `loops info`: what a pose file holds, before reading it as a trajectory.

use std::io::Write;
use std::path::PathBuf;

use anyhow::Result;
use clap::Args;

use crate::args::InputArgs;

/// What a pose file holds: for MCAP, its topics (type, encoding, messages, time span, and
/// whether poses can be read from it); for text formats, the format, poses and time span.
#[derive(Debug, Args)]
#[command(after_help = "Examples:\n  loops info drive.mcap\n  loops info 00.txt --format kitti")]
pub(crate) struct InfoArgs {
    /// The file.
    file: PathBuf,
    #[command(flatten)]
    input: InputArgs,
}

pub(crate) fn info(args: InfoArgs) -> Result<()> {
    let mut stdout = std::io::stdout().lock();
    let options = args.input.options()?;
    let has_topics =
        options.format.or_else(|| loops_io::Format::detect(&args.file)).is_some_and(loops_io::Format::has_topics);
    writeln!(stdout, "{}", args.file.display())?;
    if has_topics {
        let topics = loops_io::list_topics(&args.file)?;
        writeln!(
            stdout,
            "{:<28} {:<36} {:<9} {:>9}  {:>10}  poses",
            "topic", "type", "encoding", "messages", "span (s)"
        )?;
        for topic in &topics {
            let span = topic.log_time_span_ns.map_or("-".to_owned(), |(a, b)| format!("{:.1}", (b - a) as f64 * 1e-9));
            let poses = if topic.pose_type.is_some() { "yes" } else { "no" };
            writeln!(
                stdout,
                "{:<28} {:<36} {:<9} {:>9}  {:>10}  {poses}",
                topic.topic, topic.schema_name, topic.message_encoding, topic.message_count, span
            )?;
        }
    } else {
        let table = loops_io::read_trajectory_with(&args.file, &options)?;
        let t = &table.timestamps_s;
        let span =
            t.iter().copied().fold(f64::NEG_INFINITY, f64::max) - t.iter().copied().fold(f64::INFINITY, f64::min);
        writeln!(
            stdout,
            "  {} poses, {} coordinates each, {} orientations, over {:.3} s",
            table.timestamps_s.len(),
            table.dim,
            if table.orientations_xyzw.is_some() { "with" } else { "without" },
            span
        )?;
    }
    Ok(())
}
