//! The online engine: latency of a push, and of a push with the online sampler's
//! offer, after most of a drive is in (the cost of a pose grows with what is near it, not with
//! the drive's length). On the reference 2.1 h urban drive and on the 10⁶-pose district drive.
//! `benches/examples/online_latency.rs` prints the percentiles per push.

use criterion::{BatchSize, Criterion, criterion_group, criterion_main};
use loops_core::{
    MetricSpec, Separation, Trajectory,
    online::{Cap, OnlineLoops, OnlineSampler, OnlineSamplerOptions},
};
use std::hint::black_box;

/// Poses timed per iteration, pushed after all the others.
const TAIL: usize = 1_000;

fn bench_online(c: &mut Criterion) {
    let gamma = 40.0;
    let mut group = c.benchmark_group("online");
    group.sample_size(10);
    for (name, traj) in
        [("urban_2.1h", loops_benches::urban_drive(2.1)), ("district_1e6", loops_benches::district_drive_1e6())]
    {
        let head = traj.len() - TAIL;
        let mut online = OnlineLoops::new(MetricSpec::Euclidean, traj.dim(), gamma).expect("valid gamma");
        online.push_many(&traj.timestamps_s()[..head], &traj.coords()[..head * traj.dim()]).expect("valid poses");
        let options = OnlineSamplerOptions {
            rate: 0.05,
            cap: Cap::PerMinute(6.0),
            separation: Separation::for_gamma(gamma),
            ..OnlineSamplerOptions::default()
        };
        group.bench_function(format!("{name}_{}poses_push_{TAIL}", traj.len()), |b| {
            b.iter_batched(
                || online.clone(),
                |mut engine| push_tail(&mut engine, None, &traj, head),
                BatchSize::PerIteration,
            )
        });
        group.bench_function(format!("{name}_{}poses_push_and_offer_{TAIL}", traj.len()), |b| {
            b.iter_batched(
                || (online.clone(), OnlineSampler::new(options).expect("valid options")),
                |(mut engine, mut sampler)| push_tail(&mut engine, Some(&mut sampler), &traj, head),
                BatchSize::PerIteration,
            )
        });
    }
    group.finish();
}

/// Pushes the poses from `head` on one at a time, offering each update to `sampler`.
fn push_tail(online: &mut OnlineLoops, mut sampler: Option<&mut OnlineSampler>, traj: &Trajectory, head: usize) {
    let mut candidates = 0;
    for k in head..traj.len() {
        let update = online.push(traj.timestamps_s()[k], traj.point(k)).expect("valid pose");
        if let Some(sampler) = sampler.as_deref_mut() {
            candidates += sampler.offer(online, &update).expect("the last push, offered once").len();
        }
        black_box(&update);
    }
    black_box(candidates);
}

criterion_group!(benches, bench_online);
criterion_main!(benches);
