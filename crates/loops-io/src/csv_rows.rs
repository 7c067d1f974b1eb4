//! Result tables as CSV: serde rows through the `csv` crate (quoting, fields, records), with
//! floating-point numbers printed as Rust's `Display` prints them.
//!
//! The one thing done by hand here is the number format. The `csv` crate prints an `f64` with
//! `ryu` (`3.0`, `1e-7`, `1e16`); the files this project writes have always printed `Display`'s
//! shortest decimal that reads back as the same `f64`, without an exponent (`3`, `0.0000001`,
//! `10000000000000000`), and their readers and tests compare those bytes. [`write_csv`] passes
//! each row through a serializer adaptor that hands floats to the `csv` crate as that text and
//! everything else unchanged, so a row type stays a plain `#[derive(Serialize)]` struct of `f64`
//! that serialises to JSON as usual. A row may have parts flattened into it
//! (`#[serde(flatten)]`: the columns several tables share); serde serialises it as a map, which
//! the adaptor writes as the struct of its values.

use std::io::{self, Write};

use serde::ser::{Serialize, SerializeMap, SerializeStruct, Serializer};

/// Writes a header line with `columns`, then one line per row of `rows` (structs of numbers,
/// booleans, strings and options: `None` is an empty field), through the `csv` crate with
/// floats as `Display` prints them. The header is written even without rows.
///
/// # Errors
/// What `out` returns; an `InvalidData` error for a row that is not a flat struct.
pub(crate) fn write_csv<W: Write, R: Serialize>(
    out: W,
    columns: &[&str],
    rows: impl IntoIterator<Item = R>,
) -> io::Result<()> {
    let mut writer = ::csv::WriterBuilder::new().has_headers(false).from_writer(out);
    writer.write_record(columns)?;
    for row in rows {
        writer.serialize(DisplayFloats(&row))?;
    }
    writer.flush()
}

/// A value whose floats serialise as their `Display` text.
struct DisplayFloats<'a, T: ?Sized>(&'a T);

impl<T: Serialize + ?Sized> Serialize for DisplayFloats<'_, T> {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        self.0.serialize(Adaptor(serializer))
    }
}

/// A serializer that prints floats with `Display` and forwards the rest to `S`; struct fields and
/// options are wrapped again, so floats inside them are printed so too.
struct Adaptor<S>(S);

/// Methods of [`Serializer`] that hand their arguments to `S` unchanged.
macro_rules! forward {
    ($($method:ident($($arg:ident: $type:ty),*) -> $ok:ty;)*) => {
        $(fn $method(self, $($arg: $type),*) -> Result<$ok, S::Error> {
            self.0.$method($($arg),*)
        })*
    };
}

impl<S: Serializer> Serializer for Adaptor<S> {
    type Ok = S::Ok;
    type Error = S::Error;
    type SerializeSeq = S::SerializeSeq;
    type SerializeTuple = S::SerializeTuple;
    type SerializeTupleStruct = S::SerializeTupleStruct;
    type SerializeTupleVariant = S::SerializeTupleVariant;
    type SerializeMap = MapFields<S::SerializeStruct>;
    type SerializeStruct = Fields<S::SerializeStruct>;
    type SerializeStructVariant = S::SerializeStructVariant;

    forward! {
        serialize_bool(value: bool) -> S::Ok;
        serialize_i8(value: i8) -> S::Ok;
        serialize_i16(value: i16) -> S::Ok;
        serialize_i32(value: i32) -> S::Ok;
        serialize_i64(value: i64) -> S::Ok;
        serialize_u8(value: u8) -> S::Ok;
        serialize_u16(value: u16) -> S::Ok;
        serialize_u32(value: u32) -> S::Ok;
        serialize_u64(value: u64) -> S::Ok;
        serialize_char(value: char) -> S::Ok;
        serialize_str(value: &str) -> S::Ok;
        serialize_bytes(value: &[u8]) -> S::Ok;
        serialize_none() -> S::Ok;
        serialize_unit() -> S::Ok;
        serialize_unit_struct(name: &'static str) -> S::Ok;
        serialize_unit_variant(name: &'static str, index: u32, variant: &'static str) -> S::Ok;
        serialize_seq(len: Option<usize>) -> S::SerializeSeq;
        serialize_tuple(len: usize) -> S::SerializeTuple;
        serialize_tuple_struct(name: &'static str, len: usize) -> S::SerializeTupleStruct;
        serialize_tuple_variant(
            name: &'static str, index: u32, variant: &'static str, len: usize
        ) -> S::SerializeTupleVariant;
        serialize_struct_variant(
            name: &'static str, index: u32, variant: &'static str, len: usize
        ) -> S::SerializeStructVariant;
    }

    fn serialize_f32(self, value: f32) -> Result<S::Ok, S::Error> {
        self.0.collect_str(&value)
    }

    fn serialize_f64(self, value: f64) -> Result<S::Ok, S::Error> {
        self.0.collect_str(&value)
    }

    fn serialize_some<T: Serialize + ?Sized>(self, value: &T) -> Result<S::Ok, S::Error> {
        self.0.serialize_some(&DisplayFloats(value))
    }

    fn serialize_newtype_struct<T: Serialize + ?Sized>(self, name: &'static str, value: &T) -> Result<S::Ok, S::Error> {
        self.0.serialize_newtype_struct(name, &DisplayFloats(value))
    }

    fn serialize_newtype_variant<T: Serialize + ?Sized>(
        self,
        name: &'static str,
        index: u32,
        variant: &'static str,
        value: &T,
    ) -> Result<S::Ok, S::Error> {
        self.0.serialize_newtype_variant(name, index, variant, &DisplayFloats(value))
    }

    fn serialize_map(self, len: Option<usize>) -> Result<Self::SerializeMap, S::Error> {
        // A row with a part flattened into it (`#[serde(flatten)]`) serialises as a map: it is
        // written as the struct of its values, in order (the `csv` crate writes no maps).
        self.0.serialize_struct("row", len.unwrap_or(0)).map(MapFields)
    }

    fn serialize_struct(self, name: &'static str, len: usize) -> Result<Self::SerializeStruct, S::Error> {
        self.0.serialize_struct(name, len).map(Fields)
    }
}

/// The fields of a struct, each through [`Adaptor`].
struct Fields<S>(S);

impl<S: SerializeStruct> SerializeStruct for Fields<S> {
    type Ok = S::Ok;
    type Error = S::Error;

    fn serialize_field<T: Serialize + ?Sized>(&mut self, key: &'static str, value: &T) -> Result<(), S::Error> {
        self.0.serialize_field(key, &DisplayFloats(value))
    }

    fn skip_field(&mut self, key: &'static str) -> Result<(), S::Error> {
        self.0.skip_field(key)
    }

    fn end(self) -> Result<S::Ok, S::Error> {
        self.0.end()
    }
}

/// The entries of a map, each value through [`Adaptor`], written as the fields of a struct: the
/// header names the columns, so the keys are not written.
struct MapFields<S>(S);

impl<S: SerializeStruct> SerializeMap for MapFields<S> {
    type Ok = S::Ok;
    type Error = S::Error;

    fn serialize_key<T: Serialize + ?Sized>(&mut self, _key: &T) -> Result<(), S::Error> {
        Ok(())
    }

    fn serialize_value<T: Serialize + ?Sized>(&mut self, value: &T) -> Result<(), S::Error> {
        self.0.serialize_field("", &DisplayFloats(value))
    }

    fn end(self) -> Result<S::Ok, S::Error> {
        self.0.end()
    }
}

/// The column names of a row of type `R`: its serialised field names in order (as a JSON
/// object's keys, flattened parts included), for tests that check a header constant against its
/// row type.
#[cfg(test)]
pub(crate) fn inferred_columns<R: Serialize>(row: &R) -> Vec<String> {
    /// The keys of a JSON object, in order.
    struct Keys(Vec<String>);

    impl<'de> serde::Deserialize<'de> for Keys {
        fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
            struct Visitor;
            impl<'de> serde::de::Visitor<'de> for Visitor {
                type Value = Keys;
                fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                    f.write_str("a row as a JSON object")
                }
                fn visit_map<A: serde::de::MapAccess<'de>>(self, mut map: A) -> Result<Keys, A::Error> {
                    let mut keys = Vec::new();
                    while let Some((key, serde::de::IgnoredAny)) = map.next_entry::<String, serde::de::IgnoredAny>()? {
                        keys.push(key);
                    }
                    Ok(Keys(keys))
                }
            }
            deserializer.deserialize_map(Visitor)
        }
    }
    let json = serde_json::to_string(row).expect("a row");
    serde_json::from_str::<Keys>(&json).expect("a JSON object").0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(serde::Serialize)]
    struct Row {
        x: f64,
        y: Option<f64>,
        n: usize,
        name: &'static str,
        #[serde(skip_serializing_if = "Option::is_none")]
        extra: Option<u64>,
    }

    /// A row with parts flattened into it (a map to serde).
    #[derive(serde::Serialize)]
    struct Flattened {
        id: usize,
        #[serde(flatten)]
        row: Row,
        #[serde(flatten)]
        more: More,
    }

    #[derive(serde::Serialize)]
    struct More {
        z: f64,
    }

    fn csv(rows: &[Row]) -> String {
        let mut out = Vec::new();
        let columns: &[&str] = if rows.first().is_some_and(|r| r.extra.is_some()) {
            &["x", "y", "n", "name", "extra"]
        } else {
            &["x", "y", "n", "name"]
        };
        write_csv(&mut out, columns, rows).unwrap();
        String::from_utf8(out).unwrap()
    }

    #[test]
    fn floats_print_as_display_prints_them() {
        let values = [3.0, 1e-7, 1e16, 0.1, -0.0, 1.0 / 3.0, f64::NAN, f64::INFINITY, 5e-324, f64::MAX];
        let rows: Vec<Row> = values.iter().map(|&x| Row { x, y: None, n: 1, name: "a", extra: None }).collect();
        let text = csv(&rows);
        let expected: Vec<String> = values.iter().map(|x| format!("{x},,1,a")).collect();
        assert_eq!(text, format!("x,y,n,name\n{}\n", expected.join("\n")));
        let row = Row { x: 2.5, y: Some(3.0), n: 7, name: "with, comma", extra: Some(4) };
        assert_eq!(csv(&[row]), "x,y,n,name,extra\n2.5,3,7,\"with, comma\",4\n");
    }

    #[test]
    fn flattened_parts_are_columns_in_order() {
        let row =
            |extra| Flattened { id: 4, row: Row { x: 0.5, y: None, n: 2, name: "a,b", extra }, more: More { z: 1e-7 } };
        let mut out = Vec::new();
        write_csv(&mut out, &["id", "x", "y", "n", "name", "z"], [row(None)]).unwrap();
        assert_eq!(String::from_utf8(out).unwrap(), "id,x,y,n,name,z\n4,0.5,,2,\"a,b\",0.0000001\n");
        assert_eq!(inferred_columns(&row(None)), ["id", "x", "y", "n", "name", "z"]);
        assert_eq!(inferred_columns(&row(Some(1))), ["id", "x", "y", "n", "name", "extra", "z"]);
    }

    #[test]
    fn the_header_is_written_without_rows() {
        assert_eq!(csv(&[]), "x,y,n,name\n");
        let row = Row { x: 0.0, y: None, n: 0, name: "", extra: None };
        assert_eq!(inferred_columns(&row), ["x", "y", "n", "name"]);
    }
}
