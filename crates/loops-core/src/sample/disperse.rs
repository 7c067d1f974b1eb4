//! The dispersed σ_ρ on detection clusters: a cluster's samples spread evenly over its rows, each
//! the row's best-scored detection; and the closest-first sampler, which takes the cluster's
//! best detection first and spreads the rest the same way. (On exact components both are keyed
//! draws: `keyed`.)

use std::collections::BTreeSet;

use rand::{Rng, RngExt};

/// Evenly spaced picks along a cluster: `q` positions stratified over its rows (distinct t,
/// time order), each the best-scored detection of its row (the middle one without scores);
/// beyond one per row, the rest evenly over the remaining detections.
pub(super) fn disperse_detections<R: Rng + ?Sized>(
    members: &[u32],
    q: u64,
    xs: &[f64],
    scores: Option<&[f64]>,
    first: bool,
    rng: &mut R,
) -> Vec<u32> {
    let mut rows = vec![0usize];
    rows.extend((1..members.len()).filter(|&p| xs[members[p] as usize] != xs[members[p - 1] as usize]));
    rows.push(members.len());
    let row_count = rows.len() - 1;
    let preferred = |r: usize| -> usize {
        let (a, b) = (rows[r], rows[r + 1]);
        match scores {
            Some(s) => {
                (a..b).fold(a, |best, p| if s[members[p] as usize] > s[members[best] as usize] { p } else { best })
            }
            None => a + (b - a - 1) / 2,
        }
    };
    let positions = if first {
        // The best-scored detection of the cluster (the first of equals), or without scores
        // the middle one of the middle row.
        let best = match scores {
            Some(s) => (0..row_count).fold(0, |best, r| {
                if s[members[preferred(r)] as usize] > s[members[preferred(best)] as usize] { r } else { best }
            }),
            None => row_count / 2,
        };
        first_then_spread(row_count, members.len(), q, best, preferred, rng)
    } else {
        spread(row_count, members.len(), q, preferred, rng)
    };
    positions.into_iter().map(|p| members[p as usize]).collect()
}

/// `q` of `total` items, the `first` row's preferred item among them: with `q` at most the rows,
/// that item and `q − 1` others stratified over the other rows (as [`spread`]); beyond, as
/// [`spread`] (every row's preferred item, then the rest evenly).
fn first_then_spread<R: Rng + ?Sized>(
    rows: usize,
    total: usize,
    q: u64,
    first: usize,
    preferred: impl Fn(usize) -> usize,
    rng: &mut R,
) -> Vec<u64> {
    if q == 0 {
        return Vec::new();
    }
    if q as usize > rows {
        return spread(rows, total, q, preferred, rng);
    }
    let others: Vec<usize> = (0..rows).filter(|&r| r != first).collect();
    let mut picked = spread(others.len(), total, q - 1, |k| preferred(others[k]), rng);
    picked.push(preferred(first) as u64);
    picked
}

/// `q` of `total` items: stratified over `rows` rows (the `preferred` item of each picked row),
/// and beyond one per row, the rest evenly spaced over the items not yet picked.
fn spread<R: Rng + ?Sized>(
    rows: usize,
    total: usize,
    q: u64,
    preferred: impl Fn(usize) -> usize,
    rng: &mut R,
) -> Vec<u64> {
    let q = q as usize;
    let offset = rng.random::<f64>();
    if q <= rows {
        return (0..q)
            .map(|k| {
                let r = (((k as f64 + offset) * rows as f64 / q as f64) as usize).min(rows - 1);
                preferred(r) as u64
            })
            .collect();
    }
    let mut chosen: BTreeSet<u64> = (0..rows).map(|r| preferred(r) as u64).collect();
    let extra = q - rows;
    for k in 0..extra {
        let mut p = (((k as f64 + offset) * total as f64 / extra as f64) as usize).min(total - 1) as u64;
        while chosen.contains(&p) {
            p = (p + 1) % total as u64;
        }
        chosen.insert(p);
    }
    chosen.into_iter().collect()
}

#[cfg(test)]
mod tests {
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    use super::*;

    #[test]
    fn first_then_spread_keeps_the_first() {
        let mut rng = ChaCha8Rng::seed_from_u64(2);
        for q in 0..=12 {
            let picks = first_then_spread(10, 40, q, 7, |r| 4 * r + 1, &mut rng);
            assert_eq!(picks.len(), q as usize, "{picks:?}");
            let distinct: BTreeSet<u64> = picks.iter().copied().collect();
            assert_eq!(distinct.len(), picks.len(), "{picks:?}");
            if q > 0 {
                assert!(picks.contains(&29), "q {q}: {picks:?}");
            }
            if (1..=10).contains(&q) {
                // One per row at most: every pick is a row's preferred item.
                assert!(picks.iter().all(|p| p % 4 == 1), "{picks:?}");
            }
        }
    }

    #[test]
    fn spread_is_even() {
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let picks = spread(100, 100, 10, |r| r, &mut rng);
        assert_eq!(picks.len(), 10);
        assert!(picks.windows(2).all(|w| w[1] - w[0] == 10), "{picks:?}");
        let picks = spread(3, 10, 6, |r| 3 * r, &mut rng);
        assert_eq!(picks.len(), 6);
        assert!([0, 3, 6].iter().all(|p| picks.contains(p)));
    }
}
