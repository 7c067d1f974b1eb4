//! Result documents as JSON: pretty-printed with a final newline, through a buffer, with the
//! writer's own error handed back (a closed stdout stays `BrokenPipe`).

use std::io::{self, BufWriter, Write};

use serde::Serialize;

/// Writes `document` to `out` as pretty-printed JSON and a final newline.
///
/// # Errors
/// What `out` returns: `serde_json`'s `From` hands back the writer's own error.
pub(crate) fn write_json<W: Write, T: Serialize + ?Sized>(document: &T, out: W) -> io::Result<()> {
    let mut out = BufWriter::new(out);
    serde_json::to_writer_pretty(&mut out, document).map_err(io::Error::from)?;
    writeln!(out)?;
    out.flush()
}

/// A writer whose reader has gone (`loops components --json - | head`), for the writers' tests:
/// every write fails with `BrokenPipe`.
#[cfg(test)]
pub(crate) struct ClosedPipe;

#[cfg(test)]
impl Write for ClosedPipe {
    fn write(&mut self, _: &[u8]) -> io::Result<usize> {
        Err(io::ErrorKind::BrokenPipe.into())
    }

    fn flush(&mut self) -> io::Result<()> {
        Ok(())
    }
}
