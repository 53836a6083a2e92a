//! Writing files whole or not at all.

use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

/// A file could not be written; the operating system's reason is the source.
#[derive(Debug, thiserror::Error)]
#[error("cannot write {}", path.display())]
pub struct OutputError {
    /// The destination.
    pub path: PathBuf,
    /// Why.
    #[source]
    pub source: std::io::Error,
}

/// Write through `body` into a temporary file beside `path`, then rename it to `path`, so a
/// failure never leaves a half-written output. Generic over the caller's error type.
///
/// Only regular files (or new paths) are replaced by renaming. A symbolic link is followed and
/// its target written the same way, so the link stays a link; a device or a pipe (`/dev/null`)
/// is written in place; a folder or a dangling link is refused.
pub fn write_atomic<E: From<OutputError>>(
    path: &Path,
    body: impl FnOnce(&mut BufWriter<File>) -> std::io::Result<()>,
) -> Result<(), E> {
    let fail = |source| OutputError {
        path: path.to_path_buf(),
        source,
    };
    let refuse = |what: &str| fail(std::io::Error::new(std::io::ErrorKind::InvalidInput, what));
    let target = match std::fs::symlink_metadata(path) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => path.to_path_buf(),
        Err(e) => return Err(fail(e).into()),
        Ok(m) if m.file_type().is_symlink() => match std::fs::canonicalize(path) {
            Ok(t) => t,
            Err(_) => return Err(refuse("is a symbolic link to nothing").into()),
        },
        Ok(_) => path.to_path_buf(),
    };
    match std::fs::metadata(&target) {
        Ok(m) if m.is_dir() => return Err(refuse("is a folder").into()),
        Ok(m) if !m.is_file() => {
            // A device or a pipe: write in place; there is nothing to replace.
            let result = (|| {
                let file = std::fs::OpenOptions::new().write(true).open(&target)?;
                let mut w = BufWriter::new(file);
                body(&mut w)?;
                w.into_inner().map_err(|e| e.into_error())?;
                Ok(())
            })();
            return result.map_err(|e| fail(e).into());
        }
        _ => {}
    }
    let path = target.as_path();
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".into());
    let tmp = path.with_file_name(format!(".{name}.tmp{}", std::process::id()));
    let result = (|| {
        let mut w = BufWriter::new(File::create(&tmp)?);
        body(&mut w)?;
        let f = w.into_inner().map_err(|e| e.into_error())?;
        f.sync_all()?;
        drop(f);
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result.map_err(|source| fail(source).into())
}
