//! OBJ import.

use std::path::Path;

use glam::Vec3;

use super::MeshData;
use crate::error::{Error, Result};

/// Loads every model of an OBJ file as one mesh (triangulated, with the
/// file's normals when every vertex has one). A face with fewer than three
/// vertices is refused, naming its line: the OBJ reader would otherwise
/// pass on index lists that do not divide into triangles.
pub fn load_obj(path: &Path) -> Result<MeshData> {
    let text = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    check_faces(&text).map_err(|why| Error::malformed(path, why))?;
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
/// Every face line (`f ...`) lists at least three vertices.
fn check_faces(text: &[u8]) -> std::result::Result<(), String> {
    for (k, line) in text.split(|&b| b == b'\n').enumerate() {
        let mut words = line
            .split(|b| b.is_ascii_whitespace())
            .filter(|w| !w.is_empty());
        if words.next() == Some(b"f".as_slice()) {
            let vertices = words.take_while(|w| !w.starts_with(b"#")).count();
            if vertices < 3 {
                return Err(format!(
                    "line {}: a face needs at least 3 vertices, this one has {vertices}",
                    k + 1
                ));
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn faces_with_fewer_than_three_vertices_are_refused() {
        assert!(check_faces(b"v 0 0 0\nf 1 2 3\nf 1 2 3 4 # quad\n").is_ok());
        assert!(check_faces(b"v 0 0 0\nf 1 2\n")
            .unwrap_err()
            .contains("line 2"));
        assert!(check_faces(b"f\t1\n").unwrap_err().contains("has 1"));
        assert!(check_faces(b"f 1 2 # 3\n").is_err());
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
