//! `loops replay`: a pose log fed to the online engine pose by pose, as a SLAM front end would
//! feed it, streaming what the front end would get at each keyframe (one JSON line: its
//! loop-closure candidates, the components created and merged, the time the push took) and
//! printing latency figures at the end. With `--serve`, the same keyframes go live to Foxglove
//! (the [`serve`](crate::serve) module); with `--speed`, at the pace of the log's clock.

use std::io::Write;
use std::net::SocketAddr;
use std::path::PathBuf;
use std::time::{Duration, Instant};

use anyhow::{Context, Result, bail};
use clap::Args;
use loops_core::{
    Interrupt, Trajectory,
    online::{Candidate, Cap, OnlineLoops, OnlineSampler, OnlineSamplerOptions, Update},
};
use serde::Serialize;

use crate::args::{EngineArgs, InputArgs};
use crate::guard;
use crate::serve::LiveServer;

/// Replay a pose log through the online engine, pose by pose, as a SLAM front end would: one
/// JSON line per keyframe on stdout (its loop-closure candidates, the components created and
/// merged, the push's latency), latency figures on stderr at the end.
#[derive(Debug, Args)]
#[command(
    allow_negative_numbers = true,
    after_help = "Examples:\n  \
    loops replay drive.tum --gamma 40 --rate 0.05 --cap-per-minute 2\n  \
    loops replay drive.mcap --gamma 40 --every-s 1 | jq -c 'select(.candidates != [])'\n  \
    loops replay kitti_odometry/00.txt --axes 0,2 --gamma 6 --rate 0.02 --quiet    # latency only\n  \
    loops replay drive.mcap --gamma 40 --serve --speed 1 --quiet    # live in Foxglove: ws://127.0.0.1:8765\n\n\
    Each line: {\"pose\": last pose pushed, \"t_s\", \"poses\": poses pushed at this keyframe,\n\
    \"latency_us\": push + offer, \"loop_duration_s\": tau of the pose so far, \"candidates\":\n\
    [{\"keyframe\", \"j\", \"k\", \"component\", \"distance\", \"first\", \"improves\": [j, k] of the\n\
    first candidate, on its improvement only}], \"created\": [ids],\n\
    \"merged\": [{\"pose\", \"retired\", \"survivor\"}], \"extended_count\"}.\n\
    Ctrl-C stops after the keyframe in progress and prints the figures so far (exit code 130)."
)]
pub(crate) struct ReplayArgs {
    /// The pose log; several files are read as one trajectory (MCAP files merged by time,
    /// others joined in time order).
    #[arg(required = true, value_name = "LOG")]
    files: Vec<PathBuf>,
    #[command(flatten)]
    input: InputArgs,
    #[command(flatten)]
    engine: EngineArgs,
    #[command(flatten)]
    sampler: OnlineSamplerArgs,
    /// A keyframe every this many seconds: the poses in between are pushed together with the
    /// keyframe, in one batch (the candidates are the same) [default: 0, every pose is a
    /// keyframe].
    #[arg(long, value_name = "SECONDS", allow_hyphen_values = true)]
    every_s: Option<f64>,
    /// No JSON lines: only the figures on stderr.
    #[arg(long)]
    quiet: bool,
    /// Serve the keyframes live over Foxglove's WebSocket protocol on ADDR:PORT (port 0: a free
    /// one; the address is printed on stderr): in Foxglove, Open connection, Foxglove WebSocket.
    /// The replay starts when a client subscribes; the server closes at the end of the log
    /// (after its clients leave, 2 s at most) or on Ctrl-C. Topics as in `loops run --mcap`:
    /// /loops/trajectory, /loops/tau, /loops/components, /loops/candidates and /loops/markers
    /// (ROS 2 MarkerArray) at each keyframe, /loops/plane every 100 poses and at the end.
    #[arg(long, value_name = "ADDR:PORT", num_args = 0..=1, default_missing_value = "127.0.0.1:8765")]
    serve: Option<String>,
    /// With --serve: keep serving after the end of the log, until Ctrl-C.
    #[arg(long, requires = "serve")]
    hold: bool,
    /// Play at this many times the log's clock (1: real time) instead of as fast as it goes.
    #[arg(long, value_name = "FACTOR", allow_hyphen_values = true)]
    speed: Option<f64>,
}

/// The online sampler's flags, with the core's defaults.
#[derive(Debug, Args)]
struct OnlineSamplerArgs {
    /// σ_ρ: the expected number of candidates per component per pose (0: only each component's
    /// first candidate).
    #[arg(long, default_value_t = OnlineSamplerOptions::default().rate, allow_hyphen_values = true)]
    rate: f64,
    /// At most this many candidates per minute per component (a token bucket).
    #[arg(long, value_name = "COUNT", allow_hyphen_values = true, conflicts_with = "cap_per_metre")]
    cap_per_minute: Option<f64>,
    /// At most this many candidates per metre of travel (the metric's unit) per component.
    #[arg(long, value_name = "COUNT", allow_hyphen_values = true)]
    cap_per_metre: Option<f64>,
    /// No candidate at a component's first appearance (P1 online): only the drawn ones.
    #[arg(long)]
    no_first: bool,
    /// Where a component's first candidate goes: edge-then-closest (the closest pair at the
    /// edge of γ as it appears, then, at the keyframe after the path leaves it, the closest pair
    /// of that pass, its "improves" naming the first; none when the first was the closest),
    /// edge (the edge one only) or closest-approach (the pass's closest pair only, late). A
    /// candidate at the closest approach has its "k" earlier than its "keyframe".
    #[arg(long, value_name = "WHERE", default_value_t = OnlineSamplerOptions::default().first_offer.name().to_owned(),
        conflicts_with = "no_first")]
    first_offer: String,
    /// Every drawn candidate uniform in its row (the paper's σ_ρ), not the row's closest pair
    /// first (the default sampler's rule).
    #[arg(long)]
    uniform_in_row: bool,
    /// Seed of the random choices.
    #[arg(long, default_value_t = OnlineSamplerOptions::default().seed)]
    seed: u64,
}

impl OnlineSamplerArgs {
    fn options(&self, separation: loops_core::Separation) -> Result<OnlineSamplerOptions> {
        let cap = match (self.cap_per_minute, self.cap_per_metre) {
            (Some(c), _) => Cap::PerMinute(c),
            (None, Some(c)) => Cap::PerMetre(c),
            (None, None) => Cap::None,
        };
        Ok(OnlineSamplerOptions {
            rate: self.rate,
            cap,
            first_on_appearance: !self.no_first,
            first_offer: self.first_offer.parse()?,
            closest_in_row: OnlineSamplerOptions::default().closest_in_row && !self.uniform_in_row,
            separation,
            seed: self.seed,
        })
    }
}

/// One keyframe's line.
#[derive(Debug, Serialize)]
struct KeyframeLine<'a> {
    pose: usize,
    t_s: f64,
    poses: usize,
    latency_us: f64,
    loop_duration_s: f64,
    candidates: Vec<CandidateJson>,
    created: &'a [u32],
    merged: Vec<MergeJson>,
    extended_count: usize,
}

#[derive(Debug, Serialize)]
struct CandidateJson {
    keyframe: usize,
    j: usize,
    k: usize,
    component: u32,
    distance: f64,
    first: bool,
    /// Only on the closest approach that improves a first candidate: that one's pair.
    #[serde(skip_serializing_if = "Option::is_none")]
    improves: Option<[usize; 2]>,
}

#[derive(Debug, Serialize)]
struct MergeJson {
    pose: usize,
    retired: u32,
    survivor: u32,
}

impl KeyframeLine<'_> {
    fn new<'a>(update: &'a Update, t_s: f64, latency: Duration, candidates: &[Candidate]) -> KeyframeLine<'a> {
        KeyframeLine {
            pose: update.pose,
            t_s,
            poses: update.pose + 1 - update.first_pose,
            // Whole nanoseconds in µs: `4.496`, not the `4.4959999999999996` of seconds × 10⁶.
            latency_us: latency.as_nanos() as f64 / 1e3,
            loop_duration_s: update.loop_duration_s,
            candidates: candidates
                .iter()
                .map(|c| CandidateJson {
                    keyframe: c.keyframe,
                    j: c.pair[0],
                    k: c.pair[1],
                    component: c.component,
                    distance: c.distance,
                    first: c.first,
                    improves: c.improves,
                })
                .collect(),
            created: &update.created,
            merged: update
                .merged
                .iter()
                .map(|m| MergeJson { pose: m.pose, retired: m.retired, survivor: m.survivor })
                .collect(),
            extended_count: update.extended.len(),
        }
    }
}

/// The keyframes of `times` for a keyframe every `every_s` seconds: the last pose of each batch
/// to push. The first pose is one; then the first pose at least `every_s` after the last
/// keyframe; the last pose ends the last batch.
fn keyframes(times: &[f64], every_s: f64) -> Vec<usize> {
    let mut out = Vec::new();
    let mut last: Option<f64> = None;
    for (k, &t) in times.iter().enumerate() {
        if last.is_none_or(|last| t - last >= every_s) {
            out.push(k);
            last = Some(t);
        }
    }
    if let (Some(&end), Some(n)) = (out.last(), times.len().checked_sub(1))
        && end != n
    {
        out.push(n);
    }
    out
}

pub(crate) fn replay(args: ReplayArgs) -> Result<u8> {
    let spec = args.engine.spec()?;
    loops_core::check_gamma(args.engine.gamma)?;
    let every_s = args.every_s.unwrap_or(0.0);
    if !(every_s.is_finite() && every_s >= 0.0) {
        bail!("--every-s takes a finite number of seconds >= 0, got {every_s}");
    }
    if let Some(speed) = args.speed.filter(|&speed| !(speed.is_finite() && speed > 0.0)) {
        bail!("--speed takes a finite factor > 0, got {speed}");
    }
    let serve_address = match &args.serve {
        Some(address) => Some(
            address
                .parse::<SocketAddr>()
                .map_err(|_| anyhow::anyhow!("--serve {address}: expected ADDR:PORT, e.g. 127.0.0.1:8765"))?,
        ),
        None => None,
    };
    let separation = args.engine.separation()?;
    let mut sampler = OnlineSampler::new(args.sampler.options(separation)?)?;
    let source = crate::args::source_name(&args.files);
    let (table, traj) = args.input.read_table(&args.files, &spec)?;
    let mut engine = OnlineLoops::new(spec, traj.dim(), args.engine.gamma)?;
    let stop = Interrupt::new();
    let _stop_guard = guard::stop_on_interrupt(stop.clone());
    let mut live = match serve_address {
        Some(address) => {
            let batches = keyframes(traj.timestamps_s(), every_s).len();
            let server = LiveServer::start(address, batches * loops_io::LIVE_TOPICS.len())?;
            // The log's own positions and orientations, unless reading dropped or merged poses.
            let fits = table.positions.len() == traj.len();
            let positions = if fits { table.positions.clone() } else { loops_io::point_positions(&traj) };
            let orientations = table.orientations_xyzw.clone().filter(|_| fits);
            // The log's name, as `loops run` names its scene (several files: their names joined).
            let names: Vec<String> = args.files.iter().map(loops_io::log_name).collect();
            let scene = loops_io::LiveScene::new(&names.join("+"), positions, orientations)?;
            eprintln!(
                "loops replay: serving on ws://{} (Foxglove: Open connection, Foxglove WebSocket); waiting for a \
                 client",
                server.address()
            );
            Some((server, scene))
        }
        None => None,
    };
    let mut pace = Pace { speed: args.speed, live: live.as_mut() };
    let replayed = loops_core::with_threads(args.engine.threads, || {
        run(&traj, &mut engine, &mut sampler, every_s, args.quiet, &mut pace, &stop)
    })
    .map_err(anyhow::Error::from)
    .and_then(|replayed| replayed)
    .with_context(|| format!("replaying {source}"));
    let figures = match live {
        Some((server, scene)) => {
            if replayed.is_ok() && !stop.is_interrupted() {
                // The plane of the whole log, whatever multiple of poses the last one was.
                server.send(&Vec::from_iter(scene.plane(&engine)?));
                if args.hold {
                    eprintln!("loops replay: the log is over; serving until Ctrl-C");
                }
                server.hold(args.hold, &stop);
            }
            server.close();
            replayed?
        }
        None => replayed?,
    };
    figures.print(&source, &engine);
    Ok(if figures.interrupted || stop.is_interrupted() { guard::INTERRUPTED } else { 0 })
}

/// Where the keyframes go besides stdout, and how fast.
#[derive(Debug)]
struct Pace<'a> {
    /// Play at this many times the log's clock, or as fast as it goes.
    speed: Option<f64>,
    /// The server and the scene whose messages it sends.
    live: Option<&'a mut (LiveServer, loops_io::LiveScene)>,
}

impl Pace<'_> {
    /// Waits until the keyframe at `t_s` is due (the log's first pose at `t0_s` is due at
    /// `start`); `false` when `stop` came first.
    fn wait(&self, start: Instant, t0_s: f64, t_s: f64, stop: &Interrupt) -> bool {
        let Some(speed) = self.speed else { return !stop.is_interrupted() };
        let due = start + Duration::from_secs_f64(((t_s - t0_s) / speed).max(0.0));
        while !stop.is_interrupted() {
            let now = Instant::now();
            if now >= due {
                return true;
            }
            std::thread::sleep((due - now).min(Duration::from_millis(20)));
        }
        false
    }
}

/// What the replay measured.
#[derive(Debug)]
struct Figures {
    /// Latency of each keyframe (push + offer).
    latencies: Vec<Duration>,
    poses: usize,
    candidates: usize,
    first_candidates: usize,
    improvements: usize,
    wall: Duration,
    interrupted: bool,
}

/// Pushes the poses of `traj` keyframe by keyframe, offering each update to `sampler` and
/// printing its line (unless `quiet`), until the end or `stop`.
fn run(
    traj: &Trajectory,
    engine: &mut OnlineLoops,
    sampler: &mut OnlineSampler,
    every_s: f64,
    quiet: bool,
    pace: &mut Pace<'_>,
    stop: &Interrupt,
) -> Result<Figures> {
    let times = traj.timestamps_s();
    let dim = traj.dim();
    let batches = keyframes(times, every_s);
    let mut figures = Figures {
        latencies: Vec::with_capacity(batches.len()),
        poses: 0,
        candidates: 0,
        first_candidates: 0,
        improvements: 0,
        wall: Duration::ZERO,
        interrupted: false,
    };
    if let Some((server, _)) = pace.live.as_deref()
        && !server.wait_for_client(stop)
    {
        figures.interrupted = true;
        return Ok(figures);
    }
    let mut stdout = std::io::stdout().lock();
    let start = Instant::now();
    let mut next = 0;
    for &keyframe in &batches {
        if !pace.wait(start, times[0], times[keyframe], stop) {
            figures.interrupted = true;
            break;
        }
        let coords = &traj.coords()[next * dim..(keyframe + 1) * dim];
        let began = Instant::now();
        let update = engine.push_many(&times[next..=keyframe], coords)?;
        let candidates = sampler.offer(engine, &update)?;
        let latency = began.elapsed();
        figures.latencies.push(latency);
        figures.poses = keyframe + 1;
        figures.candidates += candidates.len();
        figures.first_candidates += candidates.iter().filter(|c| c.first).count();
        figures.improvements += candidates.iter().filter(|c| c.improves.is_some()).count();
        if let Some((server, scene)) = pace.live.as_deref_mut() {
            server.send(&scene.keyframe(engine, &update, &candidates)?);
        }
        if !quiet {
            let line = KeyframeLine::new(&update, times[keyframe], latency, &candidates);
            serde_json::to_writer(&mut stdout, &line)?;
            stdout.write_all(b"\n")?;
        }
        next = keyframe + 1;
    }
    stdout.flush()?;
    figures.wall = start.elapsed();
    Ok(figures)
}

impl Figures {
    /// The figures on stderr.
    fn print(&self, source: &str, engine: &OnlineLoops) {
        let mut sorted = self.latencies.clone();
        sorted.sort_unstable();
        let percentile = |p: f64| -> Duration {
            if sorted.is_empty() {
                return Duration::ZERO;
            }
            // Nearest rank.
            let rank = ((p / 100.0) * sorted.len() as f64).ceil().max(1.0) as usize;
            sorted[rank.min(sorted.len()) - 1]
        };
        let busy: Duration = self.latencies.iter().sum();
        let rate = if busy.is_zero() { 0.0 } else { self.poses as f64 / busy.as_secs_f64() };
        let (components, runs) =
            engine.components().fold((0_usize, 0_usize), |(n, runs), (_, c)| (n + 1, runs + c.run_count));
        let how = if self.interrupted { "interrupted after" } else { "replayed" };
        eprintln!(
            "loops replay: {how} {} poses of {source} in {} keyframes: {} candidates ({} at a component's first \
             appearance, {} improving one at its closest approach), {components} live components, {runs} runs",
            self.poses,
            self.latencies.len(),
            self.candidates,
            self.first_candidates,
            self.improvements,
        );
        eprintln!(
            "latency per keyframe (push + offer): p50 {}, p99 {}, max {}; {} poses/s pushed ({:.3} s busy, {:.3} s \
             with output)",
            micros(percentile(50.0)),
            micros(percentile(99.0)),
            micros(sorted.last().copied().unwrap_or_default()),
            rate.round(),
            busy.as_secs_f64(),
            self.wall.as_secs_f64(),
        );
        if let Some(peak) = peak_resident_mb() {
            eprintln!("peak resident memory of the process: {peak:.1} MB (the log read in, and the engine)");
        }
    }
}

/// A duration in µs, or ms above 10 ms.
fn micros(duration: Duration) -> String {
    let us = duration.as_secs_f64() * 1e6;
    if us >= 10_000.0 { format!("{:.1} ms", us / 1e3) } else { format!("{us:.1} µs") }
}

/// The process's peak resident set (Linux `VmHWM`), MB; `None` elsewhere.
fn peak_resident_mb() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|line| line.starts_with("VmHWM:"))?;
    let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb / 1024.0)
}

#[cfg(test)]
mod tests {
    use super::keyframes;

    #[test]
    fn keyframes_every_second_end_with_the_last_pose() {
        let times = [0.0, 0.4, 0.9, 1.0, 1.5, 2.2, 2.3];
        assert_eq!(keyframes(&times, 0.0), vec![0, 1, 2, 3, 4, 5, 6]);
        assert_eq!(keyframes(&times, 1.0), vec![0, 3, 5, 6]);
        assert_eq!(keyframes(&times, 10.0), vec![0, 6]);
        assert_eq!(keyframes(&[], 1.0), Vec::<usize>::new());
        assert_eq!(keyframes(&[5.0], 1.0), vec![0]);
    }
}
