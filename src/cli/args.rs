//! Argument forms shared by several subcommands.

use anyhow::{bail, Context, Result};

/// Parses a list of numbers: `a,b,c`, or an inclusive `start:end:step`
/// (the end is included when it lies on the grid, to a tolerance of 1e-9 step).
pub fn parse_list(flag: &str, spec: &str) -> Result<Vec<f64>> {
    let bad = |why: &str| anyhow::anyhow!("{flag} '{spec}': {why}");
    let spec_trim = spec.trim();
    if spec_trim.is_empty() {
        return Err(bad("empty list"));
    }
    let values = if spec_trim.contains(':') {
        let parts: Vec<&str> = spec_trim.split(':').collect();
        if parts.len() != 3 {
            return Err(bad("a range is start:end:step"));
        }
        let num = |s: &str| -> Result<f64> {
            let v: f64 = s
                .trim()
                .parse()
                .map_err(|_| bad(&format!("'{s}' is not a number")))?;
            if !v.is_finite() {
                return Err(bad(&format!("'{s}' is not finite")));
            }
            Ok(v)
        };
        let (start, end, step) = (num(parts[0])?, num(parts[1])?, num(parts[2])?);
        if step <= 0.0 {
            return Err(bad("step must be > 0"));
        }
        if end < start {
            return Err(bad("end is before start"));
        }
        let count = ((end - start) / step + 1e-9).floor() as u64 + 1;
        if count > 10_000_000 {
            return Err(bad("more than 10 million values"));
        }
        (0..count).map(|i| start + i as f64 * step).collect()
    } else {
        spec_trim
            .split(',')
            .map(|s| {
                let v: f64 = s
                    .trim()
                    .parse()
                    .map_err(|_| bad(&format!("'{}' is not a number", s.trim())))?;
                if !v.is_finite() {
                    return Err(bad(&format!("'{}' is not finite", s.trim())));
                }
                Ok(v)
            })
            .collect::<Result<Vec<f64>>>()?
    };
    Ok(values)
}

/// Parses a `min:max` range with min ≤ max.
pub fn parse_range(flag: &str, spec: &str) -> Result<(f64, f64)> {
    let parts: Vec<&str> = spec.split(':').collect();
    if parts.len() != 2 {
        bail!("{flag} '{spec}': expected min:max");
    }
    let lo: f64 = parts[0]
        .trim()
        .parse()
        .with_context(|| format!("{flag} '{spec}': '{}' is not a number", parts[0]))?;
    let hi: f64 = parts[1]
        .trim()
        .parse()
        .with_context(|| format!("{flag} '{spec}': '{}' is not a number", parts[1]))?;
    if !(lo.is_finite() && hi.is_finite()) || lo > hi {
        bail!("{flag} '{spec}': need finite min ≤ max");
    }
    Ok((lo, hi))
}

/// Checks that every angle lies in [0, 90) degrees.
/// The most (wavelength, angle[, thickness]) points one command evaluates:
/// the responses are kept in memory, and an absurd grid aborted on
/// allocation instead of failing.
pub const MAX_GRID_POINTS: usize = 10_000_000;

/// Fails when the product of `counts` exceeds [`MAX_GRID_POINTS`]; `what`
/// names the flags that set them.
pub fn check_grid(what: &str, counts: &[usize]) -> Result<()> {
    let points = counts.iter().try_fold(1usize, |n, c| n.checked_mul(*c));
    match points {
        Some(n) if n <= MAX_GRID_POINTS => Ok(()),
        _ => bail!(
            "{what}: {} points, at most {MAX_GRID_POINTS}",
            points.map_or("too many".to_string(), |n| n.to_string())
        ),
    }
}

pub fn check_angles(flag: &str, angles_deg: &[f64]) -> Result<()> {
    if let Some(a) = angles_deg.iter().find(|a| !(**a >= 0.0 && **a < 90.0)) {
        bail!("{flag}: angle {a} is outside [0, 90) degrees");
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lists_and_ranges() {
        assert_eq!(parse_list("--x", "1,2.5, 3").unwrap(), vec![1.0, 2.5, 3.0]);
        assert_eq!(
            parse_list("--x", "380:780:100").unwrap(),
            vec![380.0, 480.0, 580.0, 680.0, 780.0]
        );
        assert_eq!(parse_list("--x", "0:1:0.1").unwrap().len(), 11);
        assert_eq!(
            parse_list("--x", "0:10:3").unwrap(),
            vec![0.0, 3.0, 6.0, 9.0]
        );
        for bad in [
            "", "a", "1,,2", "1:2", "1:2:0", "2:1:1", "1:2:-1", "nan", "1,inf",
        ] {
            assert!(parse_list("--x", bad).is_err(), "{bad}");
        }
        assert_eq!(parse_range("--t", "0:1000").unwrap(), (0.0, 1000.0));
        assert!(parse_range("--t", "5:1").is_err());
        assert!(check_angles("--a", &[0.0, 89.9]).is_ok());
        assert!(check_angles("--a", &[90.0]).is_err());
        assert!(check_angles("--a", &[-1.0]).is_err());
    }
}
