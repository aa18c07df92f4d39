//! The fixed stacks every benchmark run measures: the example stack files
//! shipped in `luts/` (embedded, so the binary runs from anywhere), each with
//! the layer whose thickness varies. Together they cover what the methods
//! differ on: one lossless film (where the analytic model is at its best), an
//! absorbing film and a gain film on gold (which it cannot represent), a
//! two-layer stack, and a 10-layer mirror seen from both sides.

use std::path::Path;

use crate::color::Sampling;
use crate::error::Result;
use crate::lut::{BakeSpec, Kind, Resolution};
use crate::optics::Stack;

/// One of the fixed benchmark stacks, resolved, with the layer and range
/// over which its thickness is swept.
#[derive(Clone, Debug)]
pub struct BenchStack {
    /// Short name used on the command line and in reports.
    pub name: &'static str,
    /// One line saying what the stack is and what it tests.
    pub description: &'static str,
    /// The resolved stack, built from the embedded stack file and validated.
    pub stack: Stack,
    /// Index (from the top, 0-based) of the layer whose thickness varies.
    pub varying_layer: usize,
    /// (min, max) thickness in nm the varying layer is swept over.
    pub thickness_range_nm: (f64, f64),
}

impl BenchStack {
    /// The rgb table the benchmark bakes for this stack: 1 nm integration
    /// (the `irid bake` default) over its thickness range and every angle.
    pub fn bake_spec(&self, thickness_nodes: usize, angle_nodes: usize, half: bool) -> BakeSpec {
        BakeSpec {
            layer: self.varying_layer + 1,
            thickness_nm: self.thickness_range_nm,
            cos_theta: (0.0, 1.0),
            kind: Kind::Rgb,
            sampling: Sampling::Exact,
            resolution: Resolution::Nodes {
                thickness: thickness_nodes,
                angle: angle_nodes,
                wavelength: 1,
            },
            half,
            // The benchmark measures the table's error itself, at its own
            // points; the baker's validation would only add to the bake time.
            validation_points: 0,
            ..BakeSpec::new(self.stack.clone())
        }
    }
}

struct Def {
    name: &'static str,
    description: &'static str,
    file: &'static str,
    toml: &'static str,
    reversed: bool,
    varying_layer: usize,
    thickness_range_nm: (f64, f64),
}

const DEFS: [Def; 6] = [
    Def {
        name: "soap",
        description: "luts/soap-film.toml: soap film n=1.33 in air, 0-1000 nm",
        file: "luts/soap-film.toml",
        toml: include_str!("../../luts/soap-film.toml"),
        reversed: false,
        varying_layer: 0,
        thickness_range_nm: (0.0, 1000.0),
    },
    Def {
        name: "absorbing",
        description: "luts/absorbing-film.toml: film n=1.5+0.15i on fused silica, 0-1000 nm",
        file: "luts/absorbing-film.toml",
        toml: include_str!("../../luts/absorbing-film.toml"),
        reversed: false,
        varying_layer: 0,
        thickness_range_nm: (0.0, 1000.0),
    },
    Def {
        name: "gain-on-gold",
        description: "luts/gain-on-gold.toml: gain film n=1.5-0.05i on gold, 0-1000 nm",
        file: "luts/gain-on-gold.toml",
        toml: include_str!("../../luts/gain-on-gold.toml"),
        reversed: false,
        varying_layer: 0,
        thickness_range_nm: (0.0, 1000.0),
    },
    Def {
        name: "two-layer",
        description: "luts/two-layer.toml: absorbing film (0-500 nm) over 80 nm TiO2 on gold",
        file: "luts/two-layer.toml",
        toml: include_str!("../../luts/two-layer.toml"),
        reversed: false,
        varying_layer: 0,
        thickness_range_nm: (0.0, 500.0),
    },
    Def {
        name: "mirror-front",
        description:
            "luts/mirror-10.toml: 10-layer TiO2/silica mirror from air; top TiO2 layer 0-200 nm",
        file: "luts/mirror-10.toml",
        toml: include_str!("../../luts/mirror-10.toml"),
        reversed: false,
        varying_layer: 0,
        thickness_range_nm: (0.0, 200.0),
    },
    Def {
        name: "mirror-back",
        description:
            "the same mirror seen from inside the silica substrate; the same TiO2 layer 0-200 nm",
        file: "luts/mirror-10.toml",
        toml: include_str!("../../luts/mirror-10.toml"),
        reversed: true,
        varying_layer: 9,
        thickness_range_nm: (0.0, 200.0),
    },
];

/// Stacks only the grid workload (`irid bench --grid`, the Python peers)
/// measures: a sheet thick enough to be incoherent, which the analytic
/// models and the renders of the full run have no form for.
const GRID_ONLY: [Def; 1] = [Def {
    name: "coated-sheet",
    description:
        "luts/coated-sheet.toml: TiO2 (0-300 nm) on a 1 mm incoherent silica sheet, MgF2 behind",
    file: "luts/coated-sheet.toml",
    toml: include_str!("../../luts/coated-sheet.toml"),
    reversed: false,
    varying_layer: 0,
    thickness_range_nm: (0.0, 300.0),
}];

impl Def {
    fn build(&self) -> Result<BenchStack> {
        let stack = Stack::from_toml_str(self.toml, Path::new("luts"), self.file)?;
        let stack = if self.reversed {
            stack.reversed()
        } else {
            stack
        };
        stack.validate()?;
        Ok(BenchStack {
            name: self.name,
            description: self.description,
            stack,
            varying_layer: self.varying_layer,
            thickness_range_nm: self.thickness_range_nm,
        })
    }
}

/// Every fixed stack, resolved, in run order; fails only if an embedded
/// stack file does not resolve.
pub fn fixed_stacks() -> Result<Vec<BenchStack>> {
    DEFS.iter().map(Def::build).collect()
}

/// (name, description) of every fixed stack, in run order.
pub fn descriptions() -> Vec<(&'static str, &'static str)> {
    DEFS.iter().map(|d| (d.name, d.description)).collect()
}

/// The short name of every fixed stack, in run order.
pub fn names() -> Vec<&'static str> {
    DEFS.iter().map(|d| d.name).collect()
}

/// The short name of every stack the grid workload knows: the fixed ones,
/// then those it alone measures.
pub fn grid_names() -> Vec<&'static str> {
    DEFS.iter().chain(&GRID_ONLY).map(|d| d.name).collect()
}

/// The stack called `name` (ASCII case-insensitive) among [`grid_names`],
/// resolved; `Ok(None)` when no stack has that name.
pub fn find(name: &str) -> Result<Option<BenchStack>> {
    DEFS.iter()
        .chain(&GRID_ONLY)
        .find(|d| d.name.eq_ignore_ascii_case(name))
        .map(Def::build)
        .transpose()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_stack_resolves_over_the_exact_range() {
        let stacks = fixed_stacks().unwrap();
        assert_eq!(stacks.len(), names().len());
        let mut n = Vec::new();
        for b in &stacks {
            assert!(b.varying_layer < b.stack.layers.len(), "{}", b.name);
            for w in [360.0, 550.0, 830.0] {
                b.stack.indices_at(w, &mut n).unwrap();
            }
        }
        let sheet = find("coated-sheet").unwrap().unwrap();
        assert_eq!(sheet.stack.coherence().incoherent_layers(), &[2]);
        assert!(!names().contains(&"coated-sheet") && grid_names().contains(&"coated-sheet"));
        let back = find("mirror-back").unwrap().unwrap();
        let front = find("mirror-front").unwrap().unwrap();
        // The same physical layer varies on both sides.
        assert_eq!(back.stack.layers[9], front.stack.layers[0]);
        assert!(find("nope").unwrap().is_none());
    }
}
