mod support;
use loops_core::{Euclidean, find_loops};
use proptest::strategy::{Strategy, ValueTree};
use proptest::test_runner::TestRunner;
#[test]
fn stats() {
    let mut runner = TestRunner::new(support::config(256, 0x5EED_0002));
    for (name, strat) in [("float", support::float_case(250).boxed()), ("lattice", support::lattice_case(250).boxed())] {
        let (mut holes, mut broken, mut multi_trivial, mut nontrivial, mut ntcomps, mut n_sum, mut nt_holes, mut reconnect) = (0, 0, 0, 0, 0, 0, 0, 0);
        for _ in 0..256 {
            let case = strat.new_tree(&mut runner).unwrap().current();
            let loops = find_loops(&case.traj, &Euclidean, case.gamma).unwrap();
            n_sum += case.traj.len();
            let c = loops.components();
            if c.iter().any(|c| c.holes > 0) { holes += 1; }
            if c.iter().any(|c| !c.trivial && c.holes > 0) { nt_holes += 1; }
            let triv = c.iter().filter(|c| c.trivial).count();
            if !loops.warnings().is_empty() { broken += 1;
                if let [loops_core::Warning::DiagonalBroken { gaps, trivial_components, .. }] = loops.warnings() { if *trivial_components < gaps + 1 { reconnect += 1; } }
            }
            if triv > 1 { multi_trivial += 1; }
            if c.iter().any(|c| !c.trivial) { nontrivial += 1; }
            ntcomps += c.iter().filter(|c| !c.trivial).count();
        }
        println!("{name}: mean n {} holes {holes} nt_holes {nt_holes} broken {broken} reconnect {reconnect} multi_trivial {multi_trivial} nontrivial {nontrivial} mean ntcomps {}", n_sum / 256, ntcomps / 256);
    }
}
