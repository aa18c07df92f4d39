//! The memory budget: every allocation whose size comes from input (an
//! image's data window, a bake's node count, a render's pixel count) is
//! estimated first and refused above the budget with one line giving the
//! estimate and the limit, instead of aborting the process when the
//! allocator fails. See `docs/limits.md`.

use std::sync::atomic::{AtomicU64, Ordering};

use crate::error::{Error, Result};

/// The environment variable that sets the budget, in bytes, with an
/// optional suffix K, M, G or T (powers of 1024): `IRID_MEMORY_LIMIT=16G`.
pub const MEMORY_LIMIT_ENV: &str = "IRID_MEMORY_LIMIT";

/// The share of the machine's physical memory the default budget allows.
pub const DEFAULT_MEMORY_SHARE: f64 = 0.5;

/// The budget when the machine's memory cannot be read.
const FALLBACK_BUDGET: u64 = 4 << 30;

/// A budget set by the program itself ([`set_memory_budget`]); 0 = none.
static OVERRIDE: AtomicU64 = AtomicU64::new(0);

/// Sets the budget for this process, taking precedence over
/// [`MEMORY_LIMIT_ENV`] (a test harness keeps its allocations small this
/// way). `None` restores the default.
pub fn set_memory_budget(bytes: Option<u64>) {
    OVERRIDE.store(bytes.map_or(0, |b| b.max(1)), Ordering::Relaxed);
}

/// The budget in bytes: [`set_memory_budget`], else [`MEMORY_LIMIT_ENV`],
/// else [`DEFAULT_MEMORY_SHARE`] of physical memory.
pub fn memory_budget() -> Result<u64> {
    let set = OVERRIDE.load(Ordering::Relaxed);
    if set > 0 {
        return Ok(set);
    }
    match std::env::var(MEMORY_LIMIT_ENV) {
        Ok(text) => parse_bytes(&text).ok_or_else(|| {
            Error::invalid(
                MEMORY_LIMIT_ENV,
                format!(
                    "'{}' is not a size in bytes (a positive integer, optionally followed by K, M, G or T)",
                    crate::error::escape(&text)
                ),
            )
        }),
        Err(_) => Ok(physical_memory_once()
            .map_or(FALLBACK_BUDGET, |m| (m as f64 * DEFAULT_MEMORY_SHARE) as u64)),
    }
}

/// [`physical_memory`], read on the first call only: the budget is looked
/// up by every allocation check, thousands of times a second through the
/// Python package's small calls, and reading the control group's file each
/// time cost more than the call itself. An atomic rather than a lock, so a
/// `fork()` at any moment leaves nothing held in the child.
fn physical_memory_once() -> Option<u64> {
    const UNKNOWN: u64 = u64::MAX;
    static PHYSICAL: AtomicU64 = AtomicU64::new(0);
    match PHYSICAL.load(Ordering::Relaxed) {
        0 => {
            let memory = physical_memory();
            PHYSICAL.store(memory.unwrap_or(UNKNOWN), Ordering::Relaxed);
            memory
        }
        UNKNOWN => None,
        memory => Some(memory),
    }
}

/// `1234`, `512M`, `16G`, `1T` (powers of 1024, case-insensitive; an
/// optional trailing `B` or `iB`). None for anything else, for 0, and for
/// sizes that overflow u64.
pub fn parse_bytes(text: &str) -> Option<u64> {
    let t = text.trim();
    let t = t
        .strip_suffix("iB")
        .or_else(|| t.strip_suffix("ib"))
        .or_else(|| t.strip_suffix(['B', 'b']))
        .unwrap_or(t);
    let (digits, shift) = match t.chars().last()? {
        'k' | 'K' => (&t[..t.len() - 1], 10),
        'm' | 'M' => (&t[..t.len() - 1], 20),
        'g' | 'G' => (&t[..t.len() - 1], 30),
        't' | 'T' => (&t[..t.len() - 1], 40),
        _ => (t, 0),
    };
    if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    let n: u64 = digits.parse().ok()?;
    n.checked_mul(1u64 << shift).filter(|&b| b > 0)
}

/// Physical memory in bytes, from the operating system, or the control
/// group's limit when that is lower (a container sees the host's memory).
fn physical_memory() -> Option<u64> {
    let cgroup = std::fs::read_to_string("/sys/fs/cgroup/memory.max")
        .ok()
        .and_then(|t| t.trim().parse::<u64>().ok());
    let machine = machine_memory();
    match (machine, cgroup) {
        (Some(m), Some(c)) => Some(m.min(c)),
        (m, c) => m.or(c),
    }
}

fn machine_memory() -> Option<u64> {
    #[cfg(unix)]
    {
        // SAFETY: sysconf has no preconditions; it returns -1 on error.
        let (pages, page) = unsafe {
            (
                libc::sysconf(libc::_SC_PHYS_PAGES),
                libc::sysconf(libc::_SC_PAGESIZE),
            )
        };
        if pages > 0 && page > 0 {
            return (pages as u64).checked_mul(page as u64);
        }
    }
    None
}

/// Bytes as a short figure: `1.1 PB`, `3.9 GB`, `512 B` (powers of 1000).
pub fn human_bytes(bytes: u64) -> String {
    const UNITS: [&str; 6] = ["kB", "MB", "GB", "TB", "PB", "EB"];
    if bytes < 1000 {
        return format!("{bytes} B");
    }
    let mut v = bytes as f64 / 1000.0;
    let mut unit = 0;
    while v >= 999.95 && unit + 1 < UNITS.len() {
        v /= 1000.0;
        unit += 1;
    }
    format!("{v:.1} {}", UNITS[unit])
}

/// The product of `counts` and `bytes_each`, or None when it overflows.
pub fn product(counts: &[u64], bytes_each: u64) -> Option<u64> {
    counts
        .iter()
        .try_fold(bytes_each, |acc, &c| acc.checked_mul(c))
}

/// Refuses `what` with [`Error::OverBudget`] when its estimated size (None:
/// beyond u64) is above the budget: "WHAT: needs about 1.1 PB, above the
/// memory limit of 3.9 GB (set IRID_MEMORY_LIMIT to change it)". A
/// malformed [`MEMORY_LIMIT_ENV`] is an [`Error::InvalidInput`].
pub fn check_allocation(what: &str, estimate: Option<u64>) -> Result<()> {
    let limit = memory_budget()?;
    match estimate {
        Some(bytes) if bytes <= limit => Ok(()),
        _ => Err(Error::OverBudget {
            what: what.to_string(),
            why: format!(
                "needs about {}, above the memory limit of {} (set {MEMORY_LIMIT_ENV} to change it)",
                estimate.map_or("more than 18 EB".to_string(), human_bytes),
                human_bytes(limit)
            ),
        }),
    }
}

/// The text of the file at `path` (a stack file, a CSV table), refused
/// with [`Error::OverBudget`] when it is larger than the budget: by the
/// size the file system gives, then while reading, for files that give
/// none (a pipe, `/dev/zero`), so that no file can grow the buffer until
/// the allocator aborts. Bytes that are not UTF-8 are malformed content.
pub fn read_text(path: &std::path::Path) -> Result<String> {
    use std::io::Read;
    let limit = memory_budget()?;
    let file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    let what = format!("{}: reading the file", path.display());
    check_allocation(&what, file.metadata().ok().map(|m| m.len()))?;
    let mut bytes = Vec::new();
    file.take(limit.saturating_add(1))
        .read_to_end(&mut bytes)
        .map_err(|e| Error::io(path, e))?;
    if bytes.len() as u64 > limit {
        return Err(Error::OverBudget {
            what,
            why: format!(
                "holds more than the memory limit of {} (set {MEMORY_LIMIT_ENV} to change it)",
                human_bytes(limit)
            ),
        });
    }
    String::from_utf8(bytes).map_err(|e| {
        Error::malformed(
            path,
            format!(
                "not UTF-8 text (byte {} is not)",
                e.utf8_error().valid_up_to()
            ),
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_parse_with_binary_suffixes() {
        assert_eq!(parse_bytes("1234"), Some(1234));
        assert_eq!(parse_bytes("512M"), Some(512 << 20));
        assert_eq!(parse_bytes("16g"), Some(16 << 30));
        assert_eq!(parse_bytes(" 2GiB "), Some(2 << 30));
        assert_eq!(parse_bytes("3KB"), Some(3 << 10));
        for bad in ["", "G", "-1", "1.5G", "0", "1X", "99999999999T", "１"] {
            assert_eq!(parse_bytes(bad), None, "{bad:?}");
        }
    }

    #[test]
    fn byte_figures_are_short() {
        assert_eq!(human_bytes(512), "512 B");
        assert_eq!(human_bytes(1_100_000_000_000_000), "1.1 PB");
        assert_eq!(human_bytes(3_900_000_000), "3.9 GB");
        assert_eq!(human_bytes(u64::MAX), "18.4 EB");
    }

    #[test]
    fn text_files_are_read_within_the_budget() {
        let dir = std::env::temp_dir().join(format!("irid-read-text-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let small = dir.join("small.toml");
        std::fs::write(&small, "ambient = 1\n").unwrap();
        assert_eq!(read_text(&small).unwrap(), "ambient = 1\n");
        let binary = dir.join("binary.toml");
        std::fs::write(&binary, b"ok\xff").unwrap();
        let e = read_text(&binary).unwrap_err().to_string();
        assert!(e.ends_with("not UTF-8 text (byte 2 is not)"), "{e}");
        assert!(matches!(
            read_text(&dir.join("none")),
            Err(Error::Io { .. })
        ));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn products_overflow_to_none() {
        assert_eq!(product(&[1 << 24, 1 << 24], 4), Some(1 << 50));
        assert_eq!(product(&[1 << 32, 1 << 32], 1), None);
        assert_eq!(product(&[], 8), Some(8));
    }
}
