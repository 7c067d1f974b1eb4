//! The committed header `include/inexact_loops.h` is the one cbindgen generates from this
//! crate: this test regenerates it and fails when they differ (with `UPDATE_HEADER=1` it writes
//! the new one instead).
//!
//! A test rather than a build script: a build script may only write under `OUT_DIR`, and C and
//! C++ users should get the header from the repository without building cbindgen (and without
//! every build of the library paying for it); the diff of the header is then reviewed with the
//! change that made it.

use std::path::Path;

#[test]
fn committed_header_is_generated() {
    let crate_dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    let config = cbindgen::Config::from_file(crate_dir.join("cbindgen.toml")).expect("reading cbindgen.toml");
    let bindings = cbindgen::Builder::new()
        .with_crate(crate_dir)
        .with_config(config)
        .generate()
        .expect("cbindgen could not generate the header");
    let mut generated = Vec::new();
    bindings.write(&mut generated);
    let generated = String::from_utf8(generated).expect("the header is UTF-8");
    let path = crate_dir.join("include").join("inexact_loops.h");
    if std::env::var_os("UPDATE_HEADER").is_some() {
        std::fs::write(&path, &generated).expect("writing the header");
        return;
    }
    let committed = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(
        committed == generated,
        "{} is not the header cbindgen generates from crates/loops-capi: run `UPDATE_HEADER=1 cargo test -p \
         loops-capi --test header` and commit it",
        path.display()
    );
}
