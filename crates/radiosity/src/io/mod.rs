//! Linear systems in and out of files: form-factor matrices in Matrix Market
//! ([`matrix_market`]) and per-patch data in CSV ([`patches_csv`]); files written whole or not
//! at all ([`write_atomic`]); the one place that tells file formats by extension
//! ([`FileFormat`]). Readers check what the solvers rely on and report problems as
//! `file:line: problem`.

mod format;
pub mod matrix_market;
mod output;
pub mod patches_csv;

pub use format::FileFormat;
pub use output::{write_atomic, OutputError};

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
        message: message.into(),
    }
}

pub(crate) fn read_text(path: &Path) -> Result<String, InputError> {
    let bytes = std::fs::read(path).map_err(|source| InputError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    String::from_utf8(bytes).map_err(|e| {
        at(
            path,
            0,
            format!(
                "not UTF-8 text (invalid byte at offset {})",
                e.utf8_error().valid_up_to()
            ),
        )
    })
}
