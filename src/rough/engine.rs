//! F_eff over whole grids, and per angle for `irid color --roughness`.

use std::borrow::Cow;

use rayon::prelude::*;
use serde::Serialize;

use super::energy::{compensate, kept_share, SingleScattering};
use super::kernel::{Kernel, Rules};
use super::{check_roughness, MuGrid, Quadrature};
use crate::cancel::Cancel;
use crate::color::{linear_srgb_to_xyz, stack_colors_cancellable, SpectralIntegrator};
use crate::error::{Error, Result};
use crate::optics::{Layer, Stack};
use crate::sweep::{check_film_domain, rgb_at_nodes, Side};

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
    /// T_eff, laid out as `reflectance` (empty from [`rough_reflectance`]).
    pub transmittance: Vec<[f64; 3]>,
    /// A_T, the white refraction lobe's albedo, laid out as `albedo` (empty
    /// from [`rough_reflectance`]).
    pub transmission_albedo: Vec<f64>,
    /// What the reflection lobe's microfacets keep rather than absorb, F_eff
    /// plus the film's transmittance weighted by the same (reflection)
    /// kernel, laid out as `reflectance` (empty from
    /// [`rough_reflectance`]): exactly 1 for a lossless film, the ρ of
    /// the multiple-scattering compensation ([`energy`](super::energy)).
    pub kept: Vec<[f64; 3]>,
}

impl RoughTable {
    /// F_eff at node indices (thickness, cos θ, roughness).
    pub fn at(&self, t: usize, c: usize, r: usize) -> [f64; 3] {
        self.reflectance[(r * self.cos_theta.len() + c) * self.thickness_nm.len() + t]
    }

    /// T_eff at node indices (thickness, cos θ, roughness).
    ///
    /// # Panics
    /// On a table of [`rough_reflectance`], which has no transmittance.
    pub fn transmittance_at(&self, t: usize, c: usize, r: usize) -> [f64; 3] {
        self.transmittance[(r * self.cos_theta.len() + c) * self.thickness_nm.len() + t]
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
    rough_table(
        stack,
        layer,
        integrator,
        &nodes,
        quadrature,
        None,
        Cancel::never(),
    )
}

/// F_eff, T_eff and both lobes' albedos of `stack` seen from `side` (the
/// view in the ambient for [`Side::Front`], in the substrate for
/// [`Side::Back`]), with layer `layer` counted from the ambient as the
/// stack is written, at every node as [`rough_reflectance`]. The geometry
/// of refraction takes η = n_o / n_v, the real parts at
/// [`ETA_WAVELENGTH_NM`]. A substrate that absorbs cannot be seen from:
/// an error names it.
#[allow(clippy::too_many_arguments)]
pub fn rough_response(
    stack: &Stack,
    layer: usize,
    integrator: &SpectralIntegrator,
    thickness_nm: &[f64],
    cos_theta: &[f64],
    roughness: &[f64],
    quadrature: &Quadrature,
    side: Side,
) -> Result<RoughTable> {
    let (seen, layer) = seen_from(stack, layer, side, integrator)?;
    let eta = relative_index(&seen)?;
    let nodes = Nodes {
        thickness_nm,
        cos_theta,
        roughness,
    };
    rough_table(
        &seen,
        layer,
        integrator,
        &nodes,
        quadrature,
        Some(eta),
        Cancel::never(),
    )
}

/// The wavelength whose real indices set η for the geometry of refraction
/// (Fraunhofer's sodium D line, where n_d is given).
pub const ETA_WAVELENGTH_NM: f64 = 589.3;

/// η = n_substrate / n_ambient of a stack as seen (real parts at
/// [`ETA_WAVELENGTH_NM`]).
pub fn relative_index(seen: &Stack) -> Result<f64> {
    let n_v = seen.ambient.index_at(ETA_WAVELENGTH_NM)?.re;
    let n_o = seen.substrate.index_at(ETA_WAVELENGTH_NM)?.re;
    Ok(n_o / n_v)
}

/// `stack` and its layer `layer` as seen from `side`: the reversed stack
/// from the substrate, refused when the substrate absorbs at any of the
/// integrator's wavelengths.
pub fn seen_from<'a>(
    stack: &'a Stack,
    layer: usize,
    side: Side,
    integrator: &SpectralIntegrator,
) -> Result<(Cow<'a, Stack>, usize)> {
    if side == Side::Front {
        return Ok((Cow::Borrowed(stack), layer));
    }
    for &nm in integrator.wavelengths_nm() {
        let k = stack.substrate.index_at(nm)?.im;
        if k != 0.0 {
            return Err(Error::invalid(
                "side",
                format!(
                    "the substrate {} absorbs (k = {k} at {nm} nm): no light arrives from it, so the \
                     film cannot be seen from the substrate side",
                    stack.substrate.name
                ),
            ));
        }
    }
    let n = stack.layers.len();
    let layer = if n == 0 { layer } else { n + 1 - layer };
    Ok((Cow::Owned(stack.reversed()), layer))
}

/// The node axes of a rough table.
struct Nodes<'a> {
    thickness_nm: &'a [f64],
    cos_theta: &'a [f64],
    roughness: &'a [f64],
}

/// One (cos θ, roughness) row of a rough table: F_eff over thickness and
/// A_R, and, when asked, T_eff and A_T.
struct TableRow {
    reflectance: Vec<[f64; 3]>,
    albedo: f64,
    transmission: Option<(Vec<[f64; 3]>, f64)>,
    kept: Option<Vec<[f64; 3]>>,
}

/// The film's smooth colours a rough table weighs: reflectance (and
/// transmittance) rows of thickness × RGB per μ node of `grid`, and at the
/// table's own cos θ nodes (`mirror`, for roughness 0).
struct Smooth<'a> {
    grid: &'a MuGrid,
    rules: &'a Rules,
    on_grid: &'a [f64],
    on_grid_t: &'a [f64],
    mirror: &'a [[f64; 6]],
    n_t: usize,
}

impl Smooth<'_> {
    /// The row at cos θ node `c` (value `cv`) and roughness `rough`, with
    /// T_eff and A_T when `eta` is given.
    fn row(&self, c: usize, cv: f64, rough: f64, eta: Option<f64>) -> TableRow {
        let n_t = self.n_t;
        let mirrored = |out: &mut [[f64; 3]], at: usize| {
            for (o, v) in out.iter_mut().zip(&self.mirror[c * n_t..]) {
                *o = [v[at], v[at + 1], v[at + 2]];
            }
        };
        let transmission = eta.map(|eta| {
            let kernel = Kernel::transmission_with_rules(self.grid, cv, rough, eta, self.rules);
            let mut out = vec![[0.0; 3]; n_t];
            if rough == 0.0 {
                mirrored(&mut out, 3);
            } else {
                weigh_rows(&kernel, self.on_grid_t, 3 * n_t, out.as_flattened_mut());
            }
            (out, kernel.albedo())
        });
        let mut reflectance = vec![[0.0; 3]; n_t];
        // ρ over the reflection lobe: kept_share is linear, so it takes the
        // lobe's means.
        let keeps = |reflectance: &[[f64; 3]], through: &[[f64; 3]]| -> Vec<[f64; 3]> {
            let keep = |(f, t): (&[f64; 3], &[f64; 3])| {
                std::array::from_fn(|c| kept_share(f[c], Some(t[c])))
            };
            reflectance.iter().zip(through).map(keep).collect()
        };
        if rough == 0.0 {
            mirrored(&mut reflectance, 0);
            let kept = transmission.as_ref().map(|(t, _)| keeps(&reflectance, t));
            return TableRow {
                reflectance,
                albedo: 1.0,
                transmission,
                kept,
            };
        }
        let kernel = Kernel::with_rules(self.grid, cv, rough, self.rules);
        weigh_rows(
            &kernel,
            self.on_grid,
            3 * n_t,
            reflectance.as_flattened_mut(),
        );
        let kept = eta.map(|_| {
            let mut through = vec![[0.0; 3]; n_t];
            weigh_rows(&kernel, self.on_grid_t, 3 * n_t, through.as_flattened_mut());
            keeps(&reflectance, &through)
        });
        TableRow {
            reflectance,
            albedo: kernel.albedo(),
            transmission,
            kept,
        }
    }
}

/// [`rough_reflectance`], and with `eta` (the relative index of
/// refraction) the transmittance too; stopping with [`Error::Cancelled`]
/// once `cancel` is set (the sweep looks at it before each μ node, the
/// weighing before each (cos θ, roughness) row).
fn rough_table(
    stack: &Stack,
    layer: usize,
    integrator: &SpectralIntegrator,
    nodes: &Nodes,
    quadrature: &Quadrature,
    eta: Option<f64>,
    cancel: &Cancel,
) -> Result<RoughTable> {
    let Nodes {
        thickness_nm,
        cos_theta,
        roughness,
    } = *nodes;
    check_nodes(stack, layer, thickness_nm, cos_theta, roughness)?;
    let grid = MuGrid::for_stack(stack, quadrature.mu_intervals);
    let (n_t, n_c, n_r) = (thickness_nm.len(), cos_theta.len(), roughness.len());
    // Transmittance doubles the repacked rows and adds two outputs (T_eff
    // and what the reflection lobe keeps).
    let outputs: u64 = if eta.is_some() { 3 } else { 1 };
    let estimate = crate::limits::product(
        &[grid.nodes().len() as u64 + n_c as u64, n_t as u64],
        BYTES_PER_SWEPT_NODE + outputs.min(2).saturating_sub(1) * BYTES_PER_OUTPUT_NODE,
    )
    .zip(crate::limits::product(
        &[n_r as u64, n_c as u64, n_t as u64],
        outputs * BYTES_PER_OUTPUT_NODE,
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
    // One row of thickness × RGB per μ node: reflectance, and transmittance.
    let repack = |at: usize| -> Vec<f64> {
        smooth_on_grid
            .iter()
            .flat_map(|v| [v[at], v[at + 1], v[at + 2]])
            .collect()
    };
    let on_grid = repack(0);
    let on_grid_t = if eta.is_some() { repack(3) } else { Vec::new() };
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
    let smooth = Smooth {
        grid: &grid,
        rules: &rules,
        on_grid: &on_grid,
        on_grid_t: &on_grid_t,
        mirror: &mirror,
        n_t,
    };
    let rows: Vec<TableRow> = (0..n_r * n_c)
        .into_par_iter()
        .map(|row| {
            cancel.check()?;
            let (r, c) = (row / n_c, row % n_c);
            Ok(smooth.row(c, cos_theta[c], roughness[r], eta))
        })
        .collect::<Result<_>>()?;
    let mut table = RoughTable {
        thickness_nm: thickness_nm.to_vec(),
        cos_theta: cos_theta.to_vec(),
        roughness: roughness.to_vec(),
        reflectance: Vec::with_capacity(n_r * n_c * n_t),
        albedo: Vec::with_capacity(n_r * n_c),
        transmittance: Vec::new(),
        transmission_albedo: Vec::new(),
        kept: Vec::new(),
    };
    for row in rows {
        table.reflectance.extend(row.reflectance);
        table.albedo.push(row.albedo);
        if let Some((t, a)) = row.transmission {
            table.transmittance.extend(t);
            table.transmission_albedo.push(a);
        }
        if let Some(k) = row.kept {
            table.kept.extend(k);
        }
    }
    Ok(table)
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

/// A stack's pre-integrated rough reflectance and transmittance at one
/// view angle, as `irid color --roughness` prints it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RoughColor {
    /// View angle in the medium seen from (the ambient, or the substrate
    /// for the substrate side), degrees from the macro normal, in [0, 90).
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
    /// Linear sRGB of T_eff, the film's transmittance pre-integrated over
    /// the refraction lobe (single scattering).
    pub transmittance_rgb: [f64; 3],
    /// CIE XYZ of T_eff.
    pub transmittance_xyz: [f64; 3],
    /// A_T, the albedo of a white GGX refraction lobe (no Fresnel) into the
    /// other medium: the film's transmitted flux is T_eff times it.
    pub transmission_lobe_albedo: f64,
    /// Linear sRGB of F_ms, F_eff compensated for multiple scattering
    /// ([`energy`](super::energy), Turquin's scale): it multiplies the same
    /// white reflection lobe, so the reflected flux is A_R F_ms
    /// (`lobe_albedo` times it). F_eff itself at roughness 0.
    pub reflectance_ms_rgb: [f64; 3],
    /// CIE XYZ of F_ms.
    pub reflectance_ms_xyz: [f64; 3],
    /// Linear sRGB of T_ms, T_eff compensated likewise: the transmitted flux
    /// is A_T T_ms. A lossless film returns A_R F_ms + A_T T_ms = 1.
    pub transmittance_ms_rgb: [f64; 3],
    /// CIE XYZ of T_ms.
    pub transmittance_ms_xyz: [f64; 3],
}

/// `color` with its multiple-scattering fields filled in, its microfacets
/// keeping `kept`; `opaque` for a substrate that absorbs (no refraction
/// lobe: Turquin's conductor form, ρ = F_eff).
fn with_multiple_scattering(mut color: RoughColor, kept: [f64; 3], opaque: bool) -> RoughColor {
    let ss = SingleScattering {
        reflectance: color.reflectance_rgb,
        transmittance: color.transmittance_rgb,
        reflect_albedo: color.lobe_albedo,
        transmit_albedo: if opaque {
            0.0
        } else {
            color.transmission_lobe_albedo
        },
    };
    let kept = if opaque {
        ss.reflectance.map(|f| kept_share(f, None))
    } else {
        kept
    };
    let (r, t) = compensate(color.roughness, &ss, kept);
    color.reflectance_ms_rgb = r;
    color.reflectance_ms_xyz = linear_srgb_to_xyz(r);
    color.transmittance_ms_rgb = t;
    color.transmittance_ms_xyz = linear_srgb_to_xyz(t);
    color
}

/// Whether the substrate of `seen` absorbs at any of the integrator's
/// wavelengths (opaque: no light goes through it).
fn opaque_substrate(seen: &Stack, integrator: &SpectralIntegrator) -> Result<bool> {
    for &nm in integrator.wavelengths_nm() {
        if seen.substrate.index_at(nm)?.im != 0.0 {
            return Ok(true);
        }
    }
    Ok(false)
}

/// F_eff and T_eff of `stack` (its layers at their own thicknesses) seen
/// from its ambient at each view angle (degrees, in [0, 90)) for
/// `roughness` ∈ [0, 1]: [`rough_colors_from`] the front.
pub fn rough_colors(
    stack: &Stack,
    integrator: &SpectralIntegrator,
    angles_deg: &[f64],
    roughness: f64,
) -> Result<Vec<RoughColor>> {
    rough_colors_from(stack, integrator, angles_deg, roughness, Side::Front)
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
    rough_colors_from_cancellable(
        stack,
        integrator,
        angles_deg,
        roughness,
        Side::Front,
        cancel,
    )
}

/// F_eff, T_eff and both lobes' albedos of `stack` (its layers at their own
/// thicknesses) seen from `side` at each view angle (degrees, in [0, 90),
/// in the medium seen from) for `roughness` ∈ [0, 1]. At roughness 0 the
/// colours are the smooth ones of [`stack_colors`](crate::color::stack_colors) (of the reversed stack
/// from the substrate), exactly.
pub fn rough_colors_from(
    stack: &Stack,
    integrator: &SpectralIntegrator,
    angles_deg: &[f64],
    roughness: f64,
    side: Side,
) -> Result<Vec<RoughColor>> {
    rough_colors_from_cancellable(
        stack,
        integrator,
        angles_deg,
        roughness,
        side,
        Cancel::never(),
    )
}

/// [`rough_colors_from`], stopping with [`Error::Cancelled`] once `cancel`
/// is set (it looks between blocks of a few milliseconds).
pub fn rough_colors_from_cancellable(
    stack: &Stack,
    integrator: &SpectralIntegrator,
    angles_deg: &[f64],
    roughness: f64,
    side: Side,
    cancel: &Cancel,
) -> Result<Vec<RoughColor>> {
    check_roughness("roughness", roughness)?;
    let (seen, _) = seen_from(stack, 1, side, integrator)?;
    let eta = relative_index(&seen)?;
    if roughness == 0.0 {
        let grid = MuGrid::new(Quadrature::default().mu_intervals, None);
        let quadrature = Quadrature::default();
        return Ok(
            stack_colors_cancellable(&seen, integrator, angles_deg, cancel)?
                .into_iter()
                .map(|c| {
                    let cos = c.angle_deg.to_radians().cos();
                    let through = Kernel::transmission(&grid, cos, 0.0, eta, &quadrature).albedo();
                    RoughColor {
                        angle_deg: c.angle_deg,
                        roughness,
                        reflectance_rgb: c.reflectance_rgb,
                        reflectance_xyz: c.reflectance_xyz,
                        lobe_albedo: 1.0,
                        transmittance_rgb: c.transmittance_rgb,
                        transmittance_xyz: c.transmittance_xyz,
                        transmission_lobe_albedo: through,
                        reflectance_ms_rgb: c.reflectance_rgb,
                        reflectance_ms_xyz: c.reflectance_xyz,
                        transmittance_ms_rgb: c.transmittance_rgb,
                        transmittance_ms_xyz: c.transmittance_xyz,
                    }
                })
                .collect(),
        );
    }
    check_angles(angles_deg)?;
    if angles_deg.is_empty() {
        return Ok(Vec::new());
    }
    let opaque = opaque_substrate(&seen, integrator)?;
    let table = table_at_angles(&seen, integrator, angles_deg, roughness, Some(eta), cancel)?;
    Ok(angles_deg
        .par_iter()
        .enumerate()
        .map(|(c, &angle)| {
            let (rgb, t_rgb) = (table.at(0, c, 0), table.transmittance_at(0, c, 0));
            RoughColor {
                angle_deg: angle,
                roughness,
                reflectance_rgb: rgb,
                reflectance_xyz: linear_srgb_to_xyz(rgb),
                lobe_albedo: table.albedo[c],
                transmittance_rgb: t_rgb,
                transmittance_xyz: linear_srgb_to_xyz(t_rgb),
                transmission_lobe_albedo: table.transmission_albedo[c],
                reflectance_ms_rgb: [0.0; 3],
                reflectance_ms_xyz: [0.0; 3],
                transmittance_ms_rgb: [0.0; 3],
                transmittance_ms_xyz: [0.0; 3],
            }
        })
        .enumerate()
        .map(|(c, color)| with_multiple_scattering(color, table.kept[c], opaque))
        .collect())
}

/// F_eff alone of `stack` (its layers at their own thicknesses) seen from
/// its ambient at each view angle (degrees, in [0, 90)) for `roughness` ∈
/// [0, 1]: the `reflectance_rgb` of [`rough_colors`] bit for bit, without
/// the transmission kernel's work (what a colour fit compares).
pub fn rough_reflectance_colors(
    stack: &Stack,
    integrator: &SpectralIntegrator,
    angles_deg: &[f64],
    roughness: f64,
) -> Result<Vec<[f64; 3]>> {
    check_roughness("roughness", roughness)?;
    if roughness == 0.0 {
        return Ok(
            stack_colors_cancellable(stack, integrator, angles_deg, Cancel::never())?
                .into_iter()
                .map(|c| c.reflectance_rgb)
                .collect(),
        );
    }
    check_angles(angles_deg)?;
    if angles_deg.is_empty() {
        return Ok(Vec::new());
    }
    let table = table_at_angles(
        stack,
        integrator,
        angles_deg,
        roughness,
        None,
        Cancel::never(),
    )?;
    Ok((0..angles_deg.len()).map(|c| table.at(0, c, 0)).collect())
}

/// Refuses a view angle outside [0, 90) degrees.
fn check_angles(angles_deg: &[f64]) -> Result<()> {
    match angles_deg.iter().find(|a| !(**a >= 0.0 && **a < 90.0)) {
        Some(a) => Err(Error::invalid(
            "angle",
            format!("{a} is outside [0, 90) degrees"),
        )),
        None => Ok(()),
    }
}

/// The rough table of `seen` at its own thicknesses, one row per view
/// angle (degrees, checked, not empty) at `roughness` > 0, with the
/// transmittance when `eta` is given.
fn table_at_angles(
    seen: &Stack,
    integrator: &SpectralIntegrator,
    angles_deg: &[f64],
    roughness: f64,
    eta: Option<f64>,
    cancel: &Cancel,
) -> Result<RoughTable> {
    let cos: Vec<f64> = angles_deg.iter().map(|a| a.to_radians().cos()).collect();
    let (swept, layer) = swept_layer(seen);
    let thickness = swept.layers.get(layer - 1).map_or(0.0, |l| l.thickness_nm);
    let nodes = Nodes {
        thickness_nm: &[thickness],
        cos_theta: &cos,
        roughness: &[roughness],
    };
    rough_table(
        &swept,
        layer,
        integrator,
        &nodes,
        &Quadrature::default(),
        eta,
        cancel,
    )
}
