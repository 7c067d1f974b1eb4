//! Fallible allocation of the big buffers: a result too big for memory becomes
//! [`Error::OutOfMemory`] naming what it was for and its size, instead of aborting the process
//! (and a Python interpreter with it).
//!
//! The buffers that grow with the input or the answer go through here (time cells, path
//! lengths, the ball hierarchy, runs, labels, components, samples, images, a fleet's sessions);
//! small, bounded buffers allocate as usual.

use crate::error::{Error, Result};

/// Makes room for `additional` more elements in `vec` (amortised, as `Vec::reserve`).
///
/// # Errors
/// [`Error::OutOfMemory`] naming `what` and the size of the whole buffer after growth.
pub(crate) fn try_reserve<T>(vec: &mut Vec<T>, additional: usize, what: &'static str) -> Result<()> {
    vec.try_reserve(additional).map_err(|_| out_of_memory::<T>(vec.len().saturating_add(additional), what))
}

/// An empty vector with room for `capacity` elements.
///
/// # Errors
/// As [`try_reserve`].
pub(crate) fn try_with_capacity<T>(capacity: usize, what: &'static str) -> Result<Vec<T>> {
    let mut vec = Vec::new();
    vec.try_reserve_exact(capacity).map_err(|_| out_of_memory::<T>(capacity, what))?;
    Ok(vec)
}

/// `len` copies of `value`, allocated fallibly.
///
/// # Errors
/// As [`try_reserve`].
pub(crate) fn try_filled<T: Clone>(len: usize, value: T, what: &'static str) -> Result<Vec<T>> {
    let mut vec = try_with_capacity(len, what)?;
    vec.resize(len, value);
    Ok(vec)
}

/// A copy of `items`, allocated fallibly.
///
/// # Errors
/// As [`try_reserve`].
pub(crate) fn try_copy<T: Clone>(items: &[T], what: &'static str) -> Result<Vec<T>> {
    let mut vec = try_with_capacity(items.len(), what)?;
    vec.extend_from_slice(items);
    Ok(vec)
}

/// [`try_copy`] with the copy (and the first touch of its pages) cut among the threads of the
/// current rayon pool.
///
/// # Errors
/// As [`try_reserve`].
pub(crate) fn try_copy_parallel<T: Copy + Send + Sync>(items: &[T], what: &'static str) -> Result<Vec<T>> {
    use rayon::prelude::*;
    let mut vec = try_with_capacity(items.len(), what)?;
    vec.par_extend(items.par_iter().copied());
    Ok(vec)
}

/// Collects an iterator of known length into a vector allocated fallibly.
///
/// # Errors
/// As [`try_reserve`].
pub(crate) fn try_collect<T>(items: impl ExactSizeIterator<Item = T>, what: &'static str) -> Result<Vec<T>> {
    let mut vec = try_with_capacity(items.len(), what)?;
    vec.extend(items);
    Ok(vec)
}

fn out_of_memory<T>(elements: usize, what: &'static str) -> Error {
    let bytes = (elements as u128 * size_of::<T>() as u128).min(u64::MAX as u128) as u64;
    Error::OutOfMemory { what, bytes }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_read_as_people_write_them() {
        use crate::error::size_text;
        assert_eq!(size_text(812), "812 bytes");
        assert_eq!(size_text(3 * 1024 * 1024 + 100 * 1024), "3.1 MiB");
        assert_eq!(size_text(u64::MAX), "16.0 EiB");
    }

    #[test]
    fn an_impossible_buffer_is_an_error_naming_its_size() {
        // Half the address space: refused by the allocator without touching memory.
        let error = try_with_capacity::<u64>(usize::MAX / 16, "the test buffer").unwrap_err();
        assert_eq!(error, Error::OutOfMemory { what: "the test buffer", bytes: (usize::MAX / 16 * 8) as u64 });
        assert!(error.to_string().starts_with("out of memory: 8.0 EiB ("), "{error}");
        assert!(error.to_string().contains(" bytes) for the test buffer could not be allocated;"), "{error}");
        let mut vec = vec![1_u8];
        assert!(try_reserve(&mut vec, usize::MAX, "more").is_err());
        assert_eq!(vec, [1]);
        assert_eq!(try_filled(3, 7_u32, "three").unwrap(), [7, 7, 7]);
    }
}
