//! `find_loops` on the urban drive: exact components with areas, holes and closest pairs, and
//! loop duration τ, on one thread and on every core.

use criterion::{Criterion, criterion_group, criterion_main};
use loops_core::{Euclidean, Scale, Selection, Side, find_loops, with_threads};
use std::hint::black_box;

fn bench_find_loops(c: &mut Criterion) {
    let mut group = c.benchmark_group("find_loops");
    group.sample_size(10);
    for hours in [0.5, 2.1] {
        let traj = loops_benches::urban_drive(hours);
        for threads in [1, 2] {
            group.bench_function(format!("urban_{hours}h_{}poses_gamma40_threads{threads}", traj.len()), |b| {
                b.iter(|| {
                    with_threads(Some(threads), || {
                        let loops = find_loops(black_box(&traj), &Euclidean, 40.0).expect("valid input");
                        let tau = loops.loop_duration(Selection::All, Side::Both, Scale::Seconds).expect("all");
                        black_box((loops.components().len(), tau[0]))
                    })
                    .expect("thread pool")
                });
            });
        }
    }
    group.finish();
}

criterion_group!(benches, bench_find_loops);
criterion_main!(benches);
