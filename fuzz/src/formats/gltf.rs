//! glTF meshes: containers (GLB, data URI, external buffer), node transforms,
//! extras and the glTF writer.

use super::{jstr, nums, Files, MeshSpec};

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
