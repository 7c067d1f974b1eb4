//! [`Shared`]: the value of a class whose methods change it, used by one Python thread at a
//! time.

use std::ops::{Deref, DerefMut};
use std::sync::{Condvar, Mutex, MutexGuard, PoisonError, TryLockError};

use pyo3::prelude::*;

use crate::SIGNAL_POLL;

/// The value of a class whose methods change it (`OnlineLoops`, `OnlineSampler`, `KeyedDraw`),
/// shared by the Python threads that hold the object: each method call holds it from start to
/// end, so calls from several threads run one after another, each whole, in the order they get
/// it. A call that finds it held by another thread (which may be computing without the GIL)
/// waits without the GIL, so that the other call can finish, and lets Python run its signal
/// handlers every 50 ms meanwhile: Ctrl-C raises `KeyboardInterrupt` in the waiting call.
///
/// A method must not call back into a method of the same object (it would wait for itself);
/// none does. Two objects are held together only by `OnlineSampler.offer` (the sampler, then
/// the engine), in that order always, so no two calls wait for each other.
pub(crate) struct Shared<T> {
    value: Mutex<T>,
    /// Taken around "is the value held? then wait", and by a release before it notifies
    /// `released`: a release cannot fall between the look and the wait.
    gate: Mutex<()>,
    /// Notified whenever the value is released.
    released: Condvar,
}

/// The value of a [`Shared`], held by this call until dropped.
pub(crate) struct Held<'a, T> {
    // Dropped first (fields drop in order): the value is released, then the waiters are told.
    guard: MutexGuard<'a, T>,
    _release: Release<'a>,
}

/// Tells the waiters of a [`Shared`] that its value was released.
struct Release<'a> {
    gate: &'a Mutex<()>,
    released: &'a Condvar,
}

impl Drop for Release<'_> {
    fn drop(&mut self) {
        let _gate = self.gate.lock().unwrap_or_else(PoisonError::into_inner);
        self.released.notify_all();
    }
}

impl<T: Send> Shared<T> {
    pub(crate) fn new(value: T) -> Self {
        Self { value: Mutex::new(value), gate: Mutex::new(()), released: Condvar::new() }
    }

    /// The value, once no other call holds it.
    ///
    /// # Errors
    /// The exception of a Python signal handler (Ctrl-C: `KeyboardInterrupt`) that ran while
    /// waiting.
    pub(crate) fn lock(&self, py: Python<'_>) -> PyResult<Held<'_, T>> {
        loop {
            // The calls that hold the value catch the engine's panics; a lock poisoned all the
            // same holds the value as pyo3's own borrow flag would hand it out.
            let guard = match self.value.try_lock() {
                Ok(guard) => Some(guard),
                Err(TryLockError::Poisoned(poisoned)) => Some(poisoned.into_inner()),
                Err(TryLockError::WouldBlock) => None,
            };
            if let Some(guard) = guard {
                return Ok(Held { guard, _release: Release { gate: &self.gate, released: &self.released } });
            }
            py.detach(|| {
                let gate = self.gate.lock().unwrap_or_else(PoisonError::into_inner);
                if matches!(self.value.try_lock(), Err(TryLockError::WouldBlock)) {
                    // Woken by the release, or after SIGNAL_POLL to look at the signals.
                    let _ = self.released.wait_timeout(gate, SIGNAL_POLL);
                }
            });
            py.check_signals()?;
        }
    }
}

impl<T> Deref for Held<'_, T> {
    type Target = T;

    fn deref(&self) -> &T {
        &self.guard
    }
}

impl<T> DerefMut for Held<'_, T> {
    fn deref_mut(&mut self) -> &mut T {
        &mut self.guard
    }
}

impl<T: std::fmt::Debug> std::fmt::Debug for Shared<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.value.try_lock() {
            Ok(value) => f.debug_tuple("Shared").field(&*value).finish(),
            Err(_) => f.write_str("Shared(<in use>)"),
        }
    }
}
