use loops_core::*;
use std::time::Instant;
fn main() -> Result<(), Error> {
    let drive = UrbanDrive::default().generate()?;
    let loops = find_loops(&drive.trajectory, &Euclidean, 40.0)?;
    for rate in [0.01, 0.0306, 0.1] {
        let det = Detections::draw(&loops, SampleSize::Rate(rate), 2)?;
        for threads in [1, 2] {
            for eps in [30.0, 5.0, 1.0] {
                let t = Instant::now();
                let c = with_threads(Some(threads), || cluster_detections(&det, eps))??;
                println!("rate {rate}: {} det, eps {eps}, {threads} thr: {} clusters {:.3} s", det.len(), c.len(), t.elapsed().as_secs_f64());
            }
        }
    }
    // uniform random sparse
    let mut s = 1u64; let mut r = || { s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407); (s >> 11) as f64 / (1u64<<53) as f64 };
    let n = 1_000_000;
    let t: Vec<f64> = (0..n).map(|_| 7560.0 * r()).collect();
    let tp: Vec<f64> = (0..n).map(|_| 7560.0 * r()).collect();
    let det = Detections::new(t, tp)?;
    for eps in [30.0, 5.0, 2.0, 1.0, 0.3] {
        let t = Instant::now();
        let c = cluster_detections(&det, eps)?;
        println!("uniform 1e6 in 7560^2 eps {eps}: {} clusters {:.3} s", c.len(), t.elapsed().as_secs_f64());
    }
    Ok(())
}
