//! [`Shared`]: the value of a class whose methods change it, used by one Python thread at a
//! time.

use std::collections::BTreeSet;
use std::ops::{Deref, DerefMut};
use std::sync::{Condvar, Mutex, MutexGuard, PoisonError};

use pyo3::prelude::*;

use crate::SIGNAL_POLL;

/// The value of a class whose methods change it (`OnlineLoops`, `OnlineSampler`, `KeyedDraw`),
/// shared by the Python threads that hold the object: each method call holds it from start to
/// end, so calls from several threads run one after another, each whole, in the order they
/// asked for it (a ticket each, first come first served: a thread that calls without a pause
/// cannot keep another waiting for ever). A call that finds it held by another thread (which
/// may be computing without the GIL) waits without the GIL, so that the other call can finish,
/// and lets Python run its signal handlers every 50 ms meanwhile: Ctrl-C raises
/// `KeyboardInterrupt` in the waiting call, which gives up its turn.
///
/// A method must not call back into a method of the same object (it would wait for itself);
/// none does. Two objects are held together only by `OnlineSampler.offer` (the sampler, then
/// the engine), in that order always, so no two calls wait for each other.
///
/// Written here rather than taken from a crate: the wait must give up the GIL and come back to
/// Python's signal handlers, which a lock crate's blocking wait does not.
pub(crate) struct Shared<T> {
    value: Mutex<T>,
    /// Whose turn it is.
    queue: Mutex<Queue>,
    /// Notified whenever the turn moves.
    turn: Condvar,
}

/// The tickets of the calls of a [`Shared`].
#[derive(Debug, Default)]
struct Queue {
    /// The next ticket to give.
    next: u64,
    /// The ticket whose call holds the value, or may take it now.
    serving: u64,
    /// Tickets of calls that stopped waiting (interrupted) before their turn.
    left: BTreeSet<u64>,
}

impl Queue {
    /// The turn moves to the next ticket whose call still waits.
    fn advance(&mut self) {
        self.serving += 1;
        while self.left.remove(&self.serving) {
            self.serving += 1;
        }
    }
}

/// The value of a [`Shared`], held by this call until dropped.
pub(crate) struct Held<'a, T> {
    // Dropped first (fields drop in order): the value is released, then the turn moves.
    guard: MutexGuard<'a, T>,
    _release: Release<'a>,
}

/// Gives the turn of a [`Shared`] to the next call.
struct Release<'a> {
    queue: &'a Mutex<Queue>,
    turn: &'a Condvar,
}

impl Drop for Release<'_> {
    fn drop(&mut self) {
        self.queue.lock().unwrap_or_else(PoisonError::into_inner).advance();
        self.turn.notify_all();
    }
}

impl<T: Send> Shared<T> {
    pub(crate) fn new(value: T) -> Self {
        Self { value: Mutex::new(value), queue: Mutex::new(Queue::default()), turn: Condvar::new() }
    }

    /// The value, once the calls that asked for it before this one are done.
    ///
    /// # Errors
    /// The exception of a Python signal handler (Ctrl-C: `KeyboardInterrupt`) that ran while
    /// waiting; the call gives up its turn then.
    pub(crate) fn lock(&self, py: Python<'_>) -> PyResult<Held<'_, T>> {
        let queue = || self.queue.lock().unwrap_or_else(PoisonError::into_inner);
        let ticket = {
            let mut q = queue();
            q.next += 1;
            q.next - 1
        };
        let mut mine = queue().serving == ticket;
        while !mine {
            mine = py.detach(|| {
                let q = queue();
                if q.serving == ticket {
                    return true;
                }
                // Woken when the turn moves, or after SIGNAL_POLL to look at the signals.
                let (q, _) = self.turn.wait_timeout(q, SIGNAL_POLL).unwrap_or_else(PoisonError::into_inner);
                q.serving == ticket
            });
            if !mine && let Err(interrupted) = py.check_signals() {
                let mut q = queue();
                if q.serving == ticket {
                    q.advance();
                    drop(q);
                    self.turn.notify_all();
                } else {
                    q.left.insert(ticket);
                }
                return Err(interrupted);
            }
        }
        // The call before released the value before the turn moved. The calls that hold it
        // catch the engine's panics; a lock poisoned all the same holds the value as pyo3's own
        // borrow flag would hand it out.
        let guard = self.value.lock().unwrap_or_else(PoisonError::into_inner);
        Ok(Held { guard, _release: Release { queue: &self.queue, turn: &self.turn } })
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
