//! [`Interrupt`]: a request, from another thread, to stop a long computation.

use std::cell::RefCell;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use crate::error::{Error, Result};

/// A request to stop the engine's long computations early: a flag shared between the thread
/// that computes and the one that may ask it to stop (a Ctrl-C handler, Python's signal check,
/// a user interface's Cancel button).
///
/// Install it on the computing thread with [`run`](Self::run); the engine's long calls made
/// inside ([`find_loops`](crate::find_loops) and the sublevel set, the loop components, the
/// samplers, the drawn detections, the ε-graph clusters, the plane images) look at it every few
/// rows or items (a relaxed atomic load, nothing measurable) and return [`Error::Interrupted`]
/// soon after [`interrupt`](Self::interrupt) is called: within milliseconds, the time of one
/// block of rows. Without an installed token nothing can interrupt them. Work on the threads of
/// [`with_threads`](crate::with_threads) and of rayon's pools started inside `run` sees the
/// token too.
///
/// # Examples
/// ```
/// use loops_core::{Error, Euclidean, Interrupt, UrbanDrive, find_loops};
/// let drive = UrbanDrive { duration_s: 600.0, ..UrbanDrive::default() }.generate()?;
/// let stop = Interrupt::new();
/// // Another thread (here: this one, before the call) asks the computation to stop.
/// stop.interrupt();
/// let result = stop.run(|| find_loops(&drive.trajectory, &Euclidean, 40.0));
/// assert_eq!(result, Err(Error::Interrupted));
/// // Outside `run`, the token has no effect.
/// assert!(find_loops(&drive.trajectory, &Euclidean, 40.0).is_ok());
/// # Ok::<(), loops_core::Error>(())
/// ```
#[derive(Debug, Clone, Default)]
pub struct Interrupt {
    flag: Arc<AtomicBool>,
}

thread_local! {
    static CURRENT: RefCell<Option<Interrupt>> = const { RefCell::new(None) };
}

impl Interrupt {
    /// A token that has not been interrupted.
    pub fn new() -> Self {
        Self::default()
    }

    /// Asks every computation that watches this token to stop. Safe to call from any thread,
    /// any number of times; it cannot be undone.
    pub fn interrupt(&self) {
        self.flag.store(true, Ordering::Relaxed);
    }

    /// Whether [`interrupt`](Self::interrupt) was called.
    pub fn is_interrupted(&self) -> bool {
        self.flag.load(Ordering::Relaxed)
    }

    /// `Ok` until [`interrupt`](Self::interrupt) is called.
    ///
    /// # Errors
    /// [`Error::Interrupted`] after it.
    pub fn check(&self) -> Result<()> {
        if self.is_interrupted() { Err(Error::Interrupted) } else { Ok(()) }
    }

    /// Runs `f` with this token installed on the current thread: the engine's calls inside `f`
    /// stop with [`Error::Interrupted`] once it is interrupted. Tokens nest; the previous one is
    /// back when `f` returns or panics.
    pub fn run<R>(&self, f: impl FnOnce() -> R) -> R {
        struct Restore(Option<Interrupt>);
        impl Drop for Restore {
            fn drop(&mut self) {
                let previous = self.0.take();
                CURRENT.with(|current| *current.borrow_mut() = previous);
            }
        }
        let previous = CURRENT.with(|current| current.borrow_mut().replace(self.clone()));
        let _restore = Restore(previous);
        f()
    }

    /// The token installed on this thread by [`run`](Self::run), or one that is never
    /// interrupted. The engine's entry points take it once, on the calling thread, and hand it
    /// to their worker threads.
    pub fn current() -> Self {
        CURRENT.with(|current| current.borrow().clone()).unwrap_or_default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tokens_nest_and_come_back() {
        let (outer, inner) = (Interrupt::new(), Interrupt::new());
        inner.interrupt();
        assert!(Interrupt::current().check().is_ok());
        outer.run(|| {
            assert!(Interrupt::current().check().is_ok());
            inner.run(|| assert_eq!(Interrupt::current().check(), Err(Error::Interrupted)));
            assert!(Interrupt::current().check().is_ok());
            let caught = std::panic::catch_unwind(|| inner.run(|| panic!("inside")));
            assert!(caught.is_err());
            assert!(!Interrupt::current().is_interrupted(), "a panic restores the outer token");
        });
        assert!(!Interrupt::current().is_interrupted());
    }
}
