//! Linear systems in and out of files: form-factor matrices in Matrix Market
//! ([`matrix_market`]) and per-patch data in CSV ([`patches_csv`]). Readers check what the
//! solvers rely on and report problems as `file:line: problem`.

pub mod matrix_market;
pub mod patches_csv;

use std::path::{Path, PathBuf};

/// A problem with an input file.
#[derive(Debug, thiserror::Error)]
pub enum InputError {
    /// The file could not be read.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// A problem at a place in the file.
    #[error("{place}: {message}")]
    Invalid {
        /// `file:line`, or the file.
        place: String,
        /// What is wrong.
        message: String,
    },
}

pub(crate) fn at(path: &Path, line: usize, message: impl Into<String>) -> InputError {
    InputError::Invalid {
        place: if line > 0 {
            format!("{}:{}", path.display(), line)
        } else {
            path.display().to_string()
        },
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
