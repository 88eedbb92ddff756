//! The library's error type: what went wrong and where (a field path or a file), in one line.

/// An error the library reports to its caller. `Display` is one line naming the field or file.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A scene value is missing, malformed or out of range. `field` is a path such as
    /// `shapes[2].sdf.radius`.
    #[error("{field}: {message}")]
    Field {
        /// Path of the offending field in the scene description.
        field: String,
        /// What is wrong with it, including the offending value.
        message: String,
    },
    /// A file could not be read, written or understood.
    #[error("{path}: {message}")]
    File {
        /// The file.
        path: String,
        /// What went wrong.
        message: String,
    },
    /// A request that the renderer cannot honour (e.g. an option combination).
    #[error("{0}")]
    Unsupported(String),
}

impl Error {
    /// A field error.
    pub fn field(field: impl Into<String>, message: impl Into<String>) -> Self {
        Self::Field {
            field: field.into(),
            message: message.into(),
        }
    }
    /// A file error.
    pub fn file(path: impl AsRef<std::path::Path>, message: impl std::fmt::Display) -> Self {
        Self::File {
            path: path.as_ref().display().to_string(),
            message: message.to_string(),
        }
    }
}

/// Result with the library's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;
