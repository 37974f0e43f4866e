//! glTF 2.0 meshes (`.glb`, `.gltf` with data-URI or external buffers) through the
//! `gltf` crate, without its `import` feature: the GLB container, the JSON document,
//! its validation, the node tree and the accessor reader are the crate's; buffers
//! are decoded here (base64 data URIs) or asked for through the resolver (`.bin`).
//!
//! Output: one [`Mesh`] in the model frame holding every triangle primitive
//! (`TRIANGLES`, `TRIANGLE_STRIP`, `TRIANGLE_FAN`; points and lines ignored) of every
//! node reachable from the default scene (else scene 0, else every root node), each
//! vertex moved by its node's world transform (column-major `matrix` or `T·R·S`,
//! composed root → leaf; glTF units, normally metres). Materials and images are not
//! read, so missing textures do not matter.
//!
//! Reference: the Khronos glTF 2.0 specification (FORMATS.md §4). Because the crate's
//! reader slices buffers without bounds checks of its own, every accessor read here is
//! first checked against its buffer view and buffer (counts, strides, types, offsets)
//! so that malformed files give an [`Error::Mesh`], never a panic.

use crate::error::{Error, Result};
use crate::io::Resolver;
use crate::limits::Limits;
use crate::mesh::Mesh;
use base64::Engine;
use glam::{DMat4, DQuat, DVec3};
use gltf::accessor::{DataType, Dimensions};
use gltf::json::validation::Validate;
use gltf::mesh::Mode;

/// Required extensions that cannot change geometry (materials, textures, lights):
/// a file requiring them still gives the right silhouette.
const HARMLESS_EXTENSIONS: &[&str] = &[
    "KHR_texture_transform",
    "KHR_texture_basisu",
    "EXT_texture_webp",
    "EXT_texture_avif",
    "MSFT_texture_dds",
    "KHR_lights_punctual",
    "KHR_materials_variants",
    "KHR_xmp_json_ld",
];

/// Loads all triangle primitives of the default scene, node transforms applied.
///
/// `file` names the mesh in errors; `bytes` is a GLB container or glTF JSON text;
/// `extra(uri)` supplies external buffers (e.g. `"Box0.bin"`), by URI relative to the
/// mesh file. A missing external buffer gives [`Error::MissingFile`], everything else
/// that is wrong [`Error::Mesh`].
pub fn load(file: &str, bytes: &[u8], extra: Resolver) -> Result<Mesh> {
    load_with(file, bytes, extra, &Limits::DEFAULT)
}

/// As [`load`], the vertex and triangle counts the document declares (over every
/// instance of every mesh) checked against `limits` before any buffer is read.
pub fn load_with(file: &str, bytes: &[u8], extra: Resolver, limits: &Limits) -> Result<Mesh> {
    let err = |problem: String| Error::Mesh {
        file: file.into(),
        problem,
    };
    let (json, blob) = if bytes.starts_with(b"glTF") {
        split_glb(bytes).map_err(err)?
    } else {
        (bytes.to_vec(), None)
    };
    crate::limits::check_json_depth(file, &json)?;
    let root = parse_root(&json).map_err(err)?;
    validate(&root).map_err(err)?;
    let doc = gltf::Document::from_json_without_validation(root);
    let instances = instances(&doc).map_err(err)?;
    let (mut vertices, mut triangles) = (0u64, 0u64);
    for (gmesh, _) in &instances {
        for prim in gmesh.primitives().filter(|p| is_triangles(p.mode())) {
            let n = prim.get(&gltf::Semantic::Positions).map_or(0, |a| a.count() as u64);
            let corners = prim.indices().map_or(n, |a| a.count() as u64);
            // Saturating: declared counts are the file's word, up to u64::MAX each.
            vertices = vertices.saturating_add(n);
            triangles = triangles.saturating_add(match prim.mode() {
                Mode::Triangles => corners / 3,
                _ => corners.saturating_sub(2),
            });
        }
    }
    limits.check_mesh(file, vertices, triangles)?;
    let buffers = load_buffers(file, &doc, blob, extra, &instances)?;
    let mut mesh = Mesh::default();
    for (gmesh, world) in &instances {
        for prim in gmesh.primitives() {
            append_primitive(&mut mesh, &prim, *world, &buffers)
                .map_err(|p| err(format!("mesh {} primitive {}: {p}", gmesh.index(), prim.index())))?;
        }
    }
    if mesh.triangles.is_empty() {
        return Err(err("the scene holds no triangle primitives".into()));
    }
    mesh.validate(file)?;
    Ok(mesh)
}

/// Splits a GLB into its JSON chunk and optional BIN chunk, checking the header first
/// (the crate's splitter assumes a sane length field).
pub(crate) fn split_glb(bytes: &[u8]) -> std::result::Result<(Vec<u8>, Option<Vec<u8>>), String> {
    if bytes.len() < 20 {
        return Err(format!(
            "truncated GLB: {} bytes, shorter than its headers",
            bytes.len()
        ));
    }
    let word = |i: usize| u32::from_le_bytes([bytes[i], bytes[i + 1], bytes[i + 2], bytes[i + 3]]);
    let (version, length) = (word(4), word(8) as usize);
    if version != 2 {
        return Err(format!("GLB version {version} is not supported (expected 2)"));
    }
    if length > bytes.len() {
        return Err(format!(
            "truncated GLB: its header gives {length} bytes but the file has {}",
            bytes.len()
        ));
    }
    if length < 20 {
        return Err(format!("malformed GLB: its header gives a length of {length} bytes"));
    }
    let glb = gltf::Glb::from_slice(&bytes[..length]).map_err(|e| format!("malformed GLB: {e}"))?;
    Ok((glb.json.into_owned(), glb.bin.map(|b| b.into_owned())))
}

/// Parses the JSON document and rejects required extensions that change geometry.
fn parse_root(json: &[u8]) -> std::result::Result<gltf::json::Root, String> {
    match gltf::json::deserialize::from_slice::<gltf::json::Root>(json) {
        Ok(root) => {
            check_required(&root.extensions_required)?;
            Ok(root)
        }
        Err(e) => {
            // A document this crate cannot read may still name an unsupported
            // extension, which is the more useful message.
            if let Ok(v) = serde_json::from_slice::<serde_json::Value>(json) {
                if let Some(list) = v.get("extensionsRequired").and_then(|l| l.as_array()) {
                    let names: Vec<String> = list.iter().filter_map(|s| s.as_str().map(String::from)).collect();
                    check_required(&names)?;
                }
            }
            Err(format!("not a valid glTF document: {e}"))
        }
    }
}

fn check_required(required: &[String]) -> std::result::Result<(), String> {
    for ext in required {
        let harmless = HARMLESS_EXTENSIONS.contains(&ext.as_str()) || ext.starts_with("KHR_materials_");
        if harmless {
            continue;
        }
        return Err(match ext.as_str() {
            "KHR_draco_mesh_compression" => "Draco-compressed meshes are not supported \
                (extensionsRequired: KHR_draco_mesh_compression); export the model without compression"
                .into(),
            "EXT_meshopt_compression" | "KHR_meshopt_compression" => format!(
                "meshopt-compressed buffers are not supported (extensionsRequired: {ext}); \
                 export the model without compression"
            ),
            "KHR_mesh_quantization" => "quantized vertex positions are not supported \
                (extensionsRequired: KHR_mesh_quantization); export the model with float positions"
                .into(),
            _ => format!("the file requires the extension {ext}, which is not supported"),
        });
    }
    Ok(())
}

/// The crate's structural validation (indices in range, enums known), minus its
/// verdict on required extensions, which [`check_required`] has given already, and
/// minus missing POSITION bounds, which are not needed.
fn validate(root: &gltf::json::Root) -> std::result::Result<(), String> {
    // The crate's primitive check indexes `accessors` with POSITION unchecked: check first.
    let position = gltf::json::validation::Checked::Valid(gltf::json::mesh::Semantic::Positions);
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            if let Some(i) = prim
                .attributes
                .get(&position)
                .filter(|i| i.value() >= root.accessors.len())
            {
                return Err(format!(
                    "invalid glTF: meshes[{m}].primitives[{p}] POSITION refers to accessor {}, but there are {}",
                    i.value(),
                    root.accessors.len()
                ));
            }
        }
    }
    let mut errors = Vec::new();
    root.validate(root, gltf::json::Path::new, &mut |path, e| {
        let path = path().to_string();
        // POSITION's min/max are required by the spec but unused here; many exporters omit them.
        let unused_bounds = path.ends_with("].min") || path.ends_with("].max");
        if !path.starts_with("extensionsRequired") && !unused_bounds {
            errors.push(format!("{path}: {e}"));
        }
    });
    if errors.is_empty() {
        return Ok(());
    }
    let n = errors.len();
    errors.truncate(5);
    let more = if n > 5 {
        format!(" (and {} more)", n - 5)
    } else {
        String::new()
    };
    Err(format!("invalid glTF: {}{more}", errors.join("; ")))
}

/// Every mesh instance of the scene with its world transform, in traversal order.
fn instances(doc: &gltf::Document) -> std::result::Result<Vec<(gltf::Mesh<'_>, DMat4)>, String> {
    let roots: Vec<gltf::Node> = match doc.default_scene().or_else(|| doc.scenes().next()) {
        Some(scene) => scene.nodes().collect(),
        None => {
            let mut is_child = vec![false; doc.nodes().len()];
            for n in doc.nodes() {
                for c in n.children() {
                    is_child[c.index()] = true;
                }
            }
            doc.nodes().filter(|n| !is_child[n.index()]).collect()
        }
    };
    let mut seen = vec![false; doc.nodes().len()];
    let mut stack: Vec<(gltf::Node, DMat4)> = roots.into_iter().rev().map(|n| (n, DMat4::IDENTITY)).collect();
    let mut out = Vec::new();
    while let Some((node, parent)) = stack.pop() {
        if std::mem::replace(&mut seen[node.index()], true) {
            return Err(format!(
                "node {} is reached twice: the node hierarchy must be a tree",
                node.index()
            ));
        }
        let world = parent * local_transform(&node);
        if let Some(m) = node.mesh() {
            out.push((m, world));
        }
        let children: Vec<gltf::Node> = node.children().collect();
        stack.extend(children.into_iter().rev().map(|c| (c, world)));
    }
    Ok(out)
}

/// A node's local transform in f64: its column-major `matrix`, or `T·R·S`.
fn local_transform(node: &gltf::Node) -> DMat4 {
    match node.transform() {
        gltf::scene::Transform::Matrix { matrix } => DMat4::from_cols_array_2d(&matrix.map(|c| c.map(f64::from))),
        gltf::scene::Transform::Decomposed {
            translation: t,
            rotation: r,
            scale: s,
        } => {
            let q = DQuat::from_xyzw(r[0].into(), r[1].into(), r[2].into(), r[3].into());
            // Non-unit quaternions are normalised; a zero one gives NaN, caught by Mesh::validate.
            DMat4::from_scale_rotation_translation(
                DVec3::new(s[0].into(), s[1].into(), s[2].into()),
                q.normalize(),
                DVec3::new(t[0].into(), t[1].into(), t[2].into()),
            )
        }
    }
}

fn is_triangles(mode: Mode) -> bool {
    matches!(mode, Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan)
}

/// Fetches the bytes of every buffer the triangle primitives read (others stay `None`).
fn load_buffers(
    file: &str,
    doc: &gltf::Document,
    mut blob: Option<Vec<u8>>,
    extra: Resolver,
    instances: &[(gltf::Mesh, DMat4)],
) -> Result<Vec<Option<Vec<u8>>>> {
    let mut needed = vec![false; doc.buffers().len()];
    let mut mark = |v: gltf::buffer::View| needed[v.buffer().index()] = true;
    for (m, _) in instances {
        for p in m.primitives().filter(|p| is_triangles(p.mode())) {
            for acc in p.get(&gltf::Semantic::Positions).into_iter().chain(p.indices()) {
                if let Some(v) = acc.view() {
                    mark(v);
                }
                if let Some(s) = acc.sparse() {
                    mark(s.indices().view());
                    mark(s.values().view());
                }
            }
        }
    }
    let err = |problem: String| Error::Mesh {
        file: file.into(),
        problem,
    };
    let mut out = Vec::with_capacity(needed.len());
    for buffer in doc.buffers() {
        if !needed[buffer.index()] {
            out.push(None);
            continue;
        }
        let i = buffer.index();
        let (data, name) = match buffer.source() {
            gltf::buffer::Source::Bin => match blob.take() {
                Some(b) => (b, "the GLB's BIN chunk".to_string()),
                None => return Err(err(format!("buffers[{i}] refers to a GLB BIN chunk, which is absent"))),
            },
            gltf::buffer::Source::Uri(uri) if uri.starts_with("data:") => (
                decode_data_uri(uri).map_err(|p| err(format!("buffers[{i}]: {p}")))?,
                format!("buffers[{i}]"),
            ),
            gltf::buffer::Source::Uri(uri) => {
                let decoded = percent_decode(uri);
                let data = extra(uri)
                    .or_else(|| (decoded != uri).then(|| extra(&decoded)).flatten())
                    .ok_or_else(|| Error::MissingFile {
                        file: decoded.clone(),
                        referrer: file.into(),
                    })?;
                (data, format!("'{decoded}'"))
            }
        };
        if data.len() < buffer.length() {
            return Err(err(format!(
                "{name} holds {} bytes but buffers[{i}].byteLength is {}",
                data.len(),
                buffer.length()
            )));
        }
        out.push(Some(data));
    }
    Ok(out)
}

/// Decodes a base64 `data:` URI (any media type, e.g. `application/octet-stream` or
/// `application/gltf-buffer`).
fn decode_data_uri(uri: &str) -> std::result::Result<Vec<u8>, String> {
    let (head, payload) = uri
        .split_once(',')
        .ok_or_else(|| "data URI without a ',' separator".to_string())?;
    if !head.ends_with(";base64") {
        return Err(format!("data URI '{head},…' is not base64-encoded"));
    }
    let engine = base64::engine::GeneralPurpose::new(
        &base64::alphabet::STANDARD,
        base64::engine::GeneralPurposeConfig::new()
            .with_decode_padding_mode(base64::engine::DecodePaddingMode::Indifferent),
    );
    let clean: String = payload.chars().filter(|c| !c.is_ascii_whitespace()).collect();
    engine
        .decode(clean.as_bytes())
        .map_err(|e| format!("invalid base64 in data URI: {e}"))
}

/// Decodes `%XX` escapes of a relative URI (left unchanged where malformed).
fn percent_decode(uri: &str) -> String {
    let b = uri.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        let hex = |c: u8| (c as char).to_digit(16);
        if b[i] == b'%' && i + 2 < b.len() {
            if let (Some(h), Some(l)) = (hex(b[i + 1]), hex(b[i + 2])) {
                out.push((h * 16 + l) as u8);
                i += 3;
                continue;
            }
        }
        out.push(b[i]);
        i += 1;
    }
    String::from_utf8(out).unwrap_or_else(|_| uri.to_string())
}

/// Checks that `count` elements of `elem` bytes at `offset`, `stride` apart, lie inside
/// `view`, and `view` inside its loaded buffer.
fn check_range(
    view: &gltf::buffer::View,
    offset: usize,
    count: usize,
    elem: usize,
    buffers: &[Option<Vec<u8>>],
    what: &str,
) -> std::result::Result<(), String> {
    let vi = view.index();
    let bi = view.buffer().index();
    let buf_len = buffers.get(bi).and_then(|b| b.as_ref()).map_or(0, |b| b.len());
    let view_end = view.offset().checked_add(view.length());
    if !matches!(view_end, Some(e) if e <= buf_len) {
        return Err(format!(
            "bufferViews[{vi}] (offset {}, length {}) runs past the end of buffers[{bi}] ({buf_len} bytes)",
            view.offset(),
            view.length()
        ));
    }
    let stride = view.stride().unwrap_or(elem);
    if stride < elem {
        return Err(format!(
            "{what}: byteStride {stride} of bufferViews[{vi}] is smaller than its {elem}-byte elements"
        ));
    }
    if count == 0 {
        return Err(format!("{what}: count is 0"));
    }
    let end = stride
        .checked_mul(count - 1)
        .and_then(|x| x.checked_add(elem))
        .and_then(|x| x.checked_add(offset));
    match end {
        Some(e) if e <= view.length() => Ok(()),
        _ => Err(format!(
            "{what}: {count} elements of {elem} bytes from offset {offset} do not fit in bufferViews[{vi}] ({} bytes)",
            view.length()
        )),
    }
}

/// Checks an accessor (dense part and sparse part) so that the crate's reader cannot
/// slice out of range.
fn check_accessor(acc: &gltf::Accessor, elem: usize, buffers: &[Option<Vec<u8>>]) -> std::result::Result<(), String> {
    let what = format!("accessors[{}]", acc.index());
    if acc.count() == 0 {
        return Err(format!("{what}: count is 0"));
    }
    if let Some(view) = acc.view() {
        check_range(&view, acc.offset(), acc.count(), elem, buffers, &what)?;
    }
    if let Some(sparse) = acc.sparse() {
        let (ix, vals) = (sparse.indices(), sparse.values());
        let n = sparse.count();
        let w = format!("{what}.sparse");
        check_range(
            &ix.view(),
            ix.offset(),
            n,
            ix.index_type().size(),
            buffers,
            &format!("{w}.indices"),
        )?;
        check_range(&vals.view(), vals.offset(), n, elem, buffers, &format!("{w}.values"))?;
    }
    Ok(())
}

/// Appends one primitive's triangles, its vertices moved by `world`.
fn append_primitive(
    mesh: &mut Mesh,
    prim: &gltf::Primitive,
    world: DMat4,
    buffers: &[Option<Vec<u8>>],
) -> std::result::Result<(), String> {
    if !is_triangles(prim.mode()) {
        return Ok(());
    }
    let pos = prim
        .get(&gltf::Semantic::Positions)
        .ok_or_else(|| "has no POSITION attribute".to_string())?;
    if pos.data_type() != DataType::F32 || pos.dimensions() != Dimensions::Vec3 {
        return Err(format!(
            "POSITION (accessors[{}]) is {:?} {:?}; only float VEC3 is supported",
            pos.index(),
            pos.data_type(),
            pos.dimensions()
        ));
    }
    check_accessor(&pos, 12, buffers)?;
    if let Some(ix) = prim.indices() {
        let size = match ix.data_type() {
            DataType::U8 => 1,
            DataType::U16 => 2,
            DataType::U32 => 4,
            t => return Err(format!("indices (accessors[{}]) have component type {t:?}", ix.index())),
        };
        if ix.dimensions() != Dimensions::Scalar || ix.sparse().is_some() {
            return Err(format!(
                "indices (accessors[{}]) must be dense SCALAR values",
                ix.index()
            ));
        }
        check_accessor(&ix, size, buffers)?;
    }
    let reader = prim.reader(|b| buffers.get(b.index()).and_then(|d| d.as_deref()));
    let positions: Vec<[f32; 3]> = reader
        .read_positions()
        .ok_or_else(|| "POSITION data cannot be read".to_string())?
        .collect();
    if positions.len() != pos.count() {
        return Err(format!(
            "POSITION gives {} of its {} vertices",
            positions.len(),
            pos.count()
        ));
    }
    let n = positions.len() as u64;
    let order: Vec<u32> = match reader.read_indices() {
        Some(ix) => ix.into_u32().collect(),
        None if prim.indices().is_some() => return Err("index data cannot be read".into()),
        None => (0..n as u32).collect(),
    };
    if let Some(bad) = order.iter().find(|&&i| i as u64 >= n) {
        return Err(format!("index {bad} is beyond the primitive's {n} vertices"));
    }
    let base = u32::try_from(mesh.positions.len())
        .ok()
        .filter(|b| (*b as u64) + n <= u32::MAX as u64)
        .ok_or_else(|| "the mesh has more than 2³² vertices".to_string())?;
    mesh.positions.extend(
        positions
            .iter()
            .map(|p| world.transform_point3(DVec3::new(p[0].into(), p[1].into(), p[2].into()))),
    );
    // A mirroring transform turns the winding over; keep it counter-clockwise.
    let flip = world.determinant() < 0.0;
    let mut push = |a: u32, b: u32, c: u32| {
        let t = if flip { [c, b, a] } else { [a, b, c] };
        mesh.triangles.push(t.map(|i| base + i));
    };
    match prim.mode() {
        Mode::Triangles => order.chunks_exact(3).for_each(|t| push(t[0], t[1], t[2])),
        Mode::TriangleStrip => {
            for (i, w) in order.windows(3).enumerate() {
                // glTF: triangle i is (v_i, v_{i+1+i%2}, v_{i+2-i%2}); degenerate ones are restarts.
                let t = if i % 2 == 0 {
                    [w[0], w[1], w[2]]
                } else {
                    [w[0], w[2], w[1]]
                };
                if t[0] != t[1] && t[1] != t[2] && t[0] != t[2] {
                    push(t[0], t[1], t[2]);
                }
            }
        }
        Mode::TriangleFan => {
            for w in order.get(1..).unwrap_or(&[]).windows(2) {
                if w[0] != w[1] && w[0] != order[0] && w[1] != order[0] {
                    push(w[0], w[1], order[0]);
                }
            }
        }
        _ => {}
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::no_files;

    /// A one-primitive glTF with 4 positions (a unit square at z = 0) in a data URI.
    fn gltf_text(mode: u32, indices: Option<&[u16]>, node: &str, extra_json: &str) -> String {
        let mut bin: Vec<u8> = [[0f32, 0., 0.], [1., 0., 0.], [1., 1., 0.], [0., 1., 0.]]
            .iter()
            .flatten()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        let ix = indices.unwrap_or(&[]);
        bin.extend(ix.iter().flat_map(|i| i.to_le_bytes()));
        while !bin.len().is_multiple_of(4) {
            bin.push(0);
        }
        let b64 = base64::engine::general_purpose::STANDARD.encode(&bin);
        let (idx_acc, idx_view, idx_attr) = match indices {
            Some(ix) => (
                format!(
                    r#",{{"bufferView":1,"componentType":5123,"count":{},"type":"SCALAR"}}"#,
                    ix.len()
                ),
                format!(r#",{{"buffer":0,"byteOffset":48,"byteLength":{}}}"#, ix.len() * 2),
                r#","indices":1"#,
            ),
            None => (String::new(), String::new(), ""),
        };
        format!(
            r#"{{"asset":{{"version":"2.0"}}{extra_json},"scene":0,"scenes":[{{"nodes":[0]}}],
            "nodes":[{node}],
            "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"mode":{mode}{idx_attr}}}]}}],
            "accessors":[{{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3"}}{idx_acc}],
            "bufferViews":[{{"buffer":0,"byteLength":48}}{idx_view}],
            "buffers":[{{"byteLength":{},"uri":"data:application/octet-stream;base64,{b64}"}}]}}"#,
            bin.len()
        )
    }

    #[test]
    fn strips_fans_and_lists_cover_the_same_square() {
        let node = r#"{"mesh":0}"#;
        let list = load(
            "l.gltf",
            gltf_text(4, Some(&[0, 1, 2, 0, 2, 3]), node, "").as_bytes(),
            &no_files,
        )
        .unwrap();
        let strip = load(
            "s.gltf",
            gltf_text(5, Some(&[1, 2, 0, 3]), node, "").as_bytes(),
            &no_files,
        )
        .unwrap();
        let fan = load("f.gltf", gltf_text(6, None, node, "").as_bytes(), &no_files).unwrap();
        assert_eq!(list.triangles.len(), 2);
        assert_eq!(strip.triangles.len(), 2);
        assert_eq!(fan.triangles, vec![[1, 2, 0], [2, 3, 0]]);
        // Strip triangle 1 is (v1, v3, v2) = (2, 3, 0): counter-clockwise like triangle 0.
        assert_eq!(strip.triangles, vec![[1, 2, 0], [2, 3, 0]]);
        let lines = load("p.gltf", gltf_text(1, None, node, "").as_bytes(), &no_files).unwrap_err();
        assert!(lines.to_string().contains("no triangle primitives"), "{lines}");
    }

    #[test]
    fn trs_is_translation_rotation_scale_in_that_order() {
        // Scale x by 2, rotate 90° about z, then translate by (10, 0, 0): (1,0,0) → (10, 2, 0).
        let h = std::f64::consts::FRAC_1_SQRT_2;
        let node = format!(r#"{{"mesh":0,"translation":[10,0,0],"rotation":[0,0,{h},{h}],"scale":[2,1,1]}}"#);
        let m = load("t.gltf", gltf_text(6, None, &node, "").as_bytes(), &no_files).unwrap();
        assert!(
            (m.positions[1] - DVec3::new(10.0, 2.0, 0.0)).length() < 1e-6,
            "{:?}",
            m.positions[1]
        );
        // A mirror (negative scale) keeps the winding counter-clockwise by reversing it.
        let mirror = r#"{"mesh":0,"scale":[-1,1,1]}"#;
        let m = load("m.gltf", gltf_text(6, None, mirror, "").as_bytes(), &no_files).unwrap();
        assert_eq!(m.triangles[0], [0, 2, 1]);
    }

    #[test]
    fn required_extensions_are_named() {
        let node = r#"{"mesh":0}"#;
        let req = |e: &str| format!(r#","extensionsRequired":["{e}"],"extensionsUsed":["{e}"]"#);
        let e = load(
            "d.gltf",
            gltf_text(4, None, node, &req("KHR_draco_mesh_compression")).as_bytes(),
            &no_files,
        );
        assert!(e
            .unwrap_err()
            .to_string()
            .contains("Draco-compressed meshes are not supported"));
        let e = load(
            "o.gltf",
            gltf_text(4, None, node, &req("EXT_meshopt_compression")).as_bytes(),
            &no_files,
        );
        assert!(e.unwrap_err().to_string().contains("EXT_meshopt_compression"));
        let e = load(
            "x.gltf",
            gltf_text(4, None, node, &req("VENDOR_magic")).as_bytes(),
            &no_files,
        );
        assert!(e.unwrap_err().to_string().contains("VENDOR_magic"));
        // Material-only extensions do not change the silhouette and are accepted.
        let ok = load(
            "k.gltf",
            gltf_text(6, None, node, &req("KHR_materials_unlit")).as_bytes(),
            &no_files,
        );
        assert_eq!(ok.unwrap().triangles.len(), 2);
    }

    /// Found by `damaged_meshes_are_refused_cleanly` (tests/integration/properties.rs):
    /// an accessor declaring 2⁶³ + 3 positions, instanced three times, overflowed the
    /// count summed over the instances (a panic in debug builds); its input is
    /// `fuzz/regressions/gltf/instanced-count-overflow`.
    #[test]
    fn declared_counts_that_overflow_when_summed_are_refused_by_the_limits() {
        let nodes = r#"{"mesh":0},{"mesh":0},{"mesh":0}"#;
        let text = gltf_text(4, None, nodes, "")
            .replace(r#""nodes":[0]"#, r#""nodes":[0,1,2]"#)
            .replace(
                r#""count":4,"type":"VEC3""#,
                r#""count":9223372036854775811,"type":"VEC3""#,
            );
        assert!(text.contains("9223372036854775811") && text.contains("[0,1,2]"));
        let e = load("huge.gltf", text.as_bytes(), &no_files).unwrap_err().to_string();
        assert!(e.contains("huge.gltf") && e.contains("vertex count"), "{e}");
        // The file as the property made it (kept in the fuzz targets' raw mode: after a 0 byte).
        let kept = std::fs::read(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/fuzz/regressions/gltf/instanced-count-overflow"
        ))
        .unwrap();
        let e = load("huge.glb", &kept[1..], &no_files).unwrap_err().to_string();
        assert!(e.contains("huge.glb") && e.contains("vertex count"), "{e}");
    }

    #[test]
    fn out_of_range_data_is_an_error() {
        let node = r#"{"mesh":0}"#;
        let text = gltf_text(4, Some(&[0, 1, 7]), node, "");
        let e = load("i.gltf", text.as_bytes(), &no_files).unwrap_err().to_string();
        assert!(e.contains("index 7 is beyond"), "{e}");
        let text = gltf_text(4, None, node, "").replace(r#""count":4"#, r#""count":5"#);
        let e = load("c.gltf", text.as_bytes(), &no_files).unwrap_err().to_string();
        assert!(e.starts_with("mesh 'c.gltf'") && e.contains("do not fit"), "{e}");
        let text = gltf_text(4, None, node, "").replace(r#""byteLength":48}"#, r#""byteLength":48,"byteStride":4}"#);
        let e = load("s.gltf", text.as_bytes(), &no_files).unwrap_err().to_string();
        assert!(e.contains("byteStride 4"), "{e}");
        let cyclic = gltf_text(4, None, r#"{"mesh":0,"children":[0]}"#, "");
        let e = load("n.gltf", cyclic.as_bytes(), &no_files).unwrap_err().to_string();
        assert!(e.contains("reached twice"), "{e}");
    }

    #[test]
    fn data_uris_and_percent_escapes() {
        assert_eq!(
            decode_data_uri("data:application/gltf-buffer;base64,AAEC").unwrap(),
            vec![0, 1, 2]
        );
        assert_eq!(
            decode_data_uri("data:application/octet-stream;base64,AAE").unwrap(),
            vec![0, 1]
        );
        assert!(decode_data_uri("data:text/plain,hello").is_err());
        assert_eq!(percent_decode("my%20box.bin"), "my box.bin");
        assert_eq!(percent_decode("100%"), "100%");
    }
}
