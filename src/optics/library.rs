//! The built-in materials, by name (case-insensitive): `air`, `water`,
//! `soap`, `fused-silica`, `TiO2`, `MgF2`, `sapphire`, `gold`, `silver`,
//! `aluminium`, `copper`, plus a few aliases (chemical formulas, `aluminum`,
//! `soap-film`, `silica`).
//!
//! The lossless dielectrics are published dispersion fits, typed in here
//! with their sources; the metals and TiO2 are measured n, k tables,
//! extracted by `tools/gen/extract_materials.py` into `tools/gen/data/*.csv` and
//! generated into `library_data.rs` by `tools/gen/gen_materials.py`. Every fit
//! here was made over a range that covers the bakers' 360–830 nm (given
//! with each source); beyond it a formula extrapolates. Tables end where
//! their data ends, and asking beyond it is an error naming the material.

use super::library_data;
use super::material::{Dispersion, IndexTable, Material};

/// A tabulated material as stored in the generated data file.
pub(super) struct TableData {
    pub source: &'static str,
    pub wavelength_nm: &'static [f64],
    pub n: &'static [f64],
    pub k: &'static [f64],
}

/// The canonical names, in the order `irid` lists them.
pub fn names() -> &'static [&'static str] {
    &[
        "air",
        "water",
        "soap",
        "fused-silica",
        "TiO2",
        "MgF2",
        "sapphire",
        "gold",
        "silver",
        "aluminium",
        "copper",
    ]
}

/// The built-in material called `name` (case-insensitive), or `None`.
pub fn builtin(name: &str) -> Option<Material> {
    let key = name.trim().to_ascii_lowercase();
    let (canonical, dispersion) = match key.as_str() {
        "air" => ("air", air()),
        "water" | "h2o" => ("water", water()),
        "soap" | "soap-film" => ("soap", water()),
        "fused-silica" | "silica" | "sio2" => ("fused-silica", fused_silica()),
        "tio2" => ("TiO2", table(&library_data::TITANIA)),
        "mgf2" => ("MgF2", magnesium_fluoride()),
        "sapphire" | "al2o3" => ("sapphire", sapphire()),
        "gold" | "au" => ("gold", table(&library_data::GOLD)),
        "silver" | "ag" => ("silver", table(&library_data::SILVER)),
        "aluminium" | "aluminum" | "al" => ("aluminium", table(&library_data::ALUMINIUM)),
        "copper" | "cu" => ("copper", table(&library_data::COPPER)),
        _ => return None,
    };
    Some(Material {
        name: canonical.to_string(),
        dispersion,
    })
}

fn table(data: &TableData) -> Dispersion {
    Dispersion::Table(IndexTable {
        source: data.source.to_string(),
        wavelength_nm: data.wavelength_nm.to_vec(),
        n: data.n.to_vec(),
        k: data.k.to_vec(),
    })
}

/// Sellmeier terms from (B, C) pairs with C in µm² (the fit's own form).
fn sellmeier(a: f64, terms: &[(f64, f64)]) -> Dispersion {
    Dispersion::Sellmeier {
        a,
        b: terms.iter().map(|t| t.0).collect(),
        c: terms.iter().map(|t| t.1).collect(),
    }
}

/// Sellmeier terms from (B, λᵢ) pairs with the resonance λᵢ in µm, as
/// Malitson and Dodge publish them: C = λᵢ².
fn sellmeier_resonances(terms: &[(f64, f64)]) -> Dispersion {
    let squared: Vec<(f64, f64)> = terms.iter().map(|&(b, l)| (b, l * l)).collect();
    sellmeier(1.0, &squared)
}

/// Standard dry air (15 °C, 101 325 Pa, 450 ppm CO2): P. E. Ciddor,
/// "Refractive index of air: new equations for the visible and near
/// infrared", Appl. Opt. 35, 1566–1573 (1996), eq. (1):
/// n − 1 = 0.05792105/(238.0185 − λ⁻²) + 0.00167917/(57.362 − λ⁻²), λ in µm,
/// valid 0.23–1.69 µm. Each term B/(C − λ⁻²) is (B/C) λ²/(λ² − 1/C), and
/// n² = 1 + 2(n − 1) + (n − 1)²: a Sellmeier form for n² with the small
/// (n − 1)² term taken at 550 nm (7.72·10⁻⁸) into the constant. That
/// reproduces Ciddor's n to 4·10⁻⁹ over 0.3–0.85 µm and 10⁻⁸ over
/// 0.23–1.69 µm (tools/crosscheck/crosscheck_materials.py compares).
fn air() -> Dispersion {
    let terms = [(0.05792105, 238.0185), (0.00167917, 57.362)];
    sellmeier(
        1.0 + 7.719_375e-8,
        &terms.map(|(b, c): (f64, f64)| (2.0 * b / c, 1.0 / c)),
    )
}

/// Distilled water at 20.0 °C: M. Daimon and A. Masumura, "Measurement of
/// the refractive index of distilled water from the near-infrared region to
/// the ultraviolet region", Appl. Opt. 46, 3811–3820 (2007), four-term
/// Sellmeier fit, valid 0.182–1.129 µm. Also used for `soap`: a soap film is
/// water with a little surfactant, and the thin-film rendering literature
/// models it with water's index (n ≈ 1.33).
fn water() -> Dispersion {
    sellmeier(
        1.0,
        &[
            (5.684027565e-1, 5.101829712e-3),
            (1.726177391e-1, 1.821153936e-2),
            (2.086189578e-2, 2.620722293e-2),
            (1.130748688e-1, 1.069792721e1),
        ],
    )
}

/// Fused silica at 20 °C: I. H. Malitson, "Interspecimen comparison of the
/// refractive index of fused silica", J. Opt. Soc. Am. 55, 1205–1209 (1965),
/// valid 0.21–3.71 µm.
fn fused_silica() -> Dispersion {
    sellmeier_resonances(&[
        (0.6961663, 0.0684043),
        (0.4079426, 0.1162414),
        (0.8974794, 9.896161),
    ])
}

/// MgF2 at 19 °C, ordinary ray: M. J. Dodge, "Refractive properties of
/// magnesium fluoride", Appl. Opt. 23, 1980–1985 (1984), valid 0.2–7.0 µm.
fn magnesium_fluoride() -> Dispersion {
    sellmeier_resonances(&[
        (0.48755108, 0.04338408),
        (0.39875031, 0.09461442),
        (2.3120353, 23.793604),
    ])
}

/// Synthetic sapphire (α-Al2O3) at 20 °C, ordinary ray: I. H. Malitson and
/// M. J. Dodge, "Refractive index and birefringence of synthetic sapphire",
/// J. Opt. Soc. Am. 62, 1405 (1972), with the dispersion formula in M. J.
/// Dodge, Handbook of Laser Science and Technology IV, CRC Press (1986),
/// p. 30; valid 0.2–5.0 µm.
fn sapphire() -> Dispersion {
    sellmeier_resonances(&[
        (1.4313493, 0.0726631),
        (0.65054713, 0.1193242),
        (5.3414021, 18.028251),
    ])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Reference values computed independently from each publication's
    /// formula or table (the table values are the papers' own rows).
    #[test]
    fn known_values() {
        let cases: &[(&str, f64, f64, f64)] = &[
            // name, wavelength nm, n, k
            ("fused-silica", 587.6, 1.458_464, 0.0), // Malitson's n_d
            ("water", 589.3, 1.333_3, 0.0),
            ("sapphire", 587.6, 1.768, 0.0),
            ("MgF2", 587.6, 1.3777, 0.0),
            // TiO2: Siefke et al.'s rows at 585.2 and 588.6 nm
            ("TiO2", 587.6, 2.4116, 1.1e-8),
            ("air", 550.0, 1.000_277_84, 0.0), // Ciddor: 1.000277838
            ("gold", 548.6, 0.43, 2.455),
            ("silver", 495.9, 0.05, 3.093),
            ("copper", 659.5, 0.22, 3.747),
        ];
        for &(name, wl, n, k) in cases {
            let got = builtin(name).unwrap().index_at(wl).unwrap();
            let tol = if name == "air" { 1e-8 } else { 2e-3 };
            assert!(
                (got.re - n).abs() < tol && (got.im - k).abs() < 1e-9,
                "{name} at {wl} nm: {got} vs {n}+{k}i"
            );
        }
    }

    /// TiO2 absorbs at the violet end the bakers integrate: at 380 nm Siefke
    /// et al. give k ≈ 0.004 (the two rows around it in tools/gen/data/tio2.csv,
    /// interpolated), where the lossless DeVore fit it replaces gave 0 and
    /// was only fitted from 430 nm.
    #[test]
    fn titania_absorbs_where_its_source_says() {
        let tio2 = builtin("TiO2").unwrap();
        let rows = [
            (377.8647, 2.786287, 0.004898981),
            (380.04613, 2.7734118, 0.003973052),
        ];
        let t = (380.0 - rows[0].0) / (rows[1].0 - rows[0].0);
        let got = tio2.index_at(380.0).unwrap();
        assert!((got.re - (rows[0].1 + t * (rows[1].1 - rows[0].1))).abs() < 1e-12);
        assert!((got.im - (rows[0].2 + t * (rows[1].2 - rows[0].2))).abs() < 1e-12);
        assert!((got.im - 0.003_993).abs() < 1e-6, "{got}");
        // The absorption edge: k falls through the violet, and is negligible
        // across the rest of the visible.
        let k = |wl: f64| tio2.index_at(wl).unwrap().im;
        assert!(k(360.0) > 0.02 && k(360.0) > k(380.0) && k(380.0) > k(400.0));
        assert!(k(400.0) > 1e-4 && k(500.0) < 1e-5 && k(700.0) < 1e-7);
        assert!(!tio2.is_lossless() && !tio2.has_gain());
    }

    #[test]
    fn names_resolve_case_insensitively_and_cover_the_visible() {
        for name in names() {
            let m = builtin(name).unwrap();
            assert_eq!(&m.name, name);
            assert_eq!(builtin(&name.to_uppercase()).unwrap(), m);
            m.check().unwrap();
            let (lo, hi) = m.range_nm();
            assert!(lo <= 300.0 && hi >= 850.0, "{name}: {lo}-{hi}");
            for wl in [300.0, 380.0, 550.0, 780.0, 850.0] {
                let n = m.index_at(wl).unwrap();
                assert!(n.re > 0.0 && n.im >= 0.0, "{name} {wl}: {n}");
            }
        }
        assert!(builtin("unobtainium").is_none());
        assert_eq!(builtin("Aluminum").unwrap().name, "aluminium");
    }
}
