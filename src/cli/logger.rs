//! The command line's logger: the library reports through the `log` crate
//! (the bake's refinement rounds at debug level, for instance) and prints
//! nothing itself; this writes those records to stderr.
//!
//! `RUST_LOG` sets the level (`error`, `warn`, `info`, `debug`, `trace` or
//! `off`; the default is `warn`), and `IRID_DEBUG=1` is short for
//! `RUST_LOG=debug`.

use log::{LevelFilter, Log, Metadata, Record};

/// Writes each record as one line, `irid: LEVEL: message`.
struct Stderr;

impl Log for Stderr {
    fn enabled(&self, metadata: &Metadata) -> bool {
        metadata.level() <= log::max_level()
    }

    fn log(&self, record: &Record) {
        if self.enabled(record.metadata()) {
            let level = record.level().as_str().to_ascii_lowercase();
            eprintln!("irid: {level}: {}", record.args());
        }
    }

    fn flush(&self) {}
}

/// The level `RUST_LOG` and `IRID_DEBUG` ask for: `IRID_DEBUG` (set and not
/// `0` or empty) means debug; an unreadable `RUST_LOG` keeps the default.
pub fn level(rust_log: Option<&str>, irid_debug: Option<&str>) -> LevelFilter {
    if irid_debug.is_some_and(|v| !v.is_empty() && v != "0") {
        return LevelFilter::Debug;
    }
    rust_log
        .and_then(|v| v.trim().parse().ok())
        .unwrap_or(LevelFilter::Warn)
}

/// Installs the logger at the level the environment asks for.
pub fn install() {
    let var = |name: &str| std::env::var(name).ok();
    let level = level(var("RUST_LOG").as_deref(), var("IRID_DEBUG").as_deref());
    if log::set_logger(&Stderr).is_ok() {
        log::set_max_level(level);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn irid_debug_means_debug_and_rust_log_sets_the_level() {
        assert_eq!(level(None, None), LevelFilter::Warn);
        assert_eq!(level(None, Some("1")), LevelFilter::Debug);
        assert_eq!(level(Some("error"), Some("1")), LevelFilter::Debug);
        assert_eq!(level(Some("info"), Some("0")), LevelFilter::Info);
        assert_eq!(level(Some("TRACE"), None), LevelFilter::Trace);
        assert_eq!(level(Some("off"), None), LevelFilter::Off);
        assert_eq!(level(Some("loud"), None), LevelFilter::Warn);
    }
}
