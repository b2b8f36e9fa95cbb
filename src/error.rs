//! The library's one error type.

use std::path::PathBuf;

/// Everything that can go wrong in penumbra that a caller cannot rule out
/// beforehand: bad input files, bad views, missing GPU features.
///
/// Each variant names the file (or thing) at fault and what is wrong with it,
/// so the CLI can print `error: {err}` and stop.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A scene file could not be read or understood.
    #[error("{path}: {message}")]
    Scene {
        /// The glTF/GLB file (or the buffer/image it references).
        path: PathBuf,
        /// What is wrong, in words.
        message: String,
    },
    /// A view file (camera + light) could not be read or understood.
    #[error("{path}: {message}")]
    View {
        /// The view file.
        path: PathBuf,
        /// What is wrong, in words.
        message: String,
    },
    /// The BVH could not be built (for example: the scene has no triangles).
    #[error("BVH: {0}")]
    Bvh(String),
    /// Reading or writing a file failed.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating system's error.
        #[source]
        source: std::io::Error,
    },
}

impl Error {
    /// A scene error for `path`.
    pub fn scene(path: impl Into<PathBuf>, message: impl Into<String>) -> Self {
        Error::Scene {
            path: path.into(),
            message: message.into(),
        }
    }

    /// A view error for `path`.
    pub fn view(path: impl Into<PathBuf>, message: impl Into<String>) -> Self {
        Error::View {
            path: path.into(),
            message: message.into(),
        }
    }
}

/// `Result` with penumbra's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;
