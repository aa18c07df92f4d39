//! R and T of one stack at arbitrary points: each point its own
//! wavelength, angle and (optionally) thickness of one layer, as a spectral
//! renderer asks for them (every ray carries its own wavelengths, so no grid
//! is shared between points). The materials are evaluated at each point's
//! wavelength and the points go to the lane kernel several at a time
//! ([`lanes::solve_points_on`]), agreeing with [`solve`](super::solve) at
//! the stack's own indices ([`Stack::indices_at`]) point by point to 10⁻¹²
//! (`tests/points.rs`). A stack with incoherent layers is solved point by
//! point by [`solve_incoherent`] instead.
//!
//! With the kernel vectorized, evaluating the materials is most of the
//! work: a tabulated material's row is found by binary search in
//! [`IndexTable::index_at`], whose branches a random wavelength makes
//! unpredictable. [`PointSolver`] finds it from a uniform grid over the
//! table instead (a row per cell, then a step or two), and interpolates the
//! same rows with the same arithmetic, so the index has the same bits.

use num_complex::Complex64 as C64;

use super::incoherent::{solve_incoherent, Coherence};
use super::lanes::{self, Path};
use super::material::{Dispersion, IndexTable, Material, MAX_INDEX, MIN_INDEX};
use super::solver::Response;
use super::stack::{Stack, MAX_THICKNESS_NM, WAVELENGTH_RANGE_NM};
use crate::error::{Error, Result};

/// Points laid out for the lanes at a time: the buffers of indices and
/// thicknesses hold this many points, so a call allocates a few kilobytes
/// whatever its length.
const BLOCK: usize = 256;

/// The thickness of one layer, given per point; the other layers keep the
/// stack's own.
#[derive(Clone, Copy, Debug)]
pub struct LayerThickness<'a> {
    /// The layer, 0-based from the ambient side.
    pub layer: usize,
    /// One thickness in nm per point, 0 to [`MAX_THICKNESS_NM`].
    pub thickness_nm: &'a [f64],
}

/// A stack made ready to be solved at arbitrary points: validated once, and
/// each tabulated material given a grid that finds its row without a
/// search. Build it once and call [`PointSolver::solve`] as often as needed
/// (from several threads at once: it is read only).
#[derive(Debug)]
pub struct PointSolver<'a> {
    stack: &'a Stack,
    /// Ambient, layers, substrate.
    media: Vec<Medium<'a>>,
    /// The layers' coherence when one of them is incoherent (such points
    /// are solved one by one by [`solve_incoherent`]); None when all are
    /// coherent.
    coherence: Option<Coherence>,
}

/// How one medium's index is found at a wavelength.
#[derive(Debug)]
enum Medium<'a> {
    /// A formula (constant, Cauchy, Sellmeier): the material's own.
    Formula(&'a Material),
    /// A table, through its row grid.
    Table(RowGrid<'a>),
}

impl Stack {
    /// R and T at each point i: wavelength `wavelengths_nm[i]`, incidence
    /// `cos_theta0[i]` in the ambient, and the thickness of
    /// `varying.layer` set to `varying.thickness_nm[i]` (the stack's own
    /// where `varying` is None), into `out[i]`: [`PointSolver::solve`] for
    /// one call. See [`PointSolver`] to solve the same stack again.
    ///
    /// # Panics
    /// As [`PointSolver::solve`].
    pub fn solve_points(
        &self,
        varying: Option<LayerThickness<'_>>,
        wavelengths_nm: &[f64],
        cos_theta0: &[f64],
        out: &mut [Response],
    ) -> Result<()> {
        PointSolver::new(self)?.solve(varying, wavelengths_nm, cos_theta0, out)
    }
}

impl<'a> PointSolver<'a> {
    /// Validates `stack` ([`Stack::validate`]) and lays out a row grid for
    /// each tabulated material.
    pub fn new(stack: &'a Stack) -> Result<PointSolver<'a>> {
        stack.validate()?;
        let materials = std::iter::once(&stack.ambient)
            .chain(stack.layers.iter().map(|l| &l.material))
            .chain(std::iter::once(&stack.substrate));
        let media = materials
            .map(|m| match &m.dispersion {
                Dispersion::Table(t) => Medium::Table(RowGrid::new(m, t)),
                _ => Medium::Formula(m),
            })
            .collect();
        let coherence = (!stack.is_coherent()).then(|| stack.coherence());
        Ok(PointSolver {
            stack,
            media,
            coherence,
        })
    }

    /// R and T at each point i: wavelength `wavelengths_nm[i]`, incidence
    /// `cos_theta0[i]` in the ambient, and the thickness of
    /// `varying.layer` set to `varying.thickness_nm[i]` (the stack's own
    /// where `varying` is None), into `out[i]`. Each result is
    /// [`solve`](super::solve)'s at that point, with the indices
    /// [`Stack::indices_at`] gives, to within 10⁻¹²; the points are solved
    /// eight or four at a time (the widest vectors the CPU has).
    ///
    /// Fails, naming the argument, on the first point whose cos θ0 is not in
    /// [0, 1], whose thickness is not in [0, [`MAX_THICKNESS_NM`]] or whose
    /// layer the stack lacks (all checked before any work), or whose
    /// wavelength a material does not cover ([`Stack::indices_at`]'s error;
    /// `out` is then partly written).
    ///
    /// # Panics
    /// If `cos_theta0`, `out` or `varying.thickness_nm` do not have one entry
    /// per wavelength.
    pub fn solve(
        &self,
        varying: Option<LayerThickness<'_>>,
        wavelengths_nm: &[f64],
        cos_theta0: &[f64],
        out: &mut [Response],
    ) -> Result<()> {
        self.solve_on(Path::Best, varying, wavelengths_nm, cos_theta0, out)
    }

    /// [`PointSolver::solve`] on a chosen copy of the kernel.
    pub fn solve_on(
        &self,
        path: Path,
        varying: Option<LayerThickness<'_>>,
        wavelengths_nm: &[f64],
        cos_theta0: &[f64],
        out: &mut [Response],
    ) -> Result<()> {
        let points = wavelengths_nm.len();
        assert_eq!(cos_theta0.len(), points, "cos θ0: one per wavelength");
        assert_eq!(out.len(), points, "out: one per wavelength");
        self.check(varying, cos_theta0)?;
        let layers = self.stack.layers.len();
        let mut block = Block::new(self.stack, BLOCK.min(points));
        for start in (0..points).step_by(BLOCK) {
            let end = (start + BLOCK).min(points);
            let wavelengths = &wavelengths_nm[start..end];
            block.fill(self, varying, start, wavelengths)?;
            let cos_theta0 = &cos_theta0[start..end];
            let out = &mut out[start..end];
            match &self.coherence {
                None => lanes::solve_points_on(
                    path,
                    layers,
                    &block.indices,
                    &block.thicknesses_nm[..(end - start) * layers],
                    wavelengths,
                    cos_theta0,
                    out,
                ),
                Some(coherence) => block.solve_mixed(coherence, wavelengths, cos_theta0, out)?,
            }
        }
        Ok(())
    }

    /// Refuses a cos θ0 outside [0, 1], a thickness outside
    /// [0, [`MAX_THICKNESS_NM`]] (NaN included) and a layer the stack lacks,
    /// naming the first: [`PointSolver::solve`]'s checks before its work,
    /// for a caller that splits the points between threads and wants the
    /// first bad point's error whichever thread meets it.
    ///
    /// # Panics
    /// If `varying.thickness_nm` does not have one entry per cos θ0.
    pub fn check(&self, varying: Option<LayerThickness<'_>>, cos_theta0: &[f64]) -> Result<()> {
        if let Some(c) = cos_theta0.iter().find(|c| !(0.0..=1.0).contains(*c)) {
            return Err(Error::invalid(
                "cos_theta",
                format!("{c} is outside [0, 1]"),
            ));
        }
        let Some(v) = varying else {
            return Ok(());
        };
        assert_eq!(
            v.thickness_nm.len(),
            cos_theta0.len(),
            "thickness_nm: one per wavelength"
        );
        let layers = self.stack.layers.len();
        if v.layer >= layers {
            return Err(Error::invalid(
                "layer",
                format!(
                    "the stack has {layers} layers; there is no layer {} to vary",
                    v.layer + 1
                ),
            ));
        }
        if let Some(t) = v
            .thickness_nm
            .iter()
            .find(|t| !(0.0..=MAX_THICKNESS_NM).contains(*t))
        {
            return Err(Error::invalid(
                "thickness_nm",
                format!("must be finite, ≥ 0 and ≤ {MAX_THICKNESS_NM:e}, got {t}"),
            ));
        }
        Ok(())
    }

    /// The N + 2 indices at `wavelength_nm` appended to `out`, the values
    /// [`Stack::indices_at`] gives. Where that would fail (a wavelength out
    /// of range, an interpolated index too small) its error is returned.
    #[inline]
    fn indices_at(&self, wavelength_nm: f64, out: &mut Vec<C64>) -> Result<()> {
        let (lo, hi) = WAVELENGTH_RANGE_NM;
        if !(lo..=hi).contains(&wavelength_nm) {
            // The stack's own error (it has the words for every case).
            let mut row = Vec::new();
            self.stack.indices_at(wavelength_nm, &mut row)?;
            out.extend_from_slice(&row);
            return Ok(());
        }
        for (j, medium) in self.media.iter().enumerate() {
            let index = match medium {
                Medium::Formula(m) => m.index_at(wavelength_nm)?,
                Medium::Table(grid) => grid.index_at(wavelength_nm)?,
            };
            // The ambient is lossless: its imaginary part is ignored, as
            // Stack::indices_at ignores it.
            out.push(if j == 0 {
                C64::new(index.re, 0.0)
            } else {
                index
            });
        }
        Ok(())
    }
}

/// A table's rows found from a uniform grid of cells over its wavelengths:
/// each cell holds the row a binary search would give at its lower edge,
/// and a lookup steps from there to the row the search gives at the
/// wavelength (a step or two, since there are more cells than rows).
#[derive(Debug)]
struct RowGrid<'a> {
    material: &'a Material,
    table: &'a IndexTable,
    first_nm: f64,
    cells_per_nm: f64,
    /// Per cell: how many table wavelengths lie below its lower edge.
    start: Vec<usize>,
}

/// Cells per table row: enough that most cells hold no row boundary.
const CELLS_PER_ROW: usize = 4;

/// At most this many cells (512 KB): a longer table takes a few more steps
/// per lookup instead.
const MAX_CELLS: usize = 1 << 16;

impl<'a> RowGrid<'a> {
    fn new(material: &'a Material, table: &'a IndexTable) -> RowGrid<'a> {
        let w = &table.wavelength_nm;
        // validate() has checked the table: two rows or more, increasing.
        let (first, last) = (w[0], w[w.len() - 1]);
        let cells = (w.len() * CELLS_PER_ROW).min(MAX_CELLS);
        let cells_per_nm = cells as f64 / (last - first);
        let start = (0..cells)
            .map(|c| {
                let edge = first + c as f64 / cells_per_nm;
                w.partition_point(|&x| x < edge)
            })
            .collect();
        RowGrid {
            material,
            table,
            first_nm: first,
            cells_per_nm,
            start,
        }
    }

    /// [`Material::index_at`] of the table's material, with the same bits.
    #[inline]
    fn index_at(&self, wavelength_nm: f64) -> Result<C64> {
        let (w, n, k) = (&self.table.wavelength_nm, &self.table.n, &self.table.k);
        let rows = w.len();
        if !(wavelength_nm >= w[0] && wavelength_nm <= w[rows - 1]) {
            return self.material.index_at(wavelength_nm);
        }
        let cell = ((wavelength_nm - self.first_nm) * self.cells_per_nm) as usize;
        let mut hi = self.start[cell.min(self.start.len() - 1)];
        // Where IndexTable::index_at's partition_point lands: the first row
        // not below the wavelength (the cell's rounding may be off by one).
        while hi > 0 && w[hi - 1] >= wavelength_nm {
            hi -= 1;
        }
        while hi < rows && w[hi] < wavelength_nm {
            hi += 1;
        }
        let hi = hi.clamp(1, rows - 1);
        let lo = hi - 1;
        let t = (wavelength_nm - w[lo]) / (w[hi] - w[lo]);
        let index = C64::new(n[lo] + t * (n[hi] - n[lo]), k[lo] + t * (k[hi] - k[lo]));
        // Inside the range Material::index_at accepts for certain (|n + ik|
        // ≥ n ≥ 2 MIN_INDEX); anything else gets its verdict.
        if index.re >= 2.0 * MIN_INDEX && index.re <= MAX_INDEX && index.im.abs() <= MAX_INDEX {
            Ok(index)
        } else {
            self.material.index_at(wavelength_nm)
        }
    }
}

/// One block of points laid out as the lanes read them.
struct Block {
    /// N + 2 per point: ambient, layers, substrate.
    indices: Vec<C64>,
    /// N per point: the stack's own, with the varying layer's set per point.
    thicknesses_nm: Vec<f64>,
}

impl Block {
    fn new(stack: &Stack, points: usize) -> Block {
        Block {
            indices: Vec::with_capacity((stack.layers.len() + 2) * points),
            thicknesses_nm: stack.thicknesses_nm().repeat(points),
        }
    }

    /// The indices at `wavelengths_nm` and the thicknesses of points
    /// `start..` (only the varying layer's change from block to block).
    fn fill(
        &mut self,
        solver: &PointSolver<'_>,
        varying: Option<LayerThickness<'_>>,
        start: usize,
        wavelengths_nm: &[f64],
    ) -> Result<()> {
        self.indices.clear();
        for &wl in wavelengths_nm {
            solver.indices_at(wl, &mut self.indices)?;
        }
        if let Some(v) = varying {
            let layers = solver.stack.layers.len();
            let given = &v.thickness_nm[start..start + wavelengths_nm.len()];
            for (row, &t) in self.thicknesses_nm.chunks_exact_mut(layers).zip(given) {
                row[v.layer] = t;
            }
        }
        Ok(())
    }

    /// The points of this block of a stack with incoherent layers, one by
    /// one; fails on the first point where an incoherent layer lases,
    /// naming the layer.
    fn solve_mixed(
        &self,
        coherence: &Coherence,
        wavelengths_nm: &[f64],
        cos_theta0: &[f64],
        out: &mut [Response],
    ) -> Result<()> {
        let media = self.indices.len() / wavelengths_nm.len().max(1);
        let layers = media - 2;
        for (i, response) in out.iter_mut().enumerate() {
            let (wl, cos) = (wavelengths_nm[i], cos_theta0[i]);
            *response = solve_incoherent(
                &self.indices[i * media..(i + 1) * media],
                &self.thicknesses_nm[i * layers..(i + 1) * layers],
                coherence,
                wl,
                cos,
            )
            .map_err(|lasing| lasing.error(wl, cos))?;
        }
        Ok(())
    }
}
