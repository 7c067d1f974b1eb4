//! Corrupt logs on the command line: a corrupt log gives one line on stderr (no
//! library backtrace, no escape sequences, no source path) naming the file and the offset, and
//! a file without line breaks fails at once instead of filling the memory.

use std::process::Output;

mod support;
use support::{loops, temp_dir, write_in};

/// An MCAP record: opcode, length, body.
fn record(opcode: u8, body: &[u8]) -> Vec<u8> {
    [vec![opcode], (body.len() as u64).to_le_bytes().to_vec(), body.to_vec()].concat()
}

fn string(bytes: &[u8]) -> Vec<u8> {
    [(bytes.len() as u32).to_le_bytes().to_vec(), bytes.to_vec()].concat()
}

/// A small MCAP file: magic, header, `records`, data end, footer, magic.
fn mcap(records: &[Vec<u8>]) -> Vec<u8> {
    const MAGIC: &[u8] = b"\x89MCAP0\r\n";
    [
        MAGIC.to_vec(),
        record(0x01, &[string(b""), string(b"test")].concat()),
        records.concat(),
        record(0x0f, &[0; 4]),
        record(0x02, &[0; 20]),
        MAGIC.to_vec(),
    ]
    .concat()
}

/// The one line of stderr, checked.
fn one_line(output: &Output) -> String {
    assert_eq!(output.status.code(), Some(2), "{output:?}");
    let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
    assert_eq!(stderr.lines().count(), 1, "{stderr:?}");
    assert!(!stderr.contains('\x1b'), "{stderr:?}");
    assert!(!stderr.to_lowercase().contains("backtrace") && !stderr.contains("registry"), "{stderr:?}");
    stderr
}

#[test]
fn a_corrupt_mcap_is_one_line_naming_file_and_offset() {
    let channel =
        [1u16.to_le_bytes().to_vec(), 0u16.to_le_bytes().to_vec(), string(b"/p\xffose"), string(b"json"), string(b"")]
            .concat();
    let dir = temp_dir("corrupt-mcap");
    let non_utf8 = write_in(&dir, "non-utf8.mcap", mcap(&[record(0x04, &channel)]));
    let schema = [1u16.to_le_bytes().to_vec(), u32::MAX.to_le_bytes().to_vec(), b"geometry".to_vec()].concat();
    let huge = write_in(&dir, "huge-name.mcap", mcap(&[record(0x03, &schema)]));
    for (path, what) in [(&non_utf8, "its topic is not UTF-8"), (&huge, "its name is declared 4294967295 bytes long")] {
        let name = path.to_str().unwrap();
        for args in [vec!["info", name], vec!["components", name, "--gamma", "1"]] {
            let stderr = one_line(&loops(&args));
            assert!(stderr.starts_with(&format!("loops: error: {name} offset ")), "{stderr}");
            assert!(stderr.contains(what), "{stderr}");
        }
    }
}

#[test]
fn a_file_without_line_breaks_fails_at_its_first_line() {
    let zero = std::path::Path::new("/dev/zero");
    let dir = temp_dir("no-line-breaks");
    let long = write_in(&dir, "long.tum", vec![b'0'; 3 << 20]);
    for path in [zero, long.as_path()] {
        if !path.exists() {
            continue;
        }
        let stderr = one_line(&loops(&["components", path.to_str().unwrap(), "--format", "tum", "--gamma", "1"]));
        assert!(stderr.contains(" line 1: the line is longer than 1 MiB"), "{stderr}");
    }
}
