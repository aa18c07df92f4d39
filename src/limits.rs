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
/// else [`DEFAULT_MEMORY_SHARE`] of physical memory (or of the control
/// group's limit when lower); in every case no more than the address space
/// the process has left under its `RLIMIT_AS` ([`address_space_left`]).
pub fn memory_budget() -> Result<u64> {
    Ok(budget_and_hint()?.0)
}

/// [`memory_budget`] and what to do to raise it, for the message refusing
/// an allocation.
fn budget_and_hint() -> Result<(u64, &'static str)> {
    let set = OVERRIDE.load(Ordering::Relaxed);
    let chosen = if set > 0 {
        set
    } else {
        match std::env::var(MEMORY_LIMIT_ENV) {
            Ok(text) => parse_bytes(&text).ok_or_else(|| {
                Error::invalid(
                    MEMORY_LIMIT_ENV,
                    format!(
                        "'{}' is not a size in bytes (a positive integer, optionally followed by K, M, G or T)",
                        crate::error::escape(&text)
                    ),
                )
            })?,
            Err(_) => physical_memory_once()
                .map_or(FALLBACK_BUDGET, |m| (m as f64 * DEFAULT_MEMORY_SHARE) as u64),
        }
    };
    Ok(match address_space_left() {
        Some(left) if left < chosen => (
            left.max(1),
            "what the process's address-space limit, ulimit -v, leaves free",
        ),
        _ => (chosen, "set IRID_MEMORY_LIMIT to change it"),
    })
}

/// The share of the address space left under `RLIMIT_AS` that the budget
/// allows: the rest is headroom for what the estimates leave out (the
/// allocator's per-thread arenas reserve address space, not memory).
const ADDRESS_SPACE_SHARE: f64 = 0.75;

/// [`ADDRESS_SPACE_SHARE`] of what the process may still map under its
/// `RLIMIT_AS` (`ulimit -v`, `prlimit --as`): the limit less the address
/// space mapped now (`/proc/self/statm`). None without such a limit. Read
/// at every call, unlike the machine's memory: the mapped size changes as
/// the process runs, and a process without the limit pays one system call.
fn address_space_left() -> Option<u64> {
    #[cfg(target_os = "linux")]
    {
        let mut limit = libc::rlimit {
            rlim_cur: 0,
            rlim_max: 0,
        };
        // SAFETY: getrlimit writes the struct it is given and nothing else.
        if unsafe { libc::getrlimit(libc::RLIMIT_AS, &mut limit) } != 0
            || limit.rlim_cur == libc::RLIM_INFINITY
        {
            return None;
        }
        let limit = limit.rlim_cur;
        let mapped = std::fs::read_to_string("/proc/self/statm")
            .ok()
            .and_then(|t| t.split_whitespace().next()?.parse::<u64>().ok())
            .and_then(|pages| pages.checked_mul(page_size()?))
            .unwrap_or(0);
        Some((limit.saturating_sub(mapped) as f64 * ADDRESS_SPACE_SHARE) as u64)
    }
    #[cfg(not(target_os = "linux"))]
    {
        None
    }
}

#[cfg(unix)]
fn page_size() -> Option<u64> {
    // SAFETY: sysconf has no preconditions; it returns -1 on error.
    let page = unsafe { libc::sysconf(libc::_SC_PAGESIZE) };
    (page > 0).then_some(page as u64)
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

/// Physical memory in bytes, from the operating system, or the lowest
/// memory limit of the control groups the process is in when lower (a
/// container sees the host's memory).
fn physical_memory() -> Option<u64> {
    let groups = std::fs::read_to_string("/proc/self/cgroup").unwrap_or_default();
    [
        machine_memory(),
        cgroup_limit(&groups, std::path::Path::new("/sys/fs/cgroup")),
    ]
    .into_iter()
    .flatten()
    .min()
}

/// The lowest memory limit on the control groups listed in `groups` (the
/// text of `/proc/self/cgroup`) and their ancestors, under the hierarchy
/// mounted at `root`: v2's `memory.max` ("max": none), v1's
/// `memory/…/memory.limit_in_bytes` (a figure near 2⁶³: none). Also the
/// root's own files, which is where a container sees its own group.
fn cgroup_limit(groups: &str, root: &std::path::Path) -> Option<u64> {
    let mut files = vec![
        root.join("memory.max"),
        root.join("memory/memory.limit_in_bytes"),
    ];
    for line in groups.lines() {
        let mut fields = line.splitn(3, ':');
        let (Some(_), Some(controllers), Some(path)) =
            (fields.next(), fields.next(), fields.next())
        else {
            continue;
        };
        let (base, file) = if controllers.is_empty() {
            (root.to_path_buf(), "memory.max")
        } else if controllers.split(',').any(|c| c == "memory") {
            (root.join("memory"), "memory.limit_in_bytes")
        } else {
            continue;
        };
        let mut dir = base.join(path.trim_start_matches('/'));
        while dir.starts_with(&base) {
            files.push(dir.join(file));
            if !dir.pop() {
                break;
            }
        }
    }
    files
        .iter()
        .filter_map(|f| std::fs::read_to_string(f).ok()?.trim().parse::<u64>().ok())
        .min()
}

fn machine_memory() -> Option<u64> {
    #[cfg(unix)]
    {
        // SAFETY: sysconf has no preconditions; it returns -1 on error.
        let pages = unsafe { libc::sysconf(libc::_SC_PHYS_PAGES) };
        if pages > 0 {
            return (pages as u64).checked_mul(page_size()?);
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
    let (limit, hint) = budget_and_hint()?;
    match estimate {
        Some(bytes) if bytes <= limit => Ok(()),
        _ => Err(Error::OverBudget {
            what: what.to_string(),
            why: format!(
                "needs about {}, above the memory limit of {} ({hint})",
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
    let (limit, hint) = budget_and_hint()?;
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
                "holds more than the memory limit of {} ({hint})",
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
    fn the_lowest_control_group_limit_counts() {
        let root = std::env::temp_dir().join(format!("irid-cgroup-{}", std::process::id()));
        let write = |path: &str, text: &str| {
            let file = root.join(path);
            std::fs::create_dir_all(file.parent().unwrap()).unwrap();
            std::fs::write(file, text).unwrap();
        };
        // v2: the job's group allows more than its parent, which counts.
        write("user.slice/memory.max", "3000000\n");
        write("user.slice/job/memory.max", "max\n");
        write("user.slice/job/task/memory.max", "5000000\n");
        assert_eq!(
            cgroup_limit("0::/user.slice/job/task\n", &root),
            Some(3_000_000)
        );
        assert_eq!(cgroup_limit("0::/elsewhere\n", &root), None);
        // v1: the memory controller's hierarchy; "unlimited" is a figure
        // near 2^63 that the machine's memory undercuts.
        write("memory/docker/abc/memory.limit_in_bytes", "2000000\n");
        let v1 = "12:cpu,cpuacct:/docker/abc\n4:memory:/docker/abc\n";
        assert_eq!(cgroup_limit(v1, &root), Some(2_000_000));
        std::fs::remove_dir_all(&root).unwrap();
    }

    #[test]
    fn products_overflow_to_none() {
        assert_eq!(product(&[1 << 24, 1 << 24], 4), Some(1 << 50));
        assert_eq!(product(&[1 << 32, 1 << 32], 1), None);
        assert_eq!(product(&[], 8), Some(8));
    }
}
