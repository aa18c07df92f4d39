//! Triangle meshes with a bounding-volume hierarchy, OBJ import, and the
//! procedural torus and brilliant-cut gem of the paper's figures.

use std::path::Path;

use glam::{Mat3, Vec3};

use super::geometry::{Aabb, Ray, SurfaceHit};
use crate::error::{Error, Result};

/// Triangles stored with precomputed edges for the Möller–Trumbore test.
#[derive(Clone, Copy, Debug)]
struct Triangle {
    v0: Vec3,
    e1: Vec3,
    e2: Vec3,
    /// Unit geometric normal, e1 × e2 (counter-clockwise front face).
    normal: Vec3,
    /// Vertex indices for smooth-normal interpolation.
    idx: [u32; 3],
}

#[derive(Clone, Copy, Debug)]
struct Node {
    bounds: Aabb,
    /// Leaf: first triangle; inner: index of the left child (right = left + 1).
    first: u32,
    /// Leaf: triangle count (> 0); inner: 0.
    count: u32,
}

/// A closed or open triangle mesh. Normals face outward (counter-clockwise
/// winding seen from outside), which the tracer uses to tell inside from outside.
#[derive(Clone, Debug)]
pub struct Mesh {
    triangles: Vec<Triangle>,
    /// Per-vertex normals for smooth shading; empty for flat facets.
    vertex_normals: Vec<Vec3>,
    nodes: Vec<Node>,
}

const LEAF_SIZE: usize = 4;

impl Mesh {
    /// Builds a mesh from positions and triangle indices. `normals` may be
    /// empty (flat shading) or give one unit normal per position.
    pub fn new(positions: &[Vec3], indices: &[[u32; 3]], normals: Vec<Vec3>) -> Result<Mesh> {
        if indices.is_empty() {
            return Err(Error::invalid("mesh", "has no triangles"));
        }
        if !normals.is_empty() && normals.len() != positions.len() {
            return Err(Error::invalid(
                "mesh",
                "normal count differs from vertex count",
            ));
        }
        let mut triangles = Vec::with_capacity(indices.len());
        for tri in indices {
            if tri.iter().any(|&i| i as usize >= positions.len()) {
                return Err(Error::invalid(
                    "mesh",
                    "a triangle indexes a missing vertex",
                ));
            }
            let [a, b, c] = tri.map(|i| positions[i as usize]);
            let (e1, e2) = (b - a, c - a);
            let n = e1.cross(e2);
            // Degenerate triangles can never be hit; dropping them keeps
            // the normal well defined.
            if n.length_squared() <= 1e-24 {
                continue;
            }
            triangles.push(Triangle {
                v0: a,
                e1,
                e2,
                normal: n.normalize(),
                idx: *tri,
            });
        }
        let mut mesh = Mesh {
            triangles,
            vertex_normals: normals,
            nodes: Vec::new(),
        };
        mesh.build_bvh();
        Ok(mesh)
    }

    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    pub fn bounds(&self) -> Aabb {
        self.nodes[0].bounds
    }

    /// Each triangle's three corners.
    pub fn triangles(&self) -> impl ExactSizeIterator<Item = [Vec3; 3]> + '_ {
        self.triangles
            .iter()
            .map(|t| [t.v0, t.v0 + t.e1, t.v0 + t.e2])
    }

    fn tri_bounds(t: &Triangle) -> Aabb {
        let mut b = Aabb::EMPTY;
        b.grow(t.v0);
        b.grow(t.v0 + t.e1);
        b.grow(t.v0 + t.e2);
        b
    }

    /// Top-down build, splitting at the median centroid of the widest axis:
    /// simple, O(n log n), and good enough for meshes of a few 10k triangles.
    fn build_bvh(&mut self) {
        let n = self.triangles.len();
        self.nodes = Vec::with_capacity(2 * n / LEAF_SIZE + 1);
        self.nodes.push(Node {
            bounds: Aabb::EMPTY,
            first: 0,
            count: n as u32,
        });
        let mut todo = vec![0usize];
        while let Some(ni) = todo.pop() {
            let (first, count) = (self.nodes[ni].first as usize, self.nodes[ni].count as usize);
            let tris = &mut self.triangles[first..first + count];
            let mut bounds = Aabb::EMPTY;
            let mut centroids = Aabb::EMPTY;
            for t in tris.iter() {
                let b = Self::tri_bounds(t);
                bounds = bounds.union(&b);
                centroids.grow(b.center());
            }
            self.nodes[ni].bounds = bounds;
            if count <= LEAF_SIZE {
                continue;
            }
            let extent = centroids.max - centroids.min;
            let axis = if extent.x >= extent.y && extent.x >= extent.z {
                0
            } else if extent.y >= extent.z {
                1
            } else {
                2
            };
            if extent[axis] <= 0.0 {
                continue; // all centroids coincide: keep as one leaf
            }
            let mid = count / 2;
            tris.select_nth_unstable_by(mid, |a, b| {
                let ca = Self::tri_bounds(a).center()[axis];
                let cb = Self::tri_bounds(b).center()[axis];
                ca.total_cmp(&cb)
            });
            let left = self.nodes.len();
            self.nodes.push(Node {
                bounds: Aabb::EMPTY,
                first: first as u32,
                count: mid as u32,
            });
            self.nodes.push(Node {
                bounds: Aabb::EMPTY,
                first: (first + mid) as u32,
                count: (count - mid) as u32,
            });
            self.nodes[ni].first = left as u32;
            self.nodes[ni].count = 0;
            todo.push(left);
            todo.push(left + 1);
        }
    }

    /// Nearest hit with t in (t_min, t_max).
    pub fn intersect(&self, ray: &Ray, t_min: f32, mut t_max: f32) -> Option<SurfaceHit> {
        let inv_dir = ray.dir.recip();
        let enter = |node: u32, t_max: f32| {
            self.nodes[node as usize]
                .bounds
                .hit(ray.origin, inv_dir, t_min, t_max)
        };
        let mut best: Option<(usize, f32, f32, f32)> = None;
        // Entries are (node, where the ray enters its box). A box is
        // slab-tested once, when its parent is visited; on its turn only the
        // stored entry is compared with the nearest hit so far.
        let mut stack = [(0u32, 0.0f32); 64];
        let mut sp = 0usize;
        if let Some(near) = enter(0, t_max) {
            stack[0] = (0, near);
            sp = 1;
        }
        while sp > 0 {
            sp -= 1;
            let (ni, near) = stack[sp];
            // A hit found since the push may lie in front of this box. Only
            // t_max has changed since its slab test, so this comparison gives
            // the answer testing the box again would.
            if near > t_max {
                continue;
            }
            let node = &self.nodes[ni as usize];
            if node.count > 0 {
                let first = node.first as usize;
                for i in first..first + node.count as usize {
                    if let Some((t, u, v)) =
                        intersect_triangle(&self.triangles[i], ray, t_min, t_max)
                    {
                        t_max = t;
                        best = Some((i, t, u, v));
                    }
                }
            } else if sp + 2 <= stack.len() {
                let (l, r) = (node.first, node.first + 1);
                match (enter(l, t_max), enter(r, t_max)) {
                    // The nearer child on top, so t_max shrinks sooner.
                    (Some(dl), Some(dr)) => {
                        let (near, far) = if dr < dl {
                            ((r, dr), (l, dl))
                        } else {
                            ((l, dl), (r, dr))
                        };
                        stack[sp] = far;
                        stack[sp + 1] = near;
                        sp += 2;
                    }
                    (Some(dl), None) => {
                        stack[sp] = (l, dl);
                        sp += 1;
                    }
                    (None, Some(dr)) => {
                        stack[sp] = (r, dr);
                        sp += 1;
                    }
                    (None, None) => {}
                }
            }
        }
        let (i, t, u, v) = best?;
        let tri = &self.triangles[i];
        let shading_normal = if self.vertex_normals.is_empty() {
            tri.normal
        } else {
            let [a, b, c] = tri.idx.map(|k| self.vertex_normals[k as usize]);
            let n = ((1.0 - u - v) * a + u * b + v * c).normalize_or_zero();
            if n.dot(tri.normal) > 0.0 {
                n
            } else {
                tri.normal
            }
        };
        Some(SurfaceHit {
            t,
            normal: tri.normal,
            shading_normal,
        })
    }

    /// Applies a uniform scale, a rotation and a translation, in that order.
    pub fn transformed(
        positions: &mut [Vec3],
        normals: &mut [Vec3],
        scale: f32,
        rotation: Mat3,
        translate: Vec3,
    ) {
        for p in positions.iter_mut() {
            *p = rotation * (*p * scale) + translate;
        }
        for n in normals.iter_mut() {
            *n = (rotation * *n).normalize_or_zero();
        }
    }
}

/// Möller–Trumbore; returns (t, u, v) for hits on either face.
#[inline]
fn intersect_triangle(
    tri: &Triangle,
    ray: &Ray,
    t_min: f32,
    t_max: f32,
) -> Option<(f32, f32, f32)> {
    let p = ray.dir.cross(tri.e2);
    let det = tri.e1.dot(p);
    if det.abs() < 1e-12 {
        return None;
    }
    let inv_det = 1.0 / det;
    let s = ray.origin - tri.v0;
    let u = s.dot(p) * inv_det;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(tri.e1);
    let v = ray.dir.dot(q) * inv_det;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    let t = tri.e2.dot(q) * inv_det;
    (t > t_min && t < t_max).then_some((t, u, v))
}

/// Positions, triangles and (possibly empty) per-vertex normals.
pub type MeshData = (Vec<Vec3>, Vec<[u32; 3]>, Vec<Vec3>);

/// A torus around the y axis: `major_radius` to the tube's centre,
/// `minor_radius` the tube's; smooth normals.
pub fn torus(major_radius: f32, minor_radius: f32, segments: u32, sides: u32) -> MeshData {
    let (segments, sides) = (segments.max(3), sides.max(3));
    let mut positions = Vec::with_capacity((segments * sides) as usize);
    let mut normals = Vec::with_capacity(positions.capacity());
    for i in 0..segments {
        let u = i as f32 / segments as f32 * std::f32::consts::TAU;
        let ring_dir = Vec3::new(u.cos(), 0.0, u.sin());
        for j in 0..sides {
            let v = j as f32 / sides as f32 * std::f32::consts::TAU;
            let n = v.cos() * ring_dir + v.sin() * Vec3::Y;
            positions.push(major_radius * ring_dir + minor_radius * n);
            normals.push(n);
        }
    }
    let id = |i: u32, j: u32| (i % segments) * sides + (j % sides);
    let mut indices = Vec::with_capacity(2 * positions.len());
    for i in 0..segments {
        for j in 0..sides {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            // Counter-clockwise seen from outside the tube.
            indices.push([a, c, b]);
            indices.push([a, d, c]);
        }
    }
    (positions, indices, normals)
}

/// A round brilliant cut of girdle radius 1 centred on the y axis, table up:
/// table, star and bezel facets on the crown, upper and lower girdle facets,
/// pavilion mains to a pointed culet. Flat facets (no vertex normals).
pub fn brilliant_gem() -> MeshData {
    // Proportions of a Tolkowsky-like cut (fractions of the girdle diameter
    // 2): table 56 %, crown angle ≈ 34.5°, pavilion angle ≈ 40.75°.
    let table_r = 0.56;
    let crown_h = (1.0 - table_r) * 34.5f32.to_radians().tan();
    let girdle_h = 0.02;
    let pavilion_h = 40.75f32.to_radians().tan();
    // Rings from top to bottom: (count, radius, height, angular offset in units of the ring's step).
    let rings: [(u32, f32, f32, f32); 7] = [
        (1, 0.0, girdle_h + crown_h, 0.0),     // table centre
        (8, table_r, girdle_h + crown_h, 0.0), // table edge
        (
            8,
            0.5 * (1.0 + table_r) + 0.06,
            girdle_h + 0.45 * crown_h,
            0.5,
        ), // star/bezel points
        (16, 1.0, girdle_h, 0.0),              // girdle top
        (16, 1.0, -girdle_h, 0.0),             // girdle bottom
        (8, 0.45, -girdle_h - 0.55 * pavilion_h, 0.5), // lower girdle points
        (1, 0.0, -girdle_h - pavilion_h, 0.0), // culet
    ];
    let mut positions = Vec::new();
    let mut ring_start = Vec::new();
    for &(count, r, h, offset) in &rings {
        ring_start.push(positions.len() as u32);
        for k in 0..count {
            let a = (k as f32 + offset) / count as f32 * std::f32::consts::TAU;
            positions.push(Vec3::new(r * a.cos(), h, r * a.sin()));
        }
    }
    let mut indices = Vec::new();
    for w in 0..rings.len() - 1 {
        zip_rings(&rings, w, &ring_start, &mut indices);
    }
    orient_outward(&positions, &mut indices);
    (positions, indices, Vec::new())
}

/// Triangulates the band between two rings by merging their vertices in
/// angle order (a "zipper"): each step advances along whichever ring's next
/// vertex comes first, emitting one triangle. A one-point ring never advances.
fn zip_rings(rings: &[(u32, f32, f32, f32)], w: usize, start: &[u32], out: &mut Vec<[u32; 3]>) {
    let (na, _, _, oa) = rings[w];
    let (nb, _, _, ob) = rings[w + 1];
    let (sa, sb) = (start[w], start[w + 1]);
    let mut i = u32::from(na == 1);
    let mut j = u32::from(nb == 1);
    while i < na || j < nb {
        let next_a = (i + 1) as f32 + oa;
        let next_b = (j + 1) as f32 + ob;
        let a = sa + i % na;
        let b = sb + j % nb;
        if j >= nb || (i < na && next_a / na as f32 <= next_b / nb as f32) {
            out.push([a, sa + (i + 1) % na, b]);
            i += 1;
        } else {
            out.push([a, sb + (j + 1) % nb, b]);
            j += 1;
        }
    }
}

/// The gem is convex: flip any triangle whose normal points toward the centre.
fn orient_outward(positions: &[Vec3], indices: &mut [[u32; 3]]) {
    let mut centre = Vec3::ZERO;
    for p in positions {
        centre += *p;
    }
    centre /= positions.len() as f32;
    for tri in indices.iter_mut() {
        let [a, b, c] = tri.map(|i| positions[i as usize]);
        let n = (b - a).cross(c - a);
        if n.dot((a + b + c) / 3.0 - centre) < 0.0 {
            tri.swap(1, 2);
        }
    }
}

/// Loads every model of an OBJ file as one mesh (triangulated, with the
/// file's normals when every vertex has one).
pub fn load_obj(path: &Path) -> Result<MeshData> {
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ..Default::default()
    };
    let (models, _materials) = tobj::load_obj(path, &options).map_err(|e| match e {
        tobj::LoadError::OpenFileFailed => Error::io(
            path,
            std::io::Error::new(std::io::ErrorKind::NotFound, "cannot open mesh file"),
        ),
        other => Error::malformed(path, format!("not a valid OBJ file: {other}")),
    })?;
    let mut positions = Vec::new();
    let mut normals = Vec::new();
    let mut indices = Vec::new();
    let mut all_have_normals = true;
    for model in &models {
        let m = &model.mesh;
        let base = positions.len() as u32;
        positions.extend(
            m.positions
                .chunks_exact(3)
                .map(|p| Vec3::new(p[0], p[1], p[2])),
        );
        if m.normals.len() == m.positions.len() {
            normals.extend(
                m.normals
                    .chunks_exact(3)
                    .map(|n| Vec3::new(n[0], n[1], n[2]).normalize_or_zero()),
            );
        } else {
            all_have_normals = false;
        }
        indices.extend(
            m.indices
                .chunks_exact(3)
                .map(|t| [base + t[0], base + t[1], base + t[2]]),
        );
    }
    if indices.is_empty() {
        return Err(Error::malformed(path, "OBJ file has no faces"));
    }
    if !all_have_normals {
        normals.clear();
    }
    Ok((positions, indices, normals))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn brute_force(positions: &[Vec3], indices: &[[u32; 3]], ray: &Ray) -> Option<f32> {
        let mesh_one = |tri: &[u32; 3]| {
            let [a, b, c] = tri.map(|i| positions[i as usize]);
            let t = Triangle {
                v0: a,
                e1: b - a,
                e2: c - a,
                normal: Vec3::Y,
                idx: *tri,
            };
            intersect_triangle(&t, ray, 1e-4, f32::INFINITY).map(|h| h.0)
        };
        indices.iter().filter_map(mesh_one).min_by(f32::total_cmp)
    }

    #[test]
    fn bvh_agrees_with_brute_force_on_a_torus() {
        let (p, i, n) = torus(1.0, 0.3, 48, 24);
        let mesh = Mesh::new(&p, &i, n).unwrap();
        let mut hits = 0;
        for k in 0..400 {
            let a = k as f32 * 0.37;
            let origin = Vec3::new(3.0 * a.cos(), 0.7 * (a * 1.3).sin(), 3.0 * a.sin());
            let target = Vec3::new(0.9 * (a * 2.1).cos(), 0.2 * a.sin(), 0.9 * (a * 1.7).sin());
            let ray = Ray::new(origin, (target - origin).normalize());
            let want = brute_force(&p, &i, &ray);
            let got = mesh.intersect(&ray, 1e-4, f32::INFINITY).map(|h| h.t);
            match (want, got) {
                (Some(w), Some(g)) => {
                    assert!((w - g).abs() < 1e-5, "ray {k}: {w} vs {g}");
                    hits += 1;
                }
                (None, None) => {}
                other => panic!("ray {k}: brute force and BVH disagree: {other:?}"),
            }
        }
        assert!(hits > 100, "the test rays should mostly hit ({hits})");
    }

    /// The nearest of all triangles, tried one by one: (t, unit normal).
    fn nearest_of_all(mesh: &Mesh, ray: &Ray, t_min: f32, t_max: f32) -> Option<(f32, Vec3)> {
        mesh.triangles
            .iter()
            .filter_map(|tri| {
                intersect_triangle(tri, ray, t_min, t_max).map(|(t, _, _)| (t, tri.normal))
            })
            .min_by(|a, b| a.0.total_cmp(&b.0))
    }

    /// Random rays, from inside and outside each mesh's box, and with finite
    /// and infinite t_max, against every triangle: the BVH must find the
    /// same nearest triangle, to the bit, whichever order it visits boxes in.
    #[test]
    fn bvh_agrees_with_brute_force_on_random_rays() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_pcg::Pcg64::seed_from_u64(7);
        let point = |rng: &mut rand_pcg::Pcg64, half: f32| {
            Vec3::new(
                rng.random_range(-half..half),
                rng.random_range(-half..half),
                rng.random_range(-half..half),
            )
        };
        // Overlapping boxes of every size: the case where visiting order and
        // pruning matter most.
        let soup: Vec<Vec3> = (0..900).map(|_| point(&mut rng, 1.5)).collect();
        let soup_indices: Vec<[u32; 3]> = (0..300).map(|k| [3 * k, 3 * k + 1, 3 * k + 2]).collect();
        let (tp, ti, tn) = torus(1.0, 0.3, 40, 20);
        let (gp, gi, _) = brilliant_gem();
        let meshes = [
            ("soup", Mesh::new(&soup, &soup_indices, Vec::new()).unwrap()),
            ("torus", Mesh::new(&tp, &ti, tn).unwrap()),
            ("gem", Mesh::new(&gp, &gi, Vec::new()).unwrap()),
        ];
        for (name, mesh) in &meshes {
            let mut hits = 0;
            for k in 0..2000 {
                let origin = point(&mut rng, 3.0);
                // Half the rays aim into the mesh's box, so that many hit.
                let b = mesh.bounds();
                let toward = if k % 2 == 0 {
                    b.min + (b.max - b.min) * (point(&mut rng, 0.5) + 0.5)
                } else {
                    origin + point(&mut rng, 1.0)
                };
                let dir = (toward - origin).normalize_or(Vec3::X);
                let ray = Ray::new(origin, dir);
                let t_max = if k % 4 == 0 {
                    rng.random_range(0.5..4.0)
                } else {
                    f32::INFINITY
                };
                let want = nearest_of_all(mesh, &ray, 1e-4, t_max);
                let got = mesh.intersect(&ray, 1e-4, t_max).map(|h| (h.t, h.normal));
                assert_eq!(
                    got.map(|(t, n)| (t.to_bits(), n)),
                    want.map(|(t, n)| (t.to_bits(), n)),
                    "{name}, ray {k}: {ray:?} up to {t_max}"
                );
                hits += usize::from(got.is_some());
            }
            assert!(
                hits > 500,
                "{name}: the test rays should often hit ({hits})"
            );
        }
    }

    #[test]
    fn torus_and_gem_normals_point_outward() {
        let (p, i, n) = torus(1.0, 0.25, 32, 16);
        let torus = Mesh::new(&p, &i, n).unwrap();
        // From far outside on the x axis the first hit faces the ray.
        let ray = Ray::new(Vec3::new(5.0, 0.0, 0.0), Vec3::NEG_X);
        let h = torus.intersect(&ray, 1e-4, f32::INFINITY).unwrap();
        assert!((h.t - 3.75).abs() < 0.01);
        assert!(h.normal.dot(ray.dir) < 0.0);

        let (p, i, _) = brilliant_gem();
        let gem = Mesh::new(&p, &i, Vec::new()).unwrap();
        assert!(
            gem.triangle_count() >= 56,
            "{} facets",
            gem.triangle_count()
        );
        for dir in [
            Vec3::NEG_Y,
            Vec3::Y,
            Vec3::X,
            Vec3::new(0.3, -0.5, 0.8).normalize(),
        ] {
            let ray = Ray::new(-4.0 * dir, dir);
            let h = gem.intersect(&ray, 1e-4, f32::INFINITY).unwrap();
            assert!(
                h.normal.dot(dir) < 0.0,
                "entry face must face the ray ({dir})"
            );
            // The exit from inside sees the outward normal along the ray.
            let inside = Ray::new(ray.at(h.t + 1e-3), dir);
            let exit = gem.intersect(&inside, 1e-4, f32::INFINITY).unwrap();
            assert!(exit.normal.dot(dir) > 0.0);
        }
    }

    #[test]
    fn gem_is_closed() {
        // Every edge of a closed mesh is shared by exactly two triangles.
        let (_, indices, _) = brilliant_gem();
        let mut edges = std::collections::HashMap::new();
        for t in &indices {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                *edges.entry((a.min(b), a.max(b))).or_insert(0) += 1;
            }
        }
        assert!(
            edges.values().all(|&c| c == 2),
            "open edges in the gem mesh"
        );
    }

    #[test]
    fn obj_import_reads_faces_and_reports_missing_files() {
        let dir = std::env::temp_dir().join(format!("irid-obj-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("quad.obj");
        std::fs::write(&path, "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n").unwrap();
        let (p, i, n) = load_obj(&path).unwrap();
        assert_eq!((p.len(), i.len(), n.len()), (4, 2, 0));
        let missing = load_obj(&dir.join("nope.obj")).unwrap_err().to_string();
        assert!(missing.contains("nope.obj"), "{missing}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
