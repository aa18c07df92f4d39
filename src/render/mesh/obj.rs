//! OBJ import.

use std::path::Path;

use glam::Vec3;

use super::MeshData;
use crate::error::{Error, Result};

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
