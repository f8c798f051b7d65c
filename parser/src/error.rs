//! Errors and warnings with source locations, printed as `FILE:LINE:COL: message`.

use crate::source::Loc;
use std::fmt;
use std::path::PathBuf;

/// Something wrong in a scene, with where it is.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A problem at a place in a scene file; shows the line and a caret under the column.
    #[error("{loc}: {message}\n{}", loc.snippet())]
    At {
        /// Where the problem is.
        loc: Loc,
        /// What is wrong.
        message: String,
    },
    /// A problem with a whole file (it cannot be read, say), with no position inside it.
    #[error("{}: {message}", path.display())]
    File {
        /// The file concerned.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
}

impl Error {
    /// An error at `loc`.
    pub fn at(loc: &Loc, message: impl Into<String>) -> Self {
        Error::At {
            loc: loc.clone(),
            message: message.into(),
        }
    }

    /// An error about a whole file.
    pub fn file(path: impl Into<PathBuf>, message: impl Into<String>) -> Self {
        Error::File {
            path: path.into(),
            message: message.into(),
        }
    }

    /// The message alone, without location.
    pub fn message(&self) -> &str {
        match self {
            Error::At { message, .. } | Error::File { message, .. } => message,
        }
    }
}

/// Result with the parser's error.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// A warning: the scene is usable but something in it is ignored or suspicious.
#[derive(Clone)]
pub struct Warning {
    /// Where it is, when it has a place.
    pub loc: Option<Loc>,
    /// What is wrong.
    pub message: String,
}

impl Warning {
    /// A warning at `loc`.
    pub fn at(loc: &Loc, message: impl Into<String>) -> Self {
        Self {
            loc: Some(loc.clone()),
            message: message.into(),
        }
    }
}

impl fmt::Display for Warning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.loc {
            Some(loc) => write!(f, "{loc}: warning: {}", self.message),
            None => write!(f, "warning: {}", self.message),
        }
    }
}

impl fmt::Debug for Warning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Display::fmt(self, f)
    }
}
