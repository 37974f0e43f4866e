//! Wavefront OBJ meshes (a convenience format), through the `tobj` crate:
//! positions and faces of every object, polygons triangulated.

use crate::error::{Error, Result};
use crate::mesh::Mesh;
use glam::DVec3;

/// Loads every object of an OBJ file; materials are ignored.
pub fn load(file: &str, bytes: &[u8]) -> Result<Mesh> {
    let opts = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ignore_points: true,
        ignore_lines: true,
    };
    let mut reader = std::io::Cursor::new(bytes);
    let (models, _) = tobj::load_obj_buf(&mut reader, &opts, |_| Ok(Default::default())).map_err(|e| Error::Mesh {
        file: file.into(),
        problem: format!("not a valid OBJ file: {e}"),
    })?;
    let mut mesh = Mesh::default();
    for m in models {
        let base = mesh.positions.len() as u32;
        let p = &m.mesh.positions;
        mesh.positions.extend(
            p.chunks_exact(3)
                .map(|c| DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64)),
        );
        mesh.triangles.extend(
            m.mesh
                .indices
                .chunks_exact(3)
                .map(|t| [base + t[0], base + t[1], base + t[2]]),
        );
    }
    Ok(mesh)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quad_is_triangulated() {
        let m = load("q.obj", b"v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n").unwrap();
        assert_eq!(m.positions.len(), 4);
        assert_eq!(m.triangles.len(), 2);
    }

    #[test]
    fn garbage_is_an_error() {
        let e = load("bad.obj", b"v 0 0 0\nf 1 2 x\n");
        assert!(e.is_err() || e.unwrap().validate("bad.obj").is_err());
    }
}
