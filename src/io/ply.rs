//! Stanford PLY meshes (the BOP model format, FORMATS.md §2), through the
//! `ply-rs-bw` crate: `ascii`, `binary_little_endian` and `binary_big_endian`.
//!
//! Input: the file's bytes. Output: a [`Mesh`] whose positions are the `vertex`
//! element's `x`, `y`, `z` (any numeric type, in the file's units: BOP models are in
//! mm) and whose triangles come from the `face` element's `vertex_indices` (or
//! `vertex_index`) lists, polygons fan-triangulated. Every other property (normals,
//! colours, texture coordinates) and element is read past and dropped.
//!
//! Reference: Greg Turk's PLY description (paulbourke.net/dataformats/ply). The crate
//! parses the header and payload; values go straight into a small element type here
//! instead of its per-element hash maps.

use crate::error::{Error, Result};
use crate::limits::Limits;
use crate::mesh::Mesh;
use glam::DVec3;
use ply_rs_bw::parser::{Parser, Reader};
use ply_rs_bw::ply::{ElementDef, Encoding, Property, PropertyAccess, PropertyAccessResult, PropertyType, ScalarType};

/// The names a face's vertex list goes by.
const FACE_LISTS: [&str; 2] = ["vertex_indices", "vertex_index"];

/// One element of any kind, keeping only what a mesh needs.
#[derive(Debug, Default)]
struct Element {
    xyz: [f64; 3],
    indices: Vec<i64>,
}

fn scalar(p: &Property) -> Option<f64> {
    Some(match *p {
        Property::Char(v) => v.into(),
        Property::UChar(v) => v.into(),
        Property::Short(v) => v.into(),
        Property::UShort(v) => v.into(),
        Property::Int(v) => v.into(),
        Property::UInt(v) => v.into(),
        Property::Float(v) => v.into(),
        Property::Double(v) => v,
        _ => return None,
    })
}

fn int_list(p: Property) -> Option<Vec<i64>> {
    Some(match p {
        Property::ListChar(v) => v.into_iter().map(i64::from).collect(),
        Property::ListUChar(v) => v.into_iter().map(i64::from).collect(),
        Property::ListShort(v) => v.into_iter().map(i64::from).collect(),
        Property::ListUShort(v) => v.into_iter().map(i64::from).collect(),
        Property::ListInt(v) => v.into_iter().map(i64::from).collect(),
        Property::ListUInt(v) => v.into_iter().map(i64::from).collect(),
        _ => return None,
    })
}

impl PropertyAccess for Element {
    fn new() -> Self {
        Element::default()
    }

    fn set_property(&mut self, name: &str, p: Property) -> PropertyAccessResult {
        let axis = match name {
            "x" => 0,
            "y" => 1,
            "z" => 2,
            _ if FACE_LISTS.contains(&name) => {
                return match int_list(p) {
                    Some(l) => {
                        self.indices = l;
                        PropertyAccessResult::Set
                    }
                    None => PropertyAccessResult::UnsupportedType,
                }
            }
            _ => return PropertyAccessResult::Ignored,
        };
        match scalar(&p) {
            Some(v) => {
                self.xyz[axis] = v;
                PropertyAccessResult::Set
            }
            None => PropertyAccessResult::UnsupportedType,
        }
    }
}

fn scalar_bytes(t: &ScalarType) -> u64 {
    match t {
        ScalarType::Char | ScalarType::UChar => 1,
        ScalarType::Short | ScalarType::UShort => 2,
        ScalarType::Int | ScalarType::UInt | ScalarType::Float => 4,
        ScalarType::Double => 8,
    }
}

/// The fewest bytes one element can take: binary, each scalar's size (a list, its
/// count's); ASCII, a digit and a separator per property.
fn min_record_bytes(e: &ElementDef, encoding: &Encoding) -> u64 {
    e.properties
        .values()
        .map(|p| match (encoding, &p.data_type) {
            (Encoding::Ascii, _) => 2,
            (_, PropertyType::Scalar(t)) | (_, PropertyType::List(t, _)) => scalar_bytes(t),
        })
        .sum()
}

/// Loads a PLY mesh with the default [`Limits`]; `file` names it in errors.
pub fn load(file: &str, bytes: &[u8]) -> Result<Mesh> {
    load_with(file, bytes, &Limits::DEFAULT)
}

/// Loads a PLY mesh; its declared vertex and face counts are checked against `limits`
/// and against the bytes that follow the header before the data is read.
pub fn load_with(file: &str, bytes: &[u8], limits: &Limits) -> Result<Mesh> {
    let err = |problem: String| Error::Mesh {
        file: file.into(),
        problem,
    };
    let parser = Parser::<Element>::new();
    let mut reader = Reader::new(std::io::Cursor::new(bytes));
    let header = parser
        .read_header(&mut reader)
        .map_err(|e| err(format!("not a valid PLY header: {e}")))?;
    let vertex = header
        .elements
        .get("vertex")
        .ok_or_else(|| err("the PLY file has no 'vertex' element".into()))?;
    for axis in ["x", "y", "z"] {
        match vertex.properties.get(axis).map(|p| &p.data_type) {
            Some(PropertyType::Scalar(_)) => {}
            Some(_) => return Err(err(format!("vertex property '{axis}' is a list, not a number"))),
            None => return Err(err(format!("the 'vertex' element has no '{axis}' property"))),
        }
    }
    let face = header
        .elements
        .get("face")
        .ok_or_else(|| err("the PLY file has no 'face' element (a point cloud is not a mesh)".into()))?;
    if !FACE_LISTS.iter().any(|n| face.properties.contains_key(*n)) {
        return Err(err(
            "the 'face' element has no 'vertex_indices' (or 'vertex_index') list".into(),
        ));
    }
    if let Some(e) = header
        .elements
        .values()
        .find(|e| e.properties.is_empty() && e.count > 0)
    {
        return Err(err(format!("element '{}' has no properties", e.name)));
    }
    limits.check_mesh(file, vertex.count as u64, face.count as u64)?;
    let left = (bytes.len() as u64).saturating_sub(reader.get_ref().position());
    for e in header.elements.values() {
        let need = (e.count as u64).saturating_mul(min_record_bytes(e, &header.encoding));
        if need > left {
            return Err(err(format!(
                "declares {} '{}' elements, which need at least {need} bytes, but {left} bytes follow the header",
                e.count, e.name
            )));
        }
    }
    let mut payload = parser
        .read_payload(&mut reader, &header)
        .map_err(|e| err(format!("cannot read the PLY data: {e}")))?;
    let vertices = payload.swap_remove("vertex").unwrap_or_default();
    let faces = payload.swap_remove("face").unwrap_or_default();
    let n = vertices.len() as i64;
    let mut mesh = Mesh {
        positions: vertices.iter().map(|v| DVec3::from_array(v.xyz)).collect(),
        triangles: Vec::with_capacity(faces.len()),
    };
    for (f, face) in faces.iter().enumerate() {
        let ix = &face.indices;
        if let Some(bad) = ix.iter().find(|&&i| i < 0 || i >= n) {
            return Err(err(format!(
                "face {f} refers to vertex {bad}, but there are {n} vertices"
            )));
        }
        // Fewer than three vertices make no area: nothing to draw.
        let fan = ix.len().saturating_sub(2);
        if (mesh.triangles.len() + fan) as u64 > limits.triangles {
            limits.check_mesh(file, 0, (mesh.triangles.len() + fan) as u64)?;
        }
        for k in 2..ix.len() {
            mesh.triangles.push([ix[0] as u32, ix[k - 1] as u32, ix[k] as u32]);
        }
    }
    mesh.validate(file)?;
    Ok(mesh)
}

/// Writes a mesh as an ASCII PLY file: `x y z` as doubles (shortest exact decimal
/// form) and one `vertex_indices` list per triangle; `comment` goes in the header.
pub fn write_ascii(mesh: &Mesh, comment: &str) -> Vec<u8> {
    use std::fmt::Write;
    let comment = comment.replace(['\n', '\r'], " ");
    let mut s = format!(
        "ply\nformat ascii 1.0\ncomment {comment}\nelement vertex {}\nproperty double x\nproperty double y\n\
         property double z\nelement face {}\nproperty list uchar uint vertex_indices\nend_header\n",
        mesh.positions.len(),
        mesh.triangles.len()
    );
    for p in &mesh.positions {
        let _ = writeln!(s, "{} {} {}", p.x, p.y, p.z);
    }
    for t in &mesh.triangles {
        let _ = writeln!(s, "3 {} {} {}", t[0], t[1], t[2]);
    }
    s.into_bytes()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A unit cube as 6 quads; vertex colour and normals in between, to be skipped.
    const CORNERS: [[f32; 3]; 8] = [
        [0., 0., 0.],
        [1., 0., 0.],
        [1., 1., 0.],
        [0., 1., 0.],
        [0., 0., 1.],
        [1., 0., 1.],
        [1., 1., 1.],
        [0., 1., 1.],
    ];
    const QUADS: [[u32; 4]; 6] = [
        [0, 3, 2, 1],
        [4, 5, 6, 7],
        [0, 1, 5, 4],
        [2, 3, 7, 6],
        [1, 2, 6, 5],
        [0, 4, 7, 3],
    ];

    fn header(format: &str) -> String {
        format!(
            "ply\nformat {format} 1.0\ncomment cube\nelement vertex 8\nproperty float x\nproperty float y\n\
             property float z\nproperty float nx\nproperty uchar red\nelement face 6\n\
             property list uchar int vertex_indices\nend_header\n"
        )
    }

    fn ascii() -> Vec<u8> {
        let mut s = header("ascii");
        for c in CORNERS {
            s += &format!("{} {} {} 0.5 200\n", c[0], c[1], c[2]);
        }
        for q in QUADS {
            s += &format!("4 {} {} {} {}\n", q[0], q[1], q[2], q[3]);
        }
        s.into_bytes()
    }

    fn binary(big: bool) -> Vec<u8> {
        let fmt = if big {
            "binary_big_endian"
        } else {
            "binary_little_endian"
        };
        let mut b = header(fmt).into_bytes();
        let f = |v: f32| if big { v.to_be_bytes() } else { v.to_le_bytes() };
        let i = |v: u32| if big { v.to_be_bytes() } else { v.to_le_bytes() };
        for c in CORNERS {
            for v in c.into_iter().chain([0.5]) {
                b.extend(f(v));
            }
            b.push(200);
        }
        for q in QUADS {
            b.push(4);
            for v in q {
                b.extend(i(v));
            }
        }
        b
    }

    #[test]
    fn ascii_and_binary_give_the_same_cube() {
        let a = load("a.ply", &ascii()).unwrap();
        assert_eq!(a.positions.len(), 8);
        assert_eq!(a.triangles.len(), 12);
        assert_eq!(a.positions[6], DVec3::ONE);
        // Quad (0, 3, 2, 1) is fanned from its first vertex.
        assert_eq!(&a.triangles[..2], &[[0, 3, 2], [0, 2, 1]]);
        assert_eq!(load("le.ply", &binary(false)).unwrap(), a);
        assert_eq!(load("be.ply", &binary(true)).unwrap(), a);
    }

    #[test]
    fn written_ascii_reads_back_exactly() {
        let mut m = load("a.ply", &ascii()).unwrap();
        m.positions[3] = DVec3::new(0.1, -1e-7, 123456.789);
        let back = load("w.ply", &write_ascii(&m, "two\nlines")).unwrap();
        assert_eq!(back, m);
    }

    #[test]
    fn double_and_integer_coordinates_and_vertex_index() {
        let text = "ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\nproperty short y\nproperty uchar z\n\
                    element face 1\nproperty list uchar uint vertex_index\nend_header\n\
                    0.25 -3 7\n1 0 0\n0 1 0\n3 0 1 2\n";
        let m = load("d.ply", text.as_bytes()).unwrap();
        assert_eq!(m.positions[0], DVec3::new(0.25, -3.0, 7.0));
        assert_eq!(m.triangles, vec![[0, 1, 2]]);
    }

    #[test]
    fn malformed_files_are_errors() {
        let expect = |bytes: &[u8], what: &str| {
            let e = load("bad.ply", bytes).unwrap_err().to_string();
            assert!(e.starts_with("mesh 'bad.ply': ") && e.contains(what), "{e}");
        };
        expect(b"", "header");
        expect(b"plx\nformat ascii 1.0\nend_header\n", "header");
        expect(b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n", "header");
        expect(b"ply\nformat wobbly 1.0\nend_header\n", "header");
        expect(
            b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\n0\n",
            "'y'",
        );
        let no_face = b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n\
                        property float z\nend_header\n0 0 0\n";
        expect(no_face, "no 'face'");
        let a = ascii();
        expect(&a[..a.len() - 12], "PLY data");
        let b = binary(false);
        for cut in [b.len() - 1, b.len() - 30] {
            expect(&b[..cut], "PLY data");
        }
        // Too few bytes for the declared counts: refused before the data is read.
        expect(
            &b[..header("binary_little_endian").len() + 5],
            "need at least 136 bytes, but 5 bytes follow the header",
        );
        let out_of_range = String::from_utf8(ascii()).unwrap().replace("4 4 5 6 7", "4 4 5 6 8");
        expect(out_of_range.as_bytes(), "refers to vertex 8");
        let words = String::from_utf8(ascii()).unwrap().replace("0.5 200\n", "0.5 zz\n");
        expect(words.as_bytes(), "PLY data");
    }
}
