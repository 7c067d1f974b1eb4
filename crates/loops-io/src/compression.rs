//! Decompression for bags, every output bounded: rosbag2's per-message and per-file compression
//! (zstd, the only compressor rosbag2 ships; lz4 frames too, for third-party plugins) and ROS 1's
//! chunk compression (bz2, lz4).
//!
//! The codecs are crates: `zstd` (libzstd, as the `mcap` crate already links it), `lz4_flex`
//! (LZ4 frame format, pure Rust; ROS 1's `roslz4` writes standard LZ4 frames) and `bzip2` (with
//! its pure-Rust `libbz2-rs-sys` back end). Only the limits are ours: no output grows past what
//! its container declares (a ROS 1 chunk's `size`), or past [`MAX_MESSAGE_BYTES`] for one
//! message and [`file_limit`] for a decompressed storage file, whatever the input claims;
//! buffers grow with the output actually produced, never from a declared length alone, and
//! chunks are read as streams.

use std::fs::File;
use std::io::{self, BufReader, BufWriter, Read, Write};
use std::path::Path;

use crate::error::{IoError, Result};
use crate::printable::one_line;
use crate::temp_copy::TempCopy;

/// A compressed frame, by its magic number.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Frame {
    /// A zstd frame: `28 b5 2f fd`.
    Zstd,
    /// An LZ4 frame: `04 22 4d 18`.
    Lz4,
}

impl Frame {
    /// The frame whose magic `data` starts with.
    pub(crate) fn of(data: &[u8]) -> Option<Frame> {
        match data.get(..4)? {
            [0x28, 0xb5, 0x2f, 0xfd] => Some(Frame::Zstd),
            [0x04, 0x22, 0x4d, 0x18] => Some(Frame::Lz4),
            _ => None,
        }
    }

    /// The frame a file name's last extension names: `.zstd` (rosbag2's name), `.zst`, `.lz4`.
    pub(crate) fn of_name(path: &Path) -> Option<Frame> {
        let extension = path.extension()?.to_str()?.to_ascii_lowercase();
        match extension.as_str() {
            "zstd" | "zst" => Some(Frame::Zstd),
            "lz4" => Some(Frame::Lz4),
            _ => None,
        }
    }

    fn name(self) -> &'static str {
        match self {
            Frame::Zstd => "zstd",
            Frame::Lz4 => "lz4",
        }
    }
}

/// Largest decompressed message: 64 MiB. The messages read are poses (a `TFMessage` of a
/// thousand transforms is about 100 kB), so a larger one is corrupt.
pub(crate) const MAX_MESSAGE_BYTES: u64 = 64 << 20;

/// How many times its compressed size a storage file (`.db3.zstd`, `.mcap.zstd`) may
/// decompress to: 1000. zstd compresses logs of poses and sensor data 2 to 20 times, a
/// database's empty pages more; a thousandfold takes long runs of one byte, which is what a
/// compression bomb is made of (33 kB of zstd holding 1 GiB of zeros is 32,000 times).
pub(crate) const MAX_FILE_RATIO: u64 = 1000;

/// The least a storage file may decompress to, whatever its compressed size: 64 MiB.
pub(crate) const MIN_FILE_LIMIT: u64 = 64 << 20;

/// The most a storage file of `compressed` bytes may decompress to: [`MAX_FILE_RATIO`] times
/// its size, and at least [`MIN_FILE_LIMIT`]. The decompressed file goes to a temporary file
/// without a name in the system's temporary folder (`TMPDIR`; see `crate::temp_copy`); a full
/// disk is an error naming the file.
pub(crate) fn file_limit(compressed: u64) -> u64 {
    compressed.saturating_mul(MAX_FILE_RATIO).max(MIN_FILE_LIMIT)
}

/// How a CDR message from a rosbag2 bag with `compression_mode: message` is compressed, if it
/// is: a CDR message starts with `00`, a compressed one with its frame's magic.
pub(crate) fn message_frame(data: &[u8]) -> Option<Frame> {
    Frame::of(data)
}

thread_local! {
    /// One zstd context per thread, reused: creating one per message would cost more than the
    /// decompression of a small message.
    static ZSTD: std::cell::RefCell<Option<zstd::bulk::Decompressor<'static>>> = const { std::cell::RefCell::new(None) };
}

/// Decompresses one message, at most [`MAX_MESSAGE_BYTES`].
///
/// # Errors
/// What the codec says, or that the message decompresses to more than the limit.
pub(crate) fn decompress_message(frame: Frame, data: &[u8]) -> std::result::Result<Vec<u8>, String> {
    let failed = |error: &dyn std::fmt::Display| {
        format!("the {} compressed message does not decompress: {}", frame.name(), one_line(error))
    };
    if frame == Frame::Zstd {
        // A frame that declares its size (rosbag2's do) decompresses in one call.
        if let Ok(Some(size)) = zstd::zstd_safe::get_frame_content_size(data) {
            if size > MAX_MESSAGE_BYTES {
                return Err(too_large(frame, size));
            }
            return ZSTD.with(|cell| {
                let mut cell = cell.borrow_mut();
                let decompressor = match cell.as_mut() {
                    Some(decompressor) => decompressor,
                    None => cell.insert(zstd::bulk::Decompressor::new().map_err(|e| failed(&e))?),
                };
                let out = decompressor.decompress(data, size as usize).map_err(|e| failed(&e))?;
                if out.len() as u64 != size {
                    return Err(failed(&format!("it declares {size} bytes but holds {}", out.len())));
                }
                Ok(out)
            });
        }
    }
    let mut out = Vec::new();
    let read = match frame {
        Frame::Zstd => zstd::stream::read::Decoder::with_buffer(data)
            .and_then(|decoder| decoder.take(MAX_MESSAGE_BYTES + 1).read_to_end(&mut out)),
        Frame::Lz4 => lz4_flex::frame::FrameDecoder::new(data).take(MAX_MESSAGE_BYTES + 1).read_to_end(&mut out),
    };
    read.map_err(|e| failed(&e))?;
    if out.len() as u64 > MAX_MESSAGE_BYTES {
        return Err(too_large(frame, out.len() as u64));
    }
    Ok(out)
}

fn too_large(frame: Frame, size: u64) -> String {
    format!(
        "the {} compressed message decompresses to {size} bytes or more, over the limit of {} MiB for one message",
        frame.name(),
        MAX_MESSAGE_BYTES >> 20
    )
}

/// Decompresses the storage file at `path` (`.db3.zstd`, `.mcap.zstd`) into a temporary file,
/// at most [`file_limit`] of its size: a file with no name ([`TempCopy`]), which the system
/// frees when its handle drops or the process ends, however it ends.
///
/// # Errors
/// [`IoError::Open`] when the file cannot be read; [`IoError::Bag`] naming the file when it is
/// not in `frame`'s format, does not decompress (with the number of bytes decompressed before
/// the fault), declares (zstd) or reaches a size over the limit (naming both), or the temporary
/// file cannot be written.
pub(crate) fn decompress_file(path: &Path, frame: Frame) -> Result<TempCopy> {
    let bag_error = |message: String| IoError::Bag { path: path.to_path_buf(), message };
    let open_error = |error| IoError::Open { path: path.to_path_buf(), error };
    let file = File::open(path).map_err(open_error)?;
    let compressed = file.metadata().map_err(open_error)?.len();
    let limit = file_limit(compressed);
    let mut input = BufReader::with_capacity(1 << 20, file);
    // The magic, and for zstd the frame header with the size it may declare (at most 18 bytes).
    let mut head = [0u8; 18];
    let got = read_up_to(&mut input, &mut head).map_err(open_error)?;
    let head = &head[..got];
    if Frame::of(head) != Some(frame) {
        return Err(bag_error(format!(
            "not a {} file: it starts with {:02x?}, not the {} magic number",
            frame.name(),
            &head[..got.min(4)],
            frame.name()
        )));
    }
    let over_limit = |size: String| {
        bag_error(format!(
            "it {size}, over the limit of {limit} bytes for this file ({MAX_FILE_RATIO} times its {compressed} \
             compressed bytes, and at least {} MiB): a compression bomb, or a corrupt file",
            MIN_FILE_LIMIT >> 20
        ))
    };
    if frame == Frame::Zstd
        && let Ok(Some(declared)) = zstd::zstd_safe::get_frame_content_size(head)
        && declared > limit
    {
        return Err(over_limit(format!("declares {declared} bytes decompressed")));
    }
    let input = io::Cursor::new(head.to_vec()).chain(input);
    let temp = TempCopy::new()
        .map_err(|e| bag_error(format!("cannot create a temporary file to decompress into: {}", one_line(&e))))?;
    let mut output = Counting { inner: BufWriter::with_capacity(1 << 20, temp.file()), written: 0 };
    let copied = match frame {
        Frame::Zstd => zstd::stream::read::Decoder::new(input)
            .and_then(|decoder| io::copy(&mut decoder.take(limit + 1), &mut output)),
        Frame::Lz4 => io::copy(&mut lz4_flex::frame::FrameDecoder::new(input).take(limit + 1), &mut output),
    };
    let written = output.written;
    let flushed = copied.and_then(|_| output.inner.flush());
    drop(output);
    flushed.map_err(|e| {
        let what = if e.kind() == io::ErrorKind::Other || e.kind() == io::ErrorKind::InvalidData {
            "it does not decompress"
        } else {
            "decompressing it failed"
        };
        bag_error(format!("{what} ({} after {written} decompressed bytes): {}", frame.name(), one_line(&e)))
    })?;
    if written > limit {
        return Err(over_limit("decompresses to more".to_owned()));
    }
    Ok(temp)
}

/// Reads into `buffer` until it is full or the input ends; returns the bytes read.
fn read_up_to(reader: &mut impl Read, buffer: &mut [u8]) -> io::Result<usize> {
    let mut filled = 0;
    while filled < buffer.len() {
        match reader.read(&mut buffer[filled..]) {
            Ok(0) => break,
            Ok(n) => filled += n,
            Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(filled)
}

/// A writer that counts what it writes.
struct Counting<W> {
    inner: W,
    written: u64,
}

impl<W: Write> Write for Counting<W> {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        let n = self.inner.write(buf)?;
        self.written += n as u64;
        Ok(n)
    }
    fn flush(&mut self) -> io::Result<()> {
        self.inner.flush()
    }
}

/// How a ROS 1 chunk is compressed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum ChunkCompression {
    None,
    Bz2,
    Lz4,
}

impl ChunkCompression {
    /// The name the bag gives it.
    pub(crate) fn name(self) -> &'static str {
        match self {
            ChunkCompression::None => "uncompressed",
            ChunkCompression::Bz2 => "bz2",
            ChunkCompression::Lz4 => "lz4",
        }
    }
}

/// A ROS 1 chunk's records, decompressed as a stream from `data` (the chunk's data, bounded by
/// the caller). The caller reads no more than the size the chunk declares, and checks that the
/// stream then ends.
pub(crate) fn chunk_decoder<'a>(compression: ChunkCompression, data: impl Read + 'a) -> Box<dyn Read + 'a> {
    match compression {
        ChunkCompression::None => Box::new(data),
        ChunkCompression::Bz2 => Box::new(bzip2::read::BzDecoder::new(data)),
        ChunkCompression::Lz4 => Box::new(lz4_flex::frame::FrameDecoder::new(data)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn messages_round_trip_and_garbage_fails() {
        let plain: Vec<u8> = (0..1000u32).flat_map(|i| (i % 7).to_le_bytes()).collect();
        let zstd = zstd::bulk::compress(&plain, 3).unwrap();
        assert_eq!(message_frame(&zstd), Some(Frame::Zstd));
        assert_eq!(decompress_message(Frame::Zstd, &zstd).unwrap(), plain);
        let lz4 = {
            let mut encoder = lz4_flex::frame::FrameEncoder::new(Vec::new());
            encoder.write_all(&plain).unwrap();
            encoder.finish().unwrap()
        };
        assert_eq!(message_frame(&lz4), Some(Frame::Lz4));
        assert_eq!(decompress_message(Frame::Lz4, &lz4).unwrap(), plain);
        for cut in [4, 10, zstd.len() - 1] {
            assert!(decompress_message(Frame::Zstd, &zstd[..cut]).is_err(), "{cut}");
        }
        assert!(decompress_message(Frame::Lz4, &lz4[..lz4.len() - 10]).is_err());
        assert_eq!(message_frame(&[0, 1, 0, 0]), None);
    }

    #[test]
    fn a_message_bomb_stops_at_the_limit() {
        let zeros = vec![0u8; (MAX_MESSAGE_BYTES + 10) as usize];
        let zstd = zstd::bulk::compress(&zeros, 1).unwrap();
        let error = decompress_message(Frame::Zstd, &zstd).unwrap_err();
        assert!(error.contains("over the limit of 64 MiB"), "{error}");
    }

    #[test]
    fn chunks_decompress_as_streams() {
        let plain = b"hello chunk hello chunk hello chunk".to_vec();
        let read = |compression, data: &[u8]| {
            let mut out = Vec::new();
            chunk_decoder(compression, data).read_to_end(&mut out).map(|_| out)
        };
        assert_eq!(read(ChunkCompression::None, &plain).unwrap(), plain);
        let mut bz2 = Vec::new();
        bzip2::read::BzEncoder::new(&plain[..], bzip2::Compression::best()).read_to_end(&mut bz2).unwrap();
        assert_eq!(read(ChunkCompression::Bz2, &bz2).unwrap(), plain);
        assert!(read(ChunkCompression::Lz4, &bz2).is_err());
        assert!(read(ChunkCompression::Bz2, &bz2[..bz2.len() - 3]).is_err());
    }
}
