//! F_eff over whole grids, and per angle for `irid color --roughness`.

use std::borrow::Cow;

use rayon::prelude::*;
use serde::Serialize;

use super::kernel::{Kernel, Rules};
use super::{check_roughness, MuGrid, Quadrature};
use crate::cancel::Cancel;
use crate::color::{linear_srgb_to_xyz, stack_colors_cancellable, SpectralIntegrator};
use crate::error::{Error, Result};
use crate::optics::{Layer, Stack};
use crate::sweep::{check_film_domain, rgb_at_nodes};

/// F_eff (linear RGB of the integrator's white) over thickness × cos θ ×
/// roughness nodes, and the white lobe's directional albedo per cos θ and
/// roughness.
#[derive(Clone, Debug, PartialEq)]
pub struct RoughTable {
    /// The varying layer's thickness nodes (nm), ascending.
    pub thickness_nm: Vec<f64>,
    /// cos θ_v nodes, in the ambient.
    pub cos_theta: Vec<f64>,
    /// Roughness nodes (α = roughness²).
    pub roughness: Vec<f64>,
    /// F_eff at thickness t, cos θ c, roughness r:
    /// `reflectance[(r * cos_theta.len() + c) * thickness_nm.len() + t]`.
    pub reflectance: Vec<[f64; 3]>,
    /// ∫ D G2 / (4 cos θ_v) dl at cos θ c, roughness r:
    /// `albedo[r * cos_theta.len() + c]` (1 at roughness 0).
    pub albedo: Vec<f64>,
}

impl RoughTable {
    /// F_eff at node indices (thickness, cos θ, roughness).
    pub fn at(&self, t: usize, c: usize, r: usize) -> [f64; 3] {
        self.reflectance[(r * self.cos_theta.len() + c) * self.thickness_nm.len() + t]
    }
}

/// Bytes per (μ node × thickness node): the sweep's six values and the
/// reflectance repacked.
const BYTES_PER_SWEPT_NODE: u64 = 72;
/// Bytes per output node.
const BYTES_PER_OUTPUT_NODE: u64 = 24;

/// F_eff of `stack` with layer `layer` (from 1; any for a stack without
/// layers) at every `thickness_nm` × `cos_theta` × `roughness` node, colour
/// by `integrator`.
///
/// The film's smooth reflectance is computed once on the μ grid of
/// `quadrature` by the baker's split-stack sweep (thickness nodes × μ nodes
/// × wavelengths), and each (cos θ, roughness) pair weights it with its
/// [`Kernel`]. At roughness 0 the values are the smooth film's, computed at
/// cos θ itself. Thickness nodes must ascend; cos θ and roughness nodes may
/// come in any order and each lie in [0, 1].
pub fn rough_reflectance(
    stack: &Stack,
    layer: usize,
    integrator: &SpectralIntegrator,
    thickness_nm: &[f64],
    cos_theta: &[f64],
    roughness: &[f64],
    quadrature: &Quadrature,
) -> Result<RoughTable> {
    let nodes = Nodes {
        thickness_nm,
        cos_theta,
        roughness,
    };
    rough_table(stack, layer, integrator, nodes, quadrature, Cancel::never())
}

/// The node axes of a [`RoughTable`].
#[derive(Clone, Copy)]
struct Nodes<'a> {
    thickness_nm: &'a [f64],
    cos_theta: &'a [f64],
    roughness: &'a [f64],
}

/// [`rough_reflectance`], stopping with [`Error::Cancelled`] once `cancel`
/// is set: the sweep looks at it before each μ node, the weighing before
/// each (cos θ, roughness) row.
fn rough_table(
    stack: &Stack,
    layer: usize,
    integrator: &SpectralIntegrator,
    nodes: Nodes<'_>,
    quadrature: &Quadrature,
    cancel: &Cancel,
) -> Result<RoughTable> {
    let Nodes {
        thickness_nm,
        cos_theta,
        roughness,
    } = nodes;
    check_nodes(stack, layer, thickness_nm, cos_theta, roughness)?;
    let grid = MuGrid::for_stack(stack, quadrature.mu_intervals);
    let (n_t, n_c, n_r) = (thickness_nm.len(), cos_theta.len(), roughness.len());
    let estimate = crate::limits::product(
        &[grid.nodes().len() as u64 + n_c as u64, n_t as u64],
        BYTES_PER_SWEPT_NODE,
    )
    .zip(crate::limits::product(
        &[n_r as u64, n_c as u64, n_t as u64],
        BYTES_PER_OUTPUT_NODE,
    ))
    .and_then(|(a, b)| a.checked_add(b));
    crate::limits::check_allocation(
        &format!("a rough table of {n_t} x {n_c} x {n_r} nodes"),
        estimate,
    )?;
    let smooth_on_grid = rgb_at_nodes(
        stack,
        layer,
        integrator.clone(),
        thickness_nm,
        grid.nodes(),
        cancel,
    )?;
    // Reflectance only, one row of thickness × RGB per μ node.
    let on_grid: Vec<f64> = smooth_on_grid
        .iter()
        .flat_map(|v| [v[0], v[1], v[2]])
        .collect();
    drop(smooth_on_grid);
    let mirror = if roughness.contains(&0.0) {
        rgb_at_nodes(
            stack,
            layer,
            integrator.clone(),
            thickness_nm,
            cos_theta,
            cancel,
        )?
    } else {
        Vec::new()
    };
    let rules = Rules::new(quadrature);
    let mut reflectance = vec![[0.0; 3]; n_r * n_c * n_t];
    let mut albedo = vec![0.0; n_r * n_c];
    reflectance
        .par_chunks_mut(n_t)
        .zip(albedo.par_iter_mut())
        .enumerate()
        .try_for_each(|(row, (out, albedo))| -> Result<()> {
            cancel.check()?;
            let (r, c) = (row / n_c, row % n_c);
            if roughness[r] == 0.0 {
                for (o, v) in out.iter_mut().zip(&mirror[c * n_t..]) {
                    *o = [v[0], v[1], v[2]];
                }
                *albedo = 1.0;
                return Ok(());
            }
            let kernel = Kernel::with_rules(&grid, cos_theta[c], roughness[r], &rules);
            *albedo = kernel.albedo();
            weigh_rows(&kernel, &on_grid, 3 * n_t, out.as_flattened_mut());
            Ok(())
        })?;
    Ok(RoughTable {
        thickness_nm: thickness_nm.to_vec(),
        cos_theta: cos_theta.to_vec(),
        roughness: roughness.to_vec(),
        reflectance,
        albedo,
    })
}

/// The stack and the layer [`rough_colors`] sweeps at its own thickness:
/// the baker's split it goes through needs a coherent layer, so the first
/// coherent one, or, when every layer is incoherent, a zero-thickness layer
/// of the ambient's medium put on top, which changes nothing optically.
fn swept_layer(stack: &Stack) -> (Cow<'_, Stack>, usize) {
    if stack.layers.is_empty() {
        return (Cow::Borrowed(stack), 1);
    }
    match stack.layers.iter().position(|l| l.coherent) {
        Some(i) => (Cow::Borrowed(stack), i + 1),
        None => {
            let mut on_top = stack.clone();
            on_top
                .layers
                .insert(0, Layer::new(stack.ambient.clone(), 0.0));
            (Cow::Owned(on_top), 1)
        }
    }
}

/// `out` = Σ_j w_j × row j of `rows` (rows of `len` values), the kernel's
/// weights on its nodes.
fn weigh_rows(kernel: &Kernel, rows: &[f64], len: usize, out: &mut [f64]) {
    let (first, weights) = kernel.weights();
    out.fill(0.0);
    for (j, &w) in weights.iter().enumerate() {
        let row = &rows[(first + j) * len..(first + j + 1) * len];
        for (o, v) in out.iter_mut().zip(row) {
            *o = w.mul_add(*v, *o);
        }
    }
}

/// The nodes of [`rough_reflectance`]: the film's domain as the baker
/// checks it, thickness nodes ascending, every cos θ and roughness in
/// [0, 1], none of them empty.
fn check_nodes(
    stack: &Stack,
    layer: usize,
    thickness_nm: &[f64],
    cos_theta: &[f64],
    roughness: &[f64],
) -> Result<()> {
    for (what, nodes) in [
        ("thickness", thickness_nm),
        ("angles", cos_theta),
        ("roughness", roughness),
    ] {
        if nodes.is_empty() {
            return Err(Error::invalid(what, "no nodes"));
        }
    }
    if !thickness_nm.windows(2).all(|w| w[0] < w[1]) {
        return Err(Error::invalid("thickness", "nodes must ascend"));
    }
    let (t0, t1) = (thickness_nm[0], thickness_nm[thickness_nm.len() - 1]);
    if let Some(c) = cos_theta.iter().find(|c| !(0.0..=1.0).contains(*c)) {
        return Err(Error::invalid(
            "angles",
            format!("cos θ must be in [0, 1], got {c}"),
        ));
    }
    check_film_domain(stack, layer, (t0, t1), (0.0, 1.0))?;
    roughness
        .iter()
        .try_for_each(|&r| check_roughness("roughness", r))
}

/// A stack's pre-integrated rough reflectance at one view angle, as
/// `irid color --roughness` prints it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RoughColor {
    /// View angle in the ambient, degrees from the macro normal, in [0, 90).
    pub angle_deg: f64,
    /// GGX roughness (α = roughness²).
    pub roughness: f64,
    /// Linear sRGB of F_eff, the white of the integrator being (1, 1, 1).
    pub reflectance_rgb: [f64; 3],
    /// CIE XYZ of F_eff (Y = 1 for a perfect reflector).
    pub reflectance_xyz: [f64; 3],
    /// The directional albedo of a white GGX lobe of this roughness at this
    /// angle (single scattering): the film's own is F_eff times it.
    pub lobe_albedo: f64,
}

/// F_eff of `stack` (its layers at their own thicknesses) at each view
/// angle (degrees, in [0, 90)) for `roughness` ∈ [0, 1]. At roughness 0 it
/// is the smooth colour of [`stack_colors`](crate::color::stack_colors), exactly.
pub fn rough_colors(
    stack: &Stack,
    integrator: &SpectralIntegrator,
    angles_deg: &[f64],
    roughness: f64,
) -> Result<Vec<RoughColor>> {
    rough_colors_cancellable(stack, integrator, angles_deg, roughness, Cancel::never())
}

/// [`rough_colors`], stopping with [`Error::Cancelled`] once `cancel` is
/// set (it looks between blocks of a few milliseconds).
pub fn rough_colors_cancellable(
    stack: &Stack,
    integrator: &SpectralIntegrator,
    angles_deg: &[f64],
    roughness: f64,
    cancel: &Cancel,
) -> Result<Vec<RoughColor>> {
    check_roughness("roughness", roughness)?;
    let color = |angle_deg: f64, rgb: [f64; 3], xyz: [f64; 3], lobe_albedo: f64| RoughColor {
        angle_deg,
        roughness,
        reflectance_rgb: rgb,
        reflectance_xyz: xyz,
        lobe_albedo,
    };
    if roughness == 0.0 {
        return Ok(
            stack_colors_cancellable(stack, integrator, angles_deg, cancel)?
                .into_iter()
                .map(|c| color(c.angle_deg, c.reflectance_rgb, c.reflectance_xyz, 1.0))
                .collect(),
        );
    }
    if let Some(a) = angles_deg.iter().find(|a| !(**a >= 0.0 && **a < 90.0)) {
        return Err(Error::invalid(
            "angle",
            format!("{a} is outside [0, 90) degrees"),
        ));
    }
    if angles_deg.is_empty() {
        return Ok(Vec::new());
    }
    let cos: Vec<f64> = angles_deg.iter().map(|a| a.to_radians().cos()).collect();
    let (stack, layer) = swept_layer(stack);
    let thickness = stack.layers.get(layer - 1).map_or(0.0, |l| l.thickness_nm);
    let nodes = Nodes {
        thickness_nm: &[thickness],
        cos_theta: &cos,
        roughness: &[roughness],
    };
    let table = rough_table(
        &stack,
        layer,
        integrator,
        nodes,
        &Quadrature::default(),
        cancel,
    )?;
    Ok(angles_deg
        .iter()
        .enumerate()
        .map(|(c, &angle)| {
            let rgb = table.at(0, c, 0);
            color(angle, rgb, linear_srgb_to_xyz(rgb), table.albedo[c])
        })
        .collect())
}
