//! `OnlineSampler` (loop-closure candidates per keyframe) and `Candidate`.

use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict, PyTuple, PyType};

use crate::attached;
use crate::error::{Failure, invalid_parameter};
use crate::py_online::{OnlineLoops, Update};
use crate::py_separation::{Separation, SeparationArg};
use crate::shared::Shared;
use loops_core::online::{Cap, ComponentId, FirstOffer, OnlineSamplerOptions};

/// Picks loop-closure candidates from each :class:`Update` of an :class:`OnlineLoops`, as a
/// front end needs them while the robot drives: σ_ρ online (each component's pairs in the new
/// row drawn at ``rate`` per component per pose), a cap per component (per minute or per metre
/// of travel), a candidate the first time a component appears (P1 online) and the revisit
/// separation. Every random choice is keyed by (seed, pose, component): pushing poses one at a
/// time or in batches gives the same candidates, on every machine.
///
/// Args:
///     rate: σ_ρ, the expected number of candidates per component per pose (0: only the
///         first-appearance candidates); fractions are rounded randomly.
///     cap_per_minute: at most this many candidates per minute per component (a token bucket,
///         full at first); or
///     cap_per_metre: at most this many per metre of travel (the metric's unit) per component.
///         Give at most one.
///     first_on_appearance: P1 online: a candidate (the closest pair) in the first row where a
///         component has a pair to offer.
///     first_offer: where that candidate goes: ``"edge-then-closest"`` (the default: the
///         closest pair at the edge of γ as the component appears, and once the path has left
///         it the closest pair of that first pass, the closest approach, as a second candidate
///         whose :attr:`Candidate.improves` names the first; none when the first was already
///         the closest), ``"edge"`` (the edge candidate only) or ``"closest-approach"`` (only
///         the closest approach, offered at the keyframe after the path leaves it, beyond the
///         cap). A candidate at the closest approach has :attr:`Candidate.k` <
///         :attr:`Candidate.keyframe`.
///     closest_in_row: the first of a row's draws for a component is its closest pair in the
///         row, the others uniform (the default sampler's rule, :data:`DEFAULT_SAMPLER`, per
///         keyframe); ``False``: all uniform (the paper's σ_ρ).
///     separation: only pairs this far apart along the trajectory: ``None`` (every pair), a path
///         length, or a :class:`Separation` (e.g. ``Separation.for_gamma(gamma)``, the
///         revisits of :func:`find_loops`' default).
///     seed: the seed.
///
/// Raises:
///     InvalidParameterError: a rate negative or not finite, a cap not positive and finite,
///         both caps, a negative separation, ``separation="auto"`` (it needs γ: pass
///         ``Separation.for_gamma(gamma)``).
///
/// Example:
///     >>> import numpy as np, inexact_loops as il
///     >>> online = il.OnlineLoops(gamma=1.0, dim=2)
///     >>> sampler = il.OnlineSampler(rate=0.0, separation=il.Separation(path=3.0))
///     >>> angle = np.linspace(0.0, 2.2 * np.pi, 60)
///     >>> for k, a in enumerate(angle):
///     ...     update = online.push(float(k), [2.0 * np.cos(a), 2.0 * np.sin(a)])
///     ...     for c in sampler.offer(online, update):
///     ...         print(c.keyframe, c.j, c.first)
///     50 0 True
///
/// Threads may share a sampler: its calls run one at a time (as :class:`OnlineLoops`'). It
/// pickles with its state (buckets, the components P1 served, the pose it reached): pickled
/// with its :class:`OnlineLoops` (or offered the next update of the engine it followed), the
/// copy gives the candidates the original would; offered an update that does not start where
/// it stopped, it starts afresh.
#[pyclass(frozen, module = "inexact_loops._core")]
#[derive(Debug)]
pub(crate) struct OnlineSampler {
    /// Its options (the sampler's own copy is in `state`).
    options: OnlineSamplerOptions,
    state: Shared<SamplerState>,
}

/// What an `OnlineSampler` changes as updates are offered.
#[derive(Debug)]
struct SamplerState {
    inner: loops_core::online::OnlineSampler,
}

/// A loop-closure candidate: the pair (``j``, ``k``), j < k ≤ keyframe, within γ, to match.
/// Returned by :meth:`OnlineSampler.offer`.
///
/// Args:
///     keyframe: the pose whose push offered it.
///     j: the earlier pose.
///     k: the later pose (``None``: the keyframe; earlier only for a candidate at the closest
///         approach, offered once the pass was over).
///     component: its component's id at the keyframe.
///     distance: δ(x_j, x_k), the metric's unit.
///     first: emitted by the first-appearance rule rather than drawn.
///     improves: for the closest approach of a component's first pass, the pair of the first
///         candidate it improves (offered at the edge of γ); ``None`` otherwise.
///
/// Example:
///     >>> import inexact_loops as il
///     >>> c = il.Candidate(keyframe=12, j=3, component=1, distance=0.25, first=True)
///     >>> c.pair, c
///     ((3, 12), Candidate(keyframe=12, j=3, component=1, distance=0.25, first=True))
#[pyclass(frozen, eq, module = "inexact_loops._core")]
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Candidate {
    pub(crate) inner: loops_core::online::Candidate,
}

impl OnlineSampler {
    fn from_core(inner: loops_core::online::OnlineSampler) -> Self {
        Self { options: *inner.options(), state: Shared::new(SamplerState { inner }) }
    }
}

#[pymethods]
impl OnlineSampler {
    #[new]
    #[pyo3(signature = (*, rate=OnlineSamplerOptions::default().rate, cap_per_minute=None, cap_per_metre=None,
        first_on_appearance=OnlineSamplerOptions::default().first_on_appearance,
        first_offer=OnlineSamplerOptions::default().first_offer.name(),
        closest_in_row=OnlineSamplerOptions::default().closest_in_row, separation=None,
        seed=OnlineSamplerOptions::default().seed))]
    #[pyo3(text_signature = "(*, rate=1.0, cap_per_minute=None, cap_per_metre=None, first_on_appearance=True, \
        first_offer='edge-then-closest', closest_in_row=True, separation=None, seed=0)")]
    #[allow(clippy::too_many_arguments)]
    fn new(
        rate: f64,
        cap_per_minute: Option<f64>,
        cap_per_metre: Option<f64>,
        first_on_appearance: bool,
        first_offer: &str,
        closest_in_row: bool,
        separation: Option<SeparationArg>,
        seed: u64,
    ) -> PyResult<Self> {
        let cap = match (cap_per_minute, cap_per_metre) {
            (None, None) => Cap::None,
            (Some(c), None) => Cap::PerMinute(c),
            (None, Some(c)) => Cap::PerMetre(c),
            (Some(_), Some(_)) => {
                return Err(invalid_parameter("give cap_per_minute or cap_per_metre, not both".to_owned()));
            }
        };
        let separation = match separation {
            None => loops_core::Separation::NONE,
            Some(SeparationArg::Given(separation)) => separation,
            Some(SeparationArg::Auto) => {
                return Err(invalid_parameter(
                    "separation=\"auto\" needs gamma, which the sampler does not know: pass \
                     il.Separation.for_gamma(gamma)"
                        .to_owned(),
                ));
            }
        };
        let first_offer: FirstOffer = first_offer.parse().map_err(Failure::from)?;
        let options =
            OnlineSamplerOptions { rate, cap, first_on_appearance, first_offer, closest_in_row, separation, seed };
        let inner = loops_core::online::OnlineSampler::new(options).map_err(Failure::from)?;
        Ok(Self::from_core(inner))
    }

    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, (Bound<'py, PyBytes>,))> {
        let this = slf.get().state.lock(slf.py())?;
        crate::pickling::reduce(slf.as_any(), "OnlineSampler", &this.inner)
    }

    /// Unpickles the core's saved sampler, checked.
    #[classmethod]
    fn _from_state(cls: &Bound<'_, PyType>, state: &[u8]) -> PyResult<Self> {
        crate::pickling::restoring(cls.py(), "OnlineSampler", || {
            let inner: loops_core::online::OnlineSampler = crate::pickling::restore(cls.py(), "OnlineSampler", state)?;
            Ok(Self::from_core(inner))
        })
    }

    fn __repr__(&self) -> String {
        let o = &self.options;
        let cap = match o.cap {
            Cap::None => String::new(),
            Cap::PerMinute(c) => format!(", cap_per_minute={c}"),
            Cap::PerMetre(c) => format!(", cap_per_metre={c}"),
        };
        format!(
            "OnlineSampler(rate={}{cap}, first_on_appearance={}, first_offer={:?}, closest_in_row={}, \
             separation=Separation(path={:?}, time_s={:?}), seed={})",
            o.rate,
            if o.first_on_appearance { "True" } else { "False" },
            o.first_offer.name(),
            if o.closest_in_row { "True" } else { "False" },
            o.separation.path,
            o.separation.time_s,
            o.seed
        )
    }

    /// The loop-closure candidates that ``update`` made possible, by keyframe, component and
    /// pose. Offer every update of ``online``, in order, once each (a sampler follows one
    /// engine); after a rebuild it starts afresh.
    ///
    /// Args:
    ///     online: the :class:`OnlineLoops` that returned ``update``.
    ///     update: its last push's :class:`Update`.
    ///
    /// Returns:
    ///     list of :class:`Candidate`.
    ///
    /// Raises:
    ///     InvalidParameterError: ``update`` is not ``online``'s last (an older one, another
    ///         engine's, one from before a rebuild, or an unpickled one), or was offered already.
    ///
    /// Example:
    ///     >>> import inexact_loops as il
    ///     >>> online, sampler = il.OnlineLoops(gamma=0.5, dim=1), il.OnlineSampler()
    ///     >>> update = online.push_many([0.0, 1.0, 2.0], [0.0, 0.1, 0.0])
    ///     >>> [c.pair for c in sampler.offer(online, update) if c.first]
    ///     [(0, 1)]
    fn offer(&self, py: Python<'_>, online: &OnlineLoops, update: &Update) -> PyResult<Vec<Candidate>> {
        // The sampler, then the engine: the one order in which two objects are held together.
        let mut this = self.state.lock(py)?;
        let engine = online.engine.lock(py)?;
        // "Each update once, in order" is the core's rule (`loops_core::online::OnlineSampler::offer`).
        let candidates = attached(|| Ok(this.inner.offer(&engine.inner, &update.inner)?))?;
        Ok(candidates.into_iter().map(|inner| Candidate { inner }).collect())
    }

    /// σ_ρ's rate: candidates per component per pose.
    #[getter]
    fn rate(&self) -> f64 {
        self.options.rate
    }

    /// The cap per minute per component, or ``None``.
    #[getter]
    fn cap_per_minute(&self) -> Option<f64> {
        match self.options.cap {
            Cap::PerMinute(c) => Some(c),
            _ => None,
        }
    }

    /// The cap per metre of travel per component, or ``None``.
    #[getter]
    fn cap_per_metre(&self) -> Option<f64> {
        match self.options.cap {
            Cap::PerMetre(c) => Some(c),
            _ => None,
        }
    }

    /// Whether a component's first appearance brings a candidate (P1 online).
    #[getter]
    fn first_on_appearance(&self) -> bool {
        self.options.first_on_appearance
    }

    /// Where that candidate goes: ``"edge-then-closest"``, ``"edge"`` or ``"closest-approach"``.
    #[getter]
    fn first_offer(&self) -> &'static str {
        self.options.first_offer.name()
    }

    /// The separation the candidates keep (:class:`Separation`).
    #[getter]
    fn separation(&self) -> Separation {
        Separation { inner: self.options.separation }
    }

    /// The seed.
    #[getter]
    fn seed(&self) -> u64 {
        self.options.seed
    }
}

#[pymethods]
impl Candidate {
    #[new]
    #[pyo3(signature = (*, keyframe, j, component, distance, first, k=None, improves=None))]
    fn new(
        keyframe: usize,
        j: usize,
        component: ComponentId,
        distance: f64,
        first: bool,
        k: Option<usize>,
        improves: Option<(usize, usize)>,
    ) -> Self {
        let k = k.unwrap_or(keyframe);
        let improves = improves.map(|(a, b)| [a, b]);
        Self { inner: loops_core::online::Candidate { keyframe, pair: [j, k], component, distance, first, improves } }
    }

    /// Pickles as its constructor's keywords.
    fn __getnewargs_ex__<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyTuple>, Bound<'py, PyDict>)> {
        let c = &self.inner;
        let kwargs = PyDict::new(py);
        kwargs.set_item("keyframe", c.keyframe)?;
        kwargs.set_item("j", c.pair[0])?;
        kwargs.set_item("component", c.component)?;
        kwargs.set_item("distance", c.distance)?;
        kwargs.set_item("first", c.first)?;
        kwargs.set_item("k", c.pair[1])?;
        kwargs.set_item("improves", c.improves.map(|[a, b]| (a, b)))?;
        Ok((PyTuple::empty(py), kwargs))
    }

    fn __hash__(&self) -> u64 {
        let c = &self.inner;
        crate::pickling::hash_of(&[
            c.keyframe as u64,
            c.pair[0] as u64,
            c.pair[1] as u64,
            u64::from(c.component),
            c.distance.to_bits(),
        ])
    }

    fn __repr__(&self) -> String {
        let c = &self.inner;
        // `k` only where it is not the keyframe, so the common candidate reads as before.
        let k = if c.pair[1] == c.keyframe { String::new() } else { format!(", k={}", c.pair[1]) };
        let improves = c.improves.map_or(String::new(), |[a, b]| format!(", improves=({a}, {b})"));
        format!(
            "Candidate(keyframe={}, j={}, component={}, distance={:?}, first={}{k}{improves})",
            c.keyframe,
            c.pair[0],
            c.component,
            c.distance,
            if c.first { "True" } else { "False" }
        )
    }

    /// The pose whose push made it possible: the later pose of the pair.
    #[getter]
    fn keyframe(&self) -> usize {
        self.inner.keyframe
    }

    /// The earlier pose of the pair.
    #[getter]
    fn j(&self) -> usize {
        self.inner.pair[0]
    }

    /// The later pose of the pair: the keyframe, but for a candidate at the closest approach
    /// (offered once the pass was over).
    #[getter]
    fn k(&self) -> usize {
        self.inner.pair[1]
    }

    /// The pair ``(j, k)``.
    #[getter]
    fn pair(&self) -> (usize, usize) {
        (self.inner.pair[0], self.inner.pair[1])
    }

    /// Its component's id at the keyframe.
    #[getter]
    fn component(&self) -> ComponentId {
        self.inner.component
    }

    /// δ(x_j, x_k), the metric's unit.
    #[getter]
    fn distance(&self) -> f64 {
        self.inner.distance
    }

    /// Whether the first-appearance rule (P1 online) emitted it, rather than a draw.
    #[getter]
    fn first(&self) -> bool {
        self.inner.first
    }

    /// For the closest approach that improves a component's first candidate (offered at the
    /// edge of γ, ``first_offer="edge-then-closest"``): that candidate's pair ``(j, k)``; else
    /// ``None``.
    #[getter]
    fn improves(&self) -> Option<(usize, usize)> {
        self.inner.improves.map(|[a, b]| (a, b))
    }
}
