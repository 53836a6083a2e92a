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
    let target = match resolve(path)? {
        Target::Special(target) => {
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
        Target::File(t) => t,
    };
    let path = target.as_path();
    let tmp = temporary(path);
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

/// Where a write to a path lands.
enum Target {
    /// A regular file or a new path (a link's target when the path is a link): replaced by renaming.
    File(PathBuf),
    /// A device or a pipe: written in place.
    Special(PathBuf),
}

/// The file a write to `path` replaces: a link is followed; a folder or a dangling link is refused.
fn resolve(path: &Path) -> Result<Target, OutputError> {
    let fail = |source| OutputError {
        path: path.to_path_buf(),
        source,
    };
    let refuse = |what: &str| fail(std::io::Error::new(std::io::ErrorKind::InvalidInput, what));
    let target = match std::fs::symlink_metadata(path) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            return Ok(Target::File(path.to_path_buf()))
        }
        Err(e) => return Err(fail(e)),
        Ok(m) if m.file_type().is_symlink() => match std::fs::canonicalize(path) {
            Ok(t) => t,
            Err(_) => return Err(refuse("is a symbolic link to nothing")),
        },
        Ok(_) => path.to_path_buf(),
    };
    match std::fs::metadata(&target) {
        Ok(m) if m.is_dir() => Err(refuse("is a folder")),
        Ok(m) if !m.is_file() => Ok(Target::Special(target)),
        _ => Ok(Target::File(target)),
    }
}

/// The temporary name beside `path` that a staged write goes to.
fn temporary(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".into());
    path.with_file_name(format!(".{name}.tmp{}", std::process::id()))
}

/// Several outputs of one command, written all or none.
///
/// Each [`Staged::write`] goes to a temporary file beside its destination (or, for a device or
/// a pipe, to memory); [`Staged::commit`] then renames them all into place. If any write fails,
/// or the `Staged` is dropped without a commit, every temporary is removed and no destination
/// is touched. The renames at the end are within one folder each and do not fail in practice;
/// should one fail, the ones before it have landed and the rest are removed.
///
/// ```no_run
/// # use radiosity::io::{OutputError, Staged};
/// # use std::io::Write;
/// # fn main() -> Result<(), OutputError> {
/// let mut out = Staged::default();
/// out.write::<OutputError>("surfaces.csv".as_ref(), |w| writeln!(w, "name,power"))?;
/// out.write::<OutputError>("patches.csv".as_ref(), |w| writeln!(w, "patch,power"))?;
/// out.commit::<OutputError>()?; // both land, or neither
/// # Ok(()) }
/// ```
#[derive(Default)]
pub struct Staged {
    /// The path as given, and what it becomes at the commit.
    pending: Vec<(PathBuf, Pending)>,
}

enum Pending {
    /// Rename this temporary onto this file.
    Rename { tmp: PathBuf, target: PathBuf },
    /// Write these bytes into this device or pipe.
    Special { target: PathBuf, bytes: Vec<u8> },
}

impl Staged {
    /// Write `path`'s content through `body` into its temporary; nothing is visible under
    /// `path` until [`Staged::commit`]. Two writes to one destination are refused.
    pub fn write<E: From<OutputError>>(
        &mut self,
        path: &Path,
        body: impl FnOnce(&mut dyn std::io::Write) -> std::io::Result<()>,
    ) -> Result<(), E> {
        let fail = |source| OutputError {
            path: path.to_path_buf(),
            source,
        };
        let pending = match resolve(path)? {
            Target::Special(target) => {
                let mut bytes = Vec::new();
                body(&mut bytes).map_err(fail)?;
                Pending::Special { target, bytes }
            }
            Target::File(target) => {
                let tmp = temporary(&target);
                if self
                    .pending
                    .iter()
                    .any(|(_, p)| matches!(p, Pending::Rename { tmp: t, .. } if *t == tmp))
                {
                    return Err(fail(std::io::Error::new(
                        std::io::ErrorKind::AlreadyExists,
                        "is written twice by one command",
                    ))
                    .into());
                }
                let result = (|| {
                    let mut w = BufWriter::new(File::create(&tmp)?);
                    body(&mut w)?;
                    let f = w.into_inner().map_err(|e| e.into_error())?;
                    f.sync_all()
                })();
                if let Err(e) = result {
                    let _ = std::fs::remove_file(&tmp);
                    return Err(fail(e).into());
                }
                Pending::Rename { tmp, target }
            }
        };
        self.pending.push((path.to_path_buf(), pending));
        Ok(())
    }

    /// Move every staged output into place.
    pub fn commit<E: From<OutputError>>(mut self) -> Result<(), E> {
        let pending = std::mem::take(&mut self.pending);
        let mut rest = pending.into_iter();
        while let Some((path, p)) = rest.next() {
            let result = match p {
                Pending::Rename { tmp, target } => {
                    std::fs::rename(&tmp, &target).inspect_err(|_| {
                        let _ = std::fs::remove_file(&tmp);
                    })
                }
                Pending::Special { target, bytes } => (|| {
                    let mut f = std::fs::OpenOptions::new().write(true).open(&target)?;
                    std::io::Write::write_all(&mut f, &bytes)
                })(),
            };
            if let Err(source) = result {
                self.pending = rest.collect();
                return Err(OutputError { path, source }.into());
            }
        }
        Ok(())
    }
}

impl Drop for Staged {
    fn drop(&mut self) {
        for (_, p) in &self.pending {
            if let Pending::Rename { tmp, .. } = p {
                let _ = std::fs::remove_file(tmp);
            }
        }
    }
}
