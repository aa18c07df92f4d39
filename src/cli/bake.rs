//! `irid bake STACK.toml -o OUT.exr`: a lookup table of the stack's response.

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use anyhow::{anyhow, bail, Context, Result};
use irid::atomic::OutputSet;
use irid::lut::rough::bake_rough;
use irid::lut::{
    bake_with_progress, validate, BakeSpec, Kind, Layout, Resolution, VALIDATION_SEED,
};
use irid::optics::Stack;

use super::args::{parse_choice, parse_range, FilmArgs};

#[derive(clap::Args)]
pub struct Args {
    /// Output table (OpenEXR); written atomically.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Thickness range MIN:MAX in nm of the varying layer [default: its
    /// thickness in the stack file, a single node].
    #[arg(long)]
    pub thickness: Option<String>,
    #[command(flatten)]
    pub film: FilmArgs,
    /// rgb (linear sRGB under D65) or spectral (R and T per wavelength).
    #[arg(long, default_value = "rgb")]
    pub kind: String,
    /// Spectral integration of the rgb kind: exact (1 nm), uniform:N, rgb3.
    #[arg(long, default_value = "exact")]
    pub sampling: String,
    /// What (1, 1, 1) is in the rgb kind: d65 (a perfect reflector under
    /// D65) or e (a flat spectrum, as Blender Cycles and glTF viewers); see
    /// docs/color.md.
    #[arg(long, default_value = "d65")]
    pub white: String,
    /// Wavelength range MIN:MAX in nm of the spectral kind (360:830 is
    /// what spectral renderers such as Mitsuba sample); within the data of
    /// every material of the stack.
    #[arg(long, default_value = "380:780")]
    pub wavelengths: String,
    /// Fixed node counts T,A[,W] (thickness, angle, wavelength) instead of
    /// an error target.
    #[arg(long, conflicts_with = "max_error")]
    pub resolution: Option<String>,
    /// Largest absolute error allowed in any channel [default: 1e-3, unless
    /// --max-de alone is given].
    #[arg(long)]
    pub max_error: Option<f64>,
    /// Largest CIEDE2000 allowed between the table's and the exact colour of
    /// the reflected or transmitted light (atlas layout).
    #[arg(long, conflicts_with = "resolution")]
    pub max_de: Option<f64>,
    /// atlas (charts in the layer's optical thickness, format version 4) or
    /// grid (thickness × cos θ nodes, versions 2 and 3) [default: atlas;
    /// grid with --resolution].
    #[arg(long)]
    pub layout: Option<String>,
    /// Store f16 samples instead of f32.
    #[arg(long)]
    pub half: bool,
    /// With --resolution: evaluate the table's nodes only, without the bake
    /// check (which evaluates about four times as many to measure the
    /// table's interpolation error); the header then records no bake check.
    #[arg(long)]
    pub no_check: bool,
    /// Random points at which the table is checked against the solver (and
    /// must meet --max-error); the figures go into the header (0: none).
    #[arg(long, default_value_t = 20_000)]
    pub validate_points: usize,
    /// Write the rough table instead: the front side's reflectance
    /// pre-integrated over a GGX lobe, roughness 0 to 1 as slices of the
    /// atlas (docs/lut-format.md, "Rough tables"; docs/rough.md).
    #[arg(long)]
    pub rough: bool,
    /// The rough table's error target (largest absolute error per channel)
    /// against irid's rough reflectance [default: --max-error, else 2e-3].
    #[arg(long, requires = "rough")]
    pub rough_max_error: Option<f64>,
}

pub fn run(args: Args) -> Result<ExitCode> {
    let spec = spec_of(&args)?;
    if args.rough {
        return run_rough(&args, &spec);
    }
    // The table's path is checked before the bake, not after it.
    let mut outputs = OutputSet::new();
    outputs.input(&args.film.stack);
    let table = outputs.file(&args.output);
    let mut outputs = outputs.prepare()?;
    let bar = super::render::progress_bar("baking {bar:40} {percent:>3}% {elapsed}");
    let started = Instant::now();
    let mut lut = bake_with_progress(&spec, &|f| {
        if let Some(bar) = &bar {
            bar.set_position((f * 1000.0) as u64);
        }
    })
    .with_context(|| args.film.stack.display().to_string())?;
    let baked = started.elapsed();
    if let Some(bar) = &bar {
        bar.finish_and_clear();
    }
    print_baked(&lut, baked.as_secs_f64());
    if lut.header().error.validation.is_none() && args.validate_points > 0 {
        let stats = validate(&lut, args.validate_points, VALIDATION_SEED)?;
        lut.set_validation(stats);
    }
    if let Some(stats) = &lut.header().error.validation {
        println!(
            "validation: {} against the solver:",
            super::validate::points_and_seed(stats)
        );
        super::validate::print_stats(stats);
    }
    outputs.write(table, |tmp| lut.write_to(tmp, &args.output))?;
    outputs.commit()?;
    print_written(&args.output)
}

/// The bake the flags ask for, checked.
fn spec_of(args: &Args) -> Result<BakeSpec> {
    let stack = Stack::load(&args.film.stack)?;
    let mut spec = BakeSpec::new(stack);
    spec.layer = args.film.layer;
    if let Some(range) = args
        .film
        .thickness_nm(&spec.stack, args.thickness.as_deref())?
    {
        spec.thickness_nm = range;
    }
    spec.kind = parse_choice(&args.kind)?;
    spec.sampling = parse_choice(&args.sampling)?;
    spec.wavelength_nm = parse_range("--wavelengths", &args.wavelengths)?;
    spec.white = parse_choice(&args.white)?;
    spec.half = args.half;
    spec.validation_points = args.validate_points;
    spec.resolution = match (&args.resolution, args.max_error, args.max_de) {
        (Some(r), _, _) => parse_resolution(r, spec.kind)?,
        (None, None, Some(_)) => Resolution::MaxError(f64::INFINITY),
        (None, e, _) => Resolution::MaxError(e.unwrap_or(1e-3)),
    };
    spec.max_de = args.max_de;
    spec.layout = match &args.layout {
        Some(l) => parse_choice(l)?,
        None if args.resolution.is_some() => Layout::Grid,
        None => Layout::Atlas,
    };
    if args.resolution.is_some() && spec.layout == Layout::Atlas {
        bail!("--layout atlas: an atlas is sized for an error target, not --resolution");
    }
    spec.cos_theta = args.film.cos_theta(spec.layout() == Layout::Grid)?;
    if args.no_check && args.resolution.is_none() {
        bail!("--no-check needs --resolution: with --max-error (the default) the bake check is how the grid is chosen");
    }
    spec.check = !args.no_check;

    // Flag errors first; what fails after them comes from the stack (a
    // material undefined at some wavelength), so name its file.
    spec.validate()?;
    Ok(spec)
}

/// The bake's summary: the table's size and its bake check.
fn print_baked(lut: &irid::lut::Lut, baked_s: f64) {
    let h = lut.header();
    let sizes: Vec<String> = h.axes.iter().map(|a| a.nodes.len().to_string()).collect();
    match &h.atlas {
        Some(t) => println!(
            "baked {} {} table, atlas of {} chart(s) in {}×{} texels ({} channels{}), in {:.3} s",
            h.kind,
            h.precision,
            t.atlas.charts.len(),
            t.atlas.width,
            t.atlas.height,
            h.channels.len(),
            unsought_regions(t),
            baked_s
        ),
        None => println!(
            "baked {} {} table, {} nodes ({}), in {:.3} s",
            h.kind,
            h.precision,
            sizes.join("×"),
            h.axes
                .iter()
                .map(|a| a.name.as_str())
                .collect::<Vec<_>>()
                .join(" × "),
            baked_s
        ),
    }
    match &h.error.bake_check {
        Some(check) => println!(
            "bake check: max abs error {:.3e} over {} off-grid points",
            check.max_abs_all, check.points
        ),
        None => println!("bake check: not made (--no-check)"),
    }
}

/// Prints the written file's path and size.
fn print_written(path: &std::path::Path) -> Result<ExitCode> {
    let bytes = std::fs::metadata(path)
        .with_context(|| path.display().to_string())?
        .len();
    println!("wrote {} ({} bytes)", path.display(), bytes);
    Ok(ExitCode::SUCCESS)
}

/// `irid bake --rough`: the rough table, written atomically.
fn run_rough(args: &Args, spec: &BakeSpec) -> Result<ExitCode> {
    let target = args
        .rough_max_error
        .or(args.max_error)
        .unwrap_or(DEFAULT_ROUGH_MAX_ERROR);
    if args.half {
        bail!("--half: a rough table is stored in f32");
    }
    let mut outputs = OutputSet::new();
    outputs.input(&args.film.stack);
    let table = outputs.file(&args.output);
    let mut outputs = outputs.prepare()?;
    let started = Instant::now();
    let rough = bake_rough(spec, target, &|line| log::info!("{line}"))
        .with_context(|| args.film.stack.display().to_string())?;
    let s = rough.slices();
    println!(
        "baked rough table: {} slices (roughness (s/(S-1))^2) of {}×{} texels, {} chart(s), in {:.3} s",
        s.slices.len(),
        s.atlas.width,
        s.atlas.height,
        s.atlas.charts.len(),
        started.elapsed().as_secs_f64()
    );
    super::info::print_rough_error(rough.header());
    outputs.write(table, |tmp| rough.write_to(tmp, &args.output))?;
    outputs.commit()?;
    print_written(&args.output)
}

/// The rough table's error target without --rough-max-error or --max-error
/// (the issue's: 2e-3).
const DEFAULT_ROUGH_MAX_ERROR: f64 = 2e-3;

fn parse_resolution(spec: &str, kind: Kind) -> Result<Resolution> {
    let counts: Vec<usize> = spec
        .split(',')
        .map(|s| {
            s.trim().parse::<usize>().map_err(|_| {
                anyhow!(
                    "--resolution '{spec}': '{}' is not a whole number",
                    s.trim()
                )
            })
        })
        .collect::<Result<_>>()?;
    match (kind, &counts[..]) {
        (Kind::Rgb, &[t, a]) => Ok(Resolution::Nodes {
            thickness: t,
            angle: a,
            wavelength: 1,
        }),
        (Kind::Spectral, &[t, a, w]) => Ok(Resolution::Nodes {
            thickness: t,
            angle: a,
            wavelength: w,
        }),
        (Kind::Rgb, _) => bail!("--resolution '{spec}': an rgb table takes T,A"),
        (Kind::Spectral, _) => bail!("--resolution '{spec}': a spectral table takes T,A,W"),
    }
}

/// Where an atlas table's target is not sought, as the end of the bake's
/// summary line.
fn unsought_regions(t: &irid::lut::TableAtlas) -> String {
    let mut out = String::new();
    if t.aliased_below_cos > 0.0 {
        out += &format!(
            "; the film's fringes are aliased below cos θ {:.4}, where the target is not sought",
            t.aliased_below_cos
        );
    }
    if let Some([a, b]) = t.critical_band_cos {
        out += &format!(
            "; over cos θ {a:.4}–{b:.4} the critical angle moves with the wavelength, where the target is not sought"
        );
    }
    out
}
