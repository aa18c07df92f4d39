//! Argument forms shared by several subcommands.

use std::fmt::Display;
use std::path::PathBuf;

use anyhow::{anyhow, bail, Result};
use irid::lut::DEFAULT_COS_MIN;
use irid::optics::Stack;

/// The options `irid bake` and `irid export` share word for word: the stack
/// file, its varying layer and the angle range. (`--thickness`,
/// `--sampling`, `--white` and `--max-error` are alike but their help
/// differs between the two: each names what it means for its output.)
#[derive(clap::Args)]
pub struct FilmArgs {
    /// Stack file (TOML).
    pub stack: PathBuf,
    /// The varying layer, counted from 1 at the ambient side.
    #[arg(long, default_value_t = 1)]
    pub layer: usize,
    /// cos θ range COS_MIN:COS_MAX in the ambient [default: 0:1, every
    /// angle; cos 89°:1 for a grid table].
    #[arg(long)]
    pub angles: Option<String>,
}

impl FilmArgs {
    /// The varying layer's thickness in the stack file, the thickness range
    /// when `--thickness` is not given; `None` when `--layer` names no layer
    /// (the spec's check then says so).
    pub fn layer_thickness_nm(&self, stack: &Stack) -> Option<f64> {
        stack
            .layers
            .get(self.layer.wrapping_sub(1))
            .map(|layer| layer.thickness_nm)
    }

    /// The thickness range of the varying layer: `--thickness` when given,
    /// else the layer's own thickness in the stack file; `None` when neither
    /// applies (the spec's default and its check then stand).
    pub fn thickness_nm(
        &self,
        stack: &Stack,
        thickness: Option<&str>,
    ) -> Result<Option<(f64, f64)>> {
        match thickness {
            Some(t) => parse_range("--thickness", t).map(Some),
            None => Ok(self.layer_thickness_nm(stack).map(|t| (t, t))),
        }
    }

    /// `--angles`, or when not given every angle (0 to 1) for an atlas and
    /// cos 89° to 1 for a grid, which no error target reaches at grazing
    /// incidence near zero thickness.
    pub fn cos_theta(&self, grid: bool) -> Result<(f64, f64)> {
        match &self.angles {
            Some(a) => parse_range("--angles", a),
            None if grid => Ok((DEFAULT_COS_MIN, 1.0)),
            None => Ok((0.0, 1.0)),
        }
    }
}

/// A named choice (`--sampling`, `--white`, `--kind`): the value's own
/// parser, whose error begins with the flag's name.
pub fn parse_choice<T: std::str::FromStr>(text: &str) -> Result<T>
where
    T::Err: Display,
{
    text.parse().map_err(|e| anyhow!("--{e}"))
}

/// One number of `spec`, which must be finite; errors name the flag and spec.
fn number(flag: &str, spec: &str, text: &str) -> Result<f64> {
    let text = text.trim();
    let v: f64 = text
        .parse()
        .map_err(|_| anyhow!("{flag} '{spec}': '{text}' is not a number"))?;
    if !v.is_finite() {
        bail!("{flag} '{spec}': '{text}' is not finite");
    }
    Ok(v)
}

/// Parses a list of numbers: `a,b,c`, or an inclusive `start:end:step`
/// (the end is included when it lies on the grid, to a tolerance of 1e-9 step).
pub fn parse_list(flag: &str, spec: &str) -> Result<Vec<f64>> {
    let bad = |why: &str| anyhow!("{flag} '{spec}': {why}");
    let spec_trim = spec.trim();
    if spec_trim.is_empty() {
        return Err(bad("empty list"));
    }
    if !spec_trim.contains(':') {
        return spec_trim
            .split(',')
            .map(|s| number(flag, spec, s))
            .collect();
    }
    let parts: Vec<&str> = spec_trim.split(':').collect();
    let [start, end, step] = parts[..] else {
        return Err(bad("a range is start:end:step"));
    };
    let num = |s| number(flag, spec, s);
    let (start, end, step) = (num(start)?, num(end)?, num(step)?);
    if step <= 0.0 {
        return Err(bad("step must be > 0"));
    }
    if end < start {
        return Err(bad("end is before start"));
    }
    let count = ((end - start) / step + 1e-9).floor() as u64 + 1;
    if count > MAX_GRID_POINTS as u64 {
        return Err(bad(&format!("more than {MAX_GRID_POINTS} values")));
    }
    Ok((0..count).map(|i| start + i as f64 * step).collect())
}

/// Parses a `min:max` range with min ≤ max.
pub fn parse_range(flag: &str, spec: &str) -> Result<(f64, f64)> {
    let parts: Vec<&str> = spec.split(':').collect();
    let [lo, hi] = parts[..] else {
        bail!("{flag} '{spec}': expected min:max");
    };
    let (lo, hi) = (number(flag, spec, lo)?, number(flag, spec, hi)?);
    if lo > hi {
        bail!("{flag} '{spec}': need min ≤ max");
    }
    Ok((lo, hi))
}

/// Fails unless 1 ≤ `value` ≤ `max`, naming the flag, the limit and the value.
pub fn check_count<T: PartialOrd + From<u8> + Display>(flag: &str, value: T, max: T) -> Result<()> {
    if value < T::from(1) || value > max {
        bail!("{flag} must be between 1 and {max}, got {value}");
    }
    Ok(())
}

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

/// Checks that every angle lies in [0, 90) degrees.
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
        for bad in ["5:1", "1", "1:2:3", "0:inf", "a:1"] {
            assert!(parse_range("--t", bad).is_err(), "{bad}");
        }
        assert_eq!(
            parse_list("--x", "1,inf").unwrap_err().to_string(),
            "--x '1,inf': 'inf' is not finite"
        );
        assert!(check_count("--n", 1usize, 4).is_ok() && check_count("--n", 4u32, 4).is_ok());
        for n in [0, 5] {
            assert_eq!(
                check_count("--n", n, 4).unwrap_err().to_string(),
                format!("--n must be between 1 and 4, got {n}")
            );
        }
        assert!(check_angles("--a", &[0.0, 89.9]).is_ok());
        assert!(check_angles("--a", &[90.0]).is_err());
        assert!(check_angles("--a", &[-1.0]).is_err());
    }
}
