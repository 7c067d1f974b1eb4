//! The folder of `loops run` and `loops fleet` (`--out`): loops-io's [`OutDir`] (one run at a
//! time, a marker of what the command wrote, a scratch folder, `--force` replacing only the
//! command's own entries), taken and written under the write lock of [`guard`], so that Ctrl-C
//! falls between writes and removes the scratch folder.

use std::path::{Path, PathBuf};

use anyhow::Result;
pub(crate) use loops_io::out_dir::{FLEET, OutDir, RUN, Tool};

use crate::guard;

/// Takes `out` (which must exist) for this run of `tool` ([`OutDir::take`]), tells the
/// interrupt handler of its marker and scratch folder, and says on stderr when it removed what a
/// killed run left.
pub(crate) fn take(out: &Path, force: bool, tool: Tool) -> Result<OutDir> {
    guard::with_writes(|writes| {
        let dir = OutDir::take(out, force, tool)?;
        writes.marker(&out.join(tool.marker));
        writes.scratch(dir.scratch());
        if dir.cleaned_up() {
            eprintln!("loops: removed what an interrupted run left in {} ({})", out.display(), tool.scratch);
        }
        Ok(dir)
    })
}

/// Writes the file `name` of `out` through `fill` ([`OutDir::write_file`]).
pub(crate) fn write_file(
    out: &OutDir,
    name: &str,
    fill: impl FnOnce(&mut std::fs::File) -> std::io::Result<()>,
) -> Result<()> {
    Ok(guard::with_writes(|_| out.write_file(name, fill))?)
}

/// Fills a folder of `out` through `write` in the scratch folder, then moves it into place as
/// `name` ([`OutDir::place`], `owned` as there). The folder is removed when anything fails.
pub(crate) fn write_folder(
    out: &OutDir,
    name: &str,
    owned: bool,
    write: impl FnOnce(&Path) -> Result<()>,
) -> Result<()> {
    let staged: PathBuf = out.staging_path();
    guard::with_writes(|writes| writes.stage(&staged))?;
    let written = write(&staged);
    guard::with_writes(|writes| {
        writes.unstage(&staged);
        match written {
            Ok(()) => Ok(out.place(&staged, name, owned)?),
            Err(error) => {
                let _ = std::fs::remove_dir_all(&staged);
                Err(error)
            }
        }
    })
}

/// Refuses every output named in `outputs` (`--json`, `--out`, ...: its flag and path) that is,
/// links to, lies inside or holds one of `inputs` ([`loops_io::out_dir::refuse_output_on_input`]).
pub(crate) fn refuse_outputs_on_inputs<'a>(
    outputs: impl IntoIterator<Item = (&'a str, Option<&'a Path>)>,
    inputs: &[PathBuf],
) -> Result<()> {
    for (flag, path) in outputs {
        if let Some(path) = path {
            loops_io::out_dir::refuse_output_on_input(flag, path, inputs)?;
        }
    }
    Ok(())
}
