//! The measured-spectrum file of `irid fit --spectrum`: CSV with a header
//! naming its columns, `wavelength_nm`, `angle_deg`, `R` and/or `T`, and
//! optionally `sigma` (any order); `#` starts a comment line.

use std::path::Path;

use super::spectrum::Measurement;
use crate::error::{Error, Result};

const COLUMNS: [&str; 5] = ["wavelength_nm", "angle_deg", "R", "T", "sigma"];

/// Reads and checks a spectrum file. Errors name the file and the line.
pub fn read_spectrum_csv(path: &Path) -> Result<Measurement> {
    let text = crate::limits::read_text(path)?;
    parse_spectrum_csv(&text, path)
}

/// Parses spectrum-file text; `origin` names it in errors.
pub fn parse_spectrum_csv(text: &str, origin: &Path) -> Result<Measurement> {
    let bad = |line: usize, why: String| Error::malformed(origin, format!("line {line}: {why}"));
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim()))
        .filter(|(_, l)| !l.is_empty() && !l.starts_with('#'));
    let Some((header_line, header)) = lines.next() else {
        return Err(Error::malformed(origin, "empty: no header line"));
    };
    let names: Vec<&str> = header.split(',').map(str::trim).collect();
    let mut index = [None; 5];
    for (i, name) in names.iter().enumerate() {
        let Some(c) = COLUMNS.iter().position(|c| c == name) else {
            return Err(bad(
                header_line,
                format!("unknown column '{name}' (columns: {})", COLUMNS.join(", ")),
            ));
        };
        if index[c].replace(i).is_some() {
            return Err(bad(header_line, format!("column '{name}' appears twice")));
        }
    }
    for required in [0, 1] {
        if index[required].is_none() {
            return Err(bad(
                header_line,
                format!("missing column '{}'", COLUMNS[required]),
            ));
        }
    }
    if index[2].is_none() && index[3].is_none() {
        return Err(bad(
            header_line,
            "missing column 'R' or 'T' (one at least)".into(),
        ));
    }
    let mut columns: [Vec<f64>; 5] = Default::default();
    for (line, text) in lines {
        let fields: Vec<&str> = text.split(',').map(str::trim).collect();
        if fields.len() != names.len() {
            return Err(bad(
                line,
                format!("{} fields for {} columns", fields.len(), names.len()),
            ));
        }
        for (c, column) in columns.iter_mut().enumerate() {
            let Some(i) = index[c] else { continue };
            let v: f64 = fields[i].parse().map_err(|_| {
                bad(
                    line,
                    format!("{}: '{}' is not a number", COLUMNS[c], fields[i]),
                )
            })?;
            check_value(c, v).map_err(|why| bad(line, format!("{}: {v} {why}", COLUMNS[c])))?;
            column.push(v);
        }
    }
    if columns[0].is_empty() {
        return Err(Error::malformed(origin, "no data rows after the header"));
    }
    let [wavelength_nm, angle_deg, r, t, sigma] = columns;
    let present = |c: usize, v: Vec<f64>| index[c].map(|_| v);
    Ok(Measurement {
        wavelength_nm,
        angle_deg,
        reflectance: present(2, r),
        transmittance: present(3, t),
        sigma: present(4, sigma),
    })
}

fn check_value(column: usize, v: f64) -> std::result::Result<(), &'static str> {
    let (lo, hi) = crate::optics::WAVELENGTH_RANGE_NM;
    let ok = match column {
        0 => (lo..=hi).contains(&v),
        1 => (0.0..90.0).contains(&v),
        4 => v > 0.0 && v.is_finite(),
        _ => v.is_finite(),
    };
    if ok {
        return Ok(());
    }
    Err(match column {
        0 if v.is_finite() && v <= 0.0 => "is not a positive wavelength",
        0 => "is outside 1e-3–1e9 nm",
        1 => "is outside [0, 90) degrees",
        4 => "is not a finite number > 0",
        _ => "is not a finite number",
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Measurement> {
        parse_spectrum_csv(text, Path::new("m.csv"))
    }

    #[test]
    fn columns_in_any_order_with_comments() {
        let m = parse("# measured\nangle_deg, R, wavelength_nm, sigma\n0, 0.04, 500, 1e-3\n\n10,0.05,510,2e-3\n")
            .unwrap();
        assert_eq!(m.wavelength_nm, vec![500.0, 510.0]);
        assert_eq!(m.angle_deg, vec![0.0, 10.0]);
        assert_eq!(m.reflectance, Some(vec![0.04, 0.05]));
        assert_eq!(m.transmittance, None);
        assert_eq!(m.sigma, Some(vec![1e-3, 2e-3]));
    }

    #[test]
    fn each_fault_is_named() {
        for (text, want) in [
            ("", "m.csv: empty: no header line"),
            ("wavelength_nm,R\n500,0.1", "m.csv: line 1: missing column 'angle_deg'"),
            ("wavelength_nm,angle_deg\n500,0", "m.csv: line 1: missing column 'R' or 'T' (one at least)"),
            ("wavelength_nm,angle_deg,X\n", "m.csv: line 1: unknown column 'X' (columns: wavelength_nm, angle_deg, R, T, sigma)"),
            ("wavelength_nm,angle_deg,R,R\n", "m.csv: line 1: column 'R' appears twice"),
            ("wavelength_nm,angle_deg,R\n", "m.csv: no data rows after the header"),
            ("wavelength_nm,angle_deg,R\n500,0,NaN", "m.csv: line 2: R: NaN is not a finite number"),
            ("wavelength_nm,angle_deg,R\n-500,0,0.1", "m.csv: line 2: wavelength_nm: -500 is not a positive wavelength"),
            ("wavelength_nm,angle_deg,R\n500,90,0.1", "m.csv: line 2: angle_deg: 90 is outside [0, 90) degrees"),
            ("wavelength_nm,angle_deg,R\n500,-1,0.1", "m.csv: line 2: angle_deg: -1 is outside [0, 90) degrees"),
            ("wavelength_nm,angle_deg,R,sigma\n500,0,0.1,0", "m.csv: line 2: sigma: 0 is not a finite number > 0"),
            ("wavelength_nm,angle_deg,R\n500,0", "m.csv: line 2: 2 fields for 3 columns"),
            ("wavelength_nm,angle_deg,R\n500,0,x", "m.csv: line 2: R: 'x' is not a number"),
        ] {
            assert_eq!(parse(text).unwrap_err().to_string(), want, "{text}");
        }
    }
}
