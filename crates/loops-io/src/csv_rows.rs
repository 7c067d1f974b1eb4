//! Result tables as CSV: serde rows through the `csv` crate (quoting, fields, records), with
//! floating-point numbers printed as Rust's `Display` prints them.
//!
//! The one thing done by hand here is the number format. The `csv` crate prints an `f64` with
//! `ryu` (`3.0`, `1e-7`, `1e16`); the files this project writes have always printed `Display`'s
//! shortest decimal that reads back as the same `f64`, without an exponent (`3`, `0.0000001`,
//! `10000000000000000`), and their readers and tests compare those bytes. [`write_csv`] passes
//! each row through a serializer adaptor that hands floats to the `csv` crate as that text and
//! everything else unchanged, so a row type stays a plain `#[derive(Serialize)]` struct of `f64`
//! that serialises to JSON as usual.

use std::io::{self, Write};

use serde::ser::{Serialize, SerializeStruct, Serializer};

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

macro_rules! forward {
    ($($method:ident($type:ty)),* $(,)?) => {
        $(fn $method(self, value: $type) -> Result<S::Ok, S::Error> {
            self.0.$method(value)
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
    type SerializeMap = S::SerializeMap;
    type SerializeStruct = Fields<S::SerializeStruct>;
    type SerializeStructVariant = S::SerializeStructVariant;

    forward!(
        serialize_bool(bool),
        serialize_i8(i8),
        serialize_i16(i16),
        serialize_i32(i32),
        serialize_i64(i64),
        serialize_u8(u8),
        serialize_u16(u16),
        serialize_u32(u32),
        serialize_u64(u64),
        serialize_char(char),
        serialize_str(&str),
        serialize_bytes(&[u8]),
        serialize_unit_struct(&'static str),
    );

    fn serialize_f32(self, value: f32) -> Result<S::Ok, S::Error> {
        self.0.collect_str(&value)
    }

    fn serialize_f64(self, value: f64) -> Result<S::Ok, S::Error> {
        self.0.collect_str(&value)
    }

    fn serialize_none(self) -> Result<S::Ok, S::Error> {
        self.0.serialize_none()
    }

    fn serialize_some<T: Serialize + ?Sized>(self, value: &T) -> Result<S::Ok, S::Error> {
        self.0.serialize_some(&DisplayFloats(value))
    }

    fn serialize_unit(self) -> Result<S::Ok, S::Error> {
        self.0.serialize_unit()
    }

    fn serialize_unit_variant(self, name: &'static str, index: u32, variant: &'static str) -> Result<S::Ok, S::Error> {
        self.0.serialize_unit_variant(name, index, variant)
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

    fn serialize_seq(self, len: Option<usize>) -> Result<S::SerializeSeq, S::Error> {
        self.0.serialize_seq(len)
    }

    fn serialize_tuple(self, len: usize) -> Result<S::SerializeTuple, S::Error> {
        self.0.serialize_tuple(len)
    }

    fn serialize_tuple_struct(self, name: &'static str, len: usize) -> Result<S::SerializeTupleStruct, S::Error> {
        self.0.serialize_tuple_struct(name, len)
    }

    fn serialize_tuple_variant(
        self,
        name: &'static str,
        index: u32,
        variant: &'static str,
        len: usize,
    ) -> Result<S::SerializeTupleVariant, S::Error> {
        self.0.serialize_tuple_variant(name, index, variant, len)
    }

    fn serialize_map(self, len: Option<usize>) -> Result<S::SerializeMap, S::Error> {
        self.0.serialize_map(len)
    }

    fn serialize_struct(self, name: &'static str, len: usize) -> Result<Self::SerializeStruct, S::Error> {
        self.0.serialize_struct(name, len).map(Fields)
    }

    fn serialize_struct_variant(
        self,
        name: &'static str,
        index: u32,
        variant: &'static str,
        len: usize,
    ) -> Result<S::SerializeStructVariant, S::Error> {
        self.0.serialize_struct_variant(name, index, variant, len)
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

/// The column names the `csv` crate gives a row of type `R` (its serialised field names), for
/// tests that check a header constant against its row type.
#[cfg(test)]
pub(crate) fn inferred_columns<R: Serialize>(row: &R) -> Vec<String> {
    let mut writer = ::csv::WriterBuilder::new().has_headers(true).from_writer(Vec::new());
    writer.serialize(DisplayFloats(row)).expect("a flat row");
    let text = String::from_utf8(writer.into_inner().expect("a Vec")).expect("UTF-8");
    text.lines().next().unwrap_or_default().split(',').map(str::to_owned).collect()
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
    fn the_header_is_written_without_rows() {
        assert_eq!(csv(&[]), "x,y,n,name\n");
        let row = Row { x: 0.0, y: None, n: 0, name: "", extra: None };
        assert_eq!(inferred_columns(&row), ["x", "y", "n", "name"]);
    }
}
