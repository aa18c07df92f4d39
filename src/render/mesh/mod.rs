//! Triangle meshes: the bounding-volume hierarchy that intersects them
//! ([`Mesh`]), the procedural torus and brilliant-cut gem of the paper's
//! figures, and OBJ import.

mod bvh;
mod obj;
mod shapes;

use glam::Vec3;

pub use bvh::Mesh;
pub use obj::load_obj;
pub use shapes::{brilliant_gem, torus};

/// Positions, triangles and (possibly empty) per-vertex normals.
pub type MeshData = (Vec<Vec3>, Vec<[u32; 3]>, Vec<Vec3>);
