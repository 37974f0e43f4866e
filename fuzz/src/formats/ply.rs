//! PLY meshes: scalar types, encodings and the PLY writer.

use super::MeshSpec;

/// Appends `$x`'s bytes to `$out`, big- or little-endian.
macro_rules! put {
    ($out:expr, $big:expr, $x:expr) => {
        if $big {
            $out.extend_from_slice(&$x.to_be_bytes())
        } else {
            $out.extend_from_slice(&$x.to_le_bytes())
        }
    };
}

/// PLY scalar types.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scalar {
    Char,
    UChar,
    Short,
    UShort,
    Int,
    UInt,
    Float,
    Double,
}

pub const SCALARS: [Scalar; 8] = [
    Scalar::Char,
    Scalar::UChar,
    Scalar::Short,
    Scalar::UShort,
    Scalar::Int,
    Scalar::UInt,
    Scalar::Float,
    Scalar::Double,
];

impl Scalar {
    fn name(self, alias: bool) -> &'static str {
        let (a, b) = match self {
            Scalar::Char => ("char", "int8"),
            Scalar::UChar => ("uchar", "uint8"),
            Scalar::Short => ("short", "int16"),
            Scalar::UShort => ("ushort", "uint16"),
            Scalar::Int => ("int", "int32"),
            Scalar::UInt => ("uint", "uint32"),
            Scalar::Float => ("float", "float32"),
            Scalar::Double => ("double", "float64"),
        };
        if alias {
            b
        } else {
            a
        }
    }

    /// What a reader of this type gets back for `v`.
    pub fn stored(self, v: f64) -> f64 {
        match self {
            Scalar::Char => v as i8 as f64,
            Scalar::UChar => v as u8 as f64,
            Scalar::Short => v as i16 as f64,
            Scalar::UShort => v as u16 as f64,
            Scalar::Int => v as i32 as f64,
            Scalar::UInt => v as u32 as f64,
            Scalar::Float => v as f32 as f64,
            Scalar::Double => v,
        }
    }

    fn text(self, v: f64) -> String {
        match self {
            Scalar::Float => format!("{:?}", v as f32),
            Scalar::Double => format!("{v:?}"),
            _ => format!("{}", self.stored(v)),
        }
    }

    fn int_text(self, v: i64) -> String {
        match self {
            Scalar::Char => (v as i8).to_string(),
            Scalar::UChar => (v as u8).to_string(),
            Scalar::Short => (v as i16).to_string(),
            Scalar::UShort => (v as u16).to_string(),
            Scalar::Int => (v as i32).to_string(),
            Scalar::UInt => (v as u32).to_string(),
            Scalar::Float => format!("{:?}", v as f32),
            Scalar::Double => format!("{:?}", v as f64),
        }
    }

    fn bytes(self, v: f64, big: bool, out: &mut Vec<u8>) {
        match self {
            Scalar::Char => put!(out, big, v as i8),
            Scalar::UChar => put!(out, big, v as u8),
            Scalar::Short => put!(out, big, v as i16),
            Scalar::UShort => put!(out, big, v as u16),
            Scalar::Int => put!(out, big, v as i32),
            Scalar::UInt => put!(out, big, v as u32),
            Scalar::Float => put!(out, big, v as f32),
            Scalar::Double => put!(out, big, v),
        }
    }

    fn int_bytes(self, v: i64, big: bool, out: &mut Vec<u8>) {
        match self {
            Scalar::Char => put!(out, big, v as i8),
            Scalar::UChar => put!(out, big, v as u8),
            Scalar::Short => put!(out, big, v as i16),
            Scalar::UShort => put!(out, big, v as u16),
            Scalar::Int => put!(out, big, v as i32),
            Scalar::UInt => put!(out, big, v as u32),
            Scalar::Float => put!(out, big, v as f32),
            Scalar::Double => put!(out, big, v as f64),
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PlyEncoding {
    Ascii,
    BinaryLe,
    BinaryBe,
}

/// How a PLY file is laid out.
#[derive(Debug, Clone, PartialEq)]
pub struct PlyOpts {
    pub encoding: PlyEncoding,
    /// Type of `x`, `y`, `z`.
    pub coord: Scalar,
    /// Type of the face list's count.
    pub count: Scalar,
    /// Type of the face list's indices.
    pub index: Scalar,
    /// `int32` for `int`, …
    pub aliases: bool,
    /// `vertex_index` for `vertex_indices`.
    pub vertex_index_name: bool,
    /// `property float nx` before `x` and `property uchar red` after `z`.
    pub extra_properties: bool,
    /// An element `material` (one `uchar`) between vertices and faces.
    pub extra_element: bool,
    pub comment: bool,
    pub crlf: bool,
    /// Added to the declared counts (the data is the spec's).
    pub vertex_delta: i64,
    pub face_delta: i64,
}

impl PlyOpts {
    /// Double coordinates, `uchar` counts, `int` indices, nothing else.
    pub fn plain(encoding: PlyEncoding) -> PlyOpts {
        PlyOpts {
            encoding,
            coord: Scalar::Double,
            count: Scalar::UChar,
            index: Scalar::Int,
            aliases: false,
            vertex_index_name: false,
            extra_properties: false,
            extra_element: false,
            comment: false,
            crlf: false,
            vertex_delta: 0,
            face_delta: 0,
        }
    }
}

/// A PLY file of `mesh` laid out by `o`.
pub fn ply_bytes(mesh: &MeshSpec, o: &PlyOpts) -> Vec<u8> {
    let nl = if o.crlf { "\r\n" } else { "\n" };
    let format = match o.encoding {
        PlyEncoding::Ascii => "ascii",
        PlyEncoding::BinaryLe => "binary_little_endian",
        PlyEncoding::BinaryBe => "binary_big_endian",
    };
    let mut h = format!("ply{nl}format {format} 1.0{nl}");
    if o.comment {
        h += &format!("comment made by the reader tests{nl}");
    }
    let nv = (mesh.positions.len() as i64).saturating_add(o.vertex_delta).max(0);
    let nf = (mesh.faces.len() as i64).saturating_add(o.face_delta).max(0);
    h += &format!("element vertex {nv}{nl}");
    if o.extra_properties {
        h += &format!("property float nx{nl}");
    }
    for a in ["x", "y", "z"] {
        h += &format!("property {} {a}{nl}", o.coord.name(o.aliases));
    }
    if o.extra_properties {
        h += &format!("property uchar red{nl}");
    }
    if o.extra_element {
        h += &format!("element material 1{nl}property uchar k{nl}");
    }
    let list = if o.vertex_index_name {
        "vertex_index"
    } else {
        "vertex_indices"
    };
    h += &format!(
        "element face {nf}{nl}property list {} {} {list}{nl}end_header{nl}",
        o.count.name(o.aliases),
        o.index.name(o.aliases)
    );
    let mut out = h.into_bytes();
    let big = o.encoding == PlyEncoding::BinaryBe;
    match o.encoding {
        PlyEncoding::Ascii => {
            let mut s = String::new();
            for p in &mesh.positions {
                let mut f: Vec<String> = p.iter().map(|&v| o.coord.text(v)).collect();
                if o.extra_properties {
                    f.insert(0, "0.5".into());
                    f.push("7".into());
                }
                s += &f.join(" ");
                s += nl;
            }
            if o.extra_element {
                s += &format!("3{nl}");
            }
            for face in &mesh.faces {
                s += &o.count.int_text(face.len() as i64);
                for &i in face {
                    s += " ";
                    s += &o.index.int_text(i);
                }
                s += nl;
            }
            out.extend_from_slice(s.as_bytes());
        }
        _ => {
            for p in &mesh.positions {
                if o.extra_properties {
                    Scalar::Float.bytes(0.5, big, &mut out);
                }
                for &v in p {
                    o.coord.bytes(v, big, &mut out);
                }
                if o.extra_properties {
                    out.push(7);
                }
            }
            if o.extra_element {
                out.push(3);
            }
            for face in &mesh.faces {
                o.count.int_bytes(face.len() as i64, big, &mut out);
                for &i in face {
                    o.index.int_bytes(i, big, &mut out);
                }
            }
        }
    }
    out
}
