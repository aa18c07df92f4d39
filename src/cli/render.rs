//! `irid render`: render a scene file or a built-in scene to PNG (and EXR).

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use anyhow::{bail, Context, Result};
use irid::atomic::{Output, OutputSet, Prepared};
use irid::color::Sampling;
use irid::render::{self, scene_file, FilmMode, PreparedFilms, RenderOptions, Scene};

use super::args::check_count;

#[derive(clap::Args)]
pub struct Args {
    /// A scene file, or a built-in scene: bubbles-uniform, bubbles-noise,
    /// absorbing-sphere, absorbing-sphere-rough, gain-ring, blue-gem,
    /// two-layer-noise.
    pub scene: String,
    /// PNG output (8-bit sRGB) [default: out/SCENE.png].
    #[arg(short = 'o', long = "output")]
    pub output: Option<PathBuf>,
    /// Also write a linear float OpenEXR image.
    #[arg(long)]
    pub exr: Option<PathBuf>,
    #[arg(long)]
    pub width: Option<u32>,
    #[arg(long)]
    pub height: Option<u32>,
    /// Samples per pixel (stratified).
    #[arg(long)]
    pub spp: Option<u32>,
    /// Reflection/refraction depth.
    #[arg(long)]
    pub max_depth: Option<u32>,
    /// lut: sample baked tables (baked on demand); direct: full TMM at every hit.
    #[arg(long, default_value = "lut", value_parser = ["lut", "direct"])]
    pub film: String,
    /// Wavelength sampling of --film direct: rgb3, uniform:N or exact.
    #[arg(long)]
    pub sampling: Option<String>,
    /// With --film lut: evaluate noise thickness at every hit instead of
    /// baking it to a grid (exact, slower).
    #[arg(long)]
    pub exact_noise: bool,
    /// Where baked tables are cached [default: $IRID_CACHE_DIR, else the
    /// user's cache folder: $XDG_CACHE_HOME/irid or ~/.cache/irid on Linux].
    #[arg(long)]
    pub cache: Option<PathBuf>,
    /// Worker threads [default: all cores].
    #[arg(long)]
    pub threads: Option<usize>,
    /// Seed of the pixel sample positions and of the microfacet normals a
    /// rough film draws.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
}

/// The film mode from `--film` and `--sampling`.
pub fn film_mode(film: &str, sampling: Option<&str>, cache: &Path) -> Result<FilmMode> {
    match (film, sampling) {
        ("lut", None) => Ok(FilmMode::lut(cache)),
        ("lut", Some(_)) => {
            bail!("--sampling applies to --film direct (tables are integrated exactly)")
        }
        (_, s) => {
            let sampling: Sampling = s.unwrap_or("exact").parse()?;
            Ok(FilmMode::Direct { sampling })
        }
    }
}

/// More workers than this only exhausts the machine: starting 100000
/// threads hung instead of failing.
pub const MAX_THREADS: usize = 1024;

/// `f`'s result and its wall time in seconds.
pub fn timed<T>(f: impl FnOnce() -> T) -> (T, f64) {
    let start = Instant::now();
    let out = f();
    (out, start.elapsed().as_secs_f64())
}

/// `--threads n` is within 1..=[`MAX_THREADS`].
pub fn check_threads(n: usize) -> Result<()> {
    check_count("--threads", n, MAX_THREADS)
}

/// Runs `f` inside a pool of `threads` workers (by default, one per CPU,
/// or `RAYON_NUM_THREADS`). Inside, not from outside: a render called from
/// a thread outside the pool is handed to the workers while the caller
/// sleeps, and on one thread that hand-off made renders bimodal, up to 15 %
/// slower when the two threads sat on different CPUs (see
/// benches/film_cost.rs).
pub fn with_threads<T: Send>(threads: Option<usize>, f: impl FnOnce() -> T + Send) -> Result<T> {
    if let Some(n) = threads {
        check_threads(n)?;
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads.unwrap_or(0))
        .build()
        .context("cannot start the worker threads")?;
    Ok(pool.install(f))
}

pub fn run(args: Args) -> Result<ExitCode> {
    let cache = cache_dir(args.cache.as_deref())?;
    let mode = match film_mode(&args.film, args.sampling.as_deref(), &cache)? {
        FilmMode::Lut { cache_dir, .. } if args.exact_noise => FilmMode::lut_exact_noise(cache_dir),
        mode => mode,
    };
    let scene = Scene::load_named(&args.scene)?;
    check_size_flags(&args)?;
    let mut opts = RenderOptions::new(mode);
    opts.width = args.width;
    opts.height = args.height;
    opts.spp = args.spp;
    opts.max_depth = args.max_depth;
    opts.seed = args.seed;
    render::check_image_size(&scene, &opts)?;
    let mut outputs = Outputs::prepare(&args, &scene)?;

    let (films, image, render_s) = with_threads(args.threads, || render_with_bar(&scene, &opts))??;
    outputs
        .set
        .write(outputs.png, image.png_writer(&outputs.png_path))?;
    if let (Some(exr), Some(path)) = (outputs.exr, &args.exr) {
        outputs.set.write(exr, image.exr_writer(path))?;
    }
    outputs.set.commit()?;
    print_summary(&scene, &films, &opts, &image, render_s, args.threads);
    println!("wrote   {}", outputs.png_path.display());
    if let Some(exr) = &args.exr {
        println!("wrote   {}", exr.display());
    }
    Ok(ExitCode::SUCCESS)
}

/// The PNG (`-o`, else out/SCENE.png, making out/) and the EXR if asked,
/// checked before the render rather than after it.
struct Outputs {
    set: Prepared,
    png_path: PathBuf,
    png: Output,
    exr: Option<Output>,
}

impl Outputs {
    fn prepare(args: &Args, scene: &Scene) -> Result<Outputs> {
        let mut set = OutputSet::new();
        let png_path = match &args.output {
            Some(p) => p.clone(),
            None => {
                set.new_folder("out");
                PathBuf::from("out").join(format!("{}.png", file_stem(&scene.name)))
            }
        };
        if Path::new(&args.scene).is_file() {
            set.input(&args.scene);
        }
        let png = set.file(&png_path);
        let exr = args.exr.as_ref().map(|p| set.file(p));
        Ok(Outputs {
            set: set.prepare()?,
            png_path,
            png,
            exr,
        })
    }
}

/// `--width`, `--height`, `--spp` and `--max-depth` within what a scene
/// file may ask for.
fn check_size_flags(args: &Args) -> Result<()> {
    let (side, spp) = (scene_file::MAX_IMAGE_SIDE, scene_file::MAX_SPP);
    for (flag, v, max) in [
        ("--width", args.width, side),
        ("--height", args.height, side),
        ("--spp", args.spp, spp),
    ] {
        if let Some(v) = v {
            check_count(flag, v, max)?;
        }
    }
    if let Some(depth) = args.max_depth {
        if depth > scene_file::MAX_DEPTH {
            bail!(
                "--max-depth must be at most {}, got {depth}",
                scene_file::MAX_DEPTH
            );
        }
    }
    Ok(())
}

/// Prepares the films and renders, with a progress bar on a terminal.
/// Returns the films, the image and the render's wall time in seconds.
fn render_with_bar(
    scene: &Scene,
    opts: &RenderOptions,
) -> Result<(PreparedFilms, render::Image, f64)> {
    let films = render::prepare_films(scene, &opts.film)?;
    let bar = progress_bar("rendering {bar:40} {percent:>3}% {elapsed} (eta {eta})");
    let (image, render_s) = timed(|| {
        render::render_with_progress(scene, &films, opts, &|f| {
            if let Some(bar) = &bar {
                bar.set_position((f * 1000.0) as u64);
            }
        })
    });
    if let Some(bar) = &bar {
        bar.finish_and_clear();
    }
    Ok((films, image, render_s))
}

fn print_summary(
    scene: &Scene,
    films: &PreparedFilms,
    opts: &RenderOptions,
    image: &render::Image,
    render_s: f64,
    threads: Option<usize>,
) {
    let film = match &opts.film {
        FilmMode::Lut { .. } => format!(
            "lut: {} table(s) baked, {} from cache, {:.3} s",
            films.tables_baked,
            films.tables_cached,
            films.bake_time.as_secs_f64()
        ),
        FilmMode::Direct { sampling } => format!("direct TMM, sampling {sampling}"),
    };
    println!("scene   {}", scene.name);
    println!("films   {film}");
    let grids: Vec<_> = films.thickness_grids.iter().flatten().collect();
    if !grids.is_empty() {
        let bytes: usize = grids.iter().map(|g| g.size_bytes()).sum();
        let worst = grids
            .iter()
            .map(|g| g.max_error_nm())
            .fold(0.0f32, f32::max);
        println!(
            "noise   thickness baked to {} grid(s), {:.1} MB, max error {:.2} nm (exact noise with --film direct)",
            grids.len(),
            bytes as f64 / 1e6,
            worst
        );
    }
    println!(
        "render  {}x{}, {} spp, {:.3} s on {} thread(s)",
        image.width,
        image.height,
        opts.spp.unwrap_or(scene.settings.spp),
        render_s,
        threads.unwrap_or_else(rayon::current_num_threads)
    );
}

/// A scene name made safe as a file name.
pub fn file_stem(name: &str) -> String {
    let stem = Path::new(name)
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "render".into());
    stem.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// A progress bar over 1000 steps on stderr, when stderr is a terminal.
pub fn progress_bar(template: &str) -> Option<indicatif::ProgressBar> {
    std::io::stderr().is_terminal().then(|| {
        let bar = indicatif::ProgressBar::new(1000);
        bar.set_style(
            indicatif::ProgressStyle::with_template(template)
                .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        bar
    })
}

/// Where tables baked on demand are kept: `--cache DIR` if given, else
/// `$IRID_CACHE_DIR` if set, else the user's cache folder for irid (the
/// platform's convention: `$XDG_CACHE_HOME/irid` or `~/.cache/irid` on
/// Linux, `~/Library/Caches/irid` on macOS, `%LOCALAPPDATA%\irid\cache` on
/// Windows).
pub fn cache_dir(flag: Option<&Path>) -> Result<PathBuf> {
    if let Some(dir) = flag {
        return Ok(dir.to_path_buf());
    }
    if let Some(dir) = std::env::var_os("IRID_CACHE_DIR").filter(|d| !d.is_empty()) {
        return Ok(PathBuf::from(dir));
    }
    match directories::ProjectDirs::from("", "", "irid") {
        Some(dirs) => Ok(dirs.cache_dir().to_path_buf()),
        None => bail!(
            "no user cache folder (no home directory): give --cache DIR or set IRID_CACHE_DIR"
        ),
    }
}
