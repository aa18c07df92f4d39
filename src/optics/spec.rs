//! The stack file: a TOML description of a stack, as written by people.
//!
//! ```toml
//! ambient   = { n = 1.0 }                 # real shorthand
//! substrate = { material = "gold" }       # built-in, dispersive
//! [[layers]]
//! n = [1.5, 0.15]                         # [n, k], k > 0 absorbs, k < 0 gains
//! thickness_nm = 300.0
//! [[layers]]
//! material = "TiO2"
//! thickness_nm = 80.0
//! ```
//!
//! Every medium takes exactly one of `n = 1.33` or `n = [n, k]`,
//! `material = "name"` (see [`library`](super::library)),
//! `cauchy = [A, B]` or `[A, B, C]` (n = A + B/λ² + C/λ⁴, λ in µm),
//! `sellmeier = { b = [...], c = [...] }` with an optional `a = 1.0`
//! (n² = a + Σ bᵢλ²/(λ² − cᵢ), λ in µm, cᵢ in µm²), or
//! `table = "file.csv"` (refractiveindex.info CSV layout, relative to the
//! stack file). An optional `name` labels it in messages and headers.
//! Layers, listed from the top (ambient side) down, also need
//! `thickness_nm`, and take `coherent = false` for a thick layer whose
//! inner reflections add in power. Errors name the field: layers are
//! numbered from 1.

use std::fmt;
use std::path::{Path, PathBuf};

use serde::de::{self, Deserializer, SeqAccess, Visitor};
use serde::{Deserialize, Serialize, Serializer};

use super::library;
use super::material::{Dispersion, IndexTable, Material};
use super::stack::{Layer, Stack};
use crate::error::{Error, Result};

/// A stack as written in a file; [`StackSpec::resolve`] turns it into a
/// [`Stack`]. A scene file can embed one inline.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StackSpec {
    /// The semi-infinite medium light arrives from (no `thickness_nm`);
    /// the stack requires it to be lossless.
    pub ambient: MediumSpec,
    /// The finite layers from the top (ambient side) down, each with a
    /// `thickness_nm`; may be empty (a bare interface).
    #[serde(default)]
    pub layers: Vec<MediumSpec>,
    /// The semi-infinite medium below the last layer (no `thickness_nm`).
    pub substrate: MediumSpec,
}

/// One medium: exactly one index form, and a thickness for finite layers.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MediumSpec {
    /// A label for the material in messages and headers, replacing the one
    /// its index form would give.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// A constant index, wavelength independent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub n: Option<IndexSpec>,
    /// The name of a built-in material (the `optics::library` list; an
    /// unknown name is an error that lists them).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub material: Option<String>,
    /// Cauchy coefficients [A, B] or [A, B, C]: n = A + B/λ² + C/λ⁴ with λ
    /// in µm (C defaults to 0), k = 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cauchy: Option<Vec<f64>>,
    /// Sellmeier coefficients, λ in µm.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sellmeier: Option<SellmeierSpec>,
    /// A refractiveindex.info-style CSV of n (and k) against wavelength,
    /// relative to the stack file's directory.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub table: Option<PathBuf>,
    /// The layer's physical thickness in nm: required for layers, refused
    /// for the ambient and substrate (they are semi-infinite).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub thickness_nm: Option<f64>,
    /// `false` makes a layer incoherent (thick: its inner reflections add
    /// in power); layers are coherent by default. Refused for the ambient
    /// and substrate, which are always incoherent half-spaces.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub coherent: Option<bool>,
}

/// `n = 1.5` or `n = [1.5, 0.1]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IndexSpec {
    /// Real part of the index.
    pub n: f64,
    /// Extinction coefficient (0 when written as a single number): k > 0
    /// absorbs, k < 0 is gain.
    pub k: f64,
}

/// `sellmeier = { a = 1.0, b = [...], c = [...] }`: n² = a + Σ bᵢλ²/(λ² −
/// cᵢ) with λ in µm; k = 0.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SellmeierSpec {
    /// The constant term (1 when omitted, the classic form).
    #[serde(default = "one")]
    pub a: f64,
    /// The dimensionless strengths bᵢ, one per term.
    pub b: Vec<f64>,
    /// The resonance terms cᵢ in µm², as many as `b`.
    pub c: Vec<f64>,
}

fn one() -> f64 {
    1.0
}

impl StackSpec {
    /// Builds the stack, loading table files relative to `base_dir`, and
    /// checks it ([`Stack::validate`]). Errors name the field at fault.
    pub fn resolve(&self, base_dir: &Path) -> Result<Stack> {
        let ambient = self.ambient.resolve("ambient", base_dir, false)?;
        let substrate = self.substrate.resolve("substrate", base_dir, false)?;
        let layers = self
            .layers
            .iter()
            .enumerate()
            .map(|(i, spec)| {
                let field = format!("layers[{}]", i + 1);
                let material = spec.resolve(&field, base_dir, true)?;
                let thickness_nm = spec.thickness_nm.unwrap_or(f64::NAN);
                Ok(Layer {
                    coherent: spec.coherent.unwrap_or(true),
                    ..Layer::new(material, thickness_nm)
                })
            })
            .collect::<Result<Vec<_>>>()?;
        let stack = Stack {
            ambient,
            layers,
            substrate,
        };
        stack.validate()?;
        Ok(stack)
    }
}

impl MediumSpec {
    /// The material this medium describes, loading a table relative to
    /// `base_dir`. `field` names it in errors (`ambient`, `layers[2]`);
    /// `finite` says whether it is a layer, which must carry a thickness
    /// (the ambient and substrate must not).
    pub fn resolve(&self, field: &str, base_dir: &Path, finite: bool) -> Result<Material> {
        self.check_one_form(field)?;
        self.check_layer_keys(field, finite)?;
        let mut material = self.material_of_form(field, base_dir)?;
        if let Some(name) = &self.name {
            material.name = name.clone();
        }
        Ok(material)
    }

    fn check_one_form(&self, field: &str) -> Result<()> {
        let forms: Vec<&str> = [
            ("n", self.n.is_some()),
            ("material", self.material.is_some()),
            ("cauchy", self.cauchy.is_some()),
            ("sellmeier", self.sellmeier.is_some()),
            ("table", self.table.is_some()),
        ]
        .iter()
        .filter(|f| f.1)
        .map(|f| f.0)
        .collect();
        if forms.len() != 1 {
            return Err(Error::invalid(
                field,
                format!(
                    "give exactly one of n, material, cauchy, sellmeier, table (got {})",
                    if forms.is_empty() {
                        "none".to_string()
                    } else {
                        forms.join(" and ")
                    }
                ),
            ));
        }
        Ok(())
    }

    /// A layer needs a thickness; the ambient and substrate take neither a
    /// thickness nor a coherence flag.
    fn check_layer_keys(&self, field: &str, finite: bool) -> Result<()> {
        match (finite, self.thickness_nm) {
            (true, None) => Err(Error::invalid(
                format!("{field}.thickness_nm"),
                "missing (every layer needs a thickness)",
            )),
            (false, Some(_)) => Err(Error::invalid(
                format!("{field}.thickness_nm"),
                "not allowed: the ambient and substrate are semi-infinite",
            )),
            _ if !finite && self.coherent.is_some() => Err(Error::invalid(
                format!("{field}.coherent"),
                "not allowed: only a layer can be coherent or not (the ambient and substrate \
                 are semi-infinite and always incoherent)",
            )),
            _ => Ok(()),
        }
    }

    /// The material of the one form given (see [`Self::check_one_form`]),
    /// named after it.
    fn material_of_form(&self, field: &str, base_dir: &Path) -> Result<Material> {
        let sub = |name: &str| format!("{field}.{name}");
        Ok(if let Some(IndexSpec { n, k }) = self.n {
            Material::constant(n, k)
        } else if let Some(name) = &self.material {
            library::builtin(name).ok_or_else(|| {
                Error::invalid(
                    sub("material"),
                    format!(
                        "unknown material '{name}' (built-in: {})",
                        library::names().join(", ")
                    ),
                )
            })?
        } else if let Some(coefficients) = &self.cauchy {
            let (a, b, c) = match coefficients.as_slice() {
                [a, b] => (*a, *b, 0.0),
                [a, b, c] => (*a, *b, *c),
                _ => {
                    return Err(Error::invalid(
                        sub("cauchy"),
                        format!(
                            "expected [A, B] or [A, B, C], got {} numbers",
                            coefficients.len()
                        ),
                    ))
                }
            };
            Material {
                name: format!("cauchy({a}, {b}, {c})"),
                dispersion: Dispersion::Cauchy { a, b, c },
            }
        } else if let Some(s) = &self.sellmeier {
            Material {
                name: "sellmeier".to_string(),
                dispersion: Dispersion::Sellmeier {
                    a: s.a,
                    b: s.b.clone(),
                    c: s.c.clone(),
                },
            }
        } else if let Some(path) = &self.table {
            let full = base_dir.join(path);
            let table = IndexTable::load_csv(&full)
                .map_err(|e| e.within(&sub("table"), |what, why| Error::invalid(what, why)))?;
            Material {
                name: path.display().to_string(),
                dispersion: Dispersion::Table(table),
            }
        } else {
            unreachable!("resolve checked that exactly one form is given")
        })
    }
}

impl Stack {
    /// Reads a stack file; table paths inside it are relative to its folder.
    pub fn load(path: &Path) -> Result<Stack> {
        let text = crate::limits::read_text(path)?;
        let base_dir = path.parent().unwrap_or(Path::new(""));
        Stack::from_toml_str(&text, base_dir, &path.display().to_string())
    }

    /// Parses and resolves stack-file text; `origin` names it in errors.
    pub fn from_toml_str(text: &str, base_dir: &Path, origin: &str) -> Result<Stack> {
        let spec: StackSpec =
            toml::from_str(text).map_err(|e| crate::error::toml_error(origin, &e, text))?;
        spec.resolve(base_dir)
            .map_err(|e| e.within(origin, |origin, why| Error::malformed(origin, why)))
    }
}

impl Serialize for IndexSpec {
    fn serialize<S: Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        if self.k == 0.0 {
            s.serialize_f64(self.n)
        } else {
            [self.n, self.k].serialize(s)
        }
    }
}

impl<'de> Deserialize<'de> for IndexSpec {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        struct IndexVisitor;
        impl<'de> Visitor<'de> for IndexVisitor {
            type Value = IndexSpec;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a number n or a pair [n, k]")
            }
            fn visit_f64<E: de::Error>(self, n: f64) -> std::result::Result<IndexSpec, E> {
                Ok(IndexSpec { n, k: 0.0 })
            }
            fn visit_i64<E: de::Error>(self, n: i64) -> std::result::Result<IndexSpec, E> {
                Ok(IndexSpec {
                    n: n as f64,
                    k: 0.0,
                })
            }
            fn visit_u64<E: de::Error>(self, n: u64) -> std::result::Result<IndexSpec, E> {
                Ok(IndexSpec {
                    n: n as f64,
                    k: 0.0,
                })
            }
            fn visit_seq<A: SeqAccess<'de>>(
                self,
                mut seq: A,
            ) -> std::result::Result<IndexSpec, A::Error> {
                let n: f64 = seq
                    .next_element()?
                    .ok_or_else(|| de::Error::invalid_length(0, &self))?;
                let k: f64 = seq
                    .next_element()?
                    .ok_or_else(|| de::Error::invalid_length(1, &self))?;
                if seq.next_element::<f64>()?.is_some() {
                    return Err(de::Error::invalid_length(3, &self));
                }
                Ok(IndexSpec { n, k })
            }
        }
        d.deserialize_any(IndexVisitor)
    }
}
