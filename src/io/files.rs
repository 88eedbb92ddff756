//! Output files written whole or not at all: one file through a temporary name and a rename, a set of
//! files renamed only once every one of them is written, and the checks of an output path made before
//! anything is rendered.

use crate::error::{Error, Result};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// A fresh temporary path in the directory of `path` (a rename within one directory is atomic on POSIX
/// file systems, so readers never see a partial file).
pub(crate) fn temporary_path(path: &Path) -> PathBuf {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let unique = COUNTER.fetch_add(1, Ordering::Relaxed);
    path.with_file_name(format!(".{name}.{}.{unique}.tmp", std::process::id()))
}

/// Runs `write` on a temporary file next to `path`, then renames it to `path`; removes the temporary file
/// if anything fails.
pub(crate) fn write_atomically(path: &Path, write: impl FnOnce(&Path) -> Result<()>) -> Result<()> {
    let tmp = temporary_path(path);
    let result =
        write(&tmp).and_then(|()| std::fs::rename(&tmp, path).map_err(|e| Error::file(path, e)));
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// The file name of `path` (the whole path if it has none), as a file beside it refers to it.
pub fn file_name(path: &Path) -> String {
    let name = path.file_name().unwrap_or(path.as_os_str());
    name.to_string_lossy().into_owned()
}

/// Checks, before anything is rendered, that `path` can be an output file: its folder exists or can
/// be created (no file stands where a folder of its path would be), it is not a folder, and it ends in
/// `.extension` (case-insensitive). `what` names it in the error (e.g. `--out`).
///
/// One rule for every output: a missing folder is created when the file is written
/// ([`create_parent`]), never before, so a run that fails creates nothing.
pub fn check_output_path(path: &Path, what: &str, extension: &str) -> Result<()> {
    let problem = if let Some(file) = blocking_file(parent(path)) {
        format!("{} is a file, not a folder", file.display())
    } else if path.is_dir() {
        "is a folder".to_string()
    } else if !path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case(extension))
    {
        format!("must end in .{extension}")
    } else {
        return Ok(());
    };
    Err(Error::Unsupported(format!(
        "{what} {}: {problem}",
        path.display()
    )))
}

/// Checks, before anything is rendered, that the output folder `dir` exists or can be created (no
/// file stands where it or one of its parents would be). `what` names it in the error.
pub fn check_output_folder(dir: &Path, what: &str) -> Result<()> {
    match blocking_file(dir) {
        Some(file) => Err(Error::Unsupported(format!(
            "{what} {}: {} is a file, not a folder",
            dir.display(),
            file.display()
        ))),
        None => Ok(()),
    }
}

/// The file that stands where the folder `dir` or one of its parents would be, if any.
fn blocking_file(dir: &Path) -> Option<&Path> {
    dir.ancestors().find(|a| a.exists()).filter(|a| !a.is_dir())
}

/// The folder `path` is in (`.` for a bare file name).
fn parent(path: &Path) -> &Path {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    }
}

/// Creates the folder of the output file `path` if it is missing (with its missing parents); every
/// writer of this module calls it just before it writes.
pub fn create_parent(path: &Path) -> Result<()> {
    let dir = parent(path);
    std::fs::create_dir_all(dir).map_err(|e| Error::file(dir, format!("cannot create: {e}")))
}

/// Writes `channels` (planes of `width × height`) to the EXR `exr`, then `picture` to the PNG `png`;
/// removes the EXR if the PNG fails, so the pair is written all or nothing.
pub fn write_exr_and_png(
    exr: &Path,
    png: &Path,
    (width, height): (u32, u32),
    channels: &super::Channels,
    picture: &crate::film::Image,
) -> Result<()> {
    create_parent(exr)?;
    create_parent(png)?;
    super::write_exr(exr, width, height, channels)?;
    if let Err(e) = super::write_png(png, picture.width, picture.height, &picture.rgb) {
        let _ = std::fs::remove_file(exr);
        return Err(e);
    }
    Ok(())
}

/// Writes one file to the path given, or says why not (one line, without the path: the caller names
/// the file).
pub type Writer = Box<dyn FnOnce(&Path) -> std::result::Result<(), String>>;

/// A [`Writer`]'s message for a library error: a file error's own message without its path.
pub fn file_message(e: Error) -> String {
    match e {
        Error::File { message, .. } => message,
        e => e.to_string(),
    }
}

/// A [`Writer`] of `bytes` (text or binary) as they are.
pub fn bytes_writer(bytes: impl AsRef<[u8]> + 'static) -> Writer {
    Box::new(move |tmp| std::fs::write(tmp, bytes).map_err(|e| format!("cannot write: {e}")))
}

/// Writes every file of `files` (`(path, writer)`) to a temporary name, then renames them all; on any
/// failure removes what it wrote, so either every file is written or none. Errors name the file:
/// `out/loss.png: <the writer's message>`, `out/grad.json: cannot write: <why the rename failed>`.
pub fn write_all_or_nothing(files: Vec<(PathBuf, Writer)>) -> Result<()> {
    let mut temporaries = Vec::new();
    let mut renamed = Vec::new();
    let mut result = Ok(());
    for (path, write) in files {
        if let Err(e) = create_parent(&path) {
            result = Err(e);
            break;
        }
        let tmp = temporary_path(&path);
        temporaries.push((tmp.clone(), path.clone()));
        result = write(&tmp).map_err(|e| Error::file(&path, e));
        if result.is_err() {
            break;
        }
    }
    if result.is_ok() {
        for (tmp, path) in &temporaries {
            result = (std::fs::rename(tmp, path))
                .map_err(|e| Error::file(path, format!("cannot write: {e}")));
            if result.is_err() {
                break;
            }
            renamed.push(path.clone());
        }
    }
    if result.is_err() {
        for (tmp, _) in &temporaries {
            let _ = std::fs::remove_file(tmp);
        }
        for path in &renamed {
            let _ = std::fs::remove_file(path);
        }
    }
    result
}
