//! Typed errors. Every error a user can cause names the file and, for text formats, the
//! line and column, so `gpurt` can print `FILE:LINE:COL: message` and exit non-zero.

use std::path::PathBuf;

pub type Result<T, E = Error> = std::result::Result<T, E>;

#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// Malformed text input (NFF, ASCII STL, OBJ).
    #[error("{file}:{line}:{col}: {msg}")]
    Parse {
        file: String,
        line: u32,
        col: u32,
        msg: String,
    },
    /// Malformed binary input (binary STL); the position is a byte offset.
    #[error("{file}: at byte {offset}: {msg}")]
    Binary {
        file: String,
        offset: u64,
        msg: String,
    },
    /// A scene that parsed but cannot be rendered (e.g. a degenerate view).
    #[error("{file}: {msg}")]
    Scene { file: String, msg: String },
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("no GPU adapter found{0}")]
    NoAdapter(String),
    #[error("GPU error: {0}")]
    Gpu(String),
    #[error("{0}")]
    Image(String),
    /// A library caller's render request that cannot be honoured (a frame the scene's
    /// buffers or an accumulator do not fit).
    #[error("{0}")]
    Render(String),
    /// The viewer found no display to open its window on.
    #[error("cannot open a window: {0}")]
    NoDisplay(String),
    #[error("interrupted")]
    Interrupted,
}

impl Error {
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Error::Io {
            path: path.into(),
            source,
        }
    }
}
