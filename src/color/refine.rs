//! The exact colour where a film's fringes are narrower than a nanometre.
//!
//! `exact` integrates a spectrum against the CIE tables (D65 × x̄, ȳ, z̄, or
//! the linear-sRGB matching functions for white E), that is against the
//! weight function that interpolates the 1 nm weights linearly. Its 1 nm
//! sum is that integral wherever the spectrum is smooth on the scale of a
//! nanometre. Near grazing incidence a free-standing film (and any layer
//! between two nearly perfect reflectors) has fringes of width
//! 2 (1 − |r'_A r_B|) / √|r'_A r_B| in round-trip phase, which the phase's
//! derivative 4π Re(q) d / λ² turns into widths in wavelength far below a
//! nanometre: the 1 nm sum then hits or misses each one, and the colour it
//! gives jumps by up to a wavelength's whole weight as the thickness moves
//! by a fraction of a nanometre. There the sum takes `m` points per
//! nanometre (a power of two, at most [`MAX_SUB_STEPS`]), enough for the
//! narrowest visible fringe to span [`POINTS_PER_FRINGE`] of them, which
//! leaves the sum within a thousandth of the fringe's own contribution of
//! the integral.
//!
//! Which `m` a point needs is read off the layers' cavities: for the varying
//! layer at the point's thickness and cos θ, for every other layer at its
//! own thickness, each at [`PROBE_WAVELENGTHS`] wavelengths across the
//! range, from splits made once on a grid of cos θ (every thickness of the
//! varying layer reuses them). A fringe counts when it changes R by more
//! than [`VISIBLE_COLOUR`] of colour through one wavelength's weight: a
//! lossless stack behind total internal reflection reflects everything
//! whatever its phases, and needs no more points.
//!
//! A lossless varying layer's fringes keep their depth at every thickness
//! and narrow as 1/d, so a point's `m` costs a few operations (the baker
//! asks at every node); an absorbing layer's are evaluated at the point's
//! thickness only where a bound from its round trip at zero thickness
//! says they could need more points.

use std::sync::OnceLock;

use super::{Sampling, SpectralIntegrator};
use crate::cancel::Cancel;
use crate::error::Result;
use crate::optics::lanes::{SpectralWeights, WeightedPower};
use crate::optics::twoport::{Scratch, VaryingLayer};
use crate::optics::{Stack, StackGrid};

/// The most points per nanometre: fringes narrower than
/// `POINTS_PER_FRINGE / MAX_SUB_STEPS` nm (a soap film 1000 nm thick within
/// about 0.2° of grazing incidence) stay aliased.
pub const MAX_SUB_STEPS: usize = 64;
/// Points across the width of the narrowest visible fringe: the sampled
/// sum of a Lorentzian dip differs from its integral by about
/// 2 exp(−π × this), a thousandth at 2.4.
pub const POINTS_PER_FRINGE: f64 = 2.4;
/// Wavelengths at which the cavities are examined.
pub const PROBE_WAVELENGTHS: usize = 16;
/// The colour a fringe must be able to move through one wavelength's weight
/// to be resolved.
pub const VISIBLE_COLOUR: f64 = 1e-4;
/// cos θ nodes of the cavities' grid: logarithmic from [`COS_FLOOR`] to 1.
const COS_NODES: usize = 129;
const COS_FLOOR: f64 = 1e-4;

/// One integration with more points per nanometre.
pub struct Level {
    /// Its wavelengths and weights.
    pub integrator: SpectralIntegrator,
    /// The stack at its wavelengths.
    pub grid: StackGrid,
    /// The weights laid out for the batched solver.
    pub weights: SpectralWeights,
}

/// What the layers' cavities at one cos node of the grid demand.
#[derive(Default)]
struct CosNode {
    /// Points per step the layers of fixed thickness need (unrounded).
    fixed: f64,
    /// The varying layer where it is lossless: its visible fringes' least
    /// width in nm times its thickness in nm (their width falls as 1/d,
    /// their depth does not change); infinite when none is visible.
    lossless_width: f64,
    /// The varying layer where it absorbs or amplifies, whose fringes
    /// change with its thickness: each split, with a lower bound on its
    /// width × thickness (0 when there is none: a gain layer).
    lossy: Vec<(VaryingLayer, f64)>,
}

/// How many points per nanometre the exact colour of one stack needs, and
/// the integrations at those densities.
pub struct Refinement {
    stack: Stack,
    /// The varying layer (from 1), whose thickness each point gives.
    layer: Option<usize>,
    /// Nanometres between the base integration's wavelengths (1 for exact;
    /// 0: never refined).
    step_nm: f64,
    /// The smallest visibility that counts.
    visible: f64,
    probe_nm: Vec<f64>,
    cos_nodes: Vec<f64>,
    nodes: Vec<CosNode>,
    base: SpectralIntegrator,
    levels: Vec<OnceLock<Level>>,
}

impl Refinement {
    /// The refinement of `stack`'s colour by `integrator`, with `layer`
    /// (from 1) the one whose thickness varies point to point. Only the
    /// exact sampling is refined; the others are what their names say.
    pub fn new(
        stack: &Stack,
        layer: Option<usize>,
        integrator: &SpectralIntegrator,
    ) -> Result<Refinement> {
        Refinement::new_cancellable(stack, layer, integrator, Cancel::never())
    }

    /// [`Self::new`], stopping with [`Error::Cancelled`] once `cancel` is
    /// set: examining a stack of hundreds of layers takes seconds, and it
    /// looks at the flag before each cos θ node.
    pub fn new_cancellable(
        stack: &Stack,
        layer: Option<usize>,
        integrator: &SpectralIntegrator,
        cancel: &Cancel,
    ) -> Result<Refinement> {
        let w = integrator.wavelengths_nm();
        // A stack with incoherent (thick) layers is solved point by point,
        // its coherent parts between them: its fringes are not the splits'
        // here, and it is integrated as sampled.
        let refinable = integrator.sampling() == Sampling::Exact && stack.is_coherent();
        let step_nm = if refinable && w.len() > 1 {
            (w[w.len() - 1] - w[0]) / (w.len() - 1) as f64
        } else {
            0.0
        };
        let largest_weight = integrator
            .rgb_weights()
            .iter()
            .flat_map(|c| c.iter())
            .fold(0.0f64, |a, &b| a.max(b.abs()));
        let probe_nm: Vec<f64> = if step_nm > 0.0 {
            let span = w[w.len() - 1] - w[0];
            (0..PROBE_WAVELENGTHS)
                .map(|k| w[0] + span * k as f64 / (PROBE_WAVELENGTHS - 1) as f64)
                .collect()
        } else {
            Vec::new()
        };
        let cos_nodes: Vec<f64> = (0..COS_NODES)
            .map(|k| COS_FLOOR * (1.0 / COS_FLOOR).powf(k as f64 / (COS_NODES - 1) as f64))
            .collect();
        let mut r = Refinement {
            stack: stack.clone(),
            layer: layer.filter(|&l| l >= 1 && l <= stack.layers.len()),
            step_nm,
            visible: VISIBLE_COLOUR / largest_weight.max(1e-12),
            probe_nm,
            cos_nodes,
            nodes: Vec::new(),
            base: integrator.clone(),
            levels: (0..=MAX_SUB_STEPS.trailing_zeros())
                .map(|_| OnceLock::new())
                .collect(),
        };
        if step_nm > 0.0 {
            r.examine_cavities(cancel)?;
        }
        Ok(r)
    }

    /// Splits every layer at every cos node and probe wavelength: the
    /// varying layer's summarized per node, the others' turned into the
    /// points they need at their own thickness.
    fn examine_cavities(&mut self, cancel: &Cancel) -> Result<()> {
        let thicknesses = self.stack.thicknesses_nm();
        let mut indices: Vec<Vec<_>> = Vec::new();
        for &l in &self.probe_nm {
            let mut row = Vec::new();
            self.stack.indices_at(l, &mut row)?;
            indices.push(row);
        }
        let mut scratch = Scratch::default();
        let layers = self.stack.layers.len();
        for k in 0..COS_NODES {
            cancel.check()?;
            let c = self.cos_nodes[k];
            let mut node = CosNode {
                lossless_width: f64::INFINITY,
                ..CosNode::default()
            };
            for (p, &l) in self.probe_nm.iter().enumerate() {
                for j in 1..=layers {
                    let split = VaryingLayer::new(&indices[p], &thicknesses, j, l, c, &mut scratch);
                    if Some(j) == self.layer {
                        self.summarize(&mut node, split);
                    } else {
                        node.fixed = node.fixed.max(self.demand(&split, thicknesses[j - 1]));
                    }
                }
            }
            self.nodes.push(node);
        }
        Ok(())
    }

    /// Adds the varying layer's split at one probe wavelength to `node`.
    fn summarize(&self, node: &mut CosNode, split: VaryingLayer) {
        if split.is_degenerate() {
            return;
        }
        let loss = split.attenuation_per_nm();
        if loss == 0.0 {
            let (y, visibility) = split.fringe(1.0);
            if visibility >= self.visible && y > 0.0 {
                node.lossless_width = node.lossless_width.min(split.fringe_width_nm(y, 1.0));
            }
        } else {
            // An absorbing layer's round trip |y| shrinks with its thickness,
            // and below 1 the width 2 (1 − y) / √y only grows as it does.
            let (y0, _) = split.fringe(0.0);
            let bound = if loss > 0.0 && y0 < 1.0 {
                split.fringe_width_nm(y0, 1.0)
            } else {
                0.0
            };
            node.lossy.push((split, bound));
        }
    }

    /// Points per step a fringe `width_nm` wide needs (unrounded).
    fn points_for(&self, width_nm: f64) -> f64 {
        POINTS_PER_FRINGE * self.step_nm / width_nm
    }

    /// Points per step one layer's fringe at `thickness_nm` needs (at the
    /// wavelength and cos θ of its split `split`), unrounded; 0 when it is
    /// not visible.
    fn demand(&self, split: &VaryingLayer, thickness_nm: f64) -> f64 {
        if thickness_nm <= 0.0 || split.is_degenerate() {
            return 0.0;
        }
        let (y, visibility) = split.fringe(thickness_nm);
        if !(visibility >= self.visible && y > 0.0) {
            return 0.0;
        }
        self.points_for(split.fringe_width_nm(y, thickness_nm))
    }

    /// Points per step (unrounded) the colour at cos θ `c` with the varying
    /// layer `thickness_nm` thick needs: the most any layer's visible
    /// fringes ask for at the cos nodes around `c` (fringes sharpen
    /// towards grazing, so the lower node is the one that matters, and both
    /// are asked). Below the grid's least cos θ the demand there grows as
    /// 1 / cos θ: a fringe's width in phase, 2 (1 − y) / √y, is
    /// proportional to cos θ near grazing incidence, where the surroundings
    /// of a free-standing film reflect fully.
    pub fn demand_at(&self, thickness_nm: f64, c: f64) -> f64 {
        if self.step_nm <= 0.0 || c <= 0.0 {
            return 0.0;
        }
        let below_grid = (COS_FLOOR / c).max(1.0);
        below_grid * self.demand_on_grid(thickness_nm, c)
    }

    /// [`Self::demand_at`] with `c` taken to the grid.
    fn demand_on_grid(&self, thickness_nm: f64, c: f64) -> f64 {
        let x =
            ((c.max(COS_FLOOR) / COS_FLOOR).ln() / (1.0 / COS_FLOOR).ln()) * (COS_NODES - 1) as f64;
        let k = (x.floor() as usize).min(COS_NODES - 2);
        let mut m = self.nodes[k].fixed.max(self.nodes[k + 1].fixed);
        if self.layer.is_none() || thickness_nm <= 0.0 {
            return m;
        }
        for node in &self.nodes[k..=k + 1] {
            m = m.max(self.points_for(node.lossless_width / thickness_nm));
            for (split, bound) in &node.lossy {
                // The width alone bounds the demand (a fringe too faint to
                // see asks for nothing): the visibility's two responses are
                // paid only where the fringe could ask for more than `m`
                // and more than the one point per step every sum has.
                let enough = m.max(1.0);
                if self.points_for(bound / thickness_nm) <= enough {
                    continue;
                }
                let y = split.round_trip(thickness_nm);
                if self.points_for(split.fringe_width_nm(y, thickness_nm)) > enough {
                    m = m.max(self.demand(split, thickness_nm));
                }
            }
        }
        m
    }

    /// Points per nanometre the colour at cos θ `c` with the varying layer
    /// `thickness_nm` thick is integrated with: [`Self::demand_at`] rounded
    /// up to a power of two, at most [`MAX_SUB_STEPS`] (1: the 1 nm sum is
    /// the integral there).
    pub fn sub_steps(&self, thickness_nm: f64, c: f64) -> usize {
        let m = self.demand_at(thickness_nm, c);
        if m >= MAX_SUB_STEPS as f64 {
            MAX_SUB_STEPS
        } else if m > 1.0 {
            (m.ceil() as usize).next_power_of_two()
        } else {
            1
        }
    }

    /// True when [`MAX_SUB_STEPS`] points per nanometre resolve every
    /// visible fringe at (`thickness_nm`, `c`).
    pub fn resolves(&self, thickness_nm: f64, c: f64) -> bool {
        self.demand_at(thickness_nm, c) <= MAX_SUB_STEPS as f64
    }

    /// The base integration refined to `m` points per step (a power of two
    /// up to [`MAX_SUB_STEPS`]).
    pub fn integrator(&self, m: usize) -> SpectralIntegrator {
        self.base.refined(m)
    }

    /// The integration with `m` points per nanometre (`m` a power of two up
    /// to [`MAX_SUB_STEPS`]), made on first use.
    pub fn level(&self, m: usize) -> Result<&Level> {
        let slot = &self.levels[m.clamp(1, MAX_SUB_STEPS).trailing_zeros() as usize];
        if let Some(level) = slot.get() {
            return Ok(level);
        }
        let integrator = self.integrator(m);
        let grid = StackGrid::new(&self.stack, integrator.wavelengths_nm())?;
        let weights = integrator.rgb_lane_weights();
        Ok(slot.get_or_init(|| Level {
            integrator,
            grid,
            weights,
        }))
    }

    /// The colour (linear RGB of R and T) of the stack with its layer
    /// thicknesses `thicknesses_nm` at cos θ `c`, at the points per
    /// nanometre it needs: by `grid` and `weights` (the stack at the base
    /// integration's wavelengths, and its weights) where one is enough.
    pub fn weighted_spectrum(
        &self,
        grid: &StackGrid,
        weights: &SpectralWeights,
        thicknesses_nm: &[f64],
        c: f64,
    ) -> Result<WeightedPower> {
        let d = self.layer.map_or(0.0, |l| thicknesses_nm[l - 1]);
        let m = self.sub_steps(d, c);
        if m <= 1 {
            return Ok(grid.weighted_spectrum(thicknesses_nm, c, weights));
        }
        let level = self.level(m)?;
        Ok(level
            .grid
            .weighted_spectrum(thicknesses_nm, c, &level.weights))
    }
}
