//! Long arrays of numbers in the saved bytes of tiles and sublevel sets, packed: in MessagePack
//! (not human-readable) one `bin` of fixed-width little-endian values, where MessagePack would
//! write each number with its own marker and each struct as an array. Read back from either
//! that or the array of values that tile format versions 2 and 3 wrote, and that
//! human-readable formats (JSON) still write, so saved results of either kind stay readable.
//!
//! Written here: serde packs only arrays of bytes (`serde_bytes`); packing arrays of numbers
//! and of small records is what makes a fleet store's tiles (millions of run bounds and
//! τ shares) cheap to save and read back: a copy instead of a branch per number.
//!
//! Use on a field: `#[serde(with = "crate::packed")]` (a `Vec<T>`), or
//! `#[serde(with = "crate::packed::stretches")]` (a `Vec<(usize, Vec<T>)>`), with `T:` [`Packed`].

use std::marker::PhantomData;

use serde::de::{self, Deserialize, DeserializeOwned, Deserializer, SeqAccess, Visitor};
use serde::ser::{Serialize, Serializer};

/// A value of fixed width in packed form.
pub(crate) trait Packed: Sized + Serialize + DeserializeOwned {
    /// Bytes a value takes.
    const WIDTH: usize;
    /// Appends the value's `WIDTH` bytes.
    fn put(&self, out: &mut Vec<u8>);
    /// The value of `WIDTH` bytes, `None` where they do not make one.
    fn take(bytes: &[u8]) -> Option<Self>;
}

/// The unsigned integers, little-endian.
macro_rules! packed_unsigned {
    ($($int:ty),+) => {$(
        impl Packed for $int {
            const WIDTH: usize = std::mem::size_of::<$int>();
            fn put(&self, out: &mut Vec<u8>) {
                out.extend_from_slice(&self.to_le_bytes());
            }
            fn take(bytes: &[u8]) -> Option<Self> {
                bytes.try_into().ok().map(<$int>::from_le_bytes)
            }
        }
    )+};
}
packed_unsigned!(u32, u64);

/// As a `u64`: the same bytes on every target; refused where it does not fit a `usize`.
impl Packed for usize {
    const WIDTH: usize = u64::WIDTH;
    fn put(&self, out: &mut Vec<u8>) {
        (*self as u64).put(out);
    }
    fn take(bytes: &[u8]) -> Option<Self> {
        u64::take(bytes).and_then(|v| usize::try_from(v).ok())
    }
}

/// Bit for bit (NaN payloads and signed zeros kept), as the `u64` of its bits.
impl Packed for f64 {
    const WIDTH: usize = u64::WIDTH;
    fn put(&self, out: &mut Vec<u8>) {
        self.to_bits().put(out);
    }
    fn take(bytes: &[u8]) -> Option<Self> {
        u64::take(bytes).map(f64::from_bits)
    }
}

impl Packed for bool {
    const WIDTH: usize = 1;
    fn put(&self, out: &mut Vec<u8>) {
        out.push(u8::from(*self));
    }
    fn take(bytes: &[u8]) -> Option<Self> {
        match bytes[0] {
            0 => Some(false),
            1 => Some(true),
            _ => None,
        }
    }
}

impl<T: Packed + Copy, const N: usize> Packed for [T; N]
where
    [T; N]: Serialize + DeserializeOwned,
{
    const WIDTH: usize = N * T::WIDTH;
    fn put(&self, out: &mut Vec<u8>) {
        for v in self {
            v.put(out);
        }
    }
    fn take(bytes: &[u8]) -> Option<Self> {
        let mut values = [T::take(&bytes[..T::WIDTH])?; N];
        for (k, v) in values.iter_mut().enumerate().skip(1) {
            *v = T::take(&bytes[k * T::WIDTH..(k + 1) * T::WIDTH])?;
        }
        Some(values)
    }
}

/// Packs a record of [`Packed`] fields: `packed_record!(Type { field: type, ... })` (every
/// field, in order) implements [`Packed`] for it.
macro_rules! packed_record {
    ($name:ty { $($field:ident: $kind:ty),+ $(,)? }) => {
        impl $crate::packed::Packed for $name {
            const WIDTH: usize = 0 $(+ <$kind as $crate::packed::Packed>::WIDTH)+;
            fn put(&self, out: &mut Vec<u8>) {
                $(<$kind as $crate::packed::Packed>::put(&self.$field, out);)+
            }
            fn take(bytes: &[u8]) -> Option<Self> {
                let mut at = 0;
                $(
                    let width = <$kind as $crate::packed::Packed>::WIDTH;
                    let $field = <$kind as $crate::packed::Packed>::take(&bytes[at..at + width])?;
                    at += width;
                )+
                debug_assert_eq!(at, bytes.len());
                Some(Self { $($field),+ })
            }
        }
    };
}
pub(crate) use packed_record;

/// Serialises `values` packed (or as an array, for human-readable formats).
pub(crate) fn serialize<T: Packed, S: Serializer>(values: &[T], serializer: S) -> Result<S::Ok, S::Error> {
    if serializer.is_human_readable() {
        return values.serialize(serializer);
    }
    let mut out = Vec::with_capacity(values.len() * T::WIDTH);
    for v in values {
        v.put(&mut out);
    }
    serializer.serialize_bytes(&out)
}

/// Reads what [`serialize`] wrote, or an array of values.
pub(crate) fn deserialize<'de, T: Packed, D: Deserializer<'de>>(deserializer: D) -> Result<Vec<T>, D::Error> {
    deserializer.deserialize_any(Values(PhantomData))
}

/// Reads packed values, or an array of them.
struct Values<T>(PhantomData<T>);

impl<'de, T: Packed> Visitor<'de> for Values<T> {
    type Value = Vec<T>;

    fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "packed values of {} bytes, or an array of values", T::WIDTH)
    }

    fn visit_bytes<E: de::Error>(self, bytes: &[u8]) -> Result<Vec<T>, E> {
        if !bytes.len().is_multiple_of(T::WIDTH) {
            return Err(E::custom(format!(
                "{} packed bytes are not a whole number of values of {} bytes",
                bytes.len(),
                T::WIDTH
            )));
        }
        let mut values = Vec::with_capacity(bytes.len() / T::WIDTH);
        for (k, b) in bytes.chunks_exact(T::WIDTH).enumerate() {
            match T::take(b) {
                Some(v) => values.push(v),
                None => return Err(E::custom(format!("packed value {k} ({b:?}) is out of range"))),
            }
        }
        Ok(values)
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Vec<T>, A::Error> {
        let mut values = Vec::with_capacity(seq.size_hint().unwrap_or(0).min(1 << 16));
        while let Some(v) = seq.next_element()? {
            values.push(v);
        }
        Ok(values)
    }
}

/// Values written as [`serialize`] writes them: an element of a packed nest.
struct Out<'a, T>(&'a [T]);

impl<T: Packed> Serialize for Out<'_, T> {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serialize(self.0, serializer)
    }
}

/// Values read as [`deserialize`] reads them: an element of a packed nest.
struct In<T>(Vec<T>);

impl<'de, T: Packed> Deserialize<'de> for In<T> {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        deserialize(deserializer).map(In)
    }
}

/// A `Vec<(usize, Vec<T>)>` (offsets with stretches of values), each stretch packed.
pub(crate) mod stretches {
    use super::*;

    pub(crate) fn serialize<T: Packed, S: Serializer>(
        stretches: &[(usize, Vec<T>)],
        serializer: S,
    ) -> Result<S::Ok, S::Error> {
        serializer.collect_seq(stretches.iter().map(|(offset, values)| (offset, Out(values))))
    }

    pub(crate) fn deserialize<'de, T: Packed, D: Deserializer<'de>>(
        deserializer: D,
    ) -> Result<Vec<(usize, Vec<T>)>, D::Error> {
        let read: Vec<(usize, In<T>)> = Vec::deserialize(deserializer)?;
        Ok(read.into_iter().map(|(offset, In(values))| (offset, values)).collect())
    }
}

/// A `Vec<Vec<T>>`, each list packed.
pub(crate) mod lists {
    use super::*;

    pub(crate) fn serialize<T: Packed, S: Serializer>(lists: &[Vec<T>], serializer: S) -> Result<S::Ok, S::Error> {
        serializer.collect_seq(lists.iter().map(|list| Out(list)))
    }

    pub(crate) fn deserialize<'de, T: Packed, D: Deserializer<'de>>(deserializer: D) -> Result<Vec<Vec<T>>, D::Error> {
        let read: Vec<In<T>> = Vec::deserialize(deserializer)?;
        Ok(read.into_iter().map(|In(list)| list).collect())
    }
}

/// A `Vec<usize>` of offsets (from 0, not decreasing: where each row's items start, and their
/// number last), packed as each row's count, a little-endian `u32` (most rows of a tile are
/// empty: 4 bytes of zeros, where the offsets take 8); read back from either that or an array
/// of the offsets. Offsets that do not start at 0 or count more than `u32::MAX` in a row are
/// written as the array.
pub(crate) mod offsets {
    use super::*;

    pub(crate) fn serialize<S: Serializer>(offsets: &[usize], serializer: S) -> Result<S::Ok, S::Error> {
        let counts: Option<Vec<u32>> = (offsets.first() == Some(&0))
            .then(|| offsets.windows(2).map(|w| w[1].checked_sub(w[0]).and_then(|c| u32::try_from(c).ok())).collect())
            .flatten();
        match counts {
            Some(counts) if !serializer.is_human_readable() => super::serialize(&counts, serializer),
            _ => offsets.serialize(serializer),
        }
    }

    pub(crate) fn deserialize<'de, D: Deserializer<'de>>(deserializer: D) -> Result<Vec<usize>, D::Error> {
        deserializer.deserialize_any(Counts)
    }

    /// Reads counts (packed) or offsets (an array).
    struct Counts;

    impl<'de> Visitor<'de> for Counts {
        type Value = Vec<usize>;

        fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
            f.write_str("packed counts of 4 bytes, or an array of offsets")
        }

        fn visit_bytes<E: de::Error>(self, bytes: &[u8]) -> Result<Vec<usize>, E> {
            let counts: Vec<u32> = Values(PhantomData).visit_bytes(bytes)?;
            let mut offsets = Vec::with_capacity(counts.len() + 1);
            let mut at = 0usize;
            offsets.push(at);
            for c in counts {
                at = at.checked_add(c as usize).ok_or_else(|| E::custom("row counts overflow"))?;
                offsets.push(at);
            }
            Ok(offsets)
        }

        fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<Vec<usize>, A::Error> {
            Values(PhantomData).visit_seq(seq)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, PartialEq, serde::Serialize, serde::Deserialize)]
    struct Holder {
        #[serde(with = "crate::packed")]
        pairs: Vec<[u32; 2]>,
        #[serde(with = "crate::packed::stretches")]
        shares: Vec<(usize, Vec<f64>)>,
        #[serde(with = "crate::packed::lists")]
        labels: Vec<Vec<u32>>,
    }

    /// What versions 2 and 3 wrote: the same fields as arrays.
    #[derive(serde::Serialize)]
    struct Plain {
        pairs: Vec<[u32; 2]>,
        shares: Vec<(usize, Vec<f64>)>,
        labels: Vec<Vec<u32>>,
    }

    fn holder() -> Holder {
        Holder {
            pairs: vec![[1, u32::MAX], [0, 7]],
            shares: vec![(3, vec![0.5, -0.0, f64::MAX]), (9, vec![])],
            labels: vec![vec![4, 5], vec![]],
        }
    }

    #[test]
    fn packed_values_read_back_bit_for_bit() {
        let bytes = rmp_serde::to_vec(&holder()).unwrap();
        let back: Holder = rmp_serde::from_slice(&bytes).unwrap();
        assert_eq!(back, holder());
        assert!(back.shares[0].1[1].is_sign_negative());
        // One bin of 16 bytes for the pairs: the marker, its length, the bytes.
        let pairs = [1u32, u32::MAX, 0, 7].iter().flat_map(|v| v.to_le_bytes()).collect::<Vec<u8>>();
        assert!(bytes.windows(pairs.len() + 2).any(|w| w[..2] == [0xc4, 16] && w[2..] == pairs[..]));
    }

    #[test]
    fn arrays_of_older_versions_and_json_read_back() {
        let h = holder();
        let plain = Plain { pairs: h.pairs.clone(), shares: h.shares.clone(), labels: h.labels.clone() };
        let old: Holder = rmp_serde::from_slice(&rmp_serde::to_vec(&plain).unwrap()).unwrap();
        assert_eq!(old, h);
        let json = serde_json::to_string(&h).unwrap();
        assert_eq!(json, serde_json::to_string(&plain).unwrap());
        assert_eq!(serde_json::from_str::<Holder>(&json).unwrap(), h);
    }

    #[test]
    fn offsets_are_packed_as_counts_and_read_back_from_either() {
        #[derive(Debug, PartialEq, serde::Serialize, serde::Deserialize)]
        struct Set {
            #[serde(with = "crate::packed::offsets")]
            offsets: Vec<usize>,
        }
        #[derive(serde::Serialize)]
        struct Plain {
            offsets: Vec<usize>,
        }
        for offsets in [vec![0, 0, 3, 3, 4], vec![0], vec![], vec![2, 5], vec![0, 1usize << 40]] {
            let set = Set { offsets: offsets.clone() };
            let bytes = rmp_serde::to_vec(&set).unwrap();
            assert_eq!(rmp_serde::from_slice::<Set>(&bytes).unwrap(), set, "{offsets:?}");
            let plain = rmp_serde::to_vec(&Plain { offsets: offsets.clone() }).unwrap();
            assert_eq!(rmp_serde::from_slice::<Set>(&plain).unwrap(), set, "{offsets:?}");
            let json = serde_json::to_string(&set).unwrap();
            assert_eq!(json, serde_json::to_string(&Plain { offsets: offsets.clone() }).unwrap());
            // Counts (4 bytes a row) where they are offsets from 0 that fit, else the array.
            let packed = offsets.first() == Some(&0) && offsets.windows(2).all(|w| w[1] - w[0] <= u32::MAX as usize);
            assert_eq!(bytes != plain, packed, "{offsets:?}");
        }
        let counts = [0u32, 2, 0, 1].iter().flat_map(|c| c.to_le_bytes()).collect::<Vec<u8>>();
        assert!(rmp_serde::to_vec(&Set { offsets: vec![0, 0, 2, 2, 3] }).unwrap().ends_with(&counts));
    }

    #[test]
    fn packed_bytes_of_another_width_or_range_are_refused() {
        #[derive(Debug, serde::Serialize)]
        struct Raw {
            #[serde(with = "serde_bytes_like")]
            pairs: Vec<u8>,
            shares: Vec<(usize, Vec<f64>)>,
            labels: Vec<Vec<u32>>,
        }
        mod serde_bytes_like {
            pub fn serialize<S: serde::Serializer>(v: &[u8], s: S) -> Result<S::Ok, S::Error> {
                s.serialize_bytes(v)
            }
        }
        let raw = Raw { pairs: vec![0; 12], shares: vec![], labels: vec![] };
        let error = rmp_serde::from_slice::<Holder>(&rmp_serde::to_vec(&raw).unwrap()).unwrap_err();
        assert!(error.to_string().contains("12 packed bytes are not a whole number of values of 8 bytes"), "{error}");
        assert_eq!(bool::take(&[2]), None);
        assert_eq!(bool::take(&[1]), Some(true));
    }
}
