//! The facts every report header carries: when, on what, with how many cores
//! and worker threads.

use std::time::{SystemTime, UNIX_EPOCH};

/// The machine a benchmark ran on, as a report header states it.
#[derive(Clone, Debug)]
pub struct Machine {
    /// The first `model name` of /proc/cpuinfo, or "unknown" where there
    /// is none (not Linux, or no such line).
    pub cpu_model: String,
    /// Logical CPUs the process may use.
    pub cores: usize,
    /// Workers of the rayon pool `current` was called in: the run's own
    /// pool, so what the bakes and renders actually ran on.
    pub threads: usize,
    /// UTC, `YYYY-MM-DD HH:MM`.
    pub date_utc: String,
}

impl Machine {
    /// The facts now: call it from inside the run's rayon pool so `threads`
    /// counts that pool's workers.
    pub fn current() -> Machine {
        Machine {
            cpu_model: cpu_model().unwrap_or_else(|| "unknown".to_string()),
            cores: std::thread::available_parallelism()
                .map(|n| n.get())
                .unwrap_or(1),
            threads: rayon::current_num_threads(),
            date_utc: utc_now(),
        }
    }

    /// One line for a report header.
    pub fn summary(&self) -> String {
        format!(
            "{} logical cores, CPU {}, {} worker thread(s), {} UTC",
            self.cores, self.cpu_model, self.threads, self.date_utc
        )
    }
}

fn cpu_model() -> Option<String> {
    let info = std::fs::read_to_string("/proc/cpuinfo").ok()?;
    info.lines()
        .find(|l| l.starts_with("model name"))
        .and_then(|l| l.split_once(':'))
        .map(|(_, v)| v.trim().to_string())
}

fn utc_now() -> String {
    let secs = SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map(|d| d.as_secs() as i64)
        .unwrap_or(0);
    let (y, m, d) = civil_from_days(secs.div_euclid(86_400));
    let s = secs.rem_euclid(86_400);
    format!("{y:04}-{m:02}-{d:02} {:02}:{:02}", s / 3600, (s / 60) % 60)
}

/// Days since 1970-01-01 to a proleptic Gregorian date (H. Hinnant's
/// algorithm: eras of 400 years, March-based years so leap days come last).
fn civil_from_days(days: i64) -> (i64, u32, u32) {
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = (doy - (153 * mp + 2) / 5 + 1) as u32;
    let m = if mp < 10 { mp + 3 } else { mp - 9 } as u32;
    let y = yoe + era * 400 + i64::from(m <= 2);
    (y, m, d)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn civil_dates() {
        assert_eq!(civil_from_days(0), (1970, 1, 1));
        assert_eq!(civil_from_days(11_016), (2000, 2, 29));
        assert_eq!(civil_from_days(20_597), (2026, 5, 24));
        assert_eq!(civil_from_days(-1), (1969, 12, 31));
    }
}
