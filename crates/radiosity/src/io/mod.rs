//! Linear systems in and out of files: form-factor matrices in Matrix Market
//! ([`matrix_market`]) and per-patch data in CSV ([`patches_csv`]); files written whole or not
//! at all ([`write_atomic`]); the one place that tells file formats by extension
//! ([`FileFormat`]). Readers check what the solvers rely on and report problems as
//! `file:line: problem`.

mod format;
pub mod matrix_market;
mod output;
pub mod patches_csv;
pub mod view3d;

pub use format::FileFormat;
pub use output::{write_atomic, OutputError, Staged};

use crate::loc::FileLoc;
use std::path::{Path, PathBuf};

/// A problem with an input file.
#[derive(Debug, thiserror::Error)]
pub enum InputError {
    /// The file could not be read (the operating system's reason is the source).
    #[error("cannot read {}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// A problem at a place in the file.
    #[error("{at}: {message}")]
    Invalid {
        /// Where.
        at: FileLoc,
        /// What is wrong.
        message: String,
    },
}

pub(crate) fn at(path: &Path, line: usize, message: impl Into<String>) -> InputError {
    InputError::Invalid {
        at: FileLoc::line(path, line),
        message: crate::loc::shorten(message.into()),
    }
}

pub(crate) fn read_text(path: &Path) -> Result<String, InputError> {
    let bytes = read_input(path).map_err(|source| InputError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let text = String::from_utf8(bytes).map_err(|e| {
        at(
            path,
            0,
            format!(
                "not UTF-8 text (invalid byte at offset {})",
                e.utf8_error().valid_up_to()
            ),
        )
    })?;
    if let Some(line) = overlong_line(&text) {
        return Err(at(
            path,
            line,
            format!("a line longer than {} MiB", MAX_LINE_BYTES >> 20),
        ));
    }
    Ok(text)
}

/// Longest line of a text input (OBJ, MTL, MGF, Matrix Market, CSV), bytes: far past any real
/// line (an OBJ face of 4,096 vertices with texture and normal indices is under 100 KiB).
pub const MAX_LINE_BYTES: usize = 1 << 20;

/// The 1-based number of the first line longer than [`MAX_LINE_BYTES`], if any.
pub fn overlong_line(text: &str) -> Option<usize> {
    text.split('\n')
        .position(|l| l.len() > MAX_LINE_BYTES)
        .map(|k| k + 1)
}

/// Largest input file read, bytes.
pub const MAX_INPUT_BYTES: u64 = 4 << 30;

/// Read an input file whole: a regular file (not a device, a pipe or a folder, which could be
/// endless or block), of at most [`MAX_INPUT_BYTES`]; the read stops there even if the file
/// grows meanwhile. Every loader reads through this, files named inside other files included.
pub fn read_input(path: &Path) -> std::io::Result<Vec<u8>> {
    use std::io::Read;
    let meta = std::fs::metadata(path)?;
    if !meta.is_file() {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            "not a regular file",
        ));
    }
    if meta.len() > MAX_INPUT_BYTES {
        return Err(too_large());
    }
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    std::fs::File::open(path)?
        .take(MAX_INPUT_BYTES + 1)
        .read_to_end(&mut bytes)?;
    if bytes.len() as u64 > MAX_INPUT_BYTES {
        return Err(too_large());
    }
    Ok(bytes)
}

fn too_large() -> std::io::Error {
    std::io::Error::new(
        std::io::ErrorKind::InvalidInput,
        format!("larger than the {} GiB input limit", MAX_INPUT_BYTES >> 30),
    )
}
