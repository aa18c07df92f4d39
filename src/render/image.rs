//! Rendered images: linear RGB in memory, tiled parallel rendering, and
//! the comparison of two renders.

use glam::Vec3;
use rayon::prelude::*;

use super::camera::Camera;
use super::film::FilmShading;
use super::random::{SampleRng, SplitMix};
use super::tracer::Tracer;

/// A linear-RGB image (exposure applied), rows top to bottom.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Linear sRGB radiance (R, G, B) per pixel, row-major from the top-left
    /// corner: pixel (x, y) is at index y · width + x. Unclamped: values
    /// can exceed 1 or, out of gamut, fall below 0.
    pub pixels: Vec<[f32; 3]>,
}

/// Square tiles: small enough to balance two threads on any scene,
/// large enough that scheduling costs nothing.
const TILE: u32 = 16;

/// How one render samples its pixels.
#[derive(Clone, Copy, Debug)]
pub struct Sampler {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Samples per pixel: a jittered k×k grid when it is a square k², else
    /// a jittered Latin hypercube; 1 (or 0) takes the pixel centre.
    pub spp: u32,
    /// Hashed with the pixel and sample index into each sample's jitter and
    /// microfacet normals, so the image depends on it and not on scheduling.
    pub seed: u64,
    /// Factor applied to each pixel's mean radiance.
    pub exposure: f32,
}

/// Renders every pixel. Each pixel's sample positions come from a hash of
/// (seed, pixel, sample), so the image does not depend on thread count or
/// scheduling: the same seed gives the same image bit for bit.
///
/// Called from outside a one-worker pool, it renders on the calling
/// thread: handing every tile to the worker while the caller sleeps made
/// renders bimodal on this project's 2-CPU VM, up to 15 % slower when the
/// two threads sat on different CPUs (benches/film_cost.rs).
///
/// `progress` is called with the fraction of tiles done after each tile,
/// from whichever thread rendered it.
pub fn render_tiles<F: FilmShading, const ROUGH: bool>(
    tracer: &Tracer<F, ROUGH>,
    camera: &Camera,
    s: &Sampler,
    progress: &(dyn Fn(f64) + Sync),
) -> Image {
    let on_caller = rayon::current_thread_index().is_none() && rayon::current_num_threads() == 1;
    render_tiles_on(tracer, camera, s, on_caller, progress)
}

/// [`render_tiles`], on the calling thread alone or on the current pool.
fn render_tiles_on<F: FilmShading, const ROUGH: bool>(
    tracer: &Tracer<F, ROUGH>,
    camera: &Camera,
    s: &Sampler,
    on_caller: bool,
    progress: &(dyn Fn(f64) + Sync),
) -> Image {
    let tiles_x = s.width.div_ceil(TILE);
    let tiles_y = s.height.div_ceil(TILE);
    let tile_count = tiles_x * tiles_y;
    let done = std::sync::atomic::AtomicU32::new(0);
    let render_tile = |k: u32| {
        let (x0, y0) = ((k % tiles_x) * TILE, (k / tiles_x) * TILE);
        let (x1, y1) = ((x0 + TILE).min(s.width), (y0 + TILE).min(s.height));
        let mut px = Vec::with_capacity(((x1 - x0) * (y1 - y0)) as usize);
        for y in y0..y1 {
            for x in x0..x1 {
                px.push(render_pixel(tracer, camera, s, x, y).to_array());
            }
        }
        let d = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
        progress(f64::from(d) / f64::from(tile_count));
        (x0, y0, px)
    };
    let tiles: Vec<(u32, u32, Vec<[f32; 3]>)> = if on_caller {
        (0..tile_count).map(render_tile).collect()
    } else {
        (0..tile_count).into_par_iter().map(render_tile).collect()
    };
    let mut pixels = vec![[0.0f32; 3]; (s.width * s.height) as usize];
    for (x0, y0, px) in tiles {
        let w = (x0 + TILE).min(s.width) - x0;
        for (i, p) in px.into_iter().enumerate() {
            let (x, y) = (x0 + i as u32 % w, y0 + i as u32 / w);
            pixels[(y * s.width + x) as usize] = p;
        }
    }
    Image {
        width: s.width,
        height: s.height,
        pixels,
    }
}

/// Stratified samples: a jittered k×k grid when spp is a square, otherwise
/// a jittered Latin hypercube (each row and each column stratum used once);
/// one sample per pixel goes through the pixel centre.
fn render_pixel<F: FilmShading, const ROUGH: bool>(
    tracer: &Tracer<F, ROUGH>,
    camera: &Camera,
    s: &Sampler,
    x: u32,
    y: u32,
) -> Vec3 {
    let pixel_index = u64::from(y) * u64::from(s.width) + u64::from(x);
    let (w, h) = (s.width as f32, s.height as f32);
    let mut sum = Vec3::ZERO;
    if s.spp <= 1 {
        let ray = camera.ray((x as f32 + 0.5) / w, (y as f32 + 0.5) / h);
        SampleRng::start(SplitMix::for_sample(s.seed, pixel_index, 0));
        return s.exposure * tracer.trace(&ray, 0);
    }
    let k = (s.spp as f32).sqrt().round() as u32;
    let square = k * k == s.spp;
    for i in 0..s.spp {
        let mut rng = SplitMix::for_sample(s.seed, pixel_index, i);
        let (jx, jy) = (rng.next_f32(), rng.next_f32());
        let (sx, sy) = if square {
            (
                ((i % k) as f32 + jx) / k as f32,
                ((i / k) as f32 + jy) / k as f32,
            )
        } else {
            // Column i, row from a seeded permutation of the strata.
            let row = permuted(i, s.spp, s.seed ^ pixel_index);
            (
                (i as f32 + jx) / s.spp as f32,
                (row as f32 + jy) / s.spp as f32,
            )
        };
        let ray = camera.ray((x as f32 + sx) / w, (y as f32 + sy) / h);
        // The rest of the sample's numbers go to the surfaces it meets.
        SampleRng::start(rng);
        sum += tracer.trace(&ray, 0);
    }
    s.exposure * sum / s.spp as f32
}

/// The image of `i` under a pseudo-random permutation of 0..n, by cycle
/// walking a keyed bijection on the next power of two.
fn permuted(i: u32, n: u32, key: u64) -> u32 {
    let bits = n.next_power_of_two().trailing_zeros().max(1);
    let mask = (1u64 << bits) - 1;
    let mut v = u64::from(i);
    loop {
        // Odd multiplication and xor-shift are bijections modulo 2^bits.
        for round in 0..3u64 {
            v = (v ^ ((key >> (round * 8)) & mask)) & mask;
            v = (v.wrapping_mul(0x2545_F491_4F6C_DD1D | 1)) & mask;
            v ^= v >> (bits / 2).max(1);
        }
        if v < u64::from(n) {
            return v as u32;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn permutation_is_a_bijection() {
        for n in [2u32, 3, 5, 8, 13, 100] {
            for key in [0u64, 7, 0xDEAD_BEEF_1234] {
                let mut seen = vec![false; n as usize];
                for i in 0..n {
                    let p = permuted(i, n, key) as usize;
                    assert!(!seen[p], "n {n} key {key}: {p} twice");
                    seen[p] = true;
                }
            }
        }
    }

    /// The calling thread alone and a pool of workers render the same
    /// image, bit for bit, at one sample per pixel and at several, with a
    /// width that is not a whole number of tiles.
    #[test]
    fn caller_and_pool_render_the_same_image() {
        // The paper's timing scene with bare glass: no tables to bake.
        let scene = crate::render::Scene::builtin("two-layer-noise")
            .unwrap()
            .unwrap()
            .without_films(|_| unreachable!("two-layer-noise coats glass"));
        let tracer: Tracer<crate::render::LutFilm> = Tracer {
            scene: &scene,
            films: &[],
            thickness_grids: &[],
            max_depth: 4,
        };
        let c = &scene.camera;
        let camera = Camera::new(c.position, c.look_at, c.up, c.vfov_deg, 37.0 / 21.0);
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .unwrap();
        for spp in [1, 3] {
            let sampler = Sampler {
                width: 37,
                height: 21,
                spp,
                seed: 5,
                exposure: 1.0,
            };
            let alone = render_tiles_on(&tracer, &camera, &sampler, true, &|_| {});
            let pooled =
                pool.install(|| render_tiles_on(&tracer, &camera, &sampler, false, &|_| {}));
            assert_eq!(alone, pooled, "{spp} spp");
            assert!(alone.pixels.iter().any(|p| p[0] > 0.0));
        }
    }
}
