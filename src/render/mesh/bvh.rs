//! The mesh and its bounding-volume hierarchy.

use glam::{Mat3, Vec3};

use crate::error::{Error, Result};
use crate::render::geometry::{Aabb, Ray, SurfaceHit};

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
        if triangles.is_empty() {
            return Err(Error::invalid(
                "mesh",
                "has no usable triangle: every face has zero area (coincident or collinear vertices)",
            ));
        }
        let mut mesh = Mesh {
            triangles,
            vertex_normals: normals,
            nodes: Vec::new(),
        };
        mesh.build_bvh();
        Ok(mesh)
    }

    /// Triangles kept: the faces given, less the degenerate (zero-area)
    /// ones dropped when the mesh was built.
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// The box around every kept triangle (the BVH root's bounds), in the
    /// coordinates of the vertex positions.
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::mesh::brilliant_gem;
    use crate::render::mesh::torus;

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
}
