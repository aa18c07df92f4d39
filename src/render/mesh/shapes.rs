//! Procedural meshes: the torus and the round brilliant-cut gem.

use glam::Vec3;

use super::MeshData;

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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::geometry::Ray;
    use crate::render::mesh::Mesh;
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
}
