//! The benchmark proper: for each fixed stack and each method, the time per
//! shading evaluation (one thickness, one angle, to linear sRGB) and the
//! error against the 1 nm exact reference at random points.
//!
//! Times are single-threaded: a renderer parallelizes over pixels, so what
//! matters is the cost of one evaluation. Each method evaluates all points in
//! one loop and the wall time is divided by the count, so compare methods by
//! their ratios within one run; absolute figures move with the machine's load.

use std::hint::black_box;
use std::time::Instant;

use rand::{Rng, SeedableRng};

use super::stacks::{fixed_stacks, BenchStack};
use crate::analytic::{AnalyticFilm, Variant};
use crate::color::{delta_e2000_rgb, Sampling, SpectralIntegrator};
use crate::error::{Error, Result};
use crate::lut;
use crate::optics::{solve, StackGrid};

/// What a benchmark run measures and how thoroughly.
#[derive(Clone, Debug)]
pub struct Options {
    /// Random (thickness, cos θ) points per stack.
    pub points: usize,
    /// Seed of the PCG64 stream that draws the points, so runs compare.
    pub seed: u64,
    /// LUT resolutions as (thickness nodes, angle nodes), coarse to fine.
    pub lut_resolutions: Vec<(usize, usize)>,
    /// Whether each LUT resolution is also measured stored as f16.
    pub lut_half: bool,
    /// Built-in scenes rendered in full, and at what size (width, height).
    pub render_scenes: Vec<&'static str>,
    /// (width, height) in pixels of each full render.
    pub render_size: (u32, u32),
    /// Runs of each inverse-design workload (gradient, fits) the report
    /// gives the fastest of.
    pub inverse_repeat: usize,
}

impl Options {
    /// The published benchmark: 10 000 points per stack, four LUT
    /// resolutions from 16×8 to 1024×64 with f16 copies, two scenes
    /// rendered at 160×120, and the inverse-design workloads 20 times.
    pub fn full() -> Options {
        Options {
            points: 10_000,
            seed: 1,
            lut_resolutions: vec![(16, 8), (64, 16), (256, 32), (1024, 64)],
            lut_half: true,
            render_scenes: vec!["bubbles-noise", "absorbing-sphere"],
            render_size: (160, 120),
            inverse_repeat: 20,
        }
    }

    /// Small enough for a test: fewer points, three LUT resolutions.
    pub fn quick() -> Options {
        Options {
            points: 200,
            seed: 1,
            lut_resolutions: vec![(8, 4), (32, 8), (128, 16)],
            lut_half: true,
            render_scenes: vec!["absorbing-sphere"],
            render_size: (32, 24),
            inverse_repeat: 2,
        }
    }
}

/// A group of methods that share a technique (and a colour on the plot).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Family {
    /// The transfer matrix solved per evaluation, under some sampling.
    Direct,
    /// Baked rgb tables, bilinearly interpolated.
    Lut,
    /// The single-film analytic model.
    Analytic,
}

impl Family {
    /// Every family, in report and legend order (the order of
    /// [`Family::index`]).
    pub const ALL: [Family; 3] = [Family::Direct, Family::Lut, Family::Analytic];

    /// The family's name in reports and the plot legend.
    pub fn label(self) -> &'static str {
        match self {
            Family::Direct => "direct TMM",
            Family::Lut => "LUT (bilinear)",
            Family::Analytic => "analytic (one film)",
        }
    }

    /// Position in [`Family::ALL`]; selects the plot colour.
    pub fn index(self) -> usize {
        self as usize
    }
}

/// One way of computing a film's reflectance colour that the benchmark
/// times and scores.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Method {
    /// The solver at every wavelength of this sampling, integrated to
    /// linear sRGB (`exact` is the reference).
    Direct(Sampling),
    /// A baked rgb table over the stack's thickness range and cos θ ∈
    /// [0, 1], sampled bilinearly.
    Lut {
        /// Nodes on the thickness axis.
        thickness_nodes: usize,
        /// Nodes on the cos θ axis.
        angle_nodes: usize,
        /// Stored as f16 (the f32 table rounded) rather than f32.
        half: bool,
    },
    /// The analytic one-film model (only for stacks with exactly one
    /// layer).
    Analytic(Variant),
}

impl Method {
    /// The method's name in reports, e.g. `direct exact`, `LUT 64x16 f32`.
    pub fn name(&self) -> String {
        match self {
            Method::Direct(s) => format!("direct {s}"),
            Method::Lut {
                thickness_nodes,
                angle_nodes,
                half,
            } => format!(
                "LUT {thickness_nodes}x{angle_nodes} {}",
                if *half { "f16" } else { "f32" }
            ),
            Method::Analytic(v) => v.label().to_string(),
        }
    }

    /// The family the method belongs to.
    pub fn family(&self) -> Family {
        match self {
            Method::Direct(_) => Family::Direct,
            Method::Lut { .. } => Family::Lut,
            Method::Analytic(_) => Family::Analytic,
        }
    }
}

/// One method on one stack.
#[derive(Clone, Debug)]
pub struct Row {
    /// The fixed stack's short name.
    pub stack: String,
    /// The method measured.
    pub method: Method,
    /// Single-threaded nanoseconds per evaluation (one thickness, one
    /// angle, to linear sRGB), from the fastest repetition of the loop.
    pub ns_per_eval: f64,
    /// Largest |ΔR| over points and channels (linear sRGB reflectance).
    pub max_abs: f64,
    /// 99th percentile over points of the largest channel |ΔR|.
    pub p99_abs: f64,
    /// Mean CIEDE2000 between the method's and the exact reflectance
    /// colour over the finite points.
    pub mean_de2000: f64,
    /// Largest CIEDE2000 over the finite points.
    pub max_de2000: f64,
    /// Points evaluated, non-finite ones included.
    pub points: usize,
    /// Points where the method returned a non-finite colour.
    pub nonfinite: usize,
    /// One-off cost before the first evaluation (baking, for a LUT).
    pub setup_s: Option<f64>,
    /// The largest reference reflectance channel over the points: errors
    /// read differently on a gain stack whose reflectance exceeds 1.
    pub reference_max: f64,
}

/// A method that could not be measured on a stack, and why.
#[derive(Clone, Debug)]
pub struct Skipped {
    /// The fixed stack's short name.
    pub stack: String,
    /// The method that was not measured.
    pub method: Method,
    /// The reason, e.g. values beyond f16's range.
    pub why: String,
}

/// Every method measured on every fixed stack, and those that could not be.
pub fn run(options: &Options) -> Result<(Vec<Row>, Vec<Skipped>)> {
    let (mut rows, mut skipped) = (Vec::new(), Vec::new());
    for bench in fixed_stacks()? {
        let (r, s) = run_stack(&bench, options)?;
        rows.extend(r);
        skipped.extend(s);
    }
    Ok((rows, skipped))
}

/// Every method measured on one stack: the exact direct method first (the
/// reference for every other row's errors), then the other samplings, the
/// LUT resolutions (and their f16 copies), and the analytic variants where
/// the stack has one layer.
pub fn run_stack(bench: &BenchStack, options: &Options) -> Result<(Vec<Row>, Vec<Skipped>)> {
    let points = sample_points(bench, options.points, options.seed);

    // The exact method is the reference: its error is zero by construction.
    let mut exact = Direct::new(bench, Sampling::Exact)?;
    let (ns, reference) = time_all(&points, |t, c| exact.eval(t, c));
    let mut rows = vec![row(
        bench,
        Method::Direct(Sampling::Exact),
        ns,
        &reference,
        &reference,
        None,
    )];
    let mut skipped = Vec::new();
    let stack = StackReference {
        bench,
        points,
        reference,
    };

    for sampling in [
        Sampling::Rgb3,
        Sampling::Uniform(9),
        Sampling::Uniform(41),
        Sampling::Uniform(81),
    ] {
        let mut direct = Direct::new(bench, sampling)?;
        rows.push(stack.row(Method::Direct(sampling), |t, c| direct.eval(t, c), None));
    }

    for &(thickness_nodes, angle_nodes) in &options.lut_resolutions {
        let (lut_rows, refused) = stack.lut_rows(thickness_nodes, angle_nodes, options.lut_half)?;
        rows.extend(lut_rows);
        skipped.extend(refused);
    }

    if let Some(film) = AnalyticFilm::from_stack(&bench.stack) {
        for variant in [Variant::BelcourBarla, Variant::Gltf] {
            rows.push(stack.row(
                Method::Analytic(variant),
                |t, c| film.reflectance_rgb(variant, t, c),
                None,
            ));
        }
    }
    Ok((rows, skipped))
}

/// One stack's points and the exact reference values at them, which every
/// other method's row is measured against.
struct StackReference<'a> {
    bench: &'a BenchStack,
    points: Vec<(f64, f64)>,
    reference: Vec<[f64; 3]>,
}

impl StackReference<'_> {
    /// `method`'s row: `eval` timed over the points and compared with the
    /// reference; `setup_s` is its bake time, if any.
    fn row(
        &self,
        method: Method,
        eval: impl FnMut(f64, f64) -> [f64; 3],
        setup_s: Option<f64>,
    ) -> Row {
        let (ns, out) = time_all(&self.points, eval);
        row(self.bench, method, ns, &out, &self.reference, setup_s)
    }

    /// The rows of the f32 table with these node counts and, with `half`,
    /// of its f16 copy, or that copy as skipped when its values exceed
    /// f16's range.
    fn lut_rows(
        &self,
        thickness_nodes: usize,
        angle_nodes: usize,
        half: bool,
    ) -> Result<(Vec<Row>, Option<Skipped>)> {
        let lut_method = |half| Method::Lut {
            thickness_nodes,
            angle_nodes,
            half,
        };
        let start = Instant::now();
        let table = lut::bake(&self.bench.bake_spec(thickness_nodes, angle_nodes, false))?;
        let bake_s = start.elapsed().as_secs_f64();
        let mut rows = vec![self.row(
            lut_method(false),
            |t, c| lut_reflectance(&table, t, c),
            Some(bake_s),
        )];
        if !half {
            return Ok((rows, None));
        }
        // The f16 table is the f32 one rounded (its setup is both), not a
        // second bake: the bake check that one would repeat is not used here.
        let start = Instant::now();
        let half = match table.rounded_to_half() {
            Ok(half) => half,
            // Values beyond f16's range (a gain film near its resonances)
            // would be stored as infinity: report that instead.
            Err(Error::HalfOverflow { why }) => {
                let refused = Skipped {
                    stack: self.bench.name.to_string(),
                    method: lut_method(true),
                    why,
                };
                return Ok((rows, Some(refused)));
            }
            Err(e) => return Err(e),
        };
        let setup_s = bake_s + start.elapsed().as_secs_f64();
        rows.push(self.row(
            lut_method(true),
            |t, c| lut_reflectance(&half, t, c),
            Some(setup_s),
        ));
        Ok((rows, None))
    }
}

#[inline]
fn lut_reflectance(table: &lut::Lut, thickness_nm: f64, cos_theta: f64) -> [f64; 3] {
    table
        .sample_rgb(thickness_nm as f32, cos_theta as f32)
        .reflectance
        .map(f64::from)
}

/// Uniform in the stack's thickness range and in cos θ ∈ [0, 1] (the
/// LUT's axes), from a seeded generator so runs are comparable.
fn sample_points(bench: &BenchStack, n: usize, seed: u64) -> Vec<(f64, f64)> {
    let mut rng = rand_pcg::Pcg64::seed_from_u64(seed);
    let (t0, t1) = bench.thickness_range_nm;
    (0..n)
        .map(|_| {
            let t = t0 + (t1 - t0) * rng.random::<f64>();
            let c = rng.random::<f64>();
            (t, c)
        })
        .collect()
}

/// Evaluates every point in one loop; repeats while the whole loop takes
/// under 50 ms (up to 5 times) and keeps the fastest, so cheap methods are
/// not timed at the clock's resolution.
fn time_all(
    points: &[(f64, f64)],
    mut eval: impl FnMut(f64, f64) -> [f64; 3],
) -> (f64, Vec<[f64; 3]>) {
    let mut out = vec![[0.0; 3]; points.len()];
    let mut best = f64::INFINITY;
    let mut total = 0.0;
    for _ in 0..5 {
        let start = Instant::now();
        for (o, &(t, c)) in out.iter_mut().zip(points) {
            *o = eval(black_box(t), black_box(c));
        }
        black_box(&out);
        let s = start.elapsed().as_secs_f64();
        best = best.min(s);
        total += s;
        if total > 0.05 {
            break;
        }
    }
    (best * 1e9 / points.len().max(1) as f64, out)
}

fn row(
    bench: &BenchStack,
    method: Method,
    ns_per_eval: f64,
    out: &[[f64; 3]],
    reference: &[[f64; 3]],
    setup_s: Option<f64>,
) -> Row {
    // A non-finite output is counted apart, so that one point on a gain
    // resonance cannot turn every figure into NaN; the error figures are over
    // the finite ones. (An f16 table that would overflow is refused by the
    // baker and reported as not measured instead.)
    let mut abs: Vec<f64> = Vec::with_capacity(out.len());
    let mut de_sum = 0.0;
    let mut de_max = 0.0f64;
    let mut nonfinite = 0;
    for (a, b) in out.iter().zip(reference) {
        if !a.iter().all(|v| v.is_finite()) {
            nonfinite += 1;
            continue;
        }
        let d = (0..3).map(|c| (a[c] - b[c]).abs()).fold(0.0, f64::max);
        abs.push(d);
        let de = if a == b { 0.0 } else { delta_e2000_rgb(*a, *b) };
        de_sum += de;
        de_max = de_max.max(de);
    }
    abs.sort_by(f64::total_cmp);
    let p99 = abs
        .get(((abs.len() as f64 * 0.99).ceil() as usize).saturating_sub(1))
        .copied()
        .unwrap_or(0.0);
    Row {
        stack: bench.name.to_string(),
        method,
        ns_per_eval,
        max_abs: abs.last().copied().unwrap_or(0.0),
        p99_abs: p99,
        mean_de2000: de_sum / abs.len().max(1) as f64,
        max_de2000: de_max,
        points: out.len(),
        nonfinite,
        setup_s,
        reference_max: reference
            .iter()
            .flat_map(|c| c.iter().copied())
            .fold(0.0, f64::max),
    }
}

/// Direct evaluation as a renderer would do it: indices cached per
/// wavelength, one solve per sampled wavelength, one weighted sum per channel.
struct Direct {
    integrator: SpectralIntegrator,
    grid: StackGrid,
    thicknesses_nm: Vec<f64>,
    varying: usize,
    spectrum: Vec<f64>,
}

impl Direct {
    fn new(bench: &BenchStack, sampling: Sampling) -> Result<Direct> {
        let integrator = SpectralIntegrator::new(sampling);
        let grid = StackGrid::new(&bench.stack, integrator.wavelengths_nm())?;
        Ok(Direct {
            spectrum: vec![0.0; grid.wavelengths_nm().len()],
            integrator,
            thicknesses_nm: grid.thicknesses_nm().to_vec(),
            grid,
            varying: bench.varying_layer,
        })
    }

    #[inline]
    fn eval(&mut self, thickness_nm: f64, cos_theta: f64) -> [f64; 3] {
        self.thicknesses_nm[self.varying] = thickness_nm;
        for (s, (w, n)) in self.spectrum.iter_mut().zip(self.grid.iter()) {
            *s = solve(n, &self.thicknesses_nm, w, cos_theta).r();
        }
        self.integrator.rgb(&self.spectrum)
    }
}
