//! The fuzz targets' structured inputs: `arbitrary`-derived structures mapped onto the
//! specs of [`crate::formats`]. They are valid by default — an all-zero (or exhausted)
//! input gives a scene, mesh, PNG, BOP or NeRF folder the readers accept — and wild
//! only through what the bytes choose explicitly: [`Wild`] numbers in edit lists,
//! out-of-range indices, odd types, byte damage ([`ADamage`]). So the fuzzer starts
//! from inputs that get deep into the readers and mutates from there.

use crate::formats::*;
use arbitrary::{Arbitrary, Unstructured};
use localisebot::io::bop::BoxHints;
use localisebot::Limits;

/// Numbers at the edges: NaN, ±∞, 1e300, denormals, −0, the limits' bounds.
pub const EDGES: [f64; 24] = [
    f64::NAN,
    f64::INFINITY,
    f64::NEG_INFINITY,
    1e300,
    -1e300,
    5e-324,
    -5e-324,
    -0.0,
    0.0,
    1e12,
    -1e12,
    1.000_000_1e12,
    1e-3,
    9.99e-4,
    1e8,
    1.0001e8,
    1e6,
    1e-6,
    f64::MAX,
    f64::MIN,
    f64::MIN_POSITIVE,
    1e-100,
    1e154,
    2.2e-309,
];

/// Counts and indices at the edges.
pub const INTS: [i64; 15] = [
    -1,
    0,
    1,
    2,
    3,
    7,
    255,
    256,
    65536,
    1 << 20,
    1 << 31,
    u32::MAX as i64,
    1 << 40,
    -(1 << 40),
    i64::MAX,
];

/// A number from outside any sane range.
#[derive(Arbitrary, Debug, Clone, Copy)]
pub enum Wild {
    Edge(u8),
    Raw(f64),
    Int(i64),
    Small(i8),
}

impl Wild {
    pub fn f(self) -> f64 {
        match self {
            Wild::Edge(i) => EDGES[i as usize % EDGES.len()],
            Wild::Raw(v) => v,
            Wild::Int(i) => i as f64,
            Wild::Small(s) => s as f64 / 8.0,
        }
    }

    pub fn i(self) -> i64 {
        match self {
            Wild::Edge(i) => INTS[i as usize % INTS.len()],
            Wild::Raw(v) => v as i64,
            Wild::Int(i) => i,
            Wild::Small(s) => s as i64,
        }
    }

    /// An index into a glTF array: small, −1, or past any array.
    pub fn ix(self) -> i64 {
        self.i().clamp(-1, 1 << 32)
    }
}

fn lerp(u: u16, lo: f64, hi: f64) -> f64 {
    lo + (hi - lo) * (u as f64 / 65535.0)
}

fn unit_quat(q: [i8; 4]) -> [f64; 4] {
    let q = q.map(|v| v as f64);
    let n = q.iter().map(|v| v * v).sum::<f64>().sqrt();
    if n < 1.0 {
        [1.0, 0.0, 0.0, 0.0]
    } else {
        q.map(|v| v / n)
    }
}

/// A structure decoded from no bytes at all: the valid default.
pub fn default_of<'a, T: Arbitrary<'a>>() -> T {
    T::arbitrary(&mut Unstructured::new(&[])).expect("an empty input decodes")
}

// ---------------------------------------------------------------------------------

#[derive(Arbitrary, Debug, Clone)]
pub enum MeshEdit {
    Coord {
        v: u8,
        axis: u8,
        value: Wild,
    },
    Index {
        face: u8,
        k: u8,
        value: Wild,
    },
    Short(Vec<u8>),
    Flat,
    /// More vertices and faces (up to 255).
    Many(u8),
}

/// A unit triangle, up to 12 more vertices within ±12.7 and 8 more polygons of 3–5
/// corners; then the edits.
#[derive(Arbitrary, Debug, Clone)]
pub struct AMesh {
    pub extra: Vec<[i8; 3]>,
    pub faces: Vec<[u8; 6]>,
    pub edits: Vec<MeshEdit>,
}

impl AMesh {
    pub fn spec(&self) -> MeshSpec {
        let extra: Vec<[f64; 3]> = self.extra.iter().take(12).map(|p| p.map(|v| v as f64 / 10.0)).collect();
        let n = 3 + extra.len();
        let faces: Vec<Vec<i64>> = self
            .faces
            .iter()
            .take(8)
            .map(|f| {
                let k = 3 + (f[0] % 3) as usize;
                (0..k).map(|j| (f[1 + j] as usize % n) as i64).collect()
            })
            .collect();
        let mut m = MeshSpec::with_base(&extra, &faces);
        for e in self.edits.iter().take(4) {
            match e {
                MeshEdit::Coord { v, axis, value } => {
                    let n = m.positions.len();
                    m.positions[*v as usize % n][*axis as usize % 3] = value.f();
                }
                MeshEdit::Index { face, k, value } => {
                    let nf = m.faces.len();
                    let f = &mut m.faces[*face as usize % nf];
                    if !f.is_empty() {
                        let l = f.len();
                        f[*k as usize % l] = value.i();
                    }
                }
                MeshEdit::Short(c) => m.faces.push(c.iter().take(2).map(|&i| i as i64).collect()),
                MeshEdit::Flat => {
                    for p in &mut m.positions {
                        *p = [p[0], 2.0 * p[0], 0.0];
                    }
                }
                MeshEdit::Many(k) => {
                    let base = m.positions.len() as i64;
                    for i in 0..*k as i64 {
                        m.positions.push([i as f64, (i % 7) as f64, 1.0]);
                        if i >= 2 {
                            m.faces.push(vec![base + i - 2, base + i - 1, base + i]);
                        }
                    }
                }
            }
        }
        m
    }
}

#[derive(Arbitrary, Debug, Clone)]
pub struct APly {
    pub encoding: u8,
    /// Bit 7: any scalar types (else float/double coordinates, integer lists).
    pub types: u8,
    pub coord: u8,
    pub count: u8,
    pub index: u8,
    pub flags: u8,
    pub vertex_delta: Option<Wild>,
    pub face_delta: Option<Wild>,
}

impl APly {
    pub fn opts(&self) -> PlyOpts {
        let wild = self.types & 0x80 != 0;
        let pick = |x: u8, sane: &[Scalar]| {
            if wild {
                SCALARS[x as usize % SCALARS.len()]
            } else {
                sane[x as usize % sane.len()]
            }
        };
        let f = |bit: u8| self.flags & (1 << bit) != 0;
        PlyOpts {
            encoding: [PlyEncoding::Ascii, PlyEncoding::BinaryLe, PlyEncoding::BinaryBe][self.encoding as usize % 3],
            coord: pick(self.coord, &[Scalar::Double, Scalar::Float]),
            count: pick(self.count, &[Scalar::UChar, Scalar::UShort, Scalar::Int, Scalar::UInt]),
            index: pick(self.index, &[Scalar::Int, Scalar::UInt]),
            aliases: f(0),
            vertex_index_name: f(1),
            extra_properties: f(2),
            extra_element: f(3),
            comment: f(4),
            crlf: f(5),
            vertex_delta: self.vertex_delta.map_or(0, Wild::i),
            face_delta: self.face_delta.map_or(0, Wild::i),
        }
    }
}

#[derive(Arbitrary, Debug, Clone)]
pub struct AObj {
    pub flags: u8,
}

impl AObj {
    pub fn opts(&self) -> ObjOpts {
        let f = |bit: u8| self.flags & (1 << bit) != 0;
        ObjOpts {
            negative: f(0),
            texcoords: f(1),
            objects: f(2),
            comments: f(3),
            crlf: f(4),
            tabs: f(5),
            odd_space: self.flags >> 6,
        }
    }
}

#[derive(Arbitrary, Debug, Clone)]
pub enum ATransform {
    None,
    Trs {
        t: Option<[i8; 3]>,
        r: Option<[i8; 4]>,
        s: Option<[u8; 3]>,
    },
    Matrix {
        q: [i8; 4],
        t: [i8; 3],
    },
    WildMatrix([Wild; 16]),
    WildTrs {
        t: Option<[Wild; 3]>,
        r: Option<[Wild; 4]>,
        s: Option<[Wild; 3]>,
    },
}

impl ATransform {
    pub fn spec(&self) -> NodeTransform {
        match self {
            ATransform::None => NodeTransform::None,
            ATransform::Trs { t, r, s } => NodeTransform::Trs {
                t: t.map(|t| t.map(|v| v as f64 / 10.0)),
                r: r.map(|r| {
                    let [w, x, y, z] = unit_quat(r);
                    [x, y, z, w]
                }),
                s: s.map(|s| s.map(|v| 0.5 + v as f64 / 128.0)),
            },
            ATransform::Matrix { q, t } => {
                let m = rigid(unit_quat(*q), t.map(|v| v as f64 / 10.0));
                let mut c = [0.0; 16];
                for col in 0..4 {
                    for row in 0..4 {
                        c[col * 4 + row] = m[row][col];
                    }
                }
                NodeTransform::Matrix(c)
            }
            ATransform::WildMatrix(m) => NodeTransform::Matrix(m.map(Wild::f)),
            ATransform::WildTrs { t, r, s } => NodeTransform::Trs {
                t: t.map(|v| v.map(Wild::f)),
                r: r.map(|v| v.map(Wild::f)),
                s: s.map(|v| v.map(Wild::f)),
            },
        }
    }
}

#[derive(Arbitrary, Debug, Clone)]
pub enum AExtra {
    Animation([Wild; 4]),
    Skin(Vec<Wild>, Option<Wild>),
    Camera,
    Material(Option<(Wild, Wild)>),
    Required(u8),
    Sparse([Wild; 3], u8),
    Primitive(Wild, Wild, Option<Wild>),
    Cycle,
    Scene(Vec<Wild>),
    Instance,
}

const EXTENSIONS: [&str; 6] = [
    "KHR_materials_unlit",
    "KHR_texture_transform",
    "KHR_draco_mesh_compression",
    "KHR_mesh_quantization",
    "EXT_meshopt_compression",
    "EXT_unknown",
];

impl AExtra {
    pub fn spec(&self) -> GltfExtra {
        match self {
            AExtra::Animation([s, n, i, o]) => GltfExtra::Animation {
                sampler: s.ix(),
                node: n.ix(),
                input: i.ix(),
                output: o.ix(),
            },
            AExtra::Skin(j, m) => GltfExtra::Skin {
                joints: j.iter().take(4).map(|v| v.ix()).collect(),
                matrices: m.map(Wild::ix),
            },
            AExtra::Camera => GltfExtra::Camera,
            AExtra::Material(t) => GltfExtra::Material {
                texture: t.map(|(a, b)| (a.ix(), b.ix())),
            },
            AExtra::Required(k) => GltfExtra::Required(EXTENSIONS[*k as usize % EXTENSIONS.len()].into()),
            AExtra::Sparse([c, iv, vv], t) => GltfExtra::Sparse {
                count: c.ix(),
                indices_view: iv.ix(),
                values_view: vv.ix(),
                index_type: [5121, 5123, 5125, 5126][*t as usize % 4],
            },
            AExtra::Primitive(m, p, i) => GltfExtra::Primitive {
                mode: m.ix(),
                position: p.ix(),
                indices: i.map(Wild::ix),
            },
            AExtra::Cycle => GltfExtra::Cycle,
            AExtra::Scene(n) => GltfExtra::Scene {
                nodes: n.iter().take(4).map(|v| v.ix()).collect(),
            },
            AExtra::Instance => GltfExtra::Instance,
        }
    }
}

#[derive(Arbitrary, Debug, Clone)]
pub struct AGltf {
    pub container: u8,
    pub mode: Option<Wild>,
    pub index_type: u8,
    pub stride: u8,
    pub offset: u8,
    pub deltas: [Option<Wild>; 4],
    pub position_type: Option<(u8, u8)>,
    pub transform: ATransform,
    pub depth: u8,
    pub scene: u8,
    pub extras: Vec<AExtra>,
}

impl AGltf {
    pub fn opts(&self) -> GltfOpts {
        let d = |k: usize| self.deltas[k].map_or(0, Wild::i);
        GltfOpts {
            container: [Container::Glb, Container::DataUri, Container::External][self.container as usize % 3],
            mode: self.mode.map(|m| m.i()),
            index_type: match self.index_type {
                0 => Some(5125),
                1 => Some(5123),
                2 => Some(5121),
                3 => None,
                x => Some([5120, 5122, 5126, 0, 1][x as usize % 5]),
            },
            stride: match self.stride {
                0 => None,
                1 => Some(12),
                2 => Some(16),
                3 => Some(32),
                x => Some([0, 4, 8, 13, 252, 256, 1 << 31][x as usize % 7]),
            },
            offset: match self.offset {
                0 => 0,
                1 => 4,
                2 => 8,
                x => [3, 1 << 20, -4, 1 << 40][x as usize % 4],
            },
            count_delta: d(0),
            index_count_delta: d(1),
            view_len_delta: d(2),
            buffer_len_delta: d(3),
            position_type: self.position_type.map(|(c, t)| {
                (
                    [5126, 5120, 5121, 5122, 5123, 5125, 1][c as usize % 7],
                    ["VEC3", "SCALAR", "VEC2", "VEC4", "MAT4", "vec3"][t as usize % 6].to_string(),
                )
            }),
            transform: self.transform.spec(),
            depth: self.depth % 10,
            scene: match self.scene {
                0 => Some(0),
                1 => None,
                x => Some(INTS[x as usize % INTS.len()]),
            },
            extras: self.extras.iter().take(6).map(AExtra::spec).collect(),
        }
    }
}

#[derive(Arbitrary, Debug, Clone)]
pub enum AFormat {
    Ply(APly),
    Obj(AObj),
    Gltf(AGltf),
    PlyWriter,
    GlbWriter,
    GltfWriter,
}

impl AFormat {
    pub fn spec(&self) -> MeshFormat {
        match self {
            AFormat::Ply(p) => MeshFormat::Ply(p.opts()),
            AFormat::Obj(o) => MeshFormat::Obj(o.opts()),
            AFormat::Gltf(g) => MeshFormat::Gltf(g.opts()),
            AFormat::PlyWriter => MeshFormat::PlyWriter,
            AFormat::GlbWriter => MeshFormat::GlbWriter,
            AFormat::GltfWriter => MeshFormat::GltfWriter,
        }
    }
}

// ---------------------------------------------------------------------------------

/// A camera: focal lengths 5–200 px, the principal point in the image, a rigid
/// transform within ±12.7; then the edits (field, value) and another size.
#[derive(Arbitrary, Debug, Clone)]
pub struct ACamera {
    pub f: [u16; 4],
    pub q: [i8; 4],
    pub t: [i8; 3],
    pub key: u8,
    pub opengl: bool,
    pub edits: Vec<(u8, Wild)>,
    pub size: Option<(Wild, Wild)>,
}

impl ACamera {
    pub fn spec(&self, w: u32, h: u32) -> CamSpec {
        let mut c = CamSpec {
            width: w as i64,
            height: h as i64,
            fx: lerp(self.f[0], 5.0, 200.0),
            fy: lerp(self.f[1], 5.0, 200.0),
            cx: lerp(self.f[2], 0.0, w as f64),
            cy: lerp(self.f[3], 0.0, h as f64),
            matrix: rigid(self.q.map(|v| v as f64), self.t.map(|v| v as f64 / 10.0)),
            key: match self.key {
                0xFE => CamKey::Both,
                0xFF => CamKey::Neither,
                k if k % 2 == 0 => CamKey::W2c,
                _ => CamKey::C2w,
            },
            opengl: self.opengl,
        };
        for (field, v) in self.edits.iter().take(4) {
            let (field, v) = (*field as usize % 21, v.f());
            match field {
                0 => c.fx = v,
                1 => c.fy = v,
                2 => c.cx = v,
                3 => c.cy = v,
                4..=19 => c.matrix[(field - 4) / 4][(field - 4) % 4] = v,
                _ => {
                    for r in 0..3 {
                        for k in 0..3 {
                            c.matrix[r][k] *= 1.0 + v * 1e-3;
                        }
                    }
                }
            }
        }
        if let Some((w, h)) = self.size {
            c.width = w.i();
            c.height = h.i();
        }
        c
    }
}

#[derive(Arbitrary, Debug, Clone)]
pub struct APose {
    pub q: [i8; 4],
    pub how: u8,
    pub t: [i8; 3],
    pub scale: Option<[u8; 3]>,
    pub edits: Vec<(u8, Wild)>,
}

impl APose {
    pub fn spec(&self) -> PoseSpec {
        let q = unit_quat(self.q);
        let mut p = PoseSpec {
            rotation: match self.how % 3 {
                0 => RotSpec::Matrix(quat_rows(q)),
                1 => RotSpec::Quaternion(q),
                _ => RotSpec::QuaternionKey(q),
            },
            translation: self.t.map(|v| v as f64 / 10.0),
            scale: self.scale.map(|s| s.map(|v| 0.1 + v as f64 / 25.0)),
        };
        for (f, v) in self.edits.iter().take(4) {
            let (f, v) = (*f as usize % 16, v.f());
            match (f, &mut p.rotation) {
                (0..=8, RotSpec::Matrix(m)) => m[f / 3][f % 3] = v,
                (0..=3, RotSpec::Quaternion(q) | RotSpec::QuaternionKey(q)) => q[f] = v,
                (9..=11, _) => p.translation[f - 9] = v,
                (12..=14, _) => p.scale.get_or_insert([1.0; 3])[f - 12] = v,
                _ => p.scale = Some([v; 3]),
            }
        }
        p
    }
}

#[derive(Arbitrary, Debug, Clone)]
pub struct AGrasp {
    pub centre: [i8; 3],
    pub width: u8,
    pub depth: u8,
    pub edits: Vec<(u8, Wild)>,
}

impl AGrasp {
    pub fn spec(&self) -> GraspSpec {
        let mut g = GraspSpec {
            centre: self.centre.map(|v| v as f64 / 100.0),
            approach: [0.0, 0.0, 1.0],
            closing: [1.0, 0.0, 0.0],
            width: 0.01 + self.width as f64 / 255.0,
            depth: 0.01 + self.depth as f64 / 255.0,
            score: Some(0.5),
        };
        for (f, v) in self.edits.iter().take(3) {
            let (f, v) = (*f as usize % 12, v.f());
            match f {
                0..=2 => g.centre[f] = v,
                3..=5 => g.approach[f - 3] = v,
                6..=8 => g.closing[f - 6] = v,
                9 => g.width = v,
                10 => g.depth = v,
                _ => g.score = Some(v),
            }
        }
        g
    }
}

/// A mask: a pixel format and bits (the first pixel always object).
#[derive(Arbitrary, Debug, Clone)]
pub struct AMask {
    pub kind: u8,
    pub bits: Vec<u8>,
}

impl AMask {
    pub fn spec(&self, w: u32, h: u32) -> MaskSpec {
        let mut bits: Vec<u8> = self.bits.iter().take((w * h) as usize).map(|b| b % 2).collect();
        if bits.is_empty() {
            bits.push(1);
        }
        bits[0] = 1;
        MaskSpec {
            kind: PNG_KINDS[self.kind as usize % PNG_KINDS.len()],
            width: w,
            height: h,
            bits,
        }
    }
}

/// A photograph (its first pixel colourful: never taken for a mask).
#[derive(Arbitrary, Debug, Clone)]
pub struct AImage {
    pub rgb: Vec<u8>,
}

impl AImage {
    pub fn spec(&self, w: u32, h: u32) -> ImageSpec {
        let mut rgb = vec![10, 200, 30];
        rgb.extend(self.rgb.iter().take(45));
        ImageSpec {
            width: w,
            height: h,
            rgb,
            alpha: None,
        }
    }
}

#[derive(Arbitrary, Debug, Clone)]
pub enum ViewEdit {
    Name(String),
    SameName,
    NoMask,
    WildBox([Wild; 4]),
    MaskSize(u8, u8),
    EmptyMask,
    NoImage,
}

/// A view of 1–16 × 1–16 pixels: a mask (0), a mask, ignore mask and photograph (1),
/// or a photograph and a box (2); then the edits.
#[derive(Arbitrary, Debug, Clone)]
pub struct AView {
    pub size: (u8, u8),
    pub camera: ACamera,
    pub kind: u8,
    pub mask: AMask,
    pub image: AImage,
    pub hint: [u8; 4],
    pub edits: Vec<ViewEdit>,
}

impl AView {
    pub fn spec(&self, i: usize) -> ViewSpec {
        let (w, h) = (1 + (self.size.0 % 16) as u32, 1 + (self.size.1 % 16) as u32);
        let kind = self.kind % 3;
        let mask = self.mask.spec(w, h);
        let ignore = MaskSpec {
            bits: mask.pixels().iter().map(|&b| 1 - b).collect(),
            ..mask.clone()
        };
        let x0 = self.hint[0] as u32 % w;
        let y0 = self.hint[1] as u32 % h;
        let x1 = x0 + 1 + self.hint[2] as u32 % (w - x0);
        let y1 = y0 + 1 + self.hint[3] as u32 % (h - y0);
        let mut v = ViewSpec {
            name: format!("v{i}"),
            camera: self.camera.spec(w, h),
            mask: (kind != 2).then_some(mask),
            image: (kind != 0).then(|| self.image.spec(w, h)),
            ignore: (kind == 1).then_some(ignore),
            hint: (kind == 2).then_some([x0 as f64, y0 as f64, x1 as f64, y1 as f64]),
        };
        for e in self.edits.iter().take(3) {
            match e {
                ViewEdit::Name(n) => v.name = n.chars().take(16).collect(),
                ViewEdit::SameName => v.name = "v0".into(),
                ViewEdit::NoMask => v.mask = None,
                ViewEdit::WildBox(b) => v.hint = Some(b.map(Wild::f)),
                ViewEdit::MaskSize(a, b) => {
                    if let Some(m) = &mut v.mask {
                        m.width = 1 + *a as u32 % 20;
                        m.height = 1 + *b as u32 % 20;
                    }
                }
                ViewEdit::EmptyMask => {
                    if let Some(m) = &mut v.mask {
                        m.bits = vec![0];
                    }
                }
                ViewEdit::NoImage => v.image = None,
            }
        }
        v
    }
}

/// A scene of 1–4 views.
#[derive(Arbitrary, Debug, Clone)]
pub struct AScene {
    pub views: Vec<AView>,
    pub mesh: AMesh,
    pub format: AFormat,
    pub dir: u8,
    pub mesh_dir: u8,
    pub initial: Option<APose>,
    pub ground_truth: Option<APose>,
    pub grasps: Vec<AGrasp>,
    pub version: Option<Wild>,
}

impl AScene {
    pub fn spec(&self) -> SceneSpec {
        let mut views: Vec<ViewSpec> = self.views.iter().take(4).enumerate().map(|(i, v)| v.spec(i)).collect();
        if views.is_empty() {
            views.push(default_of::<AView>().spec(0));
        }
        SceneSpec {
            dir: ["", "scene/", "a/b/"][self.dir as usize % 3].into(),
            mesh_dir: ["", "meshes/"][self.mesh_dir as usize % 2].into(),
            version: self.version.map(Wild::i),
            views,
            mesh: self.mesh.spec(),
            format: self.format.spec(),
            initial_pose: self.initial.as_ref().map(APose::spec),
            ground_truth: self.ground_truth.as_ref().map(APose::spec),
            grasps: self.grasps.iter().take(3).map(AGrasp::spec).collect(),
        }
    }
}

// ---------------------------------------------------------------------------------

#[derive(Arbitrary, Debug, Clone)]
pub enum AJunk {
    Bytes(Vec<u8>),
    SceneStub,
    CameraStub,
    NullCamera,
    Deep,
    Mask(AMask),
}

impl AJunk {
    pub fn bytes(&self) -> Vec<u8> {
        match self {
            AJunk::Bytes(b) => b.iter().take(64).copied().collect(),
            AJunk::SceneStub => b"{\"mesh\": \"mesh.ply\", \"views\": []}".to_vec(),
            AJunk::CameraStub => b"{\"fx\": 1}".to_vec(),
            AJunk::NullCamera => b"{\"camera\": null, \"name\": \"v0\"}".to_vec(),
            AJunk::Deep => vec![b'['; 200],
            AJunk::Mask(m) => m.spec(3, 2).png(),
        }
    }
}

const JUNK_DIRS: [&str; 10] = ["", "a/", "../", "./", "A/", "masks/", "images/", "x\\y/", "/abs/", "é/"];
const JUNK_STEMS: [&str; 11] = [
    "scene", "v0", "V0", "mesh", "model", "mask_v0", "v0_mask", "v1_image", "", ".", "..",
];
const JUNK_EXTS: [&str; 10] = [
    ".json", ".png", ".PNG", ".glb", ".gltf", ".obj", ".ply", ".bin", "", ".JSON",
];

/// A scene's files as a page hands them over (see [`Layout`]), with junk.
#[derive(Arbitrary, Debug, Clone)]
pub struct AFileset {
    pub scene: AScene,
    pub layout: u8,
    pub wrapped: bool,
    pub styles: (u8, u8),
    pub prefix: u8,
    pub junk: Vec<(u8, u8, u8, AJunk)>,
    pub twice: Vec<u8>,
    pub rotate: u8,
}

impl AFileset {
    pub fn spec(&self) -> FilesetSpec {
        let mut scene = self.scene.spec();
        let layout = match self.layout % 3 {
            0 => Layout::Folder,
            1 => Layout::Bare,
            _ => Layout::PerView {
                wrapped: self.wrapped,
                mask_style: self.styles.0 % 4,
                image_style: self.styles.1 % 3,
            },
        };
        if let Layout::PerView { wrapped, .. } = layout {
            per_view_ready(&mut scene, wrapped);
        }
        FilesetSpec {
            scene,
            layout,
            prefix: ["", "data/", "My Scene/"][self.prefix as usize % 3].into(),
            junk: self
                .junk
                .iter()
                .take(4)
                .map(|(d, s, e, j)| {
                    let name = format!(
                        "{}{}{}",
                        JUNK_DIRS[*d as usize % JUNK_DIRS.len()],
                        JUNK_STEMS[*s as usize % JUNK_STEMS.len()],
                        JUNK_EXTS[*e as usize % JUNK_EXTS.len()]
                    );
                    (name, j.bytes())
                })
                .collect(),
            twice: self.twice.iter().take(3).map(|&t| t as usize).collect(),
            rotate: self.rotate as usize,
        }
    }
}

// ---------------------------------------------------------------------------------

#[derive(Arbitrary, Debug, Clone)]
pub struct ABopImage {
    pub q: [i8; 4],
    pub t: [i16; 3],
    pub size: (u8, u8),
    pub mask: AMask,
    pub rgb: Option<AImage>,
}

#[derive(Arbitrary, Debug, Clone)]
pub enum BopEdit {
    Num { image: u8, field: u8, value: Wild },
    Unlisted(u8),
    NoK(u8),
    NoMask(u8),
    OtherObject(u8),
    EmptyMask(u8),
    NoW2c(u8),
}

/// A BOP scene of 1–3 images of object 1 (each also showing object 2), the model as
/// a PLY file; then the edits and options.
#[derive(Arbitrary, Debug, Clone)]
pub struct ABop {
    pub images: Vec<ABopImage>,
    pub w2c: Option<([i8; 4], [i16; 3])>,
    pub scene_id: u8,
    pub model: AMesh,
    pub model_ply: APly,
    pub flags: u8,
    pub image_ids: Option<Vec<u8>>,
    pub instance: u8,
    /// Boxes from the masks: margin, jitter (as the CLI's 0.1, 0.05: 0–0.5, 0–0.25), seed, views.
    pub boxes: Option<(u8, u8, u64, u8)>,
    pub edits: Vec<BopEdit>,
}

impl ABop {
    pub fn spec(&self) -> BopSpec {
        let mut ims: Vec<ABopImage> = self.images.iter().take(3).cloned().collect();
        if ims.is_empty() {
            ims.push(default_of());
        }
        let mut images: Vec<BopImage> = ims
            .iter()
            .enumerate()
            .map(|(i, a)| {
                let (w, h) = (1 + (a.size.0 % 12) as u32, 1 + (a.size.1 % 12) as u32);
                let m = a.mask.spec(w, h);
                BopImage {
                    id: i as i64,
                    listed: true,
                    k: Some([500.0, 0.0, w as f64 / 2.0, 0.0, 500.0, h as f64 / 2.0, 0.0, 0.0, 1.0]),
                    w2c: self.w2c.map(|(q, t)| (rot9(q.map(|v| v as f64)), t.map(|v| v as f64))),
                    instances: vec![
                        BopInstance {
                            obj_id: 2,
                            r: rot9([1.0, 0.0, 0.0, 0.0]),
                            t: [0.0, 0.0, 800.0],
                            mask: None,
                            visib: Some(m.clone()),
                        },
                        BopInstance {
                            obj_id: 1,
                            r: rot9(a.q.map(|v| v as f64)),
                            t: a.t.map(|v| v as f64 / 10.0),
                            mask: Some(m.clone()),
                            visib: Some(m),
                        },
                    ],
                    rgb: a.rgb.as_ref().map(|r| r.spec(w, h)),
                }
            })
            .collect();
        let n = images.len();
        for e in self.edits.iter().take(4) {
            match e {
                BopEdit::Num { image, field, value } => {
                    let im = &mut images[*image as usize % n];
                    let (f, v) = (*field as usize % 24, value.f());
                    match f {
                        0..=8 => im.k.get_or_insert([0.0; 9])[f] = v,
                        9..=17 => im.instances[1].r[f - 9] = v,
                        18..=20 => im.instances[1].t[f - 18] = v,
                        _ => {
                            let w = im
                                .w2c
                                .get_or_insert(([1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0], [0.0; 3]));
                            w.1[f - 21] = v;
                        }
                    }
                }
                BopEdit::Unlisted(i) => images[*i as usize % n].listed = false,
                BopEdit::NoK(i) => images[*i as usize % n].k = None,
                BopEdit::NoMask(i) => images[*i as usize % n].instances[1].mask = None,
                BopEdit::OtherObject(i) => images[*i as usize % n].instances[1].obj_id = -1,
                BopEdit::EmptyMask(i) => {
                    if let Some(m) = &mut images[*i as usize % n].instances[1].mask {
                        m.bits = vec![0];
                    }
                }
                BopEdit::NoW2c(i) => images[*i as usize % n].w2c = None,
            }
        }
        BopSpec {
            scene_id: self.scene_id as u32 % 3,
            object_id: 1,
            images,
            model: self.model.spec(),
            model_ply: self.model_ply.opts(),
            image_ids: self
                .image_ids
                .as_ref()
                .map(|v| v.iter().take(4).map(|&i| i as u32 % 5).collect()),
            instance: self.instance as usize % 3,
            visible: self.flags & 1 != 0,
            metres: self.flags & 2 == 0,
            ignore_others: self.flags & 4 != 0,
            boxes: self.boxes.map(|(margin, jitter, seed, k)| BoxHints {
                margin: margin as f64 / 510.0,
                jitter: jitter as f64 / 1020.0,
                seed,
                views_with_box: k as usize % 4,
            }),
        }
    }
}

#[derive(Arbitrary, Debug, Clone)]
pub struct AIntrinsics(pub [Option<Wild>; 9]);

impl AIntrinsics {
    pub fn spec(&self) -> NerfIntrinsics {
        let v = self.0.map(|w| w.map(Wild::f));
        NerfIntrinsics {
            camera_angle_x: v[0],
            camera_angle_y: v[1],
            fl_x: v[2],
            fl_y: v[3],
            cx: v[4],
            cy: v[5],
            w: v[6],
            h: v[7],
            k1: v[8],
        }
    }
}

#[derive(Arbitrary, Debug, Clone)]
pub struct ANerfFrame {
    pub q: [i8; 4],
    pub t: [i8; 3],
    pub size: (u8, u8),
    pub alpha: Vec<u8>,
    pub rgb: AImage,
    pub with_ext: bool,
    pub with_mask: bool,
}

#[derive(Arbitrary, Debug, Clone)]
pub enum NerfEdit {
    NoImage(u8),
    EmptyPath(u8),
    SamePath(u8),
    MaskSize(u8),
    Opaque(u8),
    Matrix(u8, u8, Wild),
    Intrinsics(u8, AIntrinsics),
}

/// A NeRF folder of 1–3 frames (RGBA images whose alpha is the mask, some with a
/// mask file), `camera_angle_x` at the top; then the edits.
#[derive(Arbitrary, Debug, Clone)]
pub struct ANerf {
    pub frames: Vec<ANerfFrame>,
    pub angle: u16,
    pub dir: u8,
    pub top: Option<AIntrinsics>,
    pub edits: Vec<NerfEdit>,
}

impl ANerf {
    pub fn spec(&self) -> NerfSpec {
        let mut fs: Vec<ANerfFrame> = self.frames.iter().take(3).cloned().collect();
        if fs.is_empty() {
            fs.push(default_of());
        }
        let mut frames: Vec<NerfFrame> = fs
            .iter()
            .enumerate()
            .map(|(i, a)| {
                let (w, h) = (2 + (a.size.0 % 15) as u32, 1 + (a.size.1 % 16) as u32);
                let n = (w * h) as usize;
                let mut alpha: Vec<u8> = a.alpha.iter().take(n).map(|b| b % 2).collect();
                alpha.resize(n, 0);
                alpha[0] = 1;
                alpha[n - 1] = 0;
                let mut image = a.rgb.spec(w, h);
                image.alpha = Some(alpha.clone());
                NerfFrame {
                    file_path: format!("./train/r_{i}"),
                    with_ext: a.with_ext,
                    matrix: rigid(a.q.map(|v| v as f64), a.t.map(|v| v as f64 / 20.0)),
                    intrinsics: NerfIntrinsics::default(),
                    image: Some(image),
                    mask: a.with_mask.then(|| MaskSpec {
                        kind: PngKind::Gray8,
                        width: w,
                        height: h,
                        bits: alpha,
                    }),
                }
            })
            .collect();
        let n = frames.len();
        let first = frames[0].file_path.clone();
        for e in self.edits.iter().take(4) {
            match e {
                NerfEdit::NoImage(i) => frames[*i as usize % n].image = None,
                NerfEdit::EmptyPath(i) => frames[*i as usize % n].file_path = String::new(),
                NerfEdit::SamePath(i) => frames[*i as usize % n].file_path = first.clone(),
                NerfEdit::MaskSize(i) => {
                    if let Some(m) = &mut frames[*i as usize % n].mask {
                        m.width += 1;
                    }
                }
                NerfEdit::Opaque(i) => {
                    if let Some(im) = &mut frames[*i as usize % n].image {
                        im.alpha = None;
                    }
                }
                NerfEdit::Matrix(i, at, v) => {
                    frames[*i as usize % n].matrix[*at as usize % 4][(*at / 4) as usize % 4] = v.f()
                }
                NerfEdit::Intrinsics(i, k) => frames[*i as usize % n].intrinsics = k.spec(),
            }
        }
        NerfSpec {
            dir: ["", "lego/", "a/b/"][self.dir as usize % 3].into(),
            intrinsics: match &self.top {
                Some(k) => k.spec(),
                None => NerfIntrinsics {
                    camera_angle_x: Some(lerp(self.angle, 0.3, 2.0)),
                    ..Default::default()
                },
            },
            frames,
        }
    }
}

// ---------------------------------------------------------------------------------

#[derive(Arbitrary, Debug, Clone)]
pub enum AInsert {
    Bytes(Vec<u8>),
    Token(u8),
}

impl AInsert {
    fn bytes(&self) -> Vec<u8> {
        match self {
            AInsert::Bytes(b) => b.iter().take(16).copied().collect(),
            AInsert::Token(t) => TOKENS[*t as usize % TOKENS.len()].to_vec(),
        }
    }
}

#[derive(Arbitrary, Debug, Clone)]
pub enum AMutation {
    Flip(u32, u8),
    Truncate(u32),
    Insert(u32, AInsert),
    Overwrite(u32, AInsert),
    Repeat(u32, u8, u32),
}

/// Damage to one of the files (`target`), and the limits to load under.
#[derive(Arbitrary, Debug, Clone)]
pub struct ADamage {
    pub target: u8,
    pub mutations: Vec<AMutation>,
    pub limits: Option<(u8, u16)>,
}

impl ADamage {
    pub fn mutations(&self) -> Vec<Mutation> {
        self.mutations
            .iter()
            .take(4)
            .map(|m| match m {
                AMutation::Flip(at, bit) => Mutation::Flip {
                    at: *at as usize,
                    bit: *bit,
                },
                AMutation::Truncate(at) => Mutation::Truncate { at: *at as usize },
                AMutation::Insert(at, b) => Mutation::Insert {
                    at: *at as usize,
                    bytes: b.bytes(),
                },
                AMutation::Overwrite(at, b) => Mutation::Overwrite {
                    at: *at as usize,
                    bytes: b.bytes(),
                },
                AMutation::Repeat(from, len, to) => Mutation::Repeat {
                    from: *from as usize,
                    len: *len as usize,
                    to: *to as usize,
                },
            })
            .collect()
    }

    pub fn limits(&self) -> Limits {
        let mut l = Limits::DEFAULT;
        if let Some((name, value)) = self.limits {
            let (name, _) = Limits::NAMES[name as usize % Limits::NAMES.len()];
            l.set(name, 1 + value as u64).expect("a known limit, at least 1");
        }
        l
    }
}

#[derive(Arbitrary, Debug, Clone)]
pub struct APng {
    pub size: (u8, u8),
    pub mask: AMask,
    pub declared: Option<(Wild, Wild)>,
    pub photo: Option<(AImage, bool)>,
}
