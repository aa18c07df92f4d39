//! The library's one error type. Every variant names what was wrong so the
//! binary can print it as a single line and exit with code 2.

use std::path::PathBuf;

/// Everything the library can fail with. Each variant carries what was at
/// fault (a flag or field name, or a file path) and why, and displays as
/// one line, `what: why`; the library never panics on bad input.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A value supplied by the user is out of its allowed domain.
    #[error("{what}: {why}")]
    InvalidInput {
        /// The value at fault: a flag, a field (`layers[2].material`), a name.
        what: String,
        /// What is wrong with it and what is expected.
        why: String,
    },

    /// An f16 table (`--half`) cannot hold a value the stack reaches (a
    /// gain film near its resonances): it would be stored as infinity.
    #[error("--half: {why}")]
    HalfOverflow {
        /// Which channel overflows where (thickness, angle) and what to do.
        why: String,
    },

    /// A file could not be read or written.
    #[error("{path}: {source}")]
    Io {
        /// The file or folder.
        path: PathBuf,
        /// What the operating system reported.
        #[source]
        source: std::io::Error,
    },

    /// A file was read but its content is malformed.
    #[error("{path}: {why}")]
    Malformed {
        /// The file (or, for an inline text, the name it was given).
        path: PathBuf,
        /// Where in it and what is wrong (`line 3, column 7: ...`).
        why: String,
    },
}

impl Error {
    /// An [`Error::InvalidInput`]: `what` is at fault because `why`.
    pub fn invalid(what: impl Into<String>, why: impl Into<String>) -> Self {
        Error::InvalidInput {
            what: what.into(),
            why: why.into(),
        }
    }

    /// An [`Error::Malformed`]: the file at `path` is wrong because `why`.
    pub fn malformed(path: impl Into<PathBuf>, why: impl Into<String>) -> Self {
        Error::Malformed {
            path: path.into(),
            why: why.into(),
        }
    }

    /// An [`Error::Io`]: reading or writing `path` failed with `source`.
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Error::Io {
            path: path.into(),
            source,
        }
    }
}

/// The library's result type, with [`Error`] as the error.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// A TOML parse error as a malformed-file error: where it is (line and
/// column, 1-based) and what is wrong.
pub(crate) fn toml_error(origin: &str, e: &toml::de::Error, text: &str) -> Error {
    let at = e
        .span()
        .map(|span| {
            let before = &text[..span.start.min(text.len())];
            let line = before.matches('\n').count() + 1;
            let column = before.len() - before.rfind('\n').map_or(0, |i| i + 1) + 1;
            format!("line {line}, column {column}: ")
        })
        .unwrap_or_default();
    Error::malformed(origin, format!("{at}{}", toml_message(e, text)))
}

/// A TOML parse error's message. toml leaves it empty for some syntax errors
/// (a value missing at the end of the file), which would print as nothing
/// after the position.
pub(crate) fn toml_message(e: &toml::de::Error, text: &str) -> String {
    let message = e.message().trim();
    if !message.is_empty() {
        message.replace('\n', "; ")
    } else if e.span().is_some_and(|s| s.start >= text.trim_end().len()) {
        "unexpected end of file (a value or bracket is missing)".to_string()
    } else {
        "invalid TOML syntax".to_string()
    }
}
