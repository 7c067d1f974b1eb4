//! `loops store`: questions to a fleet store that `loops fleet --store DIR` keeps. Each query
//! prints a table, or writes its rows as CSV (`--csv FILE`, atomically, refusing an existing
//! file without `--force`; `--csv -` on stdout instead of the table). The answers are the
//! store's ([`loops_io::store`]); nothing here computes one.

use std::io::Write;
use std::path::PathBuf;

use anyhow::{Context, Result, bail};
use clap::{Args, Subcommand};

use crate::args::JsonTo;
use crate::{guard, out_dir};

/// Ask a fleet store (a folder `loops fleet --store DIR` keeps) which sessions pass near a
/// place and when, which sessions revisit a session, and which components its last update
/// added.
#[derive(Debug, Args)]
#[command(after_help = "Examples:\n  \
    loops store near city --point 120,-40 --radius 15\n  \
    loops store near city --polygon \"0,0 100,0 100,50 0,50\" --csv passes.csv\n  \
    loops store revisits city car1-day03\n  \
    loops store added city --csv -")]
pub(crate) struct StoreArgs {
    #[command(subcommand)]
    query: Query,
}

#[derive(Debug, Subcommand)]
enum Query {
    /// Which sessions pass near a point or a polygon, and when.
    ///
    /// In each stored session, every maximal run of consecutive poses within the radius of the
    /// place, in the map plane of the positions' x, y. Columns: session, name, i_start, i_end, t_start_s, t_end_s (poses and
    /// times of the run's first and last pose, on the session's clock).
    Near(NearArgs),
    /// Which sessions revisit a session.
    ///
    /// Those sharing at least one loop component with SESSION, from the store's overlap
    /// matrix. Columns: session, name, components, pair_count, area_s2,
    /// density.
    Revisits(RevisitsArgs),
    /// The components the store's last update added.
    ///
    /// Those holding a session the update added or replaced. Columns: id, session_a, session_b, a, b, trivial, area_s2, pair_count, i_min,
    /// i_max, j_min, j_max (poses within each session).
    Added(AddedArgs),
}

/// Where the rows go besides the table.
#[derive(Debug, Args)]
struct CsvArgs {
    /// Also write the rows as CSV to FILE (atomically); `-` prints the CSV on stdout instead of
    /// the table.
    #[arg(long, value_name = "FILE")]
    csv: Option<JsonTo>,
    /// Replace the CSV file if it exists.
    #[arg(long)]
    force: bool,
}

#[derive(Debug, Args)]
#[command(allow_negative_numbers = true)]
struct NearArgs {
    /// The store's folder.
    store: PathBuf,
    /// The place is the point X,Y (map-plane coordinates, metres).
    #[arg(long, value_name = "X,Y", allow_hyphen_values = true, required_unless_present = "polygon")]
    point: Option<String>,
    /// The place is the polygon of these vertices, in order, separated by spaces (at least 3;
    /// the last joins the first): a pose is near when inside it (even-odd rule) or within the
    /// radius of its edges.
    #[arg(long, value_name = "\"X,Y X,Y X,Y ...\"", allow_hyphen_values = true, conflicts_with = "point")]
    polygon: Option<String>,
    /// Within this distance of the place, metres (default: the store's gamma).
    #[arg(long, value_name = "METRES")]
    radius: Option<f64>,
    #[command(flatten)]
    csv: CsvArgs,
}

#[derive(Debug, Args)]
struct RevisitsArgs {
    /// The store's folder.
    store: PathBuf,
    /// The session, by name.
    session: String,
    #[command(flatten)]
    csv: CsvArgs,
}

#[derive(Debug, Args)]
struct AddedArgs {
    /// The store's folder.
    store: PathBuf,
    #[command(flatten)]
    csv: CsvArgs,
}

pub(crate) fn store(args: StoreArgs) -> Result<()> {
    match args.query {
        Query::Near(args) => near(args),
        Query::Revisits(args) => revisits(args),
        Query::Added(args) => added(args),
    }
}

/// The store in `dir`, read for a query.
fn read(dir: &std::path::Path) -> Result<loops_io::store::StoredFleet> {
    loops_io::store::read_store(dir).with_context(|| format!("reading the fleet store {}", dir.display()))
}

/// `X,Y` as two numbers; `flag` names the flag in the error.
fn xy(flag: &str, text: &str) -> Result<[f64; 2]> {
    let parts: Vec<&str> = text.split(',').map(str::trim).collect();
    let numbers: Vec<f64> = parts.iter().filter_map(|p| p.parse().ok()).collect();
    match numbers[..] {
        [x, y] if parts.len() == 2 => Ok([x, y]),
        _ => bail!("{flag} {text:?}: expected X,Y (two numbers separated by a comma)"),
    }
}

fn near(args: NearArgs) -> Result<()> {
    let place = match (&args.point, &args.polygon) {
        (Some(point), _) => loops_core::Place::point(xy("--point", point)?)?,
        (None, Some(polygon)) => loops_core::Place::polygon(
            polygon.split_whitespace().map(|v| xy("--polygon", v)).collect::<Result<Vec<_>>>()?,
        )?,
        (None, None) => bail!("give the place: --point X,Y or --polygon \"X,Y X,Y X,Y ...\""),
    };
    let stored = read(&args.store)?;
    let passes = stored.near(&place, args.radius)?;
    let names = stored.names();
    let rows: Vec<Vec<String>> = passes
        .iter()
        .map(|p| {
            vec![
                p.session.to_string(),
                names[p.session].to_owned(),
                p.pass.poses[0].to_string(),
                p.pass.poses[1].to_string(),
                p.pass.times_s[0].to_string(),
                p.pass.times_s[1].to_string(),
            ]
        })
        .collect();
    let write = |file: &mut dyn Write| loops_io::store::passes_to_csv(&passes, &names, file);
    emit(&args.store, &args.csv, &loops_io::store::PASS_COLUMNS, &rows, "passes", write)
}

fn revisits(args: RevisitsArgs) -> Result<()> {
    let stored = read(&args.store)?;
    let Some(session) = stored.store.session_index(&args.session) else {
        bail!(
            "session {:?} is not in the store {} ({} sessions: {})",
            args.session,
            args.store.display(),
            stored.store.sessions().len(),
            stored.names().join(", ")
        );
    };
    let revisits = stored.store.loops()?.revisits(session);
    let names = stored.names();
    let rows: Vec<Vec<String>> = revisits
        .iter()
        .map(|r| {
            vec![
                r.session.to_string(),
                names[r.session].to_owned(),
                r.components.to_string(),
                r.pair_count.to_string(),
                r.area_s2.to_string(),
                r.density.to_string(),
            ]
        })
        .collect();
    let write = |file: &mut dyn Write| loops_io::store::revisits_to_csv(&revisits, &names, file);
    emit(&args.store, &args.csv, &loops_io::store::REVISIT_COLUMNS, &rows, "sessions", write)
}

fn added(args: AddedArgs) -> Result<()> {
    let stored = read(&args.store)?;
    let loops = stored.store.loops()?;
    let ids = stored.store.added_components(&loops);
    let names = stored.names();
    let rows: Vec<Vec<String>> = ids
        .iter()
        .map(|&id| {
            let c = &loops.components()[id];
            let [a, b] = c.sessions;
            [
                id.to_string(),
                names[a].to_owned(),
                names[b].to_owned(),
                a.to_string(),
                b.to_string(),
                c.trivial.to_string(),
                c.area_s2.to_string(),
                c.pair_count.to_string(),
                c.poses[0][0].to_string(),
                c.poses[0][1].to_string(),
                c.poses[1][0].to_string(),
                c.poses[1][1].to_string(),
            ]
            .to_vec()
        })
        .collect();
    let write = |file: &mut dyn Write| loops_io::store::store_components_to_csv(&loops, &ids, &names, file);
    emit(&args.store, &args.csv, &loops_io::store::STORE_COMPONENT_COLUMNS, &rows, "components", write)
}

/// Prints `rows` under `columns` as a table (or the CSV on stdout for `--csv -`), and writes
/// the CSV file of `--csv FILE` (never onto the store, an existing file only with `--force`).
fn emit(
    store: &std::path::Path,
    csv: &CsvArgs,
    columns: &[&str],
    rows: &[Vec<String>],
    what: &str,
    write: impl Fn(&mut dyn Write) -> std::io::Result<()>,
) -> Result<()> {
    let mut stdout = std::io::stdout().lock();
    match &csv.csv {
        Some(JsonTo::Stdout) => return Ok(write(&mut stdout)?),
        Some(JsonTo::File(path)) => {
            out_dir::refuse_outputs_on_inputs([("--csv", Some(path.as_path()))], &[store.to_path_buf()])?;
            let mut files = loops_io::StagedFiles::new();
            files.stage(path, csv.force, |file| write(file)).map_err(guard::write_error)?;
            guard::with_writes(|_| files.persist()).map_err(guard::write_error)?;
        }
        None => {}
    }
    let widths: Vec<usize> = (0..columns.len())
        .map(|k| rows.iter().map(|r| r[k].chars().count()).chain([columns[k].len()]).max().unwrap_or(0))
        .collect();
    let line = |cells: &mut dyn Iterator<Item = &str>| -> String {
        let padded: Vec<String> = cells.zip(&widths).map(|(c, &w)| format!("{c:>w$}")).collect();
        padded.join("  ")
    };
    writeln!(stdout, "{}", line(&mut columns.iter().copied()))?;
    for row in rows {
        writeln!(stdout, "{}", line(&mut row.iter().map(String::as_str)))?;
    }
    writeln!(stdout, "{} {what}", rows.len())?;
    if let Some(JsonTo::File(path)) = &csv.csv {
        writeln!(stdout, "wrote {} {what} to {}", rows.len(), path.display())?;
    }
    Ok(())
}
