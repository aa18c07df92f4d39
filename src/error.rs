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

    /// An allocation sized by input would exceed the memory budget
    /// ([`crate::limits`]): the request is too large for this machine
    /// rather than malformed (Python raises `MemoryError` for it).
    #[error("{what}: {why}")]
    OverBudget {
        /// What would allocate: a flag, an argument, a file being loaded.
        what: String,
        /// The estimate and the budget, and how to change the budget.
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

    /// The caller set the call's [`crate::cancel::Cancel`]: what it had
    /// computed is dropped.
    #[error("cancelled")]
    Cancelled,

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

    /// This error as part of `context` (a field, a file), its message
    /// prefixed with `context: `. An I/O error and a refused allocation keep
    /// their kind, so that a file the system cannot read or one too large
    /// is still told from a malformed one (Python raises OSError and
    /// MemoryError for them); any other error becomes `other(context,
    /// message)`.
    pub fn within(self, context: &str, other: impl FnOnce(&str, String) -> Error) -> Error {
        match self {
            Error::Io { path, source } => {
                Error::io(format!("{context}: {}", path.display()), source)
            }
            Error::OverBudget { what, why } => Error::OverBudget {
                what: format!("{context}: {what}"),
                why,
            },
            e => other(context, e.to_string()),
        }
    }
}

/// The library's result type, with [`Error`] as the error.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// `text` with every control character (NUL, ESC, newline, DEL, C1 codes)
/// written as a Rust-style escape (`\u{1b}`), so that a name echoed from a
/// file can neither move the cursor, recolour the terminal nor split a
/// one-line message.
pub fn escape(text: &str) -> std::borrow::Cow<'_, str> {
    if !text.chars().any(char::is_control) {
        return std::borrow::Cow::Borrowed(text);
    }
    let mut out = String::with_capacity(text.len() + 8);
    for c in text.chars() {
        if c.is_control() {
            out.push_str(&format!("\\u{{{:x}}}", u32::from(c)));
        } else {
            out.push(c);
        }
    }
    std::borrow::Cow::Owned(out)
}

/// A number for a message: as written (`1.5`, `650`) in the usual range,
/// in exponent form (`1e-320`) outside it rather than hundreds of digits.
pub fn short_number(x: f64) -> String {
    if x == 0.0 || !x.is_finite() || (1e-4..1e16).contains(&x.abs()) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

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

#[cfg(test)]
mod tests {
    #[test]
    fn numbers_print_short() {
        assert_eq!(super::short_number(1.5), "1.5");
        assert_eq!(super::short_number(-650.0), "-650");
        assert_eq!(super::short_number(1e-320), "1e-320");
        assert_eq!(super::short_number(-2.5e300), "-2.5e300");
        assert_eq!(super::short_number(0.0), "0");
    }

    #[test]
    fn control_characters_are_escaped() {
        assert_eq!(super::escape("glass"), "glass");
        assert_eq!(
            super::escape("a\u{1b}[31mred\0\n\u{7f}\u{9b}é"),
            "a\\u{1b}[31mred\\u{0}\\u{a}\\u{7f}\\u{9b}é"
        );
    }
}
