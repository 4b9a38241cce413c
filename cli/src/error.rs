//! The errors `fovea` reports: each names what is wrong (and the file, where there is one).
use std::path::PathBuf;

/// Everything that can stop a `fovea` command.
#[derive(Debug, thiserror::Error)]
pub enum FoveaError {
    /// A command-line value that does not parse or is out of range.
    #[error("invalid {option}: {message}")]
    InvalidOption {
        option: &'static str,
        message: String,
    },
    /// The scene could not be loaded.
    #[error(transparent)]
    Scene(#[from] fovea_scene::error::SceneError),
    /// Reading or writing a file failed.
    #[error("{}: {message}", path.display())]
    File { path: PathBuf, message: String },
    /// A backend that cannot run here.
    #[error("{0}")]
    Backend(String),
    /// The live view cannot open or drive its window.
    #[error("fovea view: {0}")]
    View(String),
}

impl FoveaError {
    pub fn option(option: &'static str, message: impl Into<String>) -> Self {
        Self::InvalidOption {
            option,
            message: message.into(),
        }
    }

    pub fn file(path: impl Into<PathBuf>, message: impl ToString) -> Self {
        Self::File {
            path: path.into(),
            message: message.to_string(),
        }
    }
}

pub type Result<T> = std::result::Result<T, FoveaError>;
