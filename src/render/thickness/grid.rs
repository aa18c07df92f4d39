//! A noise field precomputed on a grid over one object's surface.

use glam::{Vec3, Vec3A, Vec3Swizzles, Vec4};

use super::ThicknessField;
use crate::render::geometry::Aabb;
use crate::render::scene::Shape;

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

#[cfg(test)]
mod tests {
    use super::*;

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
}
