//! Online loops: S_γ, its loop components and τ kept up to date while poses arrive one at a time
//! (or in batches), and samplers that pick loop-closure candidates per keyframe.
//!
//! Pose n adds row n of the plane's lower half: the pairs (j, n), j ≤ n, with
//! δ(x_j, x_n) ≤ γ. By symmetry it is column n of the upper half that [`find_loops`] scans by
//! rows, so the components, their counts and holes are the same. The row's runs come from the
//! same arc-length skipping and ball hierarchy as the batch (the hierarchy grows by leaves of 16
//! poses, a forest of perfect binary trees like the digits of a binary counter), and are joined
//! to the previous row's runs by union-find: components only grow and merge.
//!
//! [`find_loops`]: crate::find_loops

mod engine;
mod sampler;

pub use engine::{ComponentId, Merge, OnlineComponent, OnlineLoops, PushStamp, RowRun, Update};
pub use sampler::{Candidate, Cap, FirstOffer, OnlineSampler, OnlineSamplerOptions};
