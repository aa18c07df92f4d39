//! `irid export STACK.toml -o DIR`: GPU-ready textures of a stack's
//! response, film.json and the shaders (see docs/gpu.md).

use std::io::IsTerminal;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use anyhow::{Context, Result};
use irid::atomic::OutputSet;
use irid::export::{declare_dir, export, fill_dir, ExportSpec, Side};
use irid::optics::Stack;

use super::args::{parse_choice, FilmArgs};

#[derive(clap::Args)]
pub struct Args {
    /// Output directory; written atomically (a temporary directory beside
    /// it is renamed into place). An existing one is replaced only if it is
    /// empty or an earlier export.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Thickness range MIN:MAX in nm of the varying layer [default: its
    /// thickness in the stack file, a single texel column].
    #[arg(long)]
    pub thickness: Option<String>,
    #[command(flatten)]
    pub film: FilmArgs,
    /// Spectral integration: exact (1 nm), uniform:N, rgb3.
    #[arg(long, default_value = "exact")]
    pub sampling: String,
    /// What (1, 1, 1) is: d65 (a perfect reflector under D65, irid's
    /// default) or e (a flat spectrum, as Blender Cycles and glTF viewers).
    #[arg(long, default_value = "d65")]
    pub white: String,
    /// Largest absolute error allowed in any channel of what the GPU
    /// computes (bilinear filtering of f16 texels), against the solver.
    #[arg(long, default_value_t = 1e-3)]
    pub max_error: f64,
    /// The back side's own error target (light arriving from the
    /// substrate) [default: --max-error].
    #[arg(long)]
    pub back_max_error: Option<f64>,
    /// Export the front side only, even when light can arrive from the
    /// substrate.
    #[arg(long)]
    pub front_only: bool,
    /// Random points at which that error is measured.
    #[arg(long, default_value_t = irid::export::DEFAULT_POINTS)]
    pub points: usize,
    /// Also write 16-bit PNGs (for engines without OpenEXR import).
    #[arg(long)]
    pub png: bool,
    /// Also write the rough table: the front side's reflectance
    /// pre-integrated over a GGX lobe, roughness 0 to 1 (rough.exr,
    /// irid_film_rough; docs/gpu.md).
    #[arg(long)]
    pub rough: bool,
    /// The rough table's error target against irid's rough reflectance
    /// [default: --max-error].
    #[arg(long, requires = "rough")]
    pub rough_max_error: Option<f64>,
    /// Print nothing but errors.
    #[arg(long, short)]
    pub quiet: bool,
}

pub fn run(args: Args) -> Result<ExitCode> {
    let stack = Stack::load(&args.film.stack)?;
    let mut spec = ExportSpec::new(stack);
    spec.layer = args.film.layer;
    if let Some(range) = args
        .film
        .thickness_nm(&spec.stack, args.thickness.as_deref())?
    {
        spec.thickness_nm = range;
    }
    spec.cos_theta = args.film.cos_theta(false)?;
    spec.sampling = parse_choice(&args.sampling)?;
    spec.white = parse_choice(&args.white)?;
    spec.max_error = args.max_error;
    spec.back_max_error = args.back_max_error;
    spec.front_only = args.front_only;
    spec.points = args.points;
    spec.png = args.png;
    if args.rough {
        spec.rough_max_error = Some(args.rough_max_error.unwrap_or(args.max_error));
    }
    spec.validate()?;
    // The folder's path is checked before the export is computed.
    let mut outputs = OutputSet::new();
    outputs.input(&args.film.stack);
    let folder = declare_dir(&mut outputs, &args.output);
    let mut outputs = outputs.prepare()?;
    let quiet = args.quiet;
    // The sizes tried, as they are measured, when someone watches.
    let watch =
        !quiet && (std::io::stderr().is_terminal() || std::env::var_os("IRID_DEBUG").is_some());
    let started = Instant::now();
    let result = export(&spec, &|line| {
        if watch {
            eprintln!("  {line}");
        }
    })
    .with_context(|| args.film.stack.display().to_string())?;
    fill_dir(&result, &mut outputs, folder)?;
    outputs.commit()?;
    if !quiet {
        report(&result, &args, started.elapsed().as_secs_f64());
    }
    Ok(ExitCode::SUCCESS)
}

/// What an export printed: the atlas, then each side's chart and error.
fn report(result: &irid::export::Export, args: &Args, seconds: f64) {
    let atlas = &result.atlas;
    println!(
        "{}: {}×{} texels, {} chart{}, RGBA16F, {} KiB per texture, in {seconds:.1} s{}",
        args.output.display(),
        atlas.width,
        atlas.height,
        atlas.charts.len(),
        if atlas.charts.len() == 1 { "" } else { "s" },
        atlas.width * atlas.height * 8 / 1024,
        if result.opaque { "; opaque" } else { "" },
    );
    for side in &result.sides {
        let e = &side.error;
        let name = match side.side {
            Side::Front => "front (light from the ambient)",
            Side::Back => "back (light from the substrate)",
        };
        let texels: usize = side
            .charts
            .iter()
            .map(|&k| atlas.charts[k].rect.width * atlas.charts[k].rect.height)
            .sum();
        println!(
            "{name}: {} chart{} of {texels} texels; GPU error (f32 coordinates, bilinear, f16; relative above 1) at {} random points over cos θ {:.4}–{:.4}: max {:.2e} (target {:.0e}), p99 {:.2e}, mean {:.2e}; ΔE00 max {:.3} / {:.3}, mean {:.4} / {:.4} (R / T); 8-bit filter weights add at most {:.2e}",
            side.charts.len(),
            if side.charts.len() == 1 { "" } else { "s" },
            e.points,
            result.spec.cos_theta.0,
            result.spec.cos_theta.1,
            e.max_all(),
            result.spec.target(side.side),
            e.p99_abs.iter().fold(0.0f64, |a, &b| a.max(b)),
            e.mean_abs.iter().sum::<f64>() / 6.0,
            e.max_delta_e00[0],
            e.max_delta_e00[1],
            e.mean_delta_e00[0],
            e.mean_delta_e00[1],
            side.weights_8bit_extra,
        );
        if let Some(s) = &side.sought_error {
            println!(
                "{name}: where the target is sought: {} points, max {:.2e}, ΔE00 max {:.3} / {:.3}",
                s.points,
                s.max_all(),
                s.max_delta_e00[0],
                s.max_delta_e00[1]
            );
        }
        if let Some(a) = &side.aliased_error {
            println!(
                "{name}: below cos θ {:.6} the colour integration itself is aliased and the target is not sought: {} points there, max {:.2e}",
                side.aliased_below,
                a.points,
                a.max_all()
            );
        }
        if let (Some((lo, hi)), Some(c)) = (side.critical_band, &side.critical_error) {
            println!(
                "{name}: over cos θ {lo:.4}–{hi:.4} the critical angle moves with the wavelength and the target is not sought: {} points there, max {:.2e}, ΔE00 max {:.3} / {:.3}",
                c.points,
                c.max_all(),
                c.max_delta_e00[0],
                c.max_delta_e00[1]
            );
        }
        if let (Some(scale), Some(png)) = (result.png_scale, &side.png_error) {
            println!(
                "{name}: PNG (16-bit, scale {scale}): max error {:.2e}, ΔE00 max {:.3} / {:.3}",
                png.max_all(),
                png.max_delta_e00[0],
                png.max_delta_e00[1]
            );
        }
    }
    if let Some(rough) = &result.rough {
        report_rough(rough);
    }
}

/// What an export printed about its rough table.
fn report_rough(rough: &irid::export::RoughExport) {
    let e = &rough.error;
    println!(
        "rough (light from the ambient): {} slices (roughness 0 to 1) of {}×{} texels, {} chart{}, tiled into {}×{} texels, {} KiB; GPU error (f32 coordinates, bilinear, f16, two slices blended) at {} random points with cos θ ≥ {}: max {:.2e} (target {:.0e}), p99 {:.2e}, mean {:.2e}; ΔE00 max {:.3}, mean {:.4}",
        rough.slices,
        rough.atlas.width,
        rough.atlas.height,
        rough.atlas.charts.len(),
        if rough.atlas.charts.len() == 1 { "" } else { "s" },
        rough.texture.width,
        rough.texture.height,
        rough.texture.width * rough.texture.height * 8 / 1024,
        e.points,
        irid::export::GRAZING_COS,
        e.max_all(),
        rough.target,
        e.p99_abs.iter().fold(0.0f64, |a, &b| a.max(b)),
        e.mean_abs.iter().sum::<f64>() / 3.0,
        e.max_delta_e00,
        e.mean_delta_e00,
    );
    if let Some(g) = &rough.grazing_error {
        println!(
            "rough: below cos θ {} the target is not sought: {} points there, max {:.2e}, ΔE00 max {:.3}",
            irid::export::GRAZING_COS,
            g.points,
            g.max_all(),
            g.max_delta_e00
        );
    }
}
