//! `irid demo`: bake what the built-in scenes need, render each into `out/`,
//! and report bake time, render time and the table renders' colour error
//! against the direct transfer-matrix reference; then time the paper's
//! timing scene in LUT and direct mode and without its film.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::Result;
use irid::atomic::{Output, OutputSet, Prepared};
use irid::color::Sampling;
use irid::render::film::bare_reflectance;
use irid::render::material::Material;
use irid::render::{self, builtin_names, FilmMode, RenderOptions, Scene};

use super::render::{timed, with_threads};

#[derive(clap::Args)]
pub struct Args {
    /// Where the images go; made if missing (its parent must exist). They
    /// appear there together when the demo has finished.
    #[arg(long, default_value = "out")]
    pub out: PathBuf,
    /// Where baked tables are cached [default: $IRID_CACHE_DIR, else the
    /// user's cache folder: $XDG_CACHE_HOME/irid or ~/.cache/irid on Linux].
    #[arg(long)]
    pub cache: Option<PathBuf>,
    /// The direct reference (exact, 1 nm) renders at this fraction of each
    /// scene's width and height, to keep the demo short.
    #[arg(long, default_value_t = 0.5)]
    pub reference_scale: f64,
    /// Worker threads [default: all cores].
    #[arg(long)]
    pub threads: Option<usize>,
}

pub fn run(args: Args) -> Result<ExitCode> {
    if !(args.reference_scale > 0.0 && args.reference_scale <= 1.0) {
        anyhow::bail!(
            "--reference-scale must be in (0, 1], got {}",
            args.reference_scale
        );
    }
    let mut images = Images::prepare(&args.out)?;
    let code = with_threads(args.threads, || run_all(&args, &mut images))??;
    images.set.commit()?;
    Ok(code)
}

/// Every image the demo writes, checked before the first bake: each
/// scene's table render and direct reference in `--out` (made if missing).
/// They appear together when the demo has finished.
struct Images {
    set: Prepared,
    /// Per scene: the table render's and the reference's path and output.
    scenes: Vec<[(PathBuf, Output); 2]>,
}

impl Images {
    fn prepare(out: &Path) -> Result<Images> {
        let mut set = OutputSet::new();
        set.new_folder(out);
        let mut file = |name: String| {
            let path = out.join(name);
            let output = set.file(&path);
            (path, output)
        };
        let scenes = builtin_names()
            .into_iter()
            .map(|name| {
                [
                    file(format!("{name}.png")),
                    file(format!("{name}.direct.png")),
                ]
            })
            .collect();
        Ok(Images {
            set: set.prepare()?,
            scenes,
        })
    }

    /// Writes the `k`-th built-in scene's table render (`which` 0) or
    /// reference (1).
    fn write(&mut self, k: usize, which: usize, image: &render::Image) -> Result<()> {
        let (path, output) = &self.scenes[k][which];
        Ok(self.set.write(*output, image.png_writer(path))?)
    }
}

fn run_all(args: &Args, images: &mut Images) -> Result<ExitCode> {
    let cache = super::render::cache_dir(args.cache.as_deref())?;
    let lut = FilmMode::lut(&cache);
    println!(
        "irid demo: {} thread(s); LUT renders at full size into {}/; the direct exact (1 nm) \
         reference renders at {:.0}% of each side, compared with a LUT render of the same size",
        rayon::current_num_threads(),
        args.out.display(),
        args.reference_scale * 100.0
    );
    println!();
    println!(
        "{:<22} {:>9} {:>9} {:>10} {:>9} {:>11} {:>10} {:>9}",
        "scene", "size", "bake s", "render s", "ref size", "direct s", "dE00 mean", "dE00 p99"
    );
    for (k, name) in builtin_names().into_iter().enumerate() {
        render_and_compare(name, args, &lut, |which, image| {
            images.write(k, which, image)
        })?;
    }
    println!(
        "(bake s is 0 when every table came from the cache in {})",
        cache.display()
    );
    time_film_cost(&lut)?;
    Ok(ExitCode::SUCCESS)
}

/// Renders the built-in scene `name` with tables, then at the reference
/// scale both by direct exact evaluation and with tables, and prints a
/// table row: times and the colour error between the two. `write` gets the
/// table render as image 0 and the direct reference as image 1.
fn render_and_compare(
    name: &str,
    args: &Args,
    lut: &FilmMode,
    mut write: impl FnMut(usize, &render::Image) -> Result<()>,
) -> Result<()> {
    let exact = FilmMode::Direct {
        sampling: Sampling::Exact,
    };
    let scene = Scene::builtin(name).expect("a built-in name")?;
    let s = scene.settings;
    let opts = RenderOptions::new(lut.clone());
    let films = render::prepare_films(&scene, lut)?;
    let (image, render_s) = timed(|| render::render_with(&scene, &films, &opts));
    write(0, &image)?;

    let mut small = RenderOptions::new(exact.clone());
    small.width = Some(((f64::from(s.width) * args.reference_scale).round() as u32).max(1));
    small.height = Some(((f64::from(s.height) * args.reference_scale).round() as u32).max(1));
    let direct_films = render::prepare_films(&scene, &exact)?;
    let (reference, direct_s) = timed(|| render::render_with(&scene, &direct_films, &small));
    write(1, &reference)?;
    small.film = lut.clone();
    let lut_small = render::render_with(&scene, &films, &small);
    let de = lut_small.delta_e2000(&reference)?;
    println!(
        "{:<22} {:>9} {:>9.3} {:>10.3} {:>9} {:>11.2} {:>10.3} {:>9.3}",
        name,
        format!("{}x{}", s.width, s.height),
        films.bake_time.as_secs_f64(),
        render_s,
        format!("{}x{}", reference.width, reference.height),
        direct_s,
        de.mean,
        de.p99
    );
    Ok(())
}

/// The paper's timing scene: LUT vs the paper's direct 41-wavelength
/// method, and the same scene with the film replaced by bare glass.
fn time_film_cost(lut: &FilmMode) -> Result<()> {
    let scene = Scene::builtin("two-layer-noise").expect("built in")?;
    let opts = RenderOptions::new(lut.clone());
    let films = render::prepare_films(&scene, lut)?;
    let plain = scene.without_films(bare_metal);
    let plain_films = render::prepare_films(&plain, lut)?;
    // Sub-second renders on a shared machine: the best of several runs, the
    // two kinds interleaved so that both see the same load. Fifteen: with
    // seven, two runs minutes apart differed by several points of the
    // ratio.
    let best_pair = || {
        let (mut lut_s, mut plain_s) = (f64::INFINITY, f64::INFINITY);
        for _ in 0..TIMING_RUNS {
            lut_s = lut_s.min(timed(|| render::render_with(&scene, &films, &opts)).1);
            plain_s = plain_s.min(timed(|| render::render_with(&plain, &plain_films, &opts)).1);
        }
        (lut_s, plain_s)
    };
    let (lut_s, plain_s) = best_pair();
    // On one thread too: less exposed to other processes on the machine.
    let (lut_1, plain_1) = with_threads(Some(1), best_pair)?;
    let uniform41 = FilmMode::Direct {
        sampling: Sampling::Uniform(41),
    };
    let direct_films = render::prepare_films(&scene, &uniform41)?;
    let direct_opts = RenderOptions::new(uniform41);
    let (_, direct_s) = timed(|| render::render_with(&scene, &direct_films, &direct_opts));
    let (w, h) = (scene.settings.width, scene.settings.height);
    println!();
    println!(
        "two-layer-noise, {w}x{h}, 1 spp, {} thread(s):",
        rayon::current_num_threads()
    );
    println!("  LUT film              {lut_s:>8.4} s   (best of {TIMING_RUNS})");
    println!("  direct TMM, 41 nm     {direct_s:>8.4} s   ({:.1}x slower than LUT; the paper: ~7.2 min on one thread)", direct_s / lut_s);
    println!(
        "  plain glass, no film  {plain_s:>8.4} s   (best of {TIMING_RUNS}; film shading adds {:+.1}% in LUT mode)",
        (lut_s / plain_s - 1.0) * 100.0
    );
    println!(
        "  on one thread: LUT {lut_1:.4} s, plain glass {plain_1:.4} s: film shading adds {:+.1}%",
        (lut_1 / plain_1 - 1.0) * 100.0
    );
    Ok(())
}

/// Runs of each timed render in the timing comparison; the best counts.
const TIMING_RUNS: usize = 15;

/// The uncoated metal under a film (for scenes without films).
fn bare_metal(film: &irid::render::scene::Film) -> Material {
    let mut stack = film.stack.clone();
    stack.layers.clear();
    match bare_reflectance(&stack, 257) {
        Ok(reflectance) => Material::Metal { reflectance },
        Err(_) => Material::Diffuse {
            albedo: glam::Vec3::splat(0.5),
            checker: None,
        },
    }
}
