use std::path::PathBuf;

/// Errors sorted by whose fault they are, so the CLI can print one line that says what to fix.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// The operating system refused (missing file, permissions, full disk).
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// A file exists but its content is not what it claims to be (the file's fault).
    #[error("{}: {msg}", path.display())]
    Format { path: PathBuf, msg: String },
    /// A parameter or an in-memory capture is inconsistent (the caller's fault).
    #[error("{0}")]
    Parameter(String),
    /// A size declared by a file or requested by a user exceeds what murk will allocate.
    #[error("{0}")]
    Limits(String),
    /// Valid input that this version of murk does not handle.
    #[error("{0}")]
    Unsupported(String),
}

pub type Result<T, E = Error> = std::result::Result<T, E>;

impl Error {
    pub fn param(msg: impl Into<String>) -> Self {
        Error::Parameter(msg.into())
    }
    pub fn format(path: impl Into<PathBuf>, msg: impl Into<String>) -> Self {
        Error::Format {
            path: path.into(),
            msg: msg.into(),
        }
    }
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Error::Io {
            path: path.into(),
            source,
        }
    }
}
