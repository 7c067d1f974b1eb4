//! `loops info`: what a pose file holds, before reading it as a trajectory.

use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::Result;
use clap::Args;
use loops_io::{Format, PoseTable, ReadOptions};

use crate::args::InputArgs;

/// What a pose file holds: its format, poses and time span, a pose graph's edges and loop
/// closures, the topics and frame pairs of an MCAP file or a bag.
///
/// For MCAP files and bags: the format, the topics (type, encoding, messages, time span, and
/// whether poses can be read from them) and the frame pairs of each transform topic (/tf), for
/// --frames. For text files: the format (and whether it was given, or told from the extension
/// or the first line), poses, coordinates, orientations, time span and whether the timestamps
/// increase (or which repeat); for pose graphs also the edges and the loop closures among them.
#[derive(Debug, Args)]
#[command(after_help = "Examples:\n  loops info drive.mcap\n  \
    loops info kitti_odometry/00.txt\n  \
    loops info pose_graphs/input_INTEL_g2o.g2o\n  \
    loops info tum_rgbd/fr2_desk_groundtruth.txt\n  \
    loops info poses/00.txt --format kitti --times sequences/00/times.txt")]
pub(crate) struct InfoArgs {
    /// The files (each described in turn).
    #[arg(required = true, value_name = "FILE")]
    files: Vec<PathBuf>,
    #[command(flatten)]
    input: InputArgs,
}

pub(crate) fn info(args: InfoArgs) -> Result<()> {
    let mut stdout = std::io::stdout().lock();
    let options = args.input.options()?;
    for file in &args.files {
        describe(&mut stdout, file, &options)?;
    }
    Ok(stdout.flush()?)
}

/// What `file` holds, as `loops info` prints it.
fn describe(out: &mut impl Write, file: &Path, options: &ReadOptions) -> Result<()> {
    let (format, told) = match options.format {
        Some(format) => (format, "given"),
        None => {
            let format = loops_io::format_of(file)?;
            let told = match Format::detect(file) {
                _ if file.is_dir() => "a folder",
                Some(by_name) if by_name == format => "from the extension",
                _ => "from the first line",
            };
            (format, told)
        }
    };
    writeln!(out, "{}", file.display())?;
    writeln!(out, "  format: {format} ({told})")?;
    if format.has_topics() {
        return describe_topics(out, file);
    }
    let options = options.clone().format(format);
    let (table, graph) = match format {
        Format::G2o => {
            let graph = loops_io::read_pose_graph_with(file, &options)?;
            (graph.vertices.clone(), Some(graph))
        }
        _ => (loops_io::read_trajectory_with(file, &options)?, None),
    };
    let t = &table.timestamps_s;
    let span = t.iter().copied().fold(f64::NEG_INFINITY, f64::max) - t.iter().copied().fold(f64::INFINITY, f64::min);
    // A graph's times are its vertex ids unless a rate or a times file gave seconds.
    let over = match &graph {
        Some(graph) if options.timing == loops_io::Timing::FromFile => format!(
            "vertex ids {} to {} (no times: --rate-hz or --times gives seconds)",
            graph.vertex_ids.first().copied().unwrap_or_default(),
            graph.vertex_ids.last().copied().unwrap_or_default()
        ),
        _ => format!("over {span:.3} s"),
    };
    writeln!(
        out,
        "  {} poses, {} coordinates each, {} orientations, {over}",
        table.len(),
        table.dim,
        if table.orientations_xyzw.is_some() { "with" } else { "without" },
    )?;
    writeln!(out, "  {}", timestamp_order(&table))?;
    if let Some(graph) = graph {
        writeln!(
            out,
            "  {} edges, {} of them loop closures (between vertices more than one id apart)",
            graph.edges.len(),
            graph.loop_closures().count()
        )?;
        if let Some(chain) = &graph.chain {
            writeln!(
                out,
                "  no vertices: the poses are its {} odometry edges chained from vertex {} (--chain-edges): dead \
                 reckoning",
                chain.odometry_edges, chain.first_id
            )?;
        }
        if let Some(skipped) = &graph.skipped {
            eprintln!("loops: warning: {skipped}");
        }
    }
    Ok(())
}

/// The topics of an MCAP file or a bag, and the frame pairs of its transform topics.
fn describe_topics(out: &mut impl Write, file: &Path) -> Result<()> {
    let topics = loops_io::list_topics(file)?;
    writeln!(out, "{:<28} {:<36} {:<9} {:>9}  {:>10}  poses", "topic", "type", "encoding", "messages", "span (s)")?;
    for topic in &topics {
        let span = topic.log_time_span_ns.map_or("-".to_owned(), |(a, b)| format!("{:.1}", (b - a) as f64 * 1e-9));
        let poses = if topic.pose_type.is_some() { "yes" } else { "no" };
        writeln!(
            out,
            "{:<28} {:<36} {:<9} {:>9}  {:>10}  {poses}",
            topic.topic, topic.schema_name, topic.message_encoding, topic.message_count, span
        )?;
    }
    let has_transforms =
        topics.iter().any(|topic| topic.message_count > 0 && topic.pose_type.is_some_and(|t| t.is_transform()));
    if has_transforms {
        for (topic, pairs) in loops_io::list_frame_pairs(file)? {
            writeln!(out, "frame pairs of {topic} (parent -> child, transforms; --frames PARENT,CHILD):")?;
            for pair in pairs {
                writeln!(out, "  {pair}")?;
            }
        }
    }
    Ok(())
}

/// Whether the table's timestamps strictly increase, as a trajectory needs; if not, the
/// repeats (which --drop-duplicate-stamps drops) or the first pose out of order.
fn timestamp_order(table: &PoseTable) -> String {
    let t = &table.timestamps_s;
    let at = |index: usize| match table.source_lines.get(index) {
        Some(line) => format!("line {line}"),
        None => format!("pose {index}"),
    };
    if let Some(index) = (1..t.len()).find(|&i| t[i] < t[i - 1]) {
        return format!(
            "timestamps out of order: {} s at {} is before {} s at {}",
            t[index],
            at(index),
            t[index - 1],
            at(index - 1)
        );
    }
    let repeats: Vec<usize> = (1..t.len()).filter(|&i| t[i] == t[i - 1]).collect();
    match repeats.as_slice() {
        [] => "timestamps strictly increasing".to_owned(),
        [first, ..] => format!(
            "{} timestamp(s) repeat the one before, the first at {} ({} s); --drop-duplicate-stamps drops them",
            repeats.len(),
            at(*first),
            t[*first]
        ),
    }
}
