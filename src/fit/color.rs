//! Fitting thicknesses to colours: the reflected colour of the stack (linear
//! sRGB under a white, the exact 1 nm sum) at given angles against target
//! colours, minimizing Σ ΔE00² over the angles with the global search of
//! [`super::search`].
//!
//! The smooth film's Jacobian is exact ([`colors_with_gradient`], chained
//! through [`delta_e00_with_gradient`]). A rough film's colour (the
//! reflectance pre-integrated over a GGX lobe,
//! [`crate::rough::rough_reflectance_colors`])
//! has no thickness derivative: its Jacobian is taken by central
//! differences of that colour.

use serde::Serialize;

use super::lm::Minimum;
use super::search::{self, Library, Loss, Model};
use super::vary::Vary;
use super::SCAN_BUDGET;
use crate::color::gradient::{colors_with_gradient, delta_e00_with_gradient};
use crate::color::{delta_e2000_rgb, stack_colors, Sampling, SpectralIntegrator, White};
use crate::error::{Error, Result};
use crate::optics::lanes::SpectralWeights;
use crate::optics::{Stack, StackGrid};
use crate::rough::{check_roughness, rough_reflectance_colors};

/// A colour to match: linear sRGB of the reflectance seen at an angle.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ColorTarget {
    /// Incidence angle in the ambient, degrees in [0, 90).
    pub angle_deg: f64,
    /// Linear sRGB, (1, 1, 1) for a perfect reflector under the white.
    pub rgb: [f64; 3],
}

/// The thicknesses whose colours come closest to the targets.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ColorFit {
    /// The varied layers, 1-based from the top.
    pub layers: Vec<usize>,
    /// Their fitted thicknesses, nm.
    pub thickness_nm: Vec<f64>,
    /// The targets' angles, degrees.
    pub angle_deg: Vec<f64>,
    /// CIEDE2000 between the fitted and the target colour at each angle.
    pub delta_e2000: Vec<f64>,
    /// The fitted stack's colour at each angle (linear sRGB).
    pub rgb: Vec<[f64; 3]>,
    /// Other minima whose colours match as well: their largest ΔE00 over
    /// the angles within [`Self::tolerance_de2000`] of the best's, at
    /// thicknesses more than a scan step away (another interference order,
    /// say). The colours at these angles cannot tell them from the best.
    pub alternatives: Vec<ColorAlternative>,
    /// The ΔE00 margin of [`Self::alternatives`]: [`AMBIGUITY_DE2000`].
    pub tolerance_de2000: f64,
}

/// A colour fit's minimum other than the best.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ColorAlternative {
    /// Its thicknesses, nm, in the order of [`ColorFit::layers`].
    pub thickness_nm: Vec<f64>,
    /// Its ΔE00 against the target at each angle.
    pub delta_e2000: Vec<f64>,
}

impl ColorFit {
    /// True when another thickness matches the colours as well.
    pub fn is_ambiguous(&self) -> bool {
        !self.alternatives.is_empty()
    }
}

/// How much worse (largest ΔE00 over the angles) another minimum may match
/// and still count as matching as well: one ΔE00, about the smallest
/// colour difference an observer notices side by side.
pub const AMBIGUITY_DE2000: f64 = 1.0;

/// How far (nm, in some varied layer) another minimum must lie from the
/// best to be another optimum rather than the same one: a few nm move a
/// film's colour by several ΔE00, interference orders lie 100 nm or more
/// apart.
pub const AMBIGUITY_MIN_NM: f64 = 10.0;

/// Fits `vary`'s layers of `stack` so that its reflected colours under
/// `white` match `targets`; with `roughness`, the rough film's colours.
/// Errors name the target outside the colours any passive film can reflect.
pub fn fit_color(
    stack: &Stack,
    vary: &Vary,
    targets: &[ColorTarget],
    white: White,
    roughness: Option<f64>,
) -> Result<ColorFit> {
    if targets.is_empty() {
        return Err(Error::invalid("target_rgb", "no target colour"));
    }
    if let Some(r) = roughness {
        check_roughness("roughness", r)?;
    }
    let integrator = SpectralIntegrator::with_white(Sampling::Exact, white);
    for (j, t) in targets.iter().enumerate() {
        check_target(&integrator, t, &format!("target_rgb[{j}]"))?;
    }
    stack.validate()?;
    let model = ColorModel::new(stack, vary, targets, integrator.clone(), roughness)?;
    let loss = Targets(targets.iter().map(|t| t.rgb).collect());
    let library = Library::new(&model, &vary.bounds_nm, &vary.start(stack), SCAN_BUDGET)?;
    let found = search::search(&model, &loss, &library, &vary.bounds_nm)?;
    let best = &found.minima[0];
    let alternatives = alternatives(&found.minima);
    let fitted = vary.apply(stack, &best.x);
    let angles: Vec<f64> = targets.iter().map(|t| t.angle_deg).collect();
    let rgb: Vec<[f64; 3]> = match roughness {
        Some(r) => rough_reflectance_colors(&fitted, &integrator, &angles, r)?,
        None => stack_colors(&fitted, &integrator, &angles)?
            .iter()
            .map(|c| c.reflectance_rgb)
            .collect(),
    };
    Ok(ColorFit {
        layers: vary.layers.clone(),
        thickness_nm: best.x.clone(),
        delta_e2000: rgb
            .iter()
            .zip(targets)
            .map(|(c, t)| delta_e2000_rgb(*c, t.rgb))
            .collect(),
        angle_deg: angles,
        rgb,
        alternatives,
        tolerance_de2000: AMBIGUITY_DE2000,
    })
}

/// The minima after the best (`minima` ascending) that match the targets
/// as well, in [`ColorFit::alternatives`]' sense, each more than
/// [`AMBIGUITY_MIN_NM`] from the best and from those kept before it (two
/// refinements that stop a little apart on one optimum are one).
fn alternatives(minima: &[Minimum]) -> Vec<ColorAlternative> {
    let worst = |m: &Minimum| m.residuals.iter().copied().fold(0.0, f64::max);
    let far = |a: &[f64], b: &[f64]| {
        a.iter()
            .zip(b)
            .any(|(a, b)| (a - b).abs() > AMBIGUITY_MIN_NM)
    };
    let best = &minima[0];
    let mut kept: Vec<ColorAlternative> = Vec::new();
    for m in &minima[1..] {
        if worst(m) <= worst(best) + AMBIGUITY_DE2000
            && far(&m.x, &best.x)
            && kept.iter().all(|k| far(&m.x, &k.thickness_nm))
        {
            kept.push(ColorAlternative {
                thickness_nm: m.x.clone(),
                delta_e2000: m.residuals.clone(),
            });
        }
    }
    kept
}

/// Checks one target: its angle in [0, 90) and its colour one a passive
/// film can reflect ([`check_reachable`]); errors name `what`.
pub fn check_target(integrator: &SpectralIntegrator, t: &ColorTarget, what: &str) -> Result<()> {
    if !(0.0..90.0).contains(&t.angle_deg) {
        return Err(Error::invalid(
            what,
            format!("angle {} is outside [0, 90) degrees", t.angle_deg),
        ));
    }
    check_reachable(integrator, t.rgb).map_err(|why| {
        Error::invalid(
            what,
            format!("({}, {}, {}) {why}", t.rgb[0], t.rgb[1], t.rgb[2]),
        )
    })
}

/// Ok when `rgb` lies in the object-colour solid: the colours of the
/// spectra 0 ≤ R(λ) ≤ 1, which hold every passive film's reflectance. The
/// solid is the zonotope Σ R(λ) w(λ) of the integrator's weights w; its
/// facets are spanned by pairs of weights, and a point is inside when no
/// facet's normal u has u·rgb above the solid's support Σ max(0, u·w).
fn check_reachable(
    integrator: &SpectralIntegrator,
    rgb: [f64; 3],
) -> std::result::Result<(), String> {
    if rgb.iter().any(|c| !c.is_finite()) {
        return Err("is not a finite colour".into());
    }
    let [r, g, b] = integrator.rgb_weights();
    let w: Vec<[f64; 3]> = (0..r.len()).map(|i| [r[i], g[i], b[i]]).collect();
    let scale: f64 = w
        .iter()
        .map(|v| v.iter().map(|c| c.abs()).sum::<f64>())
        .sum();
    for i in 0..w.len() {
        for j in i + 1..w.len() {
            let u = cross(w[i], w[j]);
            let norm = dot3(u, u).sqrt();
            if norm == 0.0 {
                continue;
            }
            let (mut up, mut down) = (0.0, 0.0);
            for v in &w {
                let s = dot3(u, *v);
                if s > 0.0 {
                    up += s;
                } else {
                    down -= s;
                }
            }
            let x = dot3(u, rgb);
            // Rounding of the supports: relative to the largest product.
            let slack = 1e-9 * norm * scale;
            if x > up + slack || -x > down + slack {
                return Err(
                    "lies outside the colours any passive film can reflect (its reflectance would exceed 1 or fall below 0 somewhere)"
                        .into(),
                );
            }
        }
    }
    Ok(())
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn dot3(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// The stack's reflected colour at each target angle.
struct ColorModel {
    stack: Stack,
    vary: Vary,
    angles_deg: Vec<f64>,
    cos_theta0: Vec<f64>,
    integrator: SpectralIntegrator,
    weights: SpectralWeights,
    grid: StackGrid,
    roughness: Option<f64>,
    max_index: Vec<f64>,
}

impl ColorModel {
    fn new(
        stack: &Stack,
        vary: &Vary,
        targets: &[ColorTarget],
        integrator: SpectralIntegrator,
        roughness: Option<f64>,
    ) -> Result<ColorModel> {
        let grid = StackGrid::new(stack, integrator.wavelengths_nm())?;
        let media = stack.layers.len() + 2;
        let max_index = vary
            .layers
            .iter()
            .map(|&l| {
                grid.indices()
                    .chunks_exact(media)
                    .map(|row| row[l].re)
                    .fold(1.0, f64::max)
            })
            .collect();
        Ok(ColorModel {
            stack: stack.clone(),
            vary: vary.clone(),
            angles_deg: targets.iter().map(|t| t.angle_deg).collect(),
            cos_theta0: targets
                .iter()
                .map(|t| t.angle_deg.to_radians().cos())
                .collect(),
            weights: integrator.rgb_lane_weights(),
            integrator,
            grid,
            roughness,
            max_index,
        })
    }
}

impl Model for ColorModel {
    fn predictions(&self) -> usize {
        3 * self.angles_deg.len()
    }

    fn predict(&self, x: &[f64], out: &mut [f64]) -> Result<()> {
        if let Some(r) = self.roughness {
            let colors = rough_reflectance_colors(
                &self.vary.apply(&self.stack, x),
                &self.integrator,
                &self.angles_deg,
                r,
            )?;
            for (j, c) in colors.iter().enumerate() {
                out[3 * j..3 * j + 3].copy_from_slice(c);
            }
            return Ok(());
        }
        let mut t = Vec::new();
        self.vary.fill(&self.stack.thicknesses_nm(), x, &mut t);
        for (j, &c) in self.cos_theta0.iter().enumerate() {
            let power = self.grid.weighted_spectrum(&t, c, &self.weights);
            out[3 * j..3 * j + 3].copy_from_slice(&power.reflectance);
        }
        if out.iter().any(|v| !v.is_finite()) {
            return Err(Error::invalid(
                "fit",
                "an incoherent gain layer lases at the varied thicknesses",
            ));
        }
        Ok(())
    }

    fn predict_with_jacobian(
        &self,
        x: &[f64],
        out: &mut [f64],
        jacobian: &mut [f64],
    ) -> Result<()> {
        if self.roughness.is_none() {
            let stack = self.vary.apply(&self.stack, x);
            let colors = colors_with_gradient(&stack, &self.integrator, &self.angles_deg)?;
            let width = out.len();
            for (j, c) in colors.iter().enumerate() {
                out[3 * j..3 * j + 3].copy_from_slice(&c.reflectance_rgb);
                for (p, &layer) in self.vary.layers.iter().enumerate() {
                    let d = c.d_reflectance_rgb[layer - 1];
                    jacobian[p * width + 3 * j..p * width + 3 * j + 3].copy_from_slice(&d);
                }
            }
            return Ok(());
        }
        // The rough colour: central differences.
        self.predict(x, out)?;
        let width = out.len();
        let (mut up, mut down) = (vec![0.0; width], vec![0.0; width]);
        for p in 0..x.len() {
            let (lo, hi) = self.vary.bounds_nm[p];
            let h = 1e-3;
            let (a, b) = ((x[p] + h).min(hi.max(x[p])), (x[p] - h).max(lo.min(x[p])));
            let mut xs = x.to_vec();
            xs[p] = a;
            self.predict(&xs, &mut up)?;
            xs[p] = b;
            self.predict(&xs, &mut down)?;
            for i in 0..width {
                jacobian[p * width + i] = (up[i] - down[i]) / (a - b);
            }
        }
        Ok(())
    }

    fn scan_steps(&self) -> Vec<f64> {
        // The colour sums carry weight from about 400 nm up.
        self.max_index.iter().map(|n| 400.0 / (8.0 * n)).collect()
    }
}

/// ΔE00 of each angle's colour against its target.
struct Targets(Vec<[f64; 3]>);

impl Loss for Targets {
    fn residual_count(&self) -> usize {
        self.0.len()
    }

    /// ΔE00 of 1e-3 at every angle: far below what an eye or a camera
    /// tells apart, and where ΔE00's kink at 0 slows the refinement.
    fn chi2_floor(&self) -> f64 {
        1e-6 * self.0.len() as f64
    }

    fn residuals(&self, p: &[f64], r: &mut [f64]) {
        for (j, target) in self.0.iter().enumerate() {
            r[j] = delta_e2000_rgb([p[3 * j], p[3 * j + 1], p[3 * j + 2]], *target);
        }
    }

    fn chain(&self, p: &[f64], dp: &[f64], r: &mut [f64], jacobian: &mut [f64]) {
        self.residuals(p, r);
        let (m, width) = (self.0.len(), p.len());
        let parameters = dp.len() / width;
        for (j, target) in self.0.iter().enumerate() {
            let rgb = [p[3 * j], p[3 * j + 1], p[3 * j + 2]];
            let (_, gradient) = delta_e00_with_gradient(rgb, *target);
            for q in 0..parameters {
                jacobian[q * m + j] = (0..3)
                    .map(|c| gradient[c] * dp[q * width + 3 * j + c])
                    .sum();
            }
        }
    }
}
