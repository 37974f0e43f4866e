//! Meshes: the mesh spec, the OBJ writer, the choice of mesh format and its
//! driver, and the limits an accepted mesh or scene must respect.

use super::{check_mesh, dump_files, gltf_files, ply_bytes, Files, GltfOpts, PlyOpts};
use localisebot::io::scene::Scene;
use localisebot::io::{self, gltf_write, join, parent_dir};
use localisebot::{Camera, Limits, Mesh};

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
