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
/// Lines are split into words as `tobj` splits them (Unicode whitespace), so that
/// no line it reads as a vertex or a face escapes the count; a line that is not UTF-8
/// stops `tobj` there, so counting it as nothing keeps the count an upper bound.
fn declared(bytes: &[u8]) -> (u64, u64) {
    let (mut v, mut t) = (0u64, 0u64);
    for line in bytes.split(|&b| b == b'\n') {
        let Ok(line) = std::str::from_utf8(line) else { continue };
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => v += 1,
            Some("f") => t += (words.count() as u64).saturating_sub(2),
            _ => {}
        }
    }
    (v, t)
}

/// The file with every face corner's texture and normal indices (`v/vt/vn`) cut to its
/// position index, or `None` when no face names any: only positions are read, and
/// `tobj` 4.0 multiplies a relative texture or normal index that points before the
/// first one without checking (an overflow, a panic where overflow is checked; found
/// by fuzzing).
fn faces_by_position(bytes: &[u8]) -> Option<Vec<u8>> {
    if !bytes.contains(&b'/') {
        return None;
    }
    let mut out = Vec::with_capacity(bytes.len());
    for (k, line) in bytes.split(|&b| b == b'\n').enumerate() {
        if k > 0 {
            out.push(b'\n');
        }
        match std::str::from_utf8(line) {
            Ok(text) if text.contains('/') && text.split_whitespace().next() == Some("f") => {
                out.push(b'f');
                for corner in text.split_whitespace().skip(1) {
                    out.push(b' ');
                    out.extend_from_slice(corner.split('/').next().unwrap_or("").as_bytes());
                }
            }
            _ => out.extend_from_slice(line),
        }
    }
    Some(out)
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
    let positions_only = faces_by_position(bytes);
    let mut reader = std::io::Cursor::new(positions_only.as_deref().unwrap_or(bytes));
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
        // Words split by Unicode whitespace, as tobj splits them, count too (a
        // property test found these escaping the count).
        let odd = "v\u{3000}0 0 0\n\u{a0}v 1 0 0\nv 1\u{2003}1 0\nf\u{a0}1 2 3\u{85}3\n\u{2028}f 1 2 3\n";
        assert_eq!(declared(odd.as_bytes()), (3, 3));
        let mut l = Limits::DEFAULT;
        l.triangles = 2;
        let e = load_with("odd.obj", odd.as_bytes(), &l).unwrap_err();
        assert!(e.to_string().contains("triangle count 3 exceeds the limit of 2"), "{e}");
        let mut l = Limits::DEFAULT;
        l.triangles = 1;
        let e = load_with("q.obj", b"v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n", &l).unwrap_err();
        assert!(e.to_string().contains("triangle count 2 exceeds the limit of 1"), "{e}");
    }

    #[test]
    fn texture_and_normal_indices_are_not_read() {
        // Relative indices before the first `vt` / `vn` (tobj overflowed on these).
        for text in [
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/-3 2/1 3/1\n",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//-3 2//1 3//1\n",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\n  f\t-3/1/1 -2/1/1 -1/1/1\r\n",
        ] {
            let m = load("t.obj", text.as_bytes()).unwrap();
            assert_eq!((m.positions.len(), m.triangles.len()), (3, 1), "{text:?}");
            assert_eq!(m.positions[1], DVec3::X, "{text:?}");
        }
        let cut = faces_by_position(b"vt 0 1/2\nf 1/2/3 4//5 6\n").unwrap();
        assert_eq!(cut, b"vt 0 1/2\nf 1 4 6\n");
        assert!(faces_by_position(b"f 1 2 3\n").is_none());
    }

    #[test]
    fn garbage_is_an_error() {
        let e = load("bad.obj", b"v 0 0 0\nf 1 2 x\n");
        assert!(e.is_err() || e.unwrap().validate("bad.obj").is_err());
    }
}
