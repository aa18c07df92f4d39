//! Film thickness over a surface: uniform, or the paper's procedural field
//! d(p) = d_min + (d_max − d_min) · noise(s · p) with Perlin noise (eq. 12).

use glam::{Vec3, Vec3A, Vec3Swizzles, Vec4};

use super::geometry::Aabb;
use super::scene::Shape;

#[derive(Clone, Debug)]
pub enum ThicknessField {
    Uniform {
        thickness_nm: f32,
    },
    Noise {
        min_nm: f32,
        max_nm: f32,
        /// Frequency s, per scene unit.
        scale: f32,
        perlin: Box<Perlin>,
    },
}

impl ThicknessField {
    pub fn noise(min_nm: f32, max_nm: f32, scale: f32, seed: u32) -> ThicknessField {
        ThicknessField::Noise {
            min_nm,
            max_nm,
            scale,
            perlin: Box::new(Perlin::new(seed)),
        }
    }

    #[inline]
    pub fn at(&self, p: Vec3) -> f32 {
        match self {
            ThicknessField::Uniform { thickness_nm } => *thickness_nm,
            ThicknessField::Noise {
                min_nm,
                max_nm,
                scale,
                perlin,
            } => min_nm + (max_nm - min_nm) * perlin.unit(*scale * p),
        }
    }

    /// The thickness range the field can take: what a table must cover.
    pub fn range_nm(&self) -> (f32, f32) {
        match self {
            ThicknessField::Uniform { thickness_nm } => (*thickness_nm, *thickness_nm),
            ThicknessField::Noise { min_nm, max_nm, .. } => (*min_nm, *max_nm),
        }
    }
}

/// Ken Perlin's improved noise (2002): one of 12 edge gradients at each
/// lattice point, blended with the quintic fade 6t⁵ − 15t⁴ + 10t³.
///
/// Perlin picks a lattice point's gradient through a seeded permutation of
/// 0..256 looked up three times (p[p[p[x] + y] + z]); here an integer hash
/// of the lattice coordinates and the seed picks it instead. The field has
/// the same form and statistics, does not repeat every 256 cells, and all
/// eight corners of a cell can be hashed at once in one vector register,
/// which is what makes it cheap: the noise runs at every film hit and was
/// the largest part of what film shading adds to a LUT render (the `noise`
/// crate's f64 version costs ~70 ns an evaluation; a scalar f32 table
/// version ~16 ns; this one, in AVX2 lanes, is timed by the bench's
/// `film hit` group).
#[derive(Clone, Debug)]
pub struct Perlin {
    /// The seed, spread over 32 bits so nearby seeds give unrelated fields.
    key: u32,
    /// Whether this CPU runs the AVX2 evaluation (checked once, here).
    avx2: bool,
}

/// Offsets of a cell's eight corners from its lowest one; corner k is
/// (k & 1, (k >> 1) & 1, k >> 2), the order of the vector lanes.
const CORNER_X: [i32; 8] = [0, 1, 0, 1, 0, 1, 0, 1];
const CORNER_Y: [i32; 8] = [0, 0, 1, 1, 0, 0, 1, 1];
const CORNER_Z: [i32; 8] = [0, 0, 0, 0, 1, 1, 1, 1];

/// Large odd multipliers for the three lattice coordinates (the spatial
/// hash of Teschner et al. 2003), then Wellons' `lowbias32` finaliser, so
/// that every bit of the result depends on every input bit.
const HASH_X: u32 = 0x8DA6_B343;
const HASH_Y: u32 = 0xD816_3841;
const HASH_Z: u32 = 0xCB1A_B31F;
const MIX_1: u32 = 0x7FEB_352D;
const MIX_2: u32 = 0x846C_A68B;

/// The gradient index (0..16) of lattice point (x, y, z).
#[inline(always)]
fn gradient_index(x: i32, y: i32, z: i32, key: u32) -> u32 {
    let mut h = (x as u32).wrapping_mul(HASH_X)
        ^ (y as u32).wrapping_mul(HASH_Y)
        ^ (z as u32).wrapping_mul(HASH_Z)
        ^ key;
    h ^= h >> 16;
    h = h.wrapping_mul(MIX_1);
    h ^= h >> 15;
    h = h.wrapping_mul(MIX_2);
    h ^= h >> 16;
    h >> 28
}

/// Perlin's gradient ramp g·(x, y, z) for gradient index `h`, written as
/// his reference code's `grad` switch (indices 12..15 repeat four of the
/// 12 edge directions so that 16 choices stay unbiased).
#[inline(always)]
fn gradient_dot(h: u32, x: f32, y: f32, z: f32) -> f32 {
    let u = if h < 8 { x } else { y };
    let v = if h < 4 {
        y
    } else if h | 2 == 14 {
        x
    } else {
        z
    };
    // Sign flips by the sign bit, as the vector code does, so the two
    // agree bit for bit (−0.0 included).
    let u = f32::from_bits(u.to_bits() ^ ((h & 1) << 31));
    let v = f32::from_bits(v.to_bits() ^ ((h & 2) << 30));
    u + v
}

/// The quintic fade, on all lanes at once.
#[inline(always)]
fn fade(d: Vec4) -> Vec4 {
    d * d * d * (d * (d * 6.0 - 15.0) + 10.0)
}

impl Perlin {
    pub fn new(seed: u32) -> Perlin {
        // SplitMix64's finaliser: seeds 1 and 2 get unrelated keys.
        let mut z = u64::from(seed).wrapping_add(0x9E37_79B9_7F4A_7C15);
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        Perlin {
            key: z as u32,
            avx2: avx2_available(),
        }
    }

    /// Signed noise, 0 on the integer lattice; its range is within about ±1.
    #[inline]
    pub fn signed(&self, p: Vec3) -> f32 {
        #[cfg(target_arch = "x86_64")]
        if self.avx2 {
            // SAFETY: `avx2` is only set when the CPU has AVX2.
            return unsafe { signed_avx2(self.key, p.x, p.y, p.z) };
        }
        self.signed_portable(p)
    }

    /// Noise mapped from its signed range to [0, 1] (0.5 on the lattice);
    /// the clamp only guards the rare overshoot past ±1, so d(p) never leaves
    /// [d_min, d_max].
    #[inline]
    pub fn unit(&self, p: Vec3) -> f32 {
        (0.5 + 0.5 * self.signed(p)).clamp(0.0, 1.0)
    }

    /// The same sum as the AVX2 code, one corner at a time, in the same
    /// order of operations, so every CPU gets the same image bit for bit.
    fn signed_portable(&self, p: Vec3) -> f32 {
        let (fx, fy, fz) = (fast_floor(p.x), fast_floor(p.y), fast_floor(p.z));
        let d = Vec4::new(p.x - fx as f32, p.y - fy as f32, p.z - fz as f32, 0.0);
        let f = fade(d);
        let mut terms = [0.0f32; 8];
        for (k, term) in terms.iter_mut().enumerate() {
            let (cx, cy, cz) = (CORNER_X[k], CORNER_Y[k], CORNER_Z[k]);
            let h = gradient_index(
                fx.wrapping_add(cx),
                fy.wrapping_add(cy),
                fz.wrapping_add(cz),
                self.key,
            );
            let g = gradient_dot(h, d.x - cx as f32, d.y - cy as f32, d.z - cz as f32);
            let pick = |c: i32, t: f32| if c == 1 { t } else { 1.0 - t };
            let weight = pick(cx, f.x) * pick(cy, f.y) * pick(cz, f.z);
            *term = weight * g;
        }
        let t = terms;
        ((t[0] + t[4]) + (t[2] + t[6])) + ((t[1] + t[5]) + (t[3] + t[7]))
    }
}

/// The eight corners in the eight lanes of one AVX2 register: hash,
/// gradient choice, ramp and weight for all of them at once. Takes scalars,
/// not a `Vec3` behind a reference: it is not inlined into its caller.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn signed_avx2(key: u32, px: f32, py: f32, pz: f32) -> f32 {
    let p = Vec3::new(px, py, pz);
    use std::arch::x86_64::*;
    let (fx, fy, fz) = (fast_floor(p.x), fast_floor(p.y), fast_floor(p.z));
    let d = Vec4::new(p.x - fx as f32, p.y - fy as f32, p.z - fz as f32, 0.0);
    let f = fade(d);
    // Closures here would not inherit this function's target feature
    // and each intrinsic in them would become a call: everything is
    // written out.
    let cx = _mm256_setr_epi32(0, 1, 0, 1, 0, 1, 0, 1);
    let cy = _mm256_setr_epi32(0, 0, 1, 1, 0, 0, 1, 1);
    let cz = _mm256_setr_epi32(0, 0, 0, 0, 1, 1, 1, 1);
    let xs = _mm256_add_epi32(_mm256_set1_epi32(fx), cx);
    let ys = _mm256_add_epi32(_mm256_set1_epi32(fy), cy);
    let zs = _mm256_add_epi32(_mm256_set1_epi32(fz), cz);
    let mut h = _mm256_xor_si256(
        _mm256_xor_si256(
            _mm256_mullo_epi32(xs, _mm256_set1_epi32(HASH_X as i32)),
            _mm256_mullo_epi32(ys, _mm256_set1_epi32(HASH_Y as i32)),
        ),
        _mm256_xor_si256(
            _mm256_mullo_epi32(zs, _mm256_set1_epi32(HASH_Z as i32)),
            _mm256_set1_epi32(key as i32),
        ),
    );
    h = _mm256_xor_si256(h, _mm256_srli_epi32::<16>(h));
    h = _mm256_mullo_epi32(h, _mm256_set1_epi32(MIX_1 as i32));
    h = _mm256_xor_si256(h, _mm256_srli_epi32::<15>(h));
    h = _mm256_mullo_epi32(h, _mm256_set1_epi32(MIX_2 as i32));
    h = _mm256_xor_si256(h, _mm256_srli_epi32::<16>(h));
    let h = _mm256_srli_epi32::<28>(h);

    // Offsets from each corner: d − c, exact for c ∈ {0, 1}.
    let (cxf, cyf, czf) = (
        _mm256_cvtepi32_ps(cx),
        _mm256_cvtepi32_ps(cy),
        _mm256_cvtepi32_ps(cz),
    );
    let x = _mm256_sub_ps(_mm256_set1_ps(d.x), cxf);
    let y = _mm256_sub_ps(_mm256_set1_ps(d.y), cyf);
    let z = _mm256_sub_ps(_mm256_set1_ps(d.z), czf);
    let below_8 = _mm256_castsi256_ps(_mm256_cmpgt_epi32(_mm256_set1_epi32(8), h));
    let below_4 = _mm256_castsi256_ps(_mm256_cmpgt_epi32(_mm256_set1_epi32(4), h));
    let is_12_or_14 = _mm256_castsi256_ps(_mm256_cmpeq_epi32(
        _mm256_or_si256(h, _mm256_set1_epi32(2)),
        _mm256_set1_epi32(14),
    ));
    let u = _mm256_blendv_ps(y, x, below_8);
    let v = _mm256_blendv_ps(_mm256_blendv_ps(z, x, is_12_or_14), y, below_4);
    let sign_u = _mm256_slli_epi32::<31>(h);
    let sign_v = _mm256_slli_epi32::<30>(_mm256_and_si256(h, _mm256_set1_epi32(2)));
    let u = _mm256_xor_ps(u, _mm256_castsi256_ps(sign_u));
    let v = _mm256_xor_ps(v, _mm256_castsi256_ps(sign_v));
    let g = _mm256_add_ps(u, v);

    // Corner weights: the fade where the corner's offset is 1, one
    // minus it where 0: (1 − t) + c·(2t − 1) would round differently
    // from the portable code, so select instead.
    let wx = _mm256_blendv_ps(
        _mm256_set1_ps(1.0 - f.x),
        _mm256_set1_ps(f.x),
        _mm256_castsi256_ps(_mm256_slli_epi32::<31>(cx)),
    );
    let wy = _mm256_blendv_ps(
        _mm256_set1_ps(1.0 - f.y),
        _mm256_set1_ps(f.y),
        _mm256_castsi256_ps(_mm256_slli_epi32::<31>(cy)),
    );
    let wz = _mm256_blendv_ps(
        _mm256_set1_ps(1.0 - f.z),
        _mm256_set1_ps(f.z),
        _mm256_castsi256_ps(_mm256_slli_epi32::<31>(cz)),
    );
    let weight = _mm256_mul_ps(_mm256_mul_ps(wx, wy), wz);
    let t = _mm256_mul_ps(weight, g);

    // ((t0 + t4) + (t2 + t6)) + ((t1 + t5) + (t3 + t7)), as above.
    let s4 = _mm_add_ps(_mm256_castps256_ps128(t), _mm256_extractf128_ps::<1>(t));
    let s2 = _mm_add_ps(s4, _mm_movehl_ps(s4, s4));
    let s1 = _mm_add_ss(s2, _mm_shuffle_ps::<0b01>(s2, s2));
    _mm_cvtss_f32(s1)
}

/// A noise thickness field baked over one object: the field at the nodes
/// of a regular grid, interpolated. A sphere's grid lies on its surface
/// (six overlapping faces, interpolated bilinearly: see [`SphereGrid`]);
/// other bounded shapes get a 3-D grid over their bounding box,
/// interpolated trilinearly.
///
/// Why: in LUT mode a film hit costs a table lookup plus the noise, and the
/// noise (eight hashed gradient ramps, ~16 ns) costs more than the table.
/// Read from a grid it is one interpolated lookup, with a bounded error:
/// nodes are spaced for [`GRID_MAX_ERROR_NM`], and each bake measures the
/// error against the exact field at points on the surface. The tracer's
/// tests bound the colour error of LUT renders (grid included) against
/// direct exact renders, which evaluate the noise at every hit.
///
/// What a grid costs a render is much where its nodes sit in the cache:
/// on `two-layer-noise` a 3-D grid at a 60 nm budget (a few kB) added 2 to
/// 4 points less to the render than the same grid at 2 nm (1.8 MB). A
/// sphere's surface grid holds only nodes a hit can read, 194 kB there,
/// and added 3 points less than the 3-D grid. A bricked 3-D grid storing
/// only the bricks the surface passes through rendered 3 % slower than the
/// dense one: its extra lookup lies on the hit's dependency chain.
#[derive(Clone, Debug)]
pub struct ThicknessGrid {
    layout: GridLayout,
    /// The field at each node, in nm, in the layout's order. f32 rather
    /// than quantised to u16: a quantised value needs a conversion and a
    /// rescale on the lookup's dependency chain.
    nodes: Vec<f32>,
    /// Largest |grid − field| seen at the bake's check points on the
    /// surface, in nm.
    max_error_nm: f32,
}

#[derive(Clone, Debug)]
enum GridLayout {
    Box(BoxGrid),
    Sphere(SphereGrid),
}

/// A regular 3-D grid over a box.
#[derive(Clone, Debug)]
struct BoxGrid {
    origin: Vec4,
    /// Grid cells per scene unit.
    inv_step: Vec4,
    /// The largest grid coordinate a lookup may take, per axis: just short
    /// of the last node, so the cell's far corner always exists.
    max_coord: Vec4,
    /// Nodes per axis; x varies fastest.
    dims: [usize; 3],
}

/// A sphere's surface in six overlapping faces, one per signed axis. A
/// point belongs to the face of its largest coordinate relative to the
/// centre (its major axis); the face is a square grid of `side` × `side`
/// nodes over the other two coordinates divided by the radius, (u, v) in
/// [−1/√2, 1/√2]², which covers the face's part of the sphere (there
/// u² + v² ≤ 2/3) and a little more. Reading a point takes no division
/// and no square root: its two minor coordinates are the grid coordinates.
/// A projection onto the circumscribed cube (dividing by the major
/// coordinate) made the render slower than the 3-D grid it replaces.
///
/// Every node is a point of the sphere (u² + v² ≤ 1 on the whole square),
/// so the interpolation is between real values everywhere, across a face's
/// edge too: the faces overlap there, and at an edge the two faces agree
/// within their interpolation error. A point a distance δ off the surface
/// reads the surface within about √3·δ of it (the faces are steepest at
/// the cube's corners), which for rounded hit points is far below a node's
/// spacing.
///
/// Face 2a + s has major axis a (x, y, z) on the positive (s = 0) or
/// negative (s = 1) side; its (u, v) are the next two axes cyclically
/// (y, z for x; z, x for y; x, y for z).
#[derive(Clone, Debug)]
struct SphereGrid {
    center: Vec3A,
    /// (side − 1) / 2, the grid coordinate of the face's centre: face
    /// coordinate u maps to grid coordinate (u / FACE_HALF_WIDTH + 1) ·
    /// half_span.
    half_span: f32,
    /// Grid units per scene unit along a minor axis:
    /// half_span / (FACE_HALF_WIDTH · radius).
    to_grid: f32,
    /// The largest grid coordinate a lookup may take: just short of the
    /// last node.
    max_coord: f32,
    side: usize,
}

/// How far a face's coordinates reach: 1/√2.
const FACE_HALF_WIDTH: f32 = std::f32::consts::FRAC_1_SQRT_2;

/// The largest thickness error a grid may have against the exact field.
/// Two nanometres move an interference fringe by under a fortieth of its
/// period even in a high-index layer (a fringe spans λ/2n ≥ 80 nm); the
/// LUT renders stay well within their colour-error bounds (tests/render.rs).
pub const GRID_MAX_ERROR_NM: f32 = 2.0;
/// Linear interpolation's error falls as the square of the node spacing:
/// measured on this noise, the worst error of a 3-D grid is about
/// 1.1 · (d_max − d_min) / K² with K nodes per noise lattice cell. The
/// spacing is chosen from this with a margin, and checked at each bake.
const GRID_ERROR_COEFFICIENT: f32 = 1.3;
/// Above this many nodes (32 MiB) a grid costs more to bake and hold than
/// it saves, and the exact noise is used instead.
const MAX_GRID_NODES: usize = 1 << 23;
/// Points on the surface at which a bake compares the grid with the field,
/// and the seed that places them on a mesh.
const GRID_CHECK_POINTS: usize = 20_000;
const GRID_CHECK_SEED: u64 = 0x2545_F491_4F6C_DD1D;

impl ThicknessGrid {
    /// Bakes `field` over `shape`: over a sphere's surface, or over the
    /// bounding box of another bounded shape. `None` when the field is
    /// uniform (nothing to bake), the shape unbounded (a plane), the grid
    /// would need more than [`MAX_GRID_NODES`] nodes, or the check finds
    /// the error over [`GRID_MAX_ERROR_NM`]: the caller then evaluates the
    /// field exactly.
    pub fn bake(field: &ThicknessField, shape: &Shape) -> Option<ThicknessGrid> {
        let ThicknessField::Noise { scale, .. } = field else {
            return None;
        };
        let (min_nm, max_nm) = field.range_nm();
        let nodes_per_cell = (GRID_ERROR_COEFFICIENT * (max_nm - min_nm).abs() / GRID_MAX_ERROR_NM)
            .sqrt()
            .clamp(4.0, 256.0);
        let step = 1.0 / (nodes_per_cell * scale.abs().max(1e-6));
        let (layout, nodes) = match shape {
            Shape::Sphere(s) => SphereGrid::bake(field, s.center, s.radius, step)?,
            _ => BoxGrid::bake(field, shape.bounds()?, step)?,
        };
        let mut grid = ThicknessGrid {
            layout,
            nodes,
            max_error_nm: 0.0,
        };
        for p in surface_points(shape, GRID_CHECK_POINTS) {
            let err = (grid.at(p) - field.at(p)).abs();
            grid.max_error_nm = grid.max_error_nm.max(err);
        }
        (grid.max_error_nm <= GRID_MAX_ERROR_NM).then_some(grid)
    }

    /// Nodes in the grid.
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// Memory the nodes take.
    pub fn size_bytes(&self) -> usize {
        std::mem::size_of_val(&self.nodes[..])
    }

    /// The largest |grid − exact field| the bake measured at points on the
    /// object's surface, in nm (at most [`GRID_MAX_ERROR_NM`]).
    pub fn max_error_nm(&self) -> f32 {
        self.max_error_nm
    }

    /// The field at `p`, interpolated. A box grid gives points outside the
    /// box the value at its nearest face; a sphere's grid reads points off
    /// the surface as described at [`SphereGrid`], and never leaves the
    /// field's range.
    #[inline(always)]
    pub fn at(&self, p: Vec3) -> f32 {
        match &self.layout {
            GridLayout::Box(g) => g.at(&self.nodes, p),
            GridLayout::Sphere(g) => g.at(&self.nodes, p),
        }
    }
}

impl BoxGrid {
    fn bake(field: &ThicknessField, bounds: Aabb, step: f32) -> Option<(GridLayout, Vec<f32>)> {
        use rayon::prelude::*;
        // A margin of a node around the box: hit points computed in f32
        // may lie just outside it.
        let origin = bounds.min - Vec3::splat(step);
        let extent = bounds.max + Vec3::splat(step) - origin;
        if !extent.is_finite() || extent.min_element() < 0.0 {
            return None;
        }
        let cells = (extent / step).ceil().max(Vec3::ONE);
        if (cells.x + 1.0) * (cells.y + 1.0) * (cells.z + 1.0) > MAX_GRID_NODES as f32 {
            return None;
        }
        let dims = [
            cells.x as usize + 1,
            cells.y as usize + 1,
            cells.z as usize + 1,
        ];
        let count = dims[0] * dims[1] * dims[2];
        let nodes = (0..count)
            .into_par_iter()
            .map(|k| {
                let (i, j, l) = (
                    k % dims[0],
                    (k / dims[0]) % dims[1],
                    k / (dims[0] * dims[1]),
                );
                field.at(origin + step * Vec3::new(i as f32, j as f32, l as f32))
            })
            .collect();
        // Short of the last node by a margin f32 resolves at these sizes:
        // the far corner's weight is at most 1 − 1e-3 there, inside the
        // margin the surface never reaches.
        let below_last = |n: usize| (n - 1) as f32 - 1e-3;
        let grid = BoxGrid {
            origin: origin.extend(0.0),
            inv_step: Vec4::splat(1.0 / step),
            max_coord: Vec4::new(
                below_last(dims[0]),
                below_last(dims[1]),
                below_last(dims[2]),
                0.0,
            ),
            dims,
        };
        Some((GridLayout::Box(grid), nodes))
    }

    /// Trilinear; points outside the box take the value at its nearest face.
    ///
    /// Written for few instructions and a short dependency chain (it runs
    /// at every film hit): the coordinates stay in one vector, the clamp
    /// makes the truncation to integers a floor that cannot overflow, and
    /// one slice of the cell's span carries the bounds check for all eight
    /// reads.
    #[inline(always)]
    fn at(&self, nodes: &[f32], p: Vec3) -> f32 {
        let g = ((p.extend(0.0) - self.origin) * self.inv_step)
            .max(Vec4::ZERO)
            .min(self.max_coord);
        let (cell, f) = cell_and_fraction(g);
        let [nx, ny, _] = self.dims;
        let (row, plane) = (nx, nx * ny);
        let base = cell[0] as usize + row * cell[1] as usize + plane * cell[2] as usize;
        let span = &nodes[base..base + plane + row + 2];
        // SAFETY: every offset read below (at most plane + row + 1) is
        // inside `span`, whose bounds were checked just above; the
        // compiler cannot see that for offsets built from run-time strides.
        let v = |k: usize| unsafe { *span.get_unchecked(k) };
        let near = lerp(lerp(v(0), v(1), f.x), lerp(v(row), v(row + 1), f.x), f.y);
        let far = lerp(
            lerp(v(plane), v(plane + 1), f.x),
            lerp(v(plane + row), v(plane + row + 1), f.x),
            f.y,
        );
        lerp(near, far, f.z)
    }
}

impl SphereGrid {
    fn bake(
        field: &ThicknessField,
        center: Vec3,
        radius: f32,
        step: f32,
    ) -> Option<(GridLayout, Vec<f32>)> {
        use rayon::prelude::*;
        let radius = radius.abs();
        // Face coordinates are the two minor coordinates over the radius,
        // which on a face stay within ±1/√2 (|u|, |v| ≤ major, u² + v² +
        // major² = 1). Arc length per unit of u is at most √3 times the
        // radius (where the surface is steepest, at a cube corner), so a
        // node every step / (√3 · radius) of u is one at least every
        // `step` on the surface.
        let intervals = (2.0 * FACE_HALF_WIDTH * 3f32.sqrt() * radius / step).ceil();
        if !intervals.is_finite() || 6.0 * (intervals + 1.0).powi(2) > MAX_GRID_NODES as f32 {
            return None;
        }
        let side = intervals.max(1.0) as usize + 1;
        let half_span = (side - 1) as f32 / 2.0;
        let nodes = (0..6 * side * side)
            .into_par_iter()
            .map(|k| {
                let (face, j, i) = (k / (side * side), (k / side) % side, k % side);
                let u = FACE_HALF_WIDTH * (i as f32 / half_span - 1.0);
                let v = FACE_HALF_WIDTH * (j as f32 / half_span - 1.0);
                // u² + v² ≤ 1 on the whole square: every node is a point
                // of the sphere, those beyond the face's own region too.
                let major = (1.0 - u * u - v * v).max(0.0).sqrt();
                let major = if face % 2 == 0 { major } else { -major };
                // (u, v, major) are the (next, next-but-one, major) axes.
                let d = match face / 2 {
                    0 => Vec3::new(major, u, v),
                    1 => Vec3::new(v, major, u),
                    _ => Vec3::new(u, v, major),
                };
                field.at(center + radius * d)
            })
            .collect();
        let grid = SphereGrid {
            center: center.into(),
            half_span,
            to_grid: half_span / (FACE_HALF_WIDTH * radius),
            max_coord: (side - 1) as f32 - 1e-3,
            side,
        };
        Some((GridLayout::Sphere(grid), nodes))
    }

    /// Bilinear on the face of the point's largest coordinate. Branch-free:
    /// successive hits land on unrelated faces, and a mispredicted face
    /// choice would cost more than the lookup. All three coordinates are
    /// carried to grid cells in one vector; the face then picks two.
    #[inline(always)]
    fn at(&self, nodes: &[f32], p: Vec3) -> f32 {
        let d = Vec3A::from(p) - self.center;
        let a = d.abs();
        // Lane k set where |d_k| is the largest; the lowest set lane wins
        // a tie, and z is taken when none is set (NaN).
        let largest = a.cmpge(a.yzx()) & a.cmpge(a.zxy());
        let axis = (largest.bitmask() | 0b100).trailing_zeros() as usize;
        let face = 2 * axis + ((d.is_negative_bitmask() >> axis) & 1) as usize;
        // Vec3A's max and min return their argument where a lane is NaN.
        let g = (d * self.to_grid + Vec3A::splat(self.half_span))
            .max(Vec3A::ZERO)
            .min(Vec3A::splat(self.max_coord));
        let (cell, frac) = cell_and_fraction(g.extend(0.0));
        let frac = frac.to_array();
        // The face's (u, v) are the next two axes after its major one;
        // `& 3` keeps the indices visibly inside the four lanes.
        let ku = (if axis == 2 { 0 } else { axis + 1 }) & 3;
        let kv = (if axis == 0 { 2 } else { axis - 1 }) & 3;
        let (i, j) = (cell[ku] as usize, cell[kv] as usize);
        let (fs, ft) = (frac[ku], frac[kv]);
        let row = self.side;
        let base = (face * row + j) * row + i;
        let span = &nodes[base..base + row + 2];
        // SAFETY: offsets up to row + 1, inside `span` (checked above).
        let v = |k: usize| unsafe { *span.get_unchecked(k) };
        lerp(lerp(v(0), v(1), fs), lerp(v(row), v(row + 1), fs), ft)
    }
}

/// Grid coordinates (each ≥ 0, below 2³¹) split into their cell, the
/// integer part, and the position inside it.
#[inline(always)]
fn cell_and_fraction(g: Vec4) -> ([i32; 4], Vec4) {
    let cell = truncate(g);
    let inside = g - Vec4::new(cell[0] as f32, cell[1] as f32, cell[2] as f32, 0.0);
    (cell, inside)
}

#[inline(always)]
fn lerp(a: f32, b: f32, t: f32) -> f32 {
    a + t * (b - a)
}

/// `n` reproducible points spread over a shape's surface: a Fibonacci
/// lattice on a sphere, random barycentric points on a mesh's triangles
/// in turn.
fn surface_points(shape: &Shape, n: usize) -> Vec<Vec3> {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_pcg::Pcg64::seed_from_u64(GRID_CHECK_SEED);
    match shape {
        Shape::Sphere(s) => (0..n)
            .map(|k| {
                let z = 1.0 - 2.0 * (k as f32 + 0.5) / n as f32;
                let r = (1.0 - z * z).max(0.0).sqrt();
                let phi = k as f32 * 2.399_963;
                s.center + s.radius * Vec3::new(r * phi.cos(), z, r * phi.sin())
            })
            .collect(),
        Shape::Mesh(m) => {
            let triangles: Vec<[Vec3; 3]> = m.triangles().collect();
            if triangles.is_empty() {
                return Vec::new();
            }
            (0..n)
                .map(|k| {
                    let [a, b, c] = triangles[k % triangles.len()];
                    let (mut u, mut v): (f32, f32) = (rng.random(), rng.random());
                    if u + v > 1.0 {
                        (u, v) = (1.0 - u, 1.0 - v);
                    }
                    a + u * (b - a) + v * (c - a)
                })
                .collect()
        }
        Shape::Plane(_) => Vec::new(),
    }
}

/// Truncates the lanes of a vector known to hold values in [0, 2³¹) to
/// integers: one SSE2 instruction, where `as` would saturate lane by lane.
#[inline(always)]
fn truncate(v: Vec4) -> [i32; 4] {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{__m128, _mm_cvttps_epi32};
        let m: __m128 = v.into();
        // SAFETY: [i32; 4] and __m128i have the same size and any bits are
        // valid for both.
        unsafe { std::mem::transmute(_mm_cvttps_epi32(m)) }
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        [v.x as i32, v.y as i32, v.z as i32, v.w as i32]
    }
}

#[cfg(target_arch = "x86_64")]
fn avx2_available() -> bool {
    std::arch::is_x86_feature_detected!("avx2")
}

#[cfg(not(target_arch = "x86_64"))]
fn avx2_available() -> bool {
    false
}

/// floor() as an integer without a libm call (x86-64's baseline has no
/// SSE4.1 rounding instruction, so `f32::floor` is a function call).
#[inline]
pub(crate) fn fast_floor(x: f32) -> i32 {
    let i = x as i32;
    i - i32::from(x < i as f32)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid() -> impl Iterator<Item = Vec3> {
        (0..40).flat_map(|i| {
            (0..40).flat_map(move |j| {
                (0..10).map(move |k| {
                    Vec3::new(
                        i as f32 * 0.173,
                        j as f32 * 0.131 - 2.0,
                        k as f32 * 0.291 + 0.05,
                    )
                })
            })
        })
    }

    /// Perlin's reference formulation: gradient ramps blended by three
    /// rounds of lerps with the quintic fade, in f64, his `grad` switch
    /// written out as he wrote it; only the gradient choice is shared.
    fn reference(perlin: &Perlin, p: Vec3) -> f64 {
        let fade = |t: f64| t * t * t * (t * (t * 6.0 - 15.0) + 10.0);
        let lerp = |t: f64, a: f64, b: f64| a + t * (b - a);
        let grad = |h: u32, x: f64, y: f64, z: f64| {
            let u = if h < 8 { x } else { y };
            let v = if h < 4 {
                y
            } else if h == 12 || h == 14 {
                x
            } else {
                z
            };
            (if h & 1 == 0 { u } else { -u }) + (if h & 2 == 0 { v } else { -v })
        };
        let (x, y, z) = (f64::from(p.x), f64::from(p.y), f64::from(p.z));
        let (fx, fy, fz) = (x.floor(), y.floor(), z.floor());
        let (xi, yi, zi) = (fx as i32, fy as i32, fz as i32);
        let (x, y, z) = (x - fx, y - fy, z - fz);
        let (u, v, w) = (fade(x), fade(y), fade(z));
        let corner = |i: i32, j: i32, k: i32| {
            let h = gradient_index(xi + i, yi + j, zi + k, perlin.key);
            grad(h, x - f64::from(i), y - f64::from(j), z - f64::from(k))
        };
        lerp(
            w,
            lerp(
                v,
                lerp(u, corner(0, 0, 0), corner(1, 0, 0)),
                lerp(u, corner(0, 1, 0), corner(1, 1, 0)),
            ),
            lerp(
                v,
                lerp(u, corner(0, 0, 1), corner(1, 0, 1)),
                lerp(u, corner(0, 1, 1), corner(1, 1, 1)),
            ),
        )
    }

    #[test]
    fn weighted_sum_is_perlins_improved_noise() {
        for seed in [1, 9] {
            let mut perlin = Perlin::new(seed);
            for avx2 in [false, avx2_available()] {
                perlin.avx2 = avx2;
                for p in grid() {
                    let q = p * 1.7 - Vec3::splat(3.1);
                    let got = f64::from(perlin.signed(q));
                    let want = reference(&perlin, q);
                    assert!((got - want).abs() < 2e-6, "{q}: {got} vs {want}");
                }
            }
        }
    }

    /// The vector and portable evaluations are the same arithmetic in the
    /// same order: a render must not depend on which one the CPU runs.
    #[test]
    fn avx2_and_portable_agree_bit_for_bit() {
        if !avx2_available() {
            return;
        }
        let perlin = Perlin::new(5);
        let mut state = 1u64;
        for _ in 0..100_000 {
            let mut next = || {
                state = state
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                ((state >> 40) as f32 / (1u64 << 24) as f32 - 0.5) * 2000.0
            };
            let p = Vec3::new(next(), next(), next());
            // SAFETY: the CPU has AVX2 (checked above).
            let fast = unsafe { signed_avx2(perlin.key, p.x, p.y, p.z) };
            assert_eq!(fast.to_bits(), perlin.signed_portable(p).to_bits(), "{p}");
        }
    }

    /// Every one of the 16 gradient choices occurs, about equally often:
    /// the hash must not favour directions (that would streak the field).
    #[test]
    fn gradient_choices_are_balanced() {
        let mut counts = [0u32; 16];
        for x in -20..20 {
            for y in -20..20 {
                for z in -20..20 {
                    counts[gradient_index(x, y, z, 12345) as usize] += 1;
                }
            }
        }
        let expected = 64_000.0 / 16.0;
        for (h, &c) in counts.iter().enumerate() {
            assert!(
                (f64::from(c) - expected).abs() < 0.06 * expected,
                "gradient {h}: {c} of 64000"
            );
        }
    }

    /// Unlike Perlin's 256-entry permutation, the lattice hash does not
    /// repeat: cells 256 apart get different gradients.
    #[test]
    fn field_does_not_repeat_every_256_cells() {
        let mut perlin = Perlin::new(3);
        for avx2 in [false, avx2_available()] {
            perlin.avx2 = avx2;
            let same = grid()
                .filter(|&p| {
                    let q = p + Vec3::new(0.37, 0.11, 0.59);
                    (perlin.signed(q) - perlin.signed(q + Vec3::new(256.0, 0.0, 0.0))).abs() < 1e-6
                })
                .count();
            assert!(
                same < 100,
                "{same} of 16000 points repeat at 256 cells (avx2 {avx2})"
            );
        }
    }

    fn unit_sphere() -> Shape {
        Shape::Sphere(crate::render::geometry::Sphere {
            center: Vec3::new(0.0, 1.0, 0.0),
            radius: 1.0,
        })
    }

    /// Points on the unit sphere around (0, 1, 0) at `radius`, spread by
    /// another rule than the bake's own check.
    fn shell(radius: f32) -> impl Iterator<Item = Vec3> {
        (0..20_000).map(move |k| {
            let u = (k as f32 * 0.618_034).fract();
            let v = (k as f32 * 0.754_877_7).fract();
            let z = 2.0 * u - 1.0;
            let r = (1.0 - z * z).sqrt();
            let phi = std::f32::consts::TAU * v;
            Vec3::new(0.0, 1.0, 0.0) + radius * Vec3::new(r * phi.cos(), z, r * phi.sin())
        })
    }

    /// On the surface the grid is within its error budget of the exact
    /// field (checked independently of the bake's own check), and exact at
    /// the nodes.
    #[test]
    fn thickness_grid_follows_the_field() {
        let field = ThicknessField::noise(100.0, 600.0, 2.0, 9);
        let grid = ThicknessGrid::bake(&field, &unit_sphere()).unwrap();
        assert!(
            grid.max_error_nm <= GRID_MAX_ERROR_NM,
            "bake check {}",
            grid.max_error_nm
        );
        let (mut worst, mut sum, mut n) = (0.0f32, 0.0f64, 0);
        for p in shell(1.0) {
            let err = (grid.at(p) - field.at(p)).abs();
            worst = worst.max(err);
            sum += f64::from(err);
            n += 1;
        }
        assert!(worst < 1.2 * GRID_MAX_ERROR_NM, "worst {worst} nm");
        assert!(
            sum / f64::from(n) < 0.2 * f64::from(GRID_MAX_ERROR_NM),
            "mean {} nm",
            sum / f64::from(n)
        );
        // A sphere's grid lies on its surface; hit points a little off it
        // (rounding) read nearly the surface's value.
        let GridLayout::Sphere(layout) = &grid.layout else {
            panic!("a sphere's grid is a surface grid");
        };
        let center = Vec3::new(0.0, 1.0, 0.0);
        for (p, q) in shell(1.0).zip(shell(1.0 + 1e-4)) {
            assert!((grid.at(q) - field.at(p)).abs() < 1.2 * GRID_MAX_ERROR_NM);
        }
        for (p, q) in shell(1.0).zip(shell(1.0 - 1e-4)) {
            assert!((grid.at(q) - field.at(p)).abs() < 1.2 * GRID_MAX_ERROR_NM);
        }
        // At a node the interpolation is the node's value: node (i, j) of
        // face 3 (−y), whose (u, v) are (z, x), at nodes inside the face's
        // own part of the sphere (|u|, |v| ≤ |y|).
        let half = (layout.side - 1) as f32 / 2.0;
        let h = half as usize;
        for (i, j) in [(h - 5, h + 7), (h, 3), (h + 20, h - 9)] {
            let (u, v) = (
                FACE_HALF_WIDTH * (i as f32 / half - 1.0),
                FACE_HALF_WIDTH * (j as f32 / half - 1.0),
            );
            let node = center + Vec3::new(v, -(1.0 - u * u - v * v).sqrt(), u);
            assert!((grid.at(node) - field.at(node)).abs() < 1e-3, "({i}, {j})");
        }
        assert_eq!(grid.node_count(), 6 * layout.side * layout.side);
    }

    /// Across an edge between two faces, or a corner of three, the field
    /// read from the grid does not jump.
    #[test]
    fn sphere_grid_is_continuous_across_face_edges() {
        let field = ThicknessField::noise(100.0, 600.0, 2.0, 9);
        let grid = ThicknessGrid::bake(&field, &unit_sphere()).unwrap();
        let center = Vec3::new(0.0, 1.0, 0.0);
        let mut worst = 0.0f32;
        for k in 0..2000 {
            let t = 2.0 * (k as f32 * 0.618_034).fract() - 1.0;
            let (sx, sy, sz) = (
                if k % 2 == 0 { 1.0 } else { -1.0 },
                if k % 4 < 2 { 1.0 } else { -1.0 },
                if k % 8 < 4 { 1.0 } else { -1.0 },
            );
            // Points on the edges x = y, y = z and z = x (|t| below both),
            // and the corner x = y = z, nudged to either side.
            for edge in [
                Vec3::new(sx, sy, sz * t),
                Vec3::new(sx * t, sy, sz),
                Vec3::new(sx, sy * t, sz),
                Vec3::new(sx, sy, sz),
            ] {
                for nudge in [Vec3::X, Vec3::Y, Vec3::Z] {
                    let a = center + (edge + 1e-4 * nudge).normalize();
                    let b = center + (edge - 1e-4 * nudge).normalize();
                    worst = worst.max((grid.at(a) - grid.at(b)).abs());
                }
            }
        }
        // The field itself changes by well under 0.5 nm over 2e-4.
        assert!(worst < 0.5, "jump of {worst} nm across a face edge");
    }

    #[test]
    fn thickness_grid_on_a_mesh_follows_the_field() {
        let data = crate::render::mesh::torus(1.0, 0.3, 48, 24);
        let (positions, indices, _normals) = data;
        let mesh = crate::render::mesh::Mesh::new(&positions, &indices, Vec::new()).unwrap();
        let triangles: Vec<[Vec3; 3]> = mesh.triangles().collect();
        let shape = Shape::Mesh(std::sync::Arc::new(mesh));
        let field = ThicknessField::noise(200.0, 900.0, 3.0, 4);
        let grid = ThicknessGrid::bake(&field, &shape).unwrap();
        // Triangle centroids and edge midpoints, not the bake's points.
        for [a, b, c] in triangles {
            for p in [(a + b + c) / 3.0, 0.5 * (a + b), 0.5 * (b + c)] {
                let err = (grid.at(p) - field.at(p)).abs();
                assert!(err < 1.2 * GRID_MAX_ERROR_NM, "{p}: {err} nm");
            }
        }
        // A mesh's grid fills its bounding box; at a node the
        // interpolation is the node's value.
        let GridLayout::Box(layout) = &grid.layout else {
            panic!("a mesh's grid is a box grid");
        };
        assert_eq!(grid.node_count(), layout.dims.iter().product::<usize>());
        for cell in [Vec3::new(7.0, 11.0, 5.0), Vec3::new(1.0, 2.0, 3.0)] {
            let node = layout.origin.truncate() + cell / layout.inv_step.truncate();
            assert!((grid.at(node) - field.at(node)).abs() < 1e-3, "{cell}");
        }
        // Outside the box: the value at its nearest face, within range.
        assert_far_points_read_within(&grid, 200.0, 900.0);
    }

    /// Points far off the surface, and NaN, read values in [lo, hi].
    fn assert_far_points_read_within(grid: &ThicknessGrid, lo: f32, hi: f32) {
        for p in [
            Vec3::splat(-50.0),
            Vec3::splat(50.0),
            Vec3::new(0.0, f32::NAN, 0.0),
        ] {
            let d = grid.at(p);
            assert!((lo..=hi).contains(&d), "{p}: {d}");
        }
    }

    #[test]
    fn thickness_grid_clamps_and_is_only_baked_where_it_pays() {
        let field = ThicknessField::noise(100.0, 600.0, 2.0, 9);
        let grid = ThicknessGrid::bake(&field, &unit_sphere()).unwrap();
        assert_far_points_read_within(&grid, 100.0, 600.0);
        let uniform = ThicknessField::Uniform {
            thickness_nm: 300.0,
        };
        assert!(ThicknessGrid::bake(&uniform, &unit_sphere()).is_none());
        let plane = Shape::Plane(crate::render::geometry::Plane {
            point: Vec3::ZERO,
            normal: Vec3::Y,
        });
        assert!(ThicknessGrid::bake(&field, &plane).is_none());
        // A sphere far too large for the field's frequency keeps the exact
        // field.
        let huge = Shape::Sphere(crate::render::geometry::Sphere {
            center: Vec3::ZERO,
            radius: 300.0,
        });
        assert!(ThicknessGrid::bake(&field, &huge).is_none());
    }

    #[test]
    fn signed_noise_stays_within_one_and_is_centred() {
        let p = Perlin::new(1);
        let (mut lo, mut hi, mut sum, mut n) = (f32::MAX, f32::MIN, 0.0f64, 0);
        for i in 0..200_000 {
            let q = Vec3::new(
                i as f32 * 0.01731,
                (i % 997) as f32 * 0.0731 - 30.0,
                (i % 89) as f32 * 0.377,
            );
            let v = p.signed(q);
            lo = lo.min(v);
            hi = hi.max(v);
            sum += f64::from(v);
            n += 1;
        }
        assert!(lo >= -1.05 && hi <= 1.05, "range {lo}..{hi}");
        assert!(
            lo < -0.6 && hi > 0.6,
            "noise should use its range: {lo}..{hi}"
        );
        assert!((sum / n as f64).abs() < 0.03, "mean {}", sum / n as f64);
    }

    #[test]
    fn fast_floor_matches_floor() {
        for x in [
            -2.5f32, -2.0, -1e-7, 0.0, 0.3, 1.0, 7.9999, -1000.25, 123456.7,
        ] {
            assert_eq!(fast_floor(x), x.floor() as i32, "{x}");
        }
    }

    #[test]
    fn noise_field_stays_in_range_and_uses_it() {
        let f = ThicknessField::noise(100.0, 1000.0, 1.3, 7);
        let (mut lo, mut hi, mut sum, mut n) = (f32::MAX, f32::MIN, 0.0f64, 0);
        for p in grid() {
            let d = f.at(p);
            assert!((100.0..=1000.0).contains(&d), "d = {d} at {p}");
            lo = lo.min(d);
            hi = hi.max(d);
            sum += d as f64;
            n += 1;
        }
        // Perlin noise clusters around its middle, but a field this size must
        // spread well across the range and be centred in it.
        assert!(lo < 300.0 && hi > 800.0, "range used: {lo}..{hi}");
        let mean = sum / n as f64;
        assert!((mean - 550.0).abs() < 60.0, "mean {mean}");
    }

    #[test]
    fn noise_field_is_continuous_deterministic_and_seeded() {
        let a = ThicknessField::noise(0.0, 1.0, 2.0, 3);
        let b = ThicknessField::noise(0.0, 1.0, 2.0, 3);
        let c = ThicknessField::noise(0.0, 1.0, 2.0, 4);
        let mut differs = false;
        for p in grid() {
            assert_eq!(a.at(p).to_bits(), b.at(p).to_bits());
            differs |= (a.at(p) - c.at(p)).abs() > 1e-3;
            // The gradient of Perlin noise is bounded: a tiny step moves it little.
            let step = a.at(p + Vec3::splat(1e-4)) - a.at(p);
            assert!(step.abs() < 1e-2, "jump {step} at {p}");
        }
        assert!(differs, "another seed must give another field");
    }

    #[test]
    fn scale_sets_the_frequency() {
        // Perlin noise is 0 (mapped: 0.5) on the integer lattice of s·p,
        // including negative coordinates.
        let f = ThicknessField::noise(0.0, 1.0, 0.5, 1);
        for p in [
            Vec3::new(2.0, 4.0, -6.0),
            Vec3::new(0.0, 2.0, 8.0),
            Vec3::new(-2.0, -4.0, 0.0),
        ] {
            assert!((f.at(p) - 0.5).abs() < 1e-6);
        }
        // Halfway between lattice points it is generally not.
        assert!(grid().any(|p| (f.at(p) - 0.5).abs() > 0.1));
        let u = ThicknessField::Uniform {
            thickness_nm: 420.0,
        };
        assert_eq!(u.at(Vec3::new(1.0, 2.0, 3.0)), 420.0);
        assert_eq!(u.range_nm(), (420.0, 420.0));
    }
}
