//! The crate's one union-find: disjoint sets of consecutive ids whose root is always the
//! smallest id of the set.
//!
//! Smallest-id roots make two things cheap that a rank-based union-find does not: numbering the
//! sets by first appearance in one forward pass (a member's root is numbered before it), and
//! running several forests in parallel over disjoint slices of one parent array (each forest
//! only ever points inside its own range of ids). Loop components use both; the ε graph of
//! detections uses one forest over its grid nodes.

/// Union-find over the ids `base..base + parent.len()`, with path halving and the smaller root
/// kept on a join. O(log n) amortised per operation in the worst case, near-constant in practice
/// (the joins of a sweep come in id order, so trees stay shallow).
///
/// The parent slice is borrowed, so disjoint slices of one array can be worked on by different
/// threads; a slice starts as the identity (`parent[k] == base + k`).
pub(crate) struct MinRootForest<'a> {
    parent: &'a mut [u32],
    base: usize,
}

impl<'a> MinRootForest<'a> {
    /// A forest over the ids `base..base + parent.len()`, from the parents in `parent` (the
    /// identity for singletons).
    pub(crate) fn new(parent: &'a mut [u32], base: usize) -> Self {
        debug_assert!(base + parent.len() <= u32::MAX as usize + 1, "ids are u32");
        Self { parent, base }
    }

    /// The root of `x`, halving the path to it.
    pub(crate) fn find(&mut self, mut x: usize) -> usize {
        loop {
            let p = self.parent[x - self.base] as usize;
            if p == x {
                return x;
            }
            let grandparent = self.parent[p - self.base];
            self.parent[x - self.base] = grandparent;
            x = grandparent as usize;
        }
    }

    /// Whether `a` and `b` are in one set.
    pub(crate) fn equiv(&mut self, a: usize, b: usize) -> bool {
        self.find(a) == self.find(b)
    }

    /// Joins the sets of `a` and `b` under the smaller root.
    pub(crate) fn union(&mut self, a: usize, b: usize) {
        let (root_a, root_b) = (self.find(a), self.find(b));
        if root_a != root_b {
            let (keep, join) = (root_a.min(root_b), root_a.max(root_b));
            self.parent[join - self.base] = keep as u32;
        }
    }
}

/// Turns a parent array whose roots are the smallest ids of their sets (as left by
/// [`MinRootForest`] over ids from 0) into set numbers by first appearance, in place, and
/// returns the number of sets.
pub(crate) fn number_sets(parent: &mut [u32]) -> u32 {
    let mut count = 0u32;
    for r in 0..parent.len() {
        let p = parent[r] as usize;
        parent[r] = if p == r {
            count += 1;
            count - 1
        } else {
            // p < r: its slot already holds its set's number.
            parent[p]
        };
    }
    count
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// Random joins against a labelling by repeated relabelling (quadratic, obviously right).
    #[test]
    fn matches_naive_relabelling() {
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        for n in [1usize, 2, 7, 100, 1000] {
            let mut parent: Vec<u32> = (0..n as u32).collect();
            let mut naive: Vec<usize> = (0..n).collect();
            let mut forest = MinRootForest::new(&mut parent, 0);
            for _ in 0..n {
                let (a, b) = (rng.random_range(0..n), rng.random_range(0..n));
                forest.union(a, b);
                let (from, to) = (naive[a].max(naive[b]), naive[a].min(naive[b]));
                naive.iter_mut().filter(|l| **l == from).for_each(|l| *l = to);
                assert!(forest.equiv(a, b));
            }
            for (x, &root) in naive.iter().enumerate() {
                assert_eq!(forest.find(x), root, "root is the smallest member");
            }
            let count = number_sets(&mut parent);
            let mut seen = Vec::new();
            for (&number, &root) in parent.iter().zip(&naive) {
                if !seen.contains(&root) {
                    seen.push(root);
                }
                assert_eq!(number as usize, seen.iter().position(|&r| r == root).unwrap());
            }
            assert_eq!(count as usize, seen.len());
        }
    }

    #[test]
    fn offset_forest_stays_in_its_range() {
        let mut parent: Vec<u32> = (10..20).collect();
        let mut forest = MinRootForest::new(&mut parent, 10);
        forest.union(19, 12);
        forest.union(15, 19);
        assert_eq!(forest.find(15), 12);
        assert!(!forest.equiv(10, 12));
    }
}
