//! Wavefront OBJ meshes (a convenience format), through the `tobj` crate:
//! positions and faces of every object, polygons triangulated.

use crate::error::{Error, Result};
use crate::limits::Limits;
use crate::mesh::Mesh;
use glam::DVec3;

/// Loads every object of an OBJ file with the default [`Limits`]; materials are ignored.
pub fn load(file: &str, bytes: &[u8]) -> Result<Mesh> {
    load_with(file, bytes, &Limits::DEFAULT)
}

/// The vertices and triangles (polygons as fans) an OBJ file's `v` and `f` lines
/// make, counted from the text before it is parsed (the format declares no counts).
fn declared(bytes: &[u8]) -> (u64, u64) {
    let (mut v, mut t) = (0u64, 0u64);
    for line in bytes.split(|&b| b == b'\n') {
        let line = line.trim_ascii_start();
        if line.starts_with(b"v ") || line.starts_with(b"v\t") {
            v += 1;
        } else if line.starts_with(b"f ") || line.starts_with(b"f\t") {
            let corners = line[1..]
                .split(|b| b.is_ascii_whitespace())
                .filter(|w| !w.is_empty())
                .count() as u64;
            t += corners.saturating_sub(2);
        }
    }
    (v, t)
}

/// As [`load`], the counts of `v` and `f` lines checked against `limits` first.
pub fn load_with(file: &str, bytes: &[u8], limits: &Limits) -> Result<Mesh> {
    let (v, t) = declared(bytes);
    limits.check_mesh(file, v, t)?;
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
    fn counts_are_checked_before_parsing() {
        assert_eq!(
            declared(b"v 0 0 0\n  v 1 0 0\nvt 0 0\nv 1 1 0\nf 1 2 3 3\nf\t1 2 3\n"),
            (3, 3)
        );
        let mut l = Limits::DEFAULT;
        l.triangles = 1;
        let e = load_with("q.obj", b"v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n", &l).unwrap_err();
        assert!(e.to_string().contains("triangle count 2 exceeds the limit of 1"), "{e}");
    }

    #[test]
    fn garbage_is_an_error() {
        let e = load("bad.obj", b"v 0 0 0\nf 1 2 x\n");
        assert!(e.is_err() || e.unwrap().validate("bad.obj").is_err());
    }
}
