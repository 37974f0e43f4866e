//! Valid-shaped inputs for every reader, written out as files, and the one way each is
//! fed to the library and its answer checked. Shared by the two tiers of issue item 1:
//! the fuzz targets (`fuzz/fuzz_targets/`, which fill these specs from `arbitrary`
//! structures) and the stable property tests (`tests/integration/properties.rs`, which
//! fill them from proptest strategies and include this file by `#[path]`).
//!
//! A spec is plain data (numbers may be anything, NaN included; indices and counts may
//! be out of range); the writers here serialise it by hand — a JSON number that is not
//! finite becomes a token no JSON parser takes (`NaN`, `1e999`), a PNG is written
//! chunk by chunk (stored deflate blocks), a glTF's accessors and views are laid out
//! from the spec's offsets and deltas — so that the file is the spec, mistakes
//! included. [`mutate`] then damages the bytes. The `drive_*` functions are the
//! entry points the CLI and the wasm binding use; on `Ok` the `check_*` functions
//! assert what every accepted input must give: finite numbers, indices in range,
//! rotations that are rotations. They panic otherwise: that is the failure.

#![allow(dead_code)]

use localisebot::io::bop::{BopOptions, BoxHints, MaskKind, Units};
use localisebot::io::fileset::{FileRole, FileSet};
use localisebot::io::nerf::Imported;
use localisebot::io::scene::{load_scene_with, Scene, SceneJson};
use localisebot::io::{self, gltf_write, join, parent_dir};
use localisebot::limits::{FOCAL_RANGE_PX, MAX_LENGTH};
use localisebot::{Camera, Limits, Mesh, Pose};
use std::collections::BTreeMap;

/// Files by path (as the resolver is asked for them).
pub type Files = BTreeMap<String, Vec<u8>>;

/// With `LOCALISEBOT_FUZZ_DUMP=DIR` in the environment, the drivers write the files
/// they are about to read into `DIR` (to see what an input was: `examples/replay.rs`).
pub fn dump(name: &str, bytes: &[u8]) {
    static DIR: std::sync::OnceLock<Option<std::path::PathBuf>> = std::sync::OnceLock::new();
    if let Some(dir) = DIR.get_or_init(|| std::env::var_os("LOCALISEBOT_FUZZ_DUMP").map(Into::into)) {
        let safe: String = name
            .chars()
            .map(|c| {
                if c.is_ascii_alphanumeric() || c == '.' || c == '_' || c == '-' {
                    c
                } else {
                    '+'
                }
            })
            .collect();
        let _ = std::fs::create_dir_all(dir);
        let _ = std::fs::write(dir.join(safe), bytes);
    }
}

fn dump_files(files: &Files) {
    for (k, v) in files {
        dump(k, v);
    }
}

/// A resolver over `files`.
pub fn resolver(files: &Files) -> impl Fn(&str) -> Option<Vec<u8>> + '_ {
    move |p: &str| files.get(p).cloned()
}

// ---------------------------------------------------------------------------------
// JSON text by hand

/// A JSON number token for `v`: the shortest exact decimal when finite; `NaN` and
/// `±1e999` (which no JSON parser accepts as a double) otherwise.
pub fn num(v: f64) -> String {
    if v.is_nan() {
        "NaN".into()
    } else if v == f64::INFINITY {
        "1e999".into()
    } else if v == f64::NEG_INFINITY {
        "-1e999".into()
    } else {
        format!("{v:?}")
    }
}

fn nums(v: &[f64]) -> String {
    let parts: Vec<String> = v.iter().map(|&x| num(x)).collect();
    format!("[{}]", parts.join(", "))
}

fn rows4(m: &[[f64; 4]; 4]) -> String {
    let r: Vec<String> = m.iter().map(|r| nums(r)).collect();
    format!("[{}]", r.join(", "))
}

fn rows3(m: &[[f64; 3]; 3]) -> String {
    let r: Vec<String> = m.iter().map(|r| nums(r)).collect();
    format!("[{}]", r.join(", "))
}

/// A JSON string literal.
pub fn jstr(s: &str) -> String {
    let mut o = String::with_capacity(s.len() + 2);
    o.push('"');
    for c in s.chars() {
        match c {
            '"' => o.push_str("\\\""),
            '\\' => o.push_str("\\\\"),
            c if (c as u32) < 0x20 => o.push_str(&format!("\\u{:04x}", c as u32)),
            c => o.push(c),
        }
    }
    o.push('"');
    o
}

/// The rotation of a quaternion `[w, x, y, z]` (normalised; the identity when it is
/// near zero or not finite), row-major.
pub fn quat_rows(q: [f64; 4]) -> [[f64; 3]; 3] {
    let n = q.iter().map(|v| v * v).sum::<f64>().sqrt();
    if !(n > 1e-6 && n.is_finite()) {
        return [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    }
    let [w, x, y, z] = q.map(|v| v / n);
    [
        [
            1.0 - 2.0 * (y * y + z * z),
            2.0 * (x * y - w * z),
            2.0 * (x * z + w * y),
        ],
        [
            2.0 * (x * y + w * z),
            1.0 - 2.0 * (x * x + z * z),
            2.0 * (y * z - w * x),
        ],
        [
            2.0 * (x * z - w * y),
            2.0 * (y * z + w * x),
            1.0 - 2.0 * (x * x + y * y),
        ],
    ]
}

/// A rigid 4×4, row-major, from a quaternion and a translation.
pub fn rigid(q: [f64; 4], t: [f64; 3]) -> [[f64; 4]; 4] {
    let r = quat_rows(q);
    [
        [r[0][0], r[0][1], r[0][2], t[0]],
        [r[1][0], r[1][1], r[1][2], t[1]],
        [r[2][0], r[2][1], r[2][2], t[2]],
        [0.0, 0.0, 0.0, 1.0],
    ]
}

/// The rotation of a quaternion as BOP's 9 row-major numbers.
pub fn rot9(q: [f64; 4]) -> [f64; 9] {
    let r = quat_rows(q);
    [
        r[0][0], r[0][1], r[0][2], r[1][0], r[1][1], r[1][2], r[2][0], r[2][1], r[2][2],
    ]
}

// ---------------------------------------------------------------------------------
// PNG by hand

fn crc32(bytes: &[u8]) -> u32 {
    let mut c = 0xFFFF_FFFFu32;
    for &b in bytes {
        c ^= b as u32;
        for _ in 0..8 {
            c = if c & 1 != 0 { 0xEDB8_8320 ^ (c >> 1) } else { c >> 1 };
        }
    }
    !c
}

fn adler32(bytes: &[u8]) -> u32 {
    let (mut a, mut b) = (1u32, 0u32);
    for &x in bytes {
        a = (a + x as u32) % 65521;
        b = (b + a) % 65521;
    }
    (b << 16) | a
}

/// zlib data of `raw` in stored (uncompressed) deflate blocks.
pub fn zlib_stored(raw: &[u8]) -> Vec<u8> {
    let mut out = vec![0x78, 0x01];
    let blocks: Vec<&[u8]> = if raw.is_empty() {
        vec![&[][..]]
    } else {
        raw.chunks(65535).collect()
    };
    for (i, b) in blocks.iter().enumerate() {
        out.push((i + 1 == blocks.len()) as u8);
        let len = b.len() as u16;
        out.extend_from_slice(&len.to_le_bytes());
        out.extend_from_slice(&(!len).to_le_bytes());
        out.extend_from_slice(b);
    }
    out.extend_from_slice(&adler32(raw).to_be_bytes());
    out
}

fn chunk(out: &mut Vec<u8>, kind: &[u8; 4], data: &[u8]) {
    out.extend_from_slice(&(data.len() as u32).to_be_bytes());
    let start = out.len();
    out.extend_from_slice(kind);
    out.extend_from_slice(data);
    let crc = crc32(&out[start..]);
    out.extend_from_slice(&crc.to_be_bytes());
}

/// A PNG file: IHDR of `width`×`height` (`color` type, bit `depth`), optional PLTE and
/// tRNS, one IDAT holding `raw` (filtered scanlines) in stored blocks, IEND.
pub fn png_file(
    width: u32,
    height: u32,
    color: u8,
    depth: u8,
    plte: Option<&[u8]>,
    trns: Option<&[u8]>,
    raw: &[u8],
) -> Vec<u8> {
    let mut out = b"\x89PNG\r\n\x1a\n".to_vec();
    let mut ihdr = Vec::new();
    ihdr.extend_from_slice(&width.to_be_bytes());
    ihdr.extend_from_slice(&height.to_be_bytes());
    ihdr.extend_from_slice(&[depth, color, 0, 0, 0]);
    chunk(&mut out, b"IHDR", &ihdr);
    if let Some(p) = plte {
        chunk(&mut out, b"PLTE", p);
    }
    if let Some(t) = trns {
        chunk(&mut out, b"tRNS", t);
    }
    chunk(&mut out, b"IDAT", &zlib_stored(raw));
    chunk(&mut out, b"IEND", &[]);
    out
}

/// The PNG pixel formats a mask may come in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PngKind {
    Gray1,
    Gray8,
    Gray16,
    GrayAlpha8,
    Rgb8,
    Rgba8,
    Rgba16,
    Palette1,
    Palette8,
}

pub const PNG_KINDS: [PngKind; 9] = [
    PngKind::Gray1,
    PngKind::Gray8,
    PngKind::Gray16,
    PngKind::GrayAlpha8,
    PngKind::Rgb8,
    PngKind::Rgba8,
    PngKind::Rgba16,
    PngKind::Palette1,
    PngKind::Palette8,
];

impl PngKind {
    /// (colour type, bit depth).
    pub fn header(self) -> (u8, u8) {
        match self {
            PngKind::Gray1 => (0, 1),
            PngKind::Gray8 => (0, 8),
            PngKind::Gray16 => (0, 16),
            PngKind::GrayAlpha8 => (4, 8),
            PngKind::Rgb8 => (2, 8),
            PngKind::Rgba8 => (6, 8),
            PngKind::Rgba16 => (6, 16),
            PngKind::Palette1 => (3, 1),
            PngKind::Palette8 => (3, 8),
        }
    }
}

/// A mask: a PNG of `kind`, `width`×`height`, whose reading by the SPEC rule is `bits`
/// (row-major, non-zero = object; repeated cyclically when short, all background
/// when empty).
#[derive(Debug, Clone, PartialEq)]
pub struct MaskSpec {
    pub kind: PngKind,
    pub width: u32,
    pub height: u32,
    pub bits: Vec<u8>,
}

impl MaskSpec {
    /// The 0/1 pixels the mask should read as.
    pub fn pixels(&self) -> Vec<u8> {
        let n = self.width as usize * self.height as usize;
        (0..n)
            .map(|i| {
                if self.bits.is_empty() {
                    0
                } else {
                    (self.bits[i % self.bits.len()] != 0) as u8
                }
            })
            .collect()
    }

    pub fn png(&self) -> Vec<u8> {
        let (w, h) = (self.width, self.height);
        let px = self.pixels();
        let (color, depth) = self.kind.header();
        let mut raw = Vec::new();
        for y in 0..h as usize {
            raw.push(0);
            let row = &px[y * w as usize..(y + 1) * w as usize];
            match self.kind {
                PngKind::Gray1 | PngKind::Palette1 => {
                    for byte in row.chunks(8) {
                        let mut b = 0u8;
                        for (k, &v) in byte.iter().enumerate() {
                            b |= v << (7 - k);
                        }
                        raw.push(b);
                    }
                }
                PngKind::Palette8 => raw.extend_from_slice(row),
                PngKind::Gray8 => raw.extend(row.iter().map(|&v| v * 255)),
                PngKind::Gray16 => raw.extend(row.iter().flat_map(|&v| [v * 255; 2])),
                PngKind::GrayAlpha8 => raw.extend(row.iter().flat_map(|&v| [v * 255; 2])),
                PngKind::Rgb8 => raw.extend(row.iter().flat_map(|&v| [v * 255; 3])),
                PngKind::Rgba8 => raw.extend(row.iter().flat_map(|&v| [v * 255; 4])),
                PngKind::Rgba16 => raw.extend(row.iter().flat_map(|&v| [v * 255; 8])),
            }
        }
        let plte =
            matches!(self.kind, PngKind::Palette1 | PngKind::Palette8).then_some(&[0u8, 0, 0, 255, 255, 255][..]);
        png_file(w, h, color, depth, plte, None, &raw)
    }
}

/// A photograph: `rgb` repeated cyclically over the pixels (grey 128 when empty);
/// RGBA8 with alpha from `alpha` (0/1 bits, as [`MaskSpec::bits`]) when given, else
/// RGB8.
#[derive(Debug, Clone, PartialEq)]
pub struct ImageSpec {
    pub width: u32,
    pub height: u32,
    pub rgb: Vec<u8>,
    pub alpha: Option<Vec<u8>>,
}

impl ImageSpec {
    pub fn png(&self) -> Vec<u8> {
        let (w, h) = (self.width as usize, self.height as usize);
        let c = |i: usize| {
            if self.rgb.is_empty() {
                128
            } else {
                self.rgb[i % self.rgb.len()]
            }
        };
        let a = |i: usize| match &self.alpha {
            Some(b) if !b.is_empty() => (b[i % b.len()] != 0) as u8 * 255,
            _ => 0,
        };
        let mut raw = Vec::new();
        for y in 0..h {
            raw.push(0);
            for x in 0..w {
                let i = y * w + x;
                raw.extend_from_slice(&[c(3 * i), c(3 * i + 1), c(3 * i + 2)]);
                if self.alpha.is_some() {
                    raw.push(a(i));
                }
            }
        }
        let color = if self.alpha.is_some() { 6 } else { 2 };
        png_file(self.width, self.height, color, 8, None, None, &raw)
    }
}

// ---------------------------------------------------------------------------------
// Byte damage

/// One change to a file's bytes; positions are taken modulo the length.
#[derive(Debug, Clone, PartialEq)]
pub enum Mutation {
    Flip { at: usize, bit: u8 },
    Truncate { at: usize },
    Insert { at: usize, bytes: Vec<u8> },
    Overwrite { at: usize, bytes: Vec<u8> },
    Repeat { from: usize, len: usize, to: usize },
}

/// Byte strings worth inserting: numbers at the edges, JSON and PLY punctuation.
pub const TOKENS: &[&[u8]] = &[
    b"9999999999",
    b"-1",
    b"1e309",
    b"-0",
    b"NaN",
    b"0",
    b"[",
    b"]",
    b"{",
    b"}",
    b"\"",
    b",",
    b"\n",
    b"end_header\n",
    b"\xff\xff\xff\x7f",
    b"4294967295",
    b"1e-320",
    b"1e300",
    b"null",
    b"\x0b",
    b"\x0c",
    "\u{a0}".as_bytes(),
];

/// Applies `ms` in turn (a file never grows past 1 MiB by them).
pub fn mutate(bytes: &mut Vec<u8>, ms: &[Mutation]) {
    for m in ms {
        let n = bytes.len();
        match m {
            Mutation::Flip { at, bit } => {
                if n > 0 {
                    bytes[at % n] ^= 1 << (bit % 8);
                }
            }
            Mutation::Truncate { at } => bytes.truncate(at % (n + 1)),
            Mutation::Insert { at, bytes: b } => {
                if n + b.len() <= 1 << 20 {
                    let i = at % (n + 1);
                    bytes.splice(i..i, b.iter().copied());
                }
            }
            Mutation::Overwrite { at, bytes: b } => {
                if n > 0 {
                    let i = at % n;
                    for (k, &v) in b.iter().enumerate().take(n - i) {
                        bytes[i + k] = v;
                    }
                }
            }
            Mutation::Repeat { from, len, to } => {
                if n > 0 && n <= 1 << 19 {
                    let f = from % n;
                    let l = (len % 256).min(n - f);
                    let piece = bytes[f..f + l].to_vec();
                    let t = to % (n + 1);
                    bytes.splice(t..t, piece);
                }
            }
        }
    }
}

/// Mutates the `target`-th file of `files` (modulo their number).
pub fn mutate_files(files: &mut Files, target: usize, ms: &[Mutation]) {
    if ms.is_empty() || files.is_empty() {
        return;
    }
    let key = files.keys().nth(target % files.len()).cloned().expect("in range");
    mutate(files.get_mut(&key).expect("present"), ms);
}

/// Text from damaged bytes (invalid UTF-8 replaced).
pub fn text_of(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

// ---------------------------------------------------------------------------------
// Meshes

/// Positions and polygons (indices 0-based, unchecked: a face may refer past the
/// vertices, or have fewer than three corners).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct MeshSpec {
    pub positions: Vec<[f64; 3]>,
    pub faces: Vec<Vec<i64>>,
}

impl MeshSpec {
    /// A triangle of unit legs at the origin, then `positions` and `faces` (whose
    /// indices count the triangle's three vertices first): with valid extra data, a
    /// mesh every reader accepts.
    pub fn with_base(positions: &[[f64; 3]], faces: &[Vec<i64>]) -> MeshSpec {
        let mut p = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        p.extend_from_slice(positions);
        let mut f = vec![vec![0, 1, 2]];
        f.extend_from_slice(faces);
        MeshSpec { positions: p, faces: f }
    }

    /// The polygons as fans, indices as written.
    pub fn fan_triangles(&self) -> Vec<[i64; 3]> {
        let mut out = Vec::new();
        for f in &self.faces {
            for k in 2..f.len() {
                out.push([f[0], f[k - 1], f[k]]);
            }
        }
        out
    }

    /// The mesh a reader should make (None when an index is out of range).
    pub fn mesh(&self) -> Option<Mesh> {
        let n = self.positions.len() as i64;
        let tris = self.fan_triangles();
        if tris.iter().flatten().any(|&i| i < 0 || i >= n) {
            return None;
        }
        Some(Mesh {
            positions: self.positions.iter().map(|p| glam::DVec3::from_array(*p)).collect(),
            triangles: tris.iter().map(|t| t.map(|i| i as u32)).collect(),
        })
    }
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
        macro_rules! put {
            ($x:expr) => {
                if big {
                    out.extend_from_slice(&$x.to_be_bytes())
                } else {
                    out.extend_from_slice(&$x.to_le_bytes())
                }
            };
        }
        match self {
            Scalar::Char => put!(v as i8),
            Scalar::UChar => put!(v as u8),
            Scalar::Short => put!(v as i16),
            Scalar::UShort => put!(v as u16),
            Scalar::Int => put!(v as i32),
            Scalar::UInt => put!(v as u32),
            Scalar::Float => put!(v as f32),
            Scalar::Double => put!(v),
        }
    }

    fn int_bytes(self, v: i64, big: bool, out: &mut Vec<u8>) {
        macro_rules! put {
            ($x:expr) => {
                if big {
                    out.extend_from_slice(&$x.to_be_bytes())
                } else {
                    out.extend_from_slice(&$x.to_le_bytes())
                }
            };
        }
        match self {
            Scalar::Char => put!(v as i8),
            Scalar::UChar => put!(v as u8),
            Scalar::Short => put!(v as i16),
            Scalar::UShort => put!(v as u16),
            Scalar::Int => put!(v as i32),
            Scalar::UInt => put!(v as u32),
            Scalar::Float => put!(v as f32),
            Scalar::Double => put!(v as f64),
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

/// How an OBJ file is written.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ObjOpts {
    /// Faces by negative (relative) indices.
    pub negative: bool,
    /// A `vt` line, and faces as `v/vt`.
    pub texcoords: bool,
    /// The faces split between two `o` objects.
    pub objects: bool,
    pub comments: bool,
    pub crlf: bool,
    pub tabs: bool,
    /// Whitespace that is not ASCII space or tab where a line starts and between its
    /// words: 1, a form feed; 2, a vertical tab before the keyword; 3, a no-break space
    /// (0: none). A reader that splits words on Unicode whitespace reads these lines.
    pub odd_space: u8,
}

/// An OBJ file of `mesh`.
pub fn obj_bytes(mesh: &MeshSpec, o: &ObjOpts) -> Vec<u8> {
    let nl = if o.crlf { "\r\n" } else { "\n" };
    let (lead, sp) = match o.odd_space % 4 {
        1 => ("", "\u{c}"),
        2 => ("\u{b}", if o.tabs { "\t" } else { " " }),
        3 => ("", "\u{a0}"),
        _ => ("", if o.tabs { "\t" } else { " " }),
    };
    let mut s = String::new();
    if o.comments {
        s += &format!("# made by the reader tests{nl}mtllib none.mtl{nl}");
    }
    for p in &mesh.positions {
        s += &format!("{lead}v{sp}{:?}{sp}{:?}{sp}{:?}{nl}", p[0], p[1], p[2]);
    }
    if o.texcoords {
        s += &format!("vt 0.5 0.5{nl}");
    }
    let n = mesh.positions.len() as i64;
    let half = mesh.faces.len() / 2;
    for (k, face) in mesh.faces.iter().enumerate() {
        if o.objects && (k == 0 || k == half) {
            s += &format!("o part{k}{nl}");
        }
        s += lead;
        s += "f";
        for &i in face {
            let ix = if o.negative {
                i.saturating_sub(n)
            } else {
                i.saturating_add(1)
            };
            s += sp;
            s += &ix.to_string();
            if o.texcoords {
                s += "/1";
            }
        }
        s += nl;
    }
    s.into_bytes()
}

/// Where a glTF's buffer is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Container {
    /// A `.glb`, the buffer in its BIN chunk.
    Glb,
    /// A `.gltf` with the buffer as a base64 data URI.
    DataUri,
    /// A `.gltf` naming an external `.bin`.
    External,
}

/// The mesh node's transform.
#[derive(Debug, Clone, PartialEq)]
pub enum NodeTransform {
    None,
    Matrix([f64; 16]),
    Trs {
        t: Option<[f64; 3]>,
        r: Option<[f64; 4]>,
        s: Option<[f64; 3]>,
    },
}

/// Something more in a glTF document, to exercise its validation and traversal.
#[derive(Debug, Clone, PartialEq)]
pub enum GltfExtra {
    Animation {
        sampler: i64,
        node: i64,
        input: i64,
        output: i64,
    },
    Skin {
        joints: Vec<i64>,
        matrices: Option<i64>,
    },
    Camera,
    Material {
        texture: Option<(i64, i64)>,
    },
    Required(String),
    /// A sparse part on the POSITION accessor.
    Sparse {
        count: i64,
        indices_view: i64,
        values_view: i64,
        index_type: i64,
    },
    /// A second primitive.
    Primitive {
        mode: i64,
        position: i64,
        indices: Option<i64>,
    },
    /// The last node's child: the root (a cycle).
    Cycle,
    /// A second scene.
    Scene {
        nodes: Vec<i64>,
    },
    /// A second instance of the mesh, under the root.
    Instance,
}

/// How a glTF document lays out its mesh: valid with the defaults of [`GltfOpts::plain`].
#[derive(Debug, Clone, PartialEq)]
pub struct GltfOpts {
    pub container: Container,
    /// The primitive's `mode` (absent: triangles).
    pub mode: Option<i64>,
    /// The indices' component type (5121, 5123, 5125), or no indices (the positions
    /// written out per triangle corner).
    pub index_type: Option<i64>,
    /// The positions' `byteStride`.
    pub stride: Option<i64>,
    /// The POSITION accessor's `byteOffset` (the data written after as many bytes).
    pub offset: i64,
    pub count_delta: i64,
    pub index_count_delta: i64,
    pub view_len_delta: i64,
    pub buffer_len_delta: i64,
    /// The POSITION accessor's `componentType` and `type`.
    pub position_type: Option<(i64, String)>,
    pub transform: NodeTransform,
    /// Nodes above the mesh's.
    pub depth: u8,
    /// The `scene` index (absent: none given).
    pub scene: Option<i64>,
    pub extras: Vec<GltfExtra>,
}

impl GltfOpts {
    pub fn plain(container: Container) -> GltfOpts {
        GltfOpts {
            container,
            mode: None,
            index_type: Some(5125),
            stride: None,
            offset: 0,
            count_delta: 0,
            index_count_delta: 0,
            view_len_delta: 0,
            buffer_len_delta: 0,
            position_type: None,
            transform: NodeTransform::None,
            depth: 0,
            scene: Some(0),
            extras: Vec::new(),
        }
    }
}

const B64: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";

pub fn base64(bytes: &[u8]) -> String {
    let mut s = String::new();
    for c in bytes.chunks(3) {
        let n = (c[0] as u32) << 16 | (*c.get(1).unwrap_or(&0) as u32) << 8 | *c.get(2).unwrap_or(&0) as u32;
        for k in 0..4 {
            if k <= c.len() {
                s.push(B64[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                s.push('=');
            }
        }
    }
    s
}

/// A GLB container of `json` and `bin`.
pub fn glb_container(json: &[u8], bin: Option<&[u8]>) -> Vec<u8> {
    let mut j = json.to_vec();
    while !j.len().is_multiple_of(4) {
        j.push(b' ');
    }
    let mut body = Vec::new();
    body.extend_from_slice(&(j.len() as u32).to_le_bytes());
    body.extend_from_slice(b"JSON");
    body.extend_from_slice(&j);
    if let Some(b) = bin {
        let mut b = b.to_vec();
        while !b.len().is_multiple_of(4) {
            b.push(0);
        }
        body.extend_from_slice(&(b.len() as u32).to_le_bytes());
        body.extend_from_slice(b"BIN\0");
        body.extend_from_slice(&b);
    }
    let mut out = b"glTF".to_vec();
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&((body.len() + 12) as u32).to_le_bytes());
    out.extend_from_slice(&body);
    out
}

/// The glTF files of `mesh` laid out by `o`: (the mesh file's name, files by name
/// relative to it). `stem` names them.
pub fn gltf_files(mesh: &MeshSpec, o: &GltfOpts, stem: &str) -> (String, Files) {
    let tris = mesh.fan_triangles();
    let at = |i: i64| mesh.positions.get(i as usize).copied().unwrap_or([0.0; 3]);
    // Vertices and the index list (or none).
    let (verts, indices): (Vec<[f64; 3]>, Option<Vec<i64>>) = match o.index_type {
        Some(_) => (mesh.positions.clone(), Some(tris.iter().flatten().copied().collect())),
        None => (tris.iter().flatten().map(|&i| at(i)).collect(), None),
    };
    let write_stride = o.stride.unwrap_or(12).clamp(12, 256) as usize;
    let pad = o.offset.clamp(0, 64) as usize;
    let mut bin = vec![0u8; pad];
    for v in &verts {
        let start = bin.len();
        for c in v {
            bin.extend_from_slice(&(*c as f32).to_le_bytes());
        }
        bin.resize(start + write_stride, 0);
    }
    let pos_len = bin.len();
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let ix_offset = bin.len();
    if let Some(ix) = &indices {
        for &i in ix {
            match o.index_type {
                Some(5121) => bin.push(i as u8),
                Some(5123) => bin.extend_from_slice(&(i as u16).to_le_bytes()),
                _ => bin.extend_from_slice(&(i as u32).to_le_bytes()),
            }
        }
    }
    let ix_len = bin.len() - ix_offset;
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let bin_name = format!("{stem}.bin");
    let mut buffer = format!(
        "{{\"byteLength\": {}",
        (bin.len() as i64).saturating_add(o.buffer_len_delta)
    );
    match o.container {
        Container::Glb => {}
        Container::DataUri => {
            buffer += &format!(", \"uri\": \"data:application/octet-stream;base64,{}\"", base64(&bin))
        }
        Container::External => buffer += &format!(", \"uri\": {}", jstr(&bin_name)),
    }
    buffer += "}";
    let mut buffers = vec![buffer];
    let mut views = vec![format!(
        "{{\"buffer\": 0, \"byteOffset\": 0, \"byteLength\": {}{}}}",
        (pos_len as i64).saturating_add(o.view_len_delta),
        o.stride.map_or(String::new(), |s| format!(", \"byteStride\": {s}"))
    )];
    let (ct, ty) = o.position_type.clone().unwrap_or((5126, "VEC3".into()));
    let mut pos_acc = format!(
        "{{\"bufferView\": 0, \"byteOffset\": {}, \"componentType\": {ct}, \"count\": {}, \"type\": {}",
        o.offset,
        (verts.len() as i64).saturating_add(o.count_delta),
        jstr(&ty)
    );
    let mut accessors = Vec::new();
    let mut prim = "{\"attributes\": {\"POSITION\": 0}".to_string();
    if let (Some(t), Some(ix)) = (o.index_type, &indices) {
        views.push(format!(
            "{{\"buffer\": 0, \"byteOffset\": {ix_offset}, \"byteLength\": {}}}",
            ix_len.max(1)
        ));
        prim += ", \"indices\": 1";
        accessors.push(format!(
            "{{\"bufferView\": 1, \"componentType\": {t}, \"count\": {}, \"type\": \"SCALAR\"}}",
            (ix.len() as i64).saturating_add(o.index_count_delta)
        ));
    }
    if let Some(m) = o.mode {
        prim += &format!(", \"mode\": {m}");
    }
    let mut extra_prims = Vec::new();
    let mut top: Vec<String> = Vec::new();
    let mut nodes_extra_root_children: Vec<usize> = Vec::new();
    let depth = o.depth.min(8) as usize;
    let mut n_nodes = depth + 1;
    let mut cycle = false;
    let mut scenes = vec![];
    let (mut anims, mut skins, mut cams, mut mats, mut req) = (vec![], vec![], vec![], vec![], vec![]);
    let mut texture_parts: Vec<String> = vec![];
    for e in &o.extras {
        match e {
            GltfExtra::Animation { sampler, node, input, output } => anims.push(format!(
                "{{\"channels\": [{{\"sampler\": {sampler}, \"target\": {{\"node\": {node}, \"path\": \"translation\"}}}}], \
                 \"samplers\": [{{\"input\": {input}, \"output\": {output}}}]}}"
            )),
            GltfExtra::Skin { joints, matrices } => {
                let j: Vec<String> = joints.iter().map(|j| j.to_string()).collect();
                skins.push(format!(
                    "{{\"joints\": [{}]{}}}",
                    j.join(", "),
                    matrices.map_or(String::new(), |m| format!(", \"inverseBindMatrices\": {m}"))
                ))
            }
            GltfExtra::Camera => cams.push("{\"type\": \"perspective\", \"perspective\": {\"yfov\": 1.0, \"znear\": 0.1}}".to_string()),
            GltfExtra::Material { texture } => {
                match texture {
                    Some((source, sampler)) => {
                        mats.push(format!("{{\"pbrMetallicRoughness\": {{\"baseColorTexture\": {{\"index\": {}}}}}}}", texture_parts.len()));
                        texture_parts.push(format!("{{\"source\": {source}, \"sampler\": {sampler}}}"));
                    }
                    None => mats.push("{}".into()),
                }
                if mats.len() == 1 {
                    prim += ", \"material\": 0";
                }
            }
            GltfExtra::Required(name) => req.push(jstr(name)),
            GltfExtra::Sparse { count, indices_view, values_view, index_type } => {
                pos_acc += &format!(
                    ", \"sparse\": {{\"count\": {count}, \"indices\": {{\"bufferView\": {indices_view}, \"componentType\": {index_type}}}, \
                     \"values\": {{\"bufferView\": {values_view}}}}}"
                );
            }
            GltfExtra::Primitive { mode, position, indices } => extra_prims.push(format!(
                "{{\"attributes\": {{\"POSITION\": {position}}}, \"mode\": {mode}{}}}",
                indices.map_or(String::new(), |i| format!(", \"indices\": {i}"))
            )),
            GltfExtra::Cycle => cycle = true,
            GltfExtra::Scene { nodes } => {
                let n: Vec<String> = nodes.iter().map(|n| n.to_string()).collect();
                scenes.push(format!("{{\"nodes\": [{}]}}", n.join(", ")));
            }
            GltfExtra::Instance => {
                nodes_extra_root_children.push(n_nodes);
                n_nodes += 1;
            }
        }
    }
    pos_acc += "}";
    accessors.insert(0, pos_acc);
    prim += "}";
    let mut prims = vec![prim];
    prims.extend(extra_prims);
    // Nodes: 0 (root, the transform) → … → depth (the mesh); extra instances under 0.
    let transform = match &o.transform {
        NodeTransform::None => String::new(),
        NodeTransform::Matrix(m) => format!(", \"matrix\": {}", nums(m)),
        NodeTransform::Trs { t, r, s } => {
            let mut x = String::new();
            if let Some(t) = t {
                x += &format!(", \"translation\": {}", nums(t));
            }
            if let Some(r) = r {
                x += &format!(", \"rotation\": {}", nums(r));
            }
            if let Some(s) = s {
                x += &format!(", \"scale\": {}", nums(s));
            }
            x
        }
    };
    let mut nodes = Vec::new();
    for k in 0..=depth {
        let mut children: Vec<usize> = Vec::new();
        if k < depth {
            children.push(k + 1);
        }
        if k == 0 {
            children.extend(&nodes_extra_root_children);
        }
        if k == depth && cycle {
            children.push(0);
        }
        let mut node = "{".to_string();
        let mut parts = Vec::new();
        if k == depth {
            parts.push("\"mesh\": 0".to_string());
        }
        if !children.is_empty() {
            let c: Vec<String> = children.iter().map(|c| c.to_string()).collect();
            parts.push(format!("\"children\": [{}]", c.join(", ")));
        }
        node += &parts.join(", ");
        if k == 0 {
            node += if parts.is_empty() {
                transform.trim_start_matches(", ")
            } else {
                &transform
            };
        }
        node += "}";
        nodes.push(node);
    }
    for _ in &nodes_extra_root_children {
        nodes.push("{\"mesh\": 0}".into());
    }
    scenes.insert(0, "{\"nodes\": [0]}".into());
    top.push("\"asset\": {\"version\": \"2.0\", \"generator\": \"reader tests\"}".into());
    if let Some(s) = o.scene {
        top.push(format!("\"scene\": {s}"));
    }
    top.push(format!("\"scenes\": [{}]", scenes.join(", ")));
    top.push(format!("\"nodes\": [{}]", nodes.join(", ")));
    top.push(format!("\"meshes\": [{{\"primitives\": [{}]}}]", prims.join(", ")));
    top.push(format!("\"accessors\": [{}]", accessors.join(", ")));
    top.push(format!("\"bufferViews\": [{}]", views.join(", ")));
    buffers.truncate(1);
    top.push(format!("\"buffers\": [{}]", buffers.join(", ")));
    for (key, list) in [
        ("animations", &anims),
        ("skins", &skins),
        ("cameras", &cams),
        ("materials", &mats),
        ("textures", &texture_parts),
    ] {
        if !list.is_empty() {
            top.push(format!("\"{key}\": [{}]", list.join(", ")));
        }
    }
    if !req.is_empty() {
        top.push(format!(
            "\"extensionsUsed\": [{0}], \"extensionsRequired\": [{0}]",
            req.join(", ")
        ));
    }
    let json = format!("{{{}}}", top.join(",\n"));
    let mut files = Files::new();
    let name = match o.container {
        Container::Glb => {
            files.insert(format!("{stem}.glb"), glb_container(json.as_bytes(), Some(&bin)));
            format!("{stem}.glb")
        }
        Container::DataUri => {
            files.insert(format!("{stem}.gltf"), json.into_bytes());
            format!("{stem}.gltf")
        }
        Container::External => {
            files.insert(format!("{stem}.gltf"), json.into_bytes());
            files.insert(bin_name, bin);
            format!("{stem}.gltf")
        }
    };
    (name, files)
}

/// A mesh file format, with its layout.
#[derive(Debug, Clone, PartialEq)]
#[allow(clippy::large_enum_variant)] // test data, made a few at a time
pub enum MeshFormat {
    Ply(PlyOpts),
    Obj(ObjOpts),
    Gltf(GltfOpts),
    /// `io::ply::write_ascii`.
    PlyWriter,
    /// `io::gltf_write::glb`.
    GlbWriter,
    /// `io::gltf_write::gltf_and_bin`.
    GltfWriter,
}

/// The files of `mesh` in `format`: (the mesh file's name, files by name relative to
/// its folder), or None when the project's writer refuses the mesh.
pub fn mesh_files(mesh: &MeshSpec, format: &MeshFormat, stem: &str) -> Option<(String, Files)> {
    let one = |name: String, bytes: Vec<u8>| Some((name.clone(), Files::from([(name, bytes)])));
    match format {
        MeshFormat::Ply(o) => one(format!("{stem}.ply"), ply_bytes(mesh, o)),
        MeshFormat::Obj(o) => one(format!("{stem}.obj"), obj_bytes(mesh, o)),
        MeshFormat::Gltf(o) => Some(gltf_files(mesh, o, stem)),
        MeshFormat::PlyWriter => one(
            format!("{stem}.ply"),
            io::ply::write_ascii(&mesh.mesh()?, "reader tests"),
        ),
        MeshFormat::GlbWriter => one(format!("{stem}.glb"), gltf_write::glb(&mesh.mesh()?, "m").ok()?),
        MeshFormat::GltfWriter => {
            let bin = format!("{stem}.bin");
            let (text, data) = gltf_write::gltf_and_bin(&mesh.mesh()?, "m", &bin).ok()?;
            let name = format!("{stem}.gltf");
            Some((name.clone(), Files::from([(name, text.into_bytes()), (bin, data)])))
        }
    }
}

/// Loads mesh file `name` of `files` (others resolved relative to it) as the CLI and
/// the binding do; checks an accepted mesh.
pub fn drive_mesh(name: &str, files: &Files, limits: &Limits) -> localisebot::Result<Mesh> {
    dump_files(files);
    let bytes = files.get(name).cloned().unwrap_or_default();
    let dir = parent_dir(name).to_string();
    let r = io::load_mesh_with(name, &bytes, &|uri| files.get(&join(&dir, uri)).cloned(), limits);
    if let Ok(m) = &r {
        check_mesh(m);
        check_mesh_limits(name, m, limits);
    }
    r
}

/// An accepted mesh is within the limits: its triangles (polygons as fans), and its
/// vertices — but an OBJ's `o` objects each keep their own copy of the vertices they
/// use, so an OBJ's are checked as declared (`v` lines), not here.
pub fn check_mesh_limits(name: &str, m: &Mesh, limits: &Limits) {
    assert!(
        m.triangles.len() as u64 <= limits.triangles,
        "{name}: accepted with {} triangles, over the limit of {}",
        m.triangles.len(),
        limits.triangles
    );
    if !name.to_ascii_lowercase().ends_with(".obj") {
        assert!(
            m.positions.len() as u64 <= limits.vertices,
            "{name}: accepted with {} vertices, over the limit of {}",
            m.positions.len(),
            limits.vertices
        );
    }
}

/// An accepted scene is within the limits: its views, their pixels, its mesh's triangles.
pub fn check_scene_limits(s: &Scene, limits: &Limits) {
    let cameras: Vec<&Camera> = s
        .views
        .iter()
        .map(|v| v.camera())
        .chain(s.photos.iter().map(|p| &p.camera))
        .collect();
    assert!(
        cameras.len() as u64 <= limits.views,
        "{} views, over the limit of {}",
        cameras.len(),
        limits.views
    );
    let px: Vec<u64> = cameras.iter().map(|c| c.width as u64 * c.height as u64).collect();
    assert!(
        px.iter().all(|&p| p <= limits.view_pixels),
        "a view over the limit of {} pixels",
        limits.view_pixels
    );
    assert!(
        px.iter().sum::<u64>() <= limits.total_pixels,
        "views over the limit of {} pixels in all",
        limits.total_pixels
    );
    assert!(
        s.mesh.triangles.len() as u64 <= limits.triangles,
        "a mesh of {} triangles, over the limit of {}",
        s.mesh.triangles.len(),
        limits.triangles
    );
}

// ---------------------------------------------------------------------------------
// Cameras, poses, grasps

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CamKey {
    W2c,
    C2w,
    Both,
    Neither,
}

/// A camera as `scene.json` writes it; `width`, `height` may be out of any range.
#[derive(Debug, Clone, PartialEq)]
pub struct CamSpec {
    pub width: i64,
    pub height: i64,
    pub fx: f64,
    pub fy: f64,
    pub cx: f64,
    pub cy: f64,
    pub matrix: [[f64; 4]; 4],
    pub key: CamKey,
    pub opengl: bool,
}

pub fn camera_json(c: &CamSpec) -> String {
    let mut s = format!(
        "{{\"width\": {}, \"height\": {}, \"fx\": {}, \"fy\": {}, \"cx\": {}, \"cy\": {}",
        c.width,
        c.height,
        num(c.fx),
        num(c.fy),
        num(c.cx),
        num(c.cy)
    );
    let m = rows4(&c.matrix);
    match c.key {
        CamKey::W2c => s += &format!(", \"world_to_camera\": {m}"),
        CamKey::C2w => s += &format!(", \"camera_to_world\": {m}"),
        CamKey::Both => s += &format!(", \"world_to_camera\": {m}, \"camera_to_world\": {m}"),
        CamKey::Neither => {}
    }
    if c.opengl {
        s += ", \"convention\": \"opengl\"";
    }
    s + "}"
}

/// Parses a camera as the readers do and converts it; checks an accepted camera.
pub fn drive_camera(text: &str) -> localisebot::Result<Camera> {
    dump("camera.json", text.as_bytes());
    let cj: localisebot::CameraJson = serde_json::from_str(text).map_err(|e| localisebot::Error::Json {
        file: "camera.json".into(),
        problem: e.to_string(),
    })?;
    let r = cj.to_camera_with_warning("v").map(|(c, _)| c);
    if let Ok(c) = &r {
        check_camera(c);
    }
    r
}

#[derive(Debug, Clone, PartialEq)]
pub enum RotSpec {
    Matrix([[f64; 3]; 3]),
    Quaternion([f64; 4]),
    /// Under the `quaternion` key.
    QuaternionKey([f64; 4]),
}

#[derive(Debug, Clone, PartialEq)]
pub struct PoseSpec {
    pub rotation: RotSpec,
    pub translation: [f64; 3],
    pub scale: Option<[f64; 3]>,
}

pub fn pose_json(p: &PoseSpec) -> String {
    let mut s = match &p.rotation {
        RotSpec::Matrix(m) => format!("{{\"rotation\": {}", rows3(m)),
        RotSpec::Quaternion(q) => format!("{{\"rotation\": {}", nums(q)),
        RotSpec::QuaternionKey(q) => format!("{{\"quaternion\": {}", nums(q)),
    };
    s += &format!(", \"translation\": {}", nums(&p.translation));
    if let Some(sc) = p.scale {
        s += &format!(", \"scale\": {}", nums(&sc));
    }
    s + "}"
}

#[derive(Debug, Clone, PartialEq)]
pub struct GraspSpec {
    pub centre: [f64; 3],
    pub approach: [f64; 3],
    pub closing: [f64; 3],
    pub width: f64,
    pub depth: f64,
    pub score: Option<f64>,
}

pub fn grasp_json(g: &GraspSpec) -> String {
    let mut s = format!(
        "{{\"centre\": {}, \"approach\": {}, \"closing\": {}, \"width\": {}, \"depth\": {}",
        nums(&g.centre),
        nums(&g.approach),
        nums(&g.closing),
        num(g.width),
        num(g.depth)
    );
    if let Some(v) = g.score {
        s += &format!(", \"score\": {}", num(v));
    }
    s + "}"
}

// ---------------------------------------------------------------------------------
// Scenes

#[derive(Debug, Clone, PartialEq)]
pub struct ViewSpec {
    pub name: String,
    pub camera: CamSpec,
    pub mask: Option<MaskSpec>,
    pub image: Option<ImageSpec>,
    pub ignore: Option<MaskSpec>,
    pub hint: Option<[f64; 4]>,
}

#[derive(Debug, Clone, PartialEq)]
pub struct SceneSpec {
    /// The scene file's folder ("" or ending in `/`).
    pub dir: String,
    /// The mesh's folder relative to the scene ("" or ending in `/`).
    pub mesh_dir: String,
    pub version: Option<i64>,
    pub views: Vec<ViewSpec>,
    pub mesh: MeshSpec,
    pub format: MeshFormat,
    pub initial_pose: Option<PoseSpec>,
    pub ground_truth: Option<PoseSpec>,
    pub grasps: Vec<GraspSpec>,
}

/// A scene file, and the files it names, by path.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneFiles {
    pub scene_file: String,
    pub text: String,
    pub files: Files,
}

/// The view's JSON entry and its files (relative to the scene's folder).
fn view_entry(i: usize, v: &ViewSpec, files: &mut Vec<(String, Vec<u8>)>) -> String {
    let mut s = format!("{{\"name\": {}", jstr(&v.name));
    if let Some(m) = &v.mask {
        let rel = format!("masks/m{i}.png");
        s += &format!(", \"mask\": {}", jstr(&rel));
        files.push((rel, m.png()));
    }
    if let Some(im) = &v.image {
        let rel = format!("images/i{i}.png");
        s += &format!(", \"image\": {}", jstr(&rel));
        files.push((rel, im.png()));
    }
    if let Some(m) = &v.ignore {
        let rel = format!("masks/ignore{i}.png");
        s += &format!(", \"ignore\": {}", jstr(&rel));
        files.push((rel, m.png()));
    }
    if let Some(b) = v.hint {
        s += &format!(", \"box\": {}", nums(&b));
    }
    s + &format!(", \"camera\": {}}}", camera_json(&v.camera))
}

/// The scene's files: `scene.json` in `dir`, the masks and images beside it, the
/// mesh in `mesh_dir` (a mesh the project's writer refuses is left out).
pub fn scene_files(s: &SceneSpec) -> SceneFiles {
    let mut rel_files = Vec::new();
    let views: Vec<String> = s
        .views
        .iter()
        .enumerate()
        .map(|(i, v)| view_entry(i, v, &mut rel_files))
        .collect();
    let mut files = Files::new();
    let mut mesh_rel = format!("{}mesh.ply", s.mesh_dir);
    if let Some((name, mf)) = mesh_files(&s.mesh, &s.format, "mesh") {
        mesh_rel = format!("{}{name}", s.mesh_dir);
        for (k, v) in mf {
            files.insert(join(&join(&s.dir, &s.mesh_dir), &k), v);
        }
    }
    for (k, v) in rel_files {
        files.insert(join(&s.dir, &k), v);
    }
    let mut text = "{".to_string();
    if let Some(v) = s.version {
        text += &format!("\"version\": {v}, ");
    }
    text += &format!(
        "\"mesh\": {}, \"views\": [\n  {}\n]",
        jstr(&mesh_rel),
        views.join(",\n  ")
    );
    if let Some(p) = &s.initial_pose {
        text += &format!(", \"initial_pose\": {}", pose_json(p));
    }
    if let Some(p) = &s.ground_truth {
        text += &format!(", \"ground_truth_pose\": {}", pose_json(p));
    }
    if !s.grasps.is_empty() {
        let g: Vec<String> = s.grasps.iter().map(grasp_json).collect();
        text += &format!(", \"grasps\": [{}]", g.join(", "));
    }
    text += "}\n";
    SceneFiles {
        scene_file: join(&s.dir, "scene.json"),
        text,
        files,
    }
}

/// Loads a scene as `localisebot fit scene.json` does; checks an accepted scene.
pub fn drive_scene(sf: &SceneFiles, limits: &Limits) -> localisebot::Result<Scene> {
    dump(&sf.scene_file, sf.text.as_bytes());
    dump_files(&sf.files);
    let r = load_scene_with(&sf.scene_file, &sf.text, &resolver(&sf.files), limits);
    if let Ok(s) = &r {
        check_scene(s);
        check_scene_limits(s, limits);
    }
    r
}

// ---------------------------------------------------------------------------------
// The file sets of the page (`FileSet`)

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Layout {
    /// The scene's folder as it is.
    Folder,
    /// Bare names (a file chooser).
    Bare,
    /// One camera `.json` per view (`wrapped`: a view entry with `camera`), masks named
    /// by `mask_style`, images by `image_style` (see [`fileset_files`]).
    PerView {
        wrapped: bool,
        mask_style: u8,
        image_style: u8,
    },
}

#[derive(Debug, Clone, PartialEq)]
pub struct FilesetSpec {
    pub scene: SceneSpec,
    pub layout: Layout,
    /// A folder above everything ("" or ending in `/`).
    pub prefix: String,
    /// More files, by path.
    pub junk: Vec<(String, Vec<u8>)>,
    /// Files given twice, the second time under a bare name (indices modulo the count).
    pub twice: Vec<usize>,
    /// The order the files are added in: a rotation of the list.
    pub rotate: usize,
}

/// Makes a scene fit one-camera-file-per-view: no poses or grasps (those files hold
/// none), no ignore masks; without `wrapped` (a bare camera, no box) a photo view gets
/// a mask instead.
pub fn per_view_ready(scene: &mut SceneSpec, wrapped: bool) {
    scene.initial_pose = None;
    scene.ground_truth = None;
    scene.grasps.clear();
    for v in &mut scene.views {
        v.ignore = None;
        if !wrapped && v.mask.is_none() {
            v.mask = v.image.as_ref().map(|im| MaskSpec {
                kind: PngKind::Gray8,
                width: im.width,
                height: im.height,
                bits: vec![1],
            });
            v.hint = None;
        }
    }
}

/// The files as a page hands them over, in order.
pub fn fileset_files(f: &FilesetSpec) -> Vec<(String, Vec<u8>)> {
    let mut out: Vec<(String, Vec<u8>)> = Vec::new();
    let sf = scene_files(&SceneSpec {
        dir: String::new(),
        ..f.scene.clone()
    });
    let base = |p: &str| p.rsplit('/').next().unwrap_or(p).to_string();
    match f.layout {
        Layout::Folder | Layout::Bare => {
            let bare = f.layout == Layout::Bare;
            let name = |p: &str| if bare { base(p) } else { format!("{}{p}", f.prefix) };
            out.push((name("scene.json"), sf.text.clone().into_bytes()));
            for (p, b) in &sf.files {
                out.push((name(p), b.clone()));
            }
        }
        Layout::PerView {
            wrapped,
            mask_style,
            image_style,
        } => {
            let p = &f.prefix;
            if let Some((mesh_name, mf)) = mesh_files(&f.scene.mesh, &f.scene.format, "model") {
                let _ = mesh_name;
                for (k, v) in mf {
                    out.push((format!("{p}{k}"), v));
                }
            }
            for v in &f.scene.views {
                let n = &v.name;
                let cam = camera_json(&v.camera);
                let text = if wrapped {
                    let mut s = format!("{{\"name\": {}, \"camera\": {cam}", jstr(n));
                    if let Some(b) = v.hint {
                        s += &format!(", \"box\": {}", nums(&b));
                    }
                    s + "}"
                } else {
                    cam
                };
                out.push((format!("{p}{n}.json"), text.into_bytes()));
                if let Some(m) = &v.mask {
                    let path = match mask_style % 4 {
                        0 => format!("{p}masks/{n}.png"),
                        1 => format!("{p}{n}_mask.png"),
                        2 => format!("{p}mask_{n}.png"),
                        _ => format!("{p}{n}.png"),
                    };
                    out.push((path, m.png()));
                }
                if let Some(im) = &v.image {
                    let path = match image_style % 3 {
                        0 => format!("{p}images/{n}.png"),
                        1 => format!("{p}{n}_image.png"),
                        _ => format!("{p}rgb/{n}.png"),
                    };
                    out.push((path, im.png()));
                }
            }
        }
    }
    let n = out.len();
    for &i in &f.twice {
        if n > 0 {
            let (p, b) = out[i % n].clone();
            out.push((base(&p), b));
        }
    }
    out.extend(f.junk.iter().cloned());
    if !out.is_empty() {
        let r = f.rotate % out.len();
        out.rotate_left(r);
    }
    out
}

/// Every call the binding makes on a set of these files, and finally
/// [`FileSet::load`] (checked when it accepts).
pub fn drive_fileset(
    files: &[(String, Vec<u8>)],
    limits: &Limits,
) -> localisebot::Result<(Scene, Vec<String>, String)> {
    let mut set = FileSet::new();
    for (i, (p, b)) in files.iter().enumerate() {
        dump(&format!("{i}-{p}"), b);
    }
    for (p, b) in files {
        set.add(p, b.clone());
    }
    set.set_limits(*limits);
    let names = set.names();
    assert!(names.len() <= files.len());
    for n in &names {
        for role in [FileRole::Mask, FileRole::Image, FileRole::Other] {
            let _ = set.find(n, role);
        }
    }
    for (p, b) in files {
        let lower = p.to_ascii_lowercase();
        if io::fileset::is_mesh_file(p) {
            let _ = io::fileset::mesh_references(p, b);
            if let Ok(m) = set.load_mesh(p, b) {
                check_mesh(&m);
                check_mesh_limits(p, &m, limits);
            }
        } else if lower.ends_with(".json") {
            let _ = io::fileset::scene_references(p, &text_of(b));
        }
    }
    let _ = set.needs_segmenter();
    if let Ok(io::fileset::Plan::Scene { file, text }) = set.plan() {
        if let Ok((s, _)) = set.load_scene(&file, &text) {
            check_scene(&s);
            check_scene_limits(&s, limits);
        }
    }
    let r = set.load();
    if let Ok((s, _, _)) = &r {
        check_scene(s);
        check_scene_limits(s, limits);
    }
    r
}

// ---------------------------------------------------------------------------------
// BOP

#[derive(Debug, Clone, PartialEq)]
pub struct BopInstance {
    pub obj_id: i64,
    pub r: [f64; 9],
    pub t: [f64; 3],
    /// `mask/IMID_GTID.png`, `mask_visib/IMID_GTID.png`.
    pub mask: Option<MaskSpec>,
    pub visib: Option<MaskSpec>,
}

#[derive(Debug, Clone, PartialEq)]
pub struct BopImage {
    pub id: i64,
    /// In `scene_camera.json`, with `cam_K` (when given) and `cam_R_w2c`/`cam_t_w2c`.
    pub listed: bool,
    pub k: Option<[f64; 9]>,
    pub w2c: Option<([f64; 9], [f64; 3])>,
    pub instances: Vec<BopInstance>,
    /// `rgb/IMID.png`.
    pub rgb: Option<ImageSpec>,
}

#[derive(Debug, Clone, PartialEq)]
pub struct BopSpec {
    pub scene_id: u32,
    pub object_id: u32,
    pub images: Vec<BopImage>,
    pub model: MeshSpec,
    pub model_ply: PlyOpts,
    pub image_ids: Option<Vec<u32>>,
    pub instance: usize,
    pub visible: bool,
    pub metres: bool,
    pub ignore_others: bool,
    pub boxes: Option<BoxHints>,
}

/// The dataset's files and the import's options.
pub fn bop_files(s: &BopSpec) -> (Files, BopOptions) {
    let mut files = Files::new();
    let dir = format!("test/{:06}", s.scene_id);
    let mut cams = Vec::new();
    let mut gts = Vec::new();
    for im in &s.images {
        if im.listed {
            let mut parts = Vec::new();
            if let Some(k) = im.k {
                parts.push(format!("\"cam_K\": {}", nums(&k)));
            }
            if let Some((r, t)) = im.w2c {
                parts.push(format!("\"cam_R_w2c\": {}, \"cam_t_w2c\": {}", nums(&r), nums(&t)));
            }
            parts.push("\"depth_scale\": 1.0".into());
            cams.push(format!("\"{}\": {{{}}}", im.id, parts.join(", ")));
        }
        let mut inst = Vec::new();
        for (g, i) in im.instances.iter().enumerate() {
            inst.push(format!(
                "{{\"cam_R_m2c\": {}, \"cam_t_m2c\": {}, \"obj_id\": {}}}",
                nums(&i.r),
                nums(&i.t),
                i.obj_id
            ));
            if let Some(m) = &i.mask {
                files.insert(format!("{dir}/mask/{:06}_{g:06}.png", im.id), m.png());
            }
            if let Some(m) = &i.visib {
                files.insert(format!("{dir}/mask_visib/{:06}_{g:06}.png", im.id), m.png());
            }
        }
        gts.push(format!("\"{}\": [{}]", im.id, inst.join(", ")));
        if let Some(rgb) = &im.rgb {
            files.insert(format!("{dir}/rgb/{:06}.png", im.id), rgb.png());
        }
    }
    files.insert(
        format!("{dir}/scene_camera.json"),
        format!("{{{}}}", cams.join(",\n")).into_bytes(),
    );
    files.insert(
        format!("{dir}/scene_gt.json"),
        format!("{{{}}}", gts.join(",\n")).into_bytes(),
    );
    files.insert(
        format!("models/obj_{:06}.ply", s.object_id),
        ply_bytes(&s.model, &s.model_ply),
    );
    let opts = BopOptions {
        image_ids: s.image_ids.clone(),
        instance: s.instance,
        masks: if s.visible { MaskKind::Visible } else { MaskKind::Full },
        units: if s.metres { Units::Metres } else { Units::Millimetres },
        ignore_others: s.ignore_others,
        boxes: s.boxes,
        ..BopOptions::new(s.scene_id, s.object_id)
    };
    (files, opts)
}

/// The BOP import as `localisebot import-bop` runs it; checks what it makes.
pub fn drive_bop(files: &Files, opts: &BopOptions) -> localisebot::Result<Imported> {
    dump_files(files);
    dump("options.txt", format!("{opts:#?}").as_bytes());
    let r = io::bop::import(&resolver(files), opts);
    if let Ok(im) = &r {
        check_imported(im);
    }
    r
}

// ---------------------------------------------------------------------------------
// NeRF

#[derive(Debug, Clone, PartialEq, Default)]
pub struct NerfIntrinsics {
    pub camera_angle_x: Option<f64>,
    pub camera_angle_y: Option<f64>,
    pub fl_x: Option<f64>,
    pub fl_y: Option<f64>,
    pub cx: Option<f64>,
    pub cy: Option<f64>,
    pub w: Option<f64>,
    pub h: Option<f64>,
    pub k1: Option<f64>,
}

impl NerfIntrinsics {
    fn json_parts(&self) -> Vec<String> {
        let mut p = Vec::new();
        for (k, v) in [
            ("camera_angle_x", self.camera_angle_x),
            ("camera_angle_y", self.camera_angle_y),
            ("fl_x", self.fl_x),
            ("fl_y", self.fl_y),
            ("cx", self.cx),
            ("cy", self.cy),
            ("w", self.w),
            ("h", self.h),
            ("k1", self.k1),
        ] {
            if let Some(v) = v {
                p.push(format!("\"{k}\": {}", num(v)));
            }
        }
        p
    }
}

#[derive(Debug, Clone, PartialEq)]
pub struct NerfFrame {
    /// The frame's `file_path` (without `.png`, as Blender writes it, unless `with_ext`).
    pub file_path: String,
    pub with_ext: bool,
    pub matrix: [[f64; 4]; 4],
    pub intrinsics: NerfIntrinsics,
    /// The image (`file_path` + `.png`); absent: the frame's image is missing.
    pub image: Option<ImageSpec>,
    /// A `mask_path` and its PNG.
    pub mask: Option<MaskSpec>,
}

#[derive(Debug, Clone, PartialEq)]
pub struct NerfSpec {
    /// The transforms file's folder ("" or ending in `/`).
    pub dir: String,
    pub intrinsics: NerfIntrinsics,
    pub frames: Vec<NerfFrame>,
}

/// (transforms file, its text, the files it names by path).
pub fn nerf_files(s: &NerfSpec) -> (String, String, Files) {
    let mut files = Files::new();
    let mut frames = Vec::new();
    for (i, f) in s.frames.iter().enumerate() {
        let path = if f.with_ext {
            format!("{}.png", f.file_path)
        } else {
            f.file_path.clone()
        };
        let mut parts = vec![
            format!("\"file_path\": {}", jstr(&path)),
            format!("\"transform_matrix\": {}", rows4(&f.matrix)),
        ];
        parts.extend(f.intrinsics.json_parts());
        if let Some(im) = &f.image {
            files.insert(join(&s.dir, &format!("{}.png", f.file_path)), im.png());
        }
        if let Some(m) = &f.mask {
            let rel = format!("masks/f{i}.png");
            parts.push(format!("\"mask_path\": {}", jstr(&rel)));
            files.insert(join(&s.dir, &rel), m.png());
        }
        frames.push(format!("{{{}}}", parts.join(", ")));
    }
    let mut top = s.intrinsics.json_parts();
    top.push(format!("\"frames\": [\n  {}\n]", frames.join(",\n  ")));
    (
        join(&s.dir, "transforms.json"),
        format!("{{{}}}\n", top.join(", ")),
        files,
    )
}

/// The NeRF import as `localisebot import-nerf` runs it; checks what it makes.
pub fn drive_nerf(transforms: &str, text: &str, files: &Files) -> localisebot::Result<Imported> {
    dump(transforms, text.as_bytes());
    dump_files(files);
    let r = io::nerf::import(transforms, text, &resolver(files), "mesh.ply");
    if let Ok(im) = &r {
        check_imported(im);
    }
    r
}

/// Loads an import's scene (with `mesh` as its mesh file when it names none of its
/// own), as the CLI does after writing it out.
pub fn load_imported(im: &Imported, mesh: Option<(&str, Vec<u8>)>) -> localisebot::Result<Scene> {
    let mut files: Files = im.files.iter().cloned().collect();
    if let Some((name, bytes)) = mesh {
        files.insert(name.to_string(), bytes);
    }
    let text = im.scene.to_json_string();
    let r = load_scene_with("scene.json", &text, &resolver(&files), &Limits::DEFAULT);
    if let Ok(s) = &r {
        check_scene(s);
    }
    r
}

// ---------------------------------------------------------------------------------
// What every accepted input must give

fn finite(what: &str, v: &[f64]) {
    assert!(v.iter().all(|x| x.is_finite()), "{what}: not finite: {v:?}");
}

pub fn check_mesh(m: &Mesh) {
    assert!(!m.triangles.is_empty(), "an accepted mesh has triangles");
    let n = m.positions.len() as u32;
    for t in &m.triangles {
        assert!(t.iter().all(|&i| i < n), "triangle {t:?} past the {n} vertices");
    }
    for p in &m.positions {
        finite("mesh vertex", &p.to_array());
        assert!(
            p.abs().max_element() <= MAX_LENGTH,
            "mesh vertex {p} beyond ±{MAX_LENGTH:e}"
        );
    }
}

fn check_rotation(what: &str, r: glam::DMat3) {
    finite(what, &r.to_cols_array());
    let e = (r.transpose() * r - glam::DMat3::IDENTITY)
        .to_cols_array()
        .iter()
        .fold(0.0f64, |a, v| a.max(v.abs()));
    assert!(
        e < 1e-6 && (r.determinant() - 1.0).abs() < 1e-6,
        "{what}: not a rotation: {r:?}"
    );
}

pub fn check_camera(c: &Camera) {
    finite("camera intrinsics", &[c.fx, c.fy, c.cx, c.cy]);
    let (lo, hi) = FOCAL_RANGE_PX;
    assert!(
        (lo..=hi).contains(&c.fx) && (lo..=hi).contains(&c.fy),
        "focal lengths {} {}",
        c.fx,
        c.fy
    );
    assert!(c.width >= 1 && c.height >= 1 && c.width <= localisebot::MAX_SIDE && c.height <= localisebot::MAX_SIDE);
    check_rotation("camera rotation", c.rotation);
    finite("camera translation", &c.translation.to_array());
    assert!(
        c.translation.abs().max_element() <= 2.0 * MAX_LENGTH,
        "camera translation {}",
        c.translation
    );
}

pub fn check_pose(p: &Pose) {
    check_rotation("pose rotation", p.rotation);
    finite("pose translation", &p.translation.to_array());
    finite("pose scale", &p.scale.to_array());
    assert!(p.scale.min_element() > 0.0, "pose scale {}", p.scale);
}

pub fn check_scene(s: &Scene) {
    check_mesh(&s.mesh);
    assert!(
        !s.views.is_empty() || !s.photos.is_empty(),
        "an accepted scene has views"
    );
    for v in &s.views {
        let c = v.camera();
        check_camera(c);
        let m = v.mask();
        assert_eq!((m.width, m.height), (c.width, c.height));
        assert_eq!(m.data.len(), (c.width * c.height) as usize);
        assert!(v.known_area() > 0);
        if let Some(ig) = v.ignore() {
            assert_eq!(ig.data.len(), m.data.len());
        }
        if let Some(im) = v.image() {
            assert_eq!(im.data.len(), 4 * m.data.len());
        }
    }
    for p in &s.photos {
        check_camera(&p.camera);
        assert_eq!(p.image.data.len(), 4 * (p.camera.width * p.camera.height) as usize);
        if let Some(b) = &p.hint {
            finite("box", &b.to_array());
        }
    }
    for p in s.initial_pose.iter().chain(&s.ground_truth_pose) {
        check_pose(p);
    }
    for g in &s.grasps {
        finite(
            "grasp",
            &[g.centre.to_array(), g.approach.to_array(), g.closing.to_array()].concat(),
        );
        finite("grasp size", &[g.width, g.depth, g.score.unwrap_or(0.0)]);
    }
}

/// An import's scene: cameras that convert, finite poses.
pub fn check_imported(im: &Imported) {
    check_scene_json(&im.scene);
    for v in &im.scene.views {
        for f in [&v.mask, &v.image, &v.ignore].into_iter().flatten() {
            assert!(
                im.files.iter().any(|(p, _)| p == f),
                "view '{}': {f} is not among the files",
                v.name
            );
        }
    }
}

pub fn check_scene_json(s: &SceneJson) {
    for v in &s.views {
        let c = v
            .camera
            .to_camera(&v.name)
            .unwrap_or_else(|e| panic!("an imported camera is refused: {e}"));
        check_camera(&c);
        if let Some(b) = v.hint_box {
            finite("box", &b);
        }
    }
    for p in s.initial_pose.iter().chain(&s.ground_truth_pose) {
        let mut all: Vec<f64> = p.translation.iter().chain(&p.scale).copied().collect();
        match &p.rotation {
            Some(localisebot::RotationJson::Matrix(m)) => all.extend(m.iter().flatten()),
            Some(localisebot::RotationJson::Quaternion(q)) => all.extend(q),
            None => {}
        }
        all.extend(p.quaternion.iter().flatten());
        finite("imported pose", &all);
    }
}

// ---------------------------------------------------------------------------------
// PNG readers

/// Decodes `bytes` as a mask and as an image (unsized and sized to `expect`), as
/// the scene loader and the importers do; checks what they give.
pub fn drive_png(
    bytes: &[u8],
    expect: (u32, u32),
) -> (
    localisebot::Result<localisebot::Mask>,
    localisebot::Result<localisebot::Rgba>,
) {
    dump("m.png", bytes);
    let m = io::mask::decode_mask(bytes, "v", "m.png");
    if let Ok(m) = &m {
        assert_eq!(m.data.len(), m.width as usize * m.height as usize);
        assert!(m.data.iter().all(|&v| v <= 1));
    }
    let i = io::mask::decode_image(bytes, "v", "i.png");
    if let Ok(i) = &i {
        assert_eq!(i.data.len(), 4 * i.width as usize * i.height as usize);
    }
    if let Ok(s) = io::mask::decode_mask_sized(bytes, "v", "m.png", expect.0, expect.1) {
        assert_eq!((s.width, s.height), expect);
    }
    if let Ok(s) = io::mask::decode_image_sized(bytes, "v", "i.png", expect.0, expect.1) {
        assert_eq!((s.width, s.height), expect);
    }
    let _ = io::mask::dimensions(bytes);
    (m, i)
}
