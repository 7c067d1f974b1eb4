//! A robot that parks twice at one place against one that parks once (10⁵ poses, γ = 40 m,
//! one thread): `find_loops`, the same with the default separation, and the online engine's
//! last 1,000 pushes (poses of the second stop). Two stops 10⁻¹⁴ m apart once cost n² (every row
//! of one stop ranked every pose of the other); they now cost about what one stop costs per run.
//! `benches/examples/two_stops.rs` prints the figures at 10⁴ to 10⁶ poses with the fleet engine.

use criterion::{BatchSize, Criterion, criterion_group, criterion_main};
use loops_core::{Euclidean, MetricSpec, Separation, find_loops_separated, online::OnlineLoops, with_threads};
use std::hint::black_box;

const POSES: usize = 100_000;
const GAMMA_M: f64 = 40.0;
/// Poses pushed per iteration, after all the others.
const TAIL: usize = 1_000;

fn bench_two_stops(c: &mut Criterion) {
    let mut group = c.benchmark_group("two_stops");
    group.sample_size(10);
    for (name, offset_m) in [("one_stop", None), ("two_stops_1e-14m", Some(1e-14)), ("two_stops_0.5m", Some(0.5))] {
        let traj = loops_benches::parked_twice(POSES, offset_m);
        for (kind, separation) in [("find_loops", Separation::NONE), ("separated", Separation::for_gamma(GAMMA_M))] {
            group.bench_function(format!("{name}_{POSES}poses_{kind}"), |b| {
                b.iter(|| {
                    with_threads(Some(1), || {
                        let loops = find_loops_separated(black_box(&traj), &Euclidean, GAMMA_M, separation);
                        loops.expect("valid input").sublevel_set().runs().len()
                    })
                    .expect("thread pool")
                })
            });
        }
        let head = traj.len() - TAIL;
        let mut online = OnlineLoops::new(MetricSpec::Euclidean, traj.dim(), GAMMA_M).expect("valid gamma");
        online.push_many(&traj.timestamps_s()[..head], &traj.coords()[..head * traj.dim()]).expect("valid poses");
        group.bench_function(format!("{name}_{POSES}poses_online_push_{TAIL}"), |b| {
            b.iter_batched(
                || online.clone(),
                |mut engine| {
                    for k in head..traj.len() {
                        black_box(engine.push(traj.timestamps_s()[k], traj.point(k)).expect("valid pose"));
                    }
                },
                BatchSize::PerIteration,
            )
        });
    }
    group.finish();
}

criterion_group!(benches, bench_two_stops);
criterion_main!(benches);
