//! Property tests of every reader (issue item 1, the stable tier CI runs on every
//! submission; `fuzz/` is the nightly tier). Strategies make valid-shaped structures —
//! scenes of 1–4 views, cameras, poses and grasps with numbers at the edges (NaN, ±∞,
//! 1e300, denormals, −0, the limits' bounds), meshes as PLY (ASCII and binary, any
//! scalar types), OBJ and glTF (GLB, data URI, external buffer; by hand and by the
//! project's writers), PNG masks and images of every pixel format, BOP and NeRF
//! folders, the files a page drops — serialise them (`fuzz/src/formats/`, shared with
//! the fuzz targets), damage the bytes (bit flips, cuts, insertions), and feed the entry
//! points the CLI and the wasm binding use. Every input must give `Ok` or a clean
//! `Err`: never a panic or a hang; an `Ok` is checked (finite numbers, indices in range,
//! rotations that are rotations, sizes within the limits they were loaded under). Each
//! valid, undamaged input must load, and give back what was written (counts, vertices,
//! mask pixels): so each property can fail.
//!
//! Bounded: 1–2 thousand small cases per property, no failure files
//! (`failure_persistence: None`); the whole module runs in a second or two. The bugs
//! they and the fuzz targets found are fixed, each with a regression test in its
//! reader's module and its input in `fuzz/regressions/`.

#[path = "../../fuzz/src/formats/mod.rs"]
mod formats;

use formats::*;
use localisebot::io::bop::BoxHints;
use localisebot::Limits;
use proptest::collection::vec;
use proptest::prelude::*;
use proptest::sample::select;

fn config(cases: u32) -> ProptestConfig {
    ProptestConfig {
        cases,
        failure_persistence: None,
        max_shrink_iters: 2048,
        ..ProptestConfig::default()
    }
}

// ---------------------------------------------------------------------------------
// Numbers

const EDGES: [f64; 24] = [
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

/// Any number, the edges often.
fn wild() -> impl Strategy<Value = f64> {
    prop_oneof![
        4 => -1e3..1e3f64,
        2 => select(EDGES.to_vec()),
        1 => any::<f64>(),
    ]
}

fn quat() -> impl Strategy<Value = [f64; 4]> {
    prop::array::uniform4(-1.0..1.0f64).prop_map(|q| {
        let n = q.iter().map(|v| v * v).sum::<f64>().sqrt();
        if n < 1e-3 {
            [1.0, 0.0, 0.0, 0.0]
        } else {
            q.map(|v| v / n)
        }
    })
}

/// Counts and indices at the edges.
fn wild_int() -> impl Strategy<Value = i64> {
    select(vec![
        -1i64,
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
    ])
}

fn mutations() -> impl Strategy<Value = Vec<Mutation>> {
    let bytes = prop_oneof![vec(any::<u8>(), 1..6), select(TOKENS.to_vec()).prop_map(|t| t.to_vec()),];
    let one = prop_oneof![
        (any::<usize>(), any::<u8>()).prop_map(|(at, bit)| Mutation::Flip { at, bit }),
        any::<usize>().prop_map(|at| Mutation::Truncate { at }),
        (any::<usize>(), bytes.clone()).prop_map(|(at, bytes)| Mutation::Insert { at, bytes }),
        (any::<usize>(), bytes).prop_map(|(at, bytes)| Mutation::Overwrite { at, bytes }),
        (any::<usize>(), any::<usize>(), any::<usize>()).prop_map(|(from, len, to)| Mutation::Repeat { from, len, to }),
    ];
    prop_oneof![1 => Just(vec![]), 1 => vec(one, 1..4)]
}

/// The defaults, or limits low enough that the small inputs here meet them.
fn limits() -> impl Strategy<Value = Limits> {
    prop_oneof![
        3 => Just(Limits::DEFAULT),
        1 => (
            select(vec!["file_bytes", "view_pixels", "total_pixels", "views", "vertices", "triangles"]),
            prop_oneof![1u64..16, 1u64..400],
        )
            .prop_map(|(name, v)| {
                let mut l = Limits::DEFAULT;
                l.set(name, v).unwrap();
                l
            }),
    ]
}

// ---------------------------------------------------------------------------------
// Meshes and their formats

/// A mesh every reader accepts: a unit triangle, up to 8 more vertices within ±10 and
/// up to 5 more polygons of 3–5 corners.
fn sane_mesh() -> impl Strategy<Value = MeshSpec> {
    vec(prop::array::uniform3(-10.0..10.0f64), 0..8)
        .prop_flat_map(|extra| {
            let n = 3 + extra.len() as i64;
            (Just(extra), vec(vec(0..n, 3..=5), 0..6))
        })
        .prop_map(|(p, f)| MeshSpec::with_base(&p, &f))
}

/// A sane mesh with some numbers and indices at the edges, and faces of 0–2 corners.
fn wild_mesh() -> impl Strategy<Value = MeshSpec> {
    (
        sane_mesh(),
        vec((any::<usize>(), 0usize..3, wild()), 0..3),
        vec((any::<usize>(), any::<usize>(), wild_int()), 0..3),
        vec(vec(0i64..12, 0..3), 0..2),
        any::<bool>(),
    )
        .prop_map(|(mut m, coords, indices, short, flat)| {
            let n = m.positions.len();
            for (i, a, v) in coords {
                m.positions[i % n][a] = v;
            }
            let nf = m.faces.len();
            for (f, k, v) in indices {
                let face = &mut m.faces[f % nf];
                let len = face.len();
                face[k % len] = v;
            }
            m.faces.extend(short);
            if flat {
                // Every vertex on one line: no area.
                for p in &mut m.positions {
                    *p = [p[0], 2.0 * p[0], 0.0];
                }
            }
            m
        })
}

fn scalar(valid: &'static [Scalar]) -> impl Strategy<Value = Scalar> {
    select(valid)
}

fn encoding() -> impl Strategy<Value = PlyEncoding> {
    select(vec![PlyEncoding::Ascii, PlyEncoding::BinaryLe, PlyEncoding::BinaryBe])
}

fn ply_opts(sane: bool) -> impl Strategy<Value = PlyOpts> {
    let (coords, counts, indices): (&'static [Scalar], &'static [Scalar], &'static [Scalar]) = if sane {
        (
            &[Scalar::Float, Scalar::Double],
            &[Scalar::UChar, Scalar::UShort, Scalar::Int, Scalar::UInt],
            &[Scalar::Int, Scalar::UInt],
        )
    } else {
        (&SCALARS, &SCALARS, &SCALARS)
    };
    let delta = if sane {
        Just(0i64).boxed()
    } else {
        prop_oneof![3 => Just(0i64), 1 => wild_int()].boxed()
    };
    (
        encoding(),
        scalar(coords),
        scalar(counts),
        scalar(indices),
        prop::array::uniform6(any::<bool>()),
        delta.clone(),
        delta,
    )
        .prop_map(|(encoding, coord, count, index, f, vertex_delta, face_delta)| PlyOpts {
            encoding,
            coord,
            count,
            index,
            aliases: f[0],
            vertex_index_name: f[1],
            extra_properties: f[2],
            extra_element: f[3],
            comment: f[4],
            crlf: f[5],
            vertex_delta,
            face_delta,
        })
}

fn obj_opts() -> impl Strategy<Value = ObjOpts> {
    prop::array::uniform6(any::<bool>()).prop_map(|f| ObjOpts {
        negative: f[0],
        texcoords: f[1],
        objects: f[2],
        comments: f[3],
        crlf: f[4],
        tabs: f[5],
        odd_space: 0,
    })
}

fn container() -> impl Strategy<Value = Container> {
    select(vec![Container::Glb, Container::DataUri, Container::External])
}

fn sane_transform() -> impl Strategy<Value = NodeTransform> {
    prop_oneof![
        Just(NodeTransform::None),
        (
            prop::option::of(prop::array::uniform3(-5.0..5.0f64)),
            prop::option::of(quat().prop_map(|[w, x, y, z]| [x, y, z, w])),
            prop::option::of(prop::array::uniform3(0.5..2.0f64)),
        )
            .prop_map(|(t, r, s)| NodeTransform::Trs { t, r, s }),
        (quat(), prop::array::uniform3(-5.0..5.0f64)).prop_map(|(q, t)| {
            let m = rigid(q, t);
            let mut c = [0.0; 16];
            for (col, row) in (0..4).flat_map(|c| (0..4).map(move |r| (c, r))) {
                c[col * 4 + row] = m[row][col];
            }
            NodeTransform::Matrix(c)
        }),
    ]
}

fn wild_transform() -> impl Strategy<Value = NodeTransform> {
    prop_oneof![
        sane_transform(),
        prop::array::uniform16(wild()).prop_map(NodeTransform::Matrix),
        (
            prop::option::of(prop::array::uniform3(wild())),
            prop::option::of(prop::array::uniform4(wild())),
            prop::option::of(prop::array::uniform3(wild())),
        )
            .prop_map(|(t, r, s)| NodeTransform::Trs { t, r, s }),
    ]
}

fn wild_extra() -> BoxedStrategy<GltfExtra> {
    let ix = || wild_int().prop_map(|v| v.clamp(-1, 1 << 32));
    prop_oneof![
        (ix(), ix(), ix(), ix()).prop_map(|(sampler, node, input, output)| GltfExtra::Animation {
            sampler,
            node,
            input,
            output
        }),
        (vec(ix(), 0..3), prop::option::of(ix())).prop_map(|(joints, matrices)| GltfExtra::Skin { joints, matrices }),
        Just(GltfExtra::Camera),
        prop::option::of((ix(), ix())).prop_map(|texture| GltfExtra::Material { texture }),
        select(vec![
            "KHR_draco_mesh_compression",
            "KHR_mesh_quantization",
            "EXT_meshopt_compression",
            "KHR_texture_transform",
            "KHR_materials_unlit",
            "EXT_unknown",
        ])
        .prop_map(|s| GltfExtra::Required(s.into())),
        (ix(), ix(), ix(), select(vec![5121i64, 5123, 5125, 5126])).prop_map(
            |(count, indices_view, values_view, index_type)| GltfExtra::Sparse {
                count,
                indices_view,
                values_view,
                index_type
            }
        ),
        (ix(), ix(), prop::option::of(ix())).prop_map(|(mode, position, indices)| GltfExtra::Primitive {
            mode,
            position,
            indices
        }),
        Just(GltfExtra::Cycle),
        vec(ix(), 0..3).prop_map(|nodes| GltfExtra::Scene { nodes }),
        Just(GltfExtra::Instance),
    ]
    .boxed()
}

fn gltf_opts(sane: bool) -> BoxedStrategy<GltfOpts> {
    if sane {
        (
            container(),
            select(vec![None, Some(4i64)]),
            select(vec![None, Some(5121i64), Some(5123), Some(5125)]),
            select(vec![None, Some(12i64), Some(16), Some(32)]),
            select(vec![0i64, 4, 8]),
            sane_transform(),
            0u8..3,
            select(vec![None, Some(0i64)]),
            vec(
                prop_oneof![
                    Just(GltfExtra::Camera),
                    Just(GltfExtra::Material { texture: None }),
                    Just(GltfExtra::Instance),
                    Just(GltfExtra::Required("KHR_materials_unlit".into())),
                ],
                0..3,
            ),
        )
            .prop_map(
                |(container, mode, index_type, stride, offset, transform, depth, scene, extras)| GltfOpts {
                    mode,
                    index_type,
                    stride,
                    offset,
                    transform,
                    depth,
                    scene,
                    extras,
                    ..GltfOpts::plain(container)
                },
            )
            .boxed()
    } else {
        let delta = || prop_oneof![3 => Just(0i64), 1 => wild_int(), 1 => -4i64..4];
        (
            (
                container(),
                prop::option::of(prop_oneof![0i64..7, wild_int()]),
                prop::option::of(select(vec![5120i64, 5121, 5122, 5123, 5125, 5126, 0])),
                prop::option::of(select(vec![0i64, 4, 8, 12, 13, 16, 252, 256, 1 << 31])),
                prop_oneof![3 => Just(0i64), 1 => select(vec![4i64, 3, 1 << 20, -4, 1 << 40])],
            ),
            (delta(), delta(), delta(), delta()),
            prop::option::of((
                select(vec![5120i64, 5121, 5122, 5123, 5125, 5126, 1]),
                select(vec!["SCALAR", "VEC2", "VEC3", "VEC4", "MAT4", "vec3"]),
            )),
            wild_transform(),
            0u8..10,
            prop::option::of(wild_int()),
            vec(wild_extra(), 0..4),
        )
            .prop_map(
                |(
                    (container, mode, index_type, stride, offset),
                    (count_delta, index_count_delta, view_len_delta, buffer_len_delta),
                    position_type,
                    transform,
                    depth,
                    scene,
                    extras,
                )| GltfOpts {
                    container,
                    mode,
                    index_type,
                    stride,
                    offset,
                    count_delta,
                    index_count_delta,
                    view_len_delta,
                    buffer_len_delta,
                    position_type: position_type.map(|(c, t)| (c, t.to_string())),
                    transform,
                    depth,
                    scene,
                    extras,
                },
            )
            .boxed()
    }
}

fn mesh_format(sane: bool) -> impl Strategy<Value = MeshFormat> {
    prop_oneof![
        3 => ply_opts(sane).prop_map(MeshFormat::Ply),
        2 => obj_opts().prop_map(MeshFormat::Obj),
        3 => gltf_opts(sane).prop_map(MeshFormat::Gltf),
        1 => Just(MeshFormat::PlyWriter),
        1 => Just(MeshFormat::GlbWriter),
        1 => Just(MeshFormat::GltfWriter),
    ]
}

/// The (vertices, triangles) a reader must give for a sane mesh in a sane format.
fn expected_counts(m: &MeshSpec, f: &MeshFormat) -> (Option<usize>, usize) {
    let tris = m.fan_triangles().len();
    let n = m.positions.len();
    match f {
        MeshFormat::Ply(_) | MeshFormat::PlyWriter | MeshFormat::GlbWriter | MeshFormat::GltfWriter => (Some(n), tris),
        // OBJ keeps the vertices its faces use.
        MeshFormat::Obj(_) => (None, tris),
        MeshFormat::Gltf(o) => {
            let k = 1 + o.extras.iter().filter(|e| **e == GltfExtra::Instance).count();
            let v = if o.index_type.is_some() { n } else { 3 * tris };
            (Some(k * v), k * tris)
        }
    }
}

proptest! {
    #![proptest_config(config(2048))]

    /// A valid mesh file loads, with the vertices and triangles written (PLY: the very
    /// numbers, as its scalar type stores them).
    #[test]
    fn meshes_load_as_written(mesh in sane_mesh(), format in mesh_format(true)) {
        let (name, files) = mesh_files(&mesh, &format, "mesh").expect("the writers take a valid mesh");
        let m = drive_mesh(&name, &files, &Limits::DEFAULT)
            .unwrap_or_else(|e| panic!("{format:?}: {e}\n{}", text_of(&files[&name])));
        let (v, t) = expected_counts(&mesh, &format);
        prop_assert_eq!(m.triangles.len(), t);
        if let Some(v) = v {
            prop_assert_eq!(m.positions.len(), v);
        } else {
            // Each `o` object keeps its own copy of the vertices its faces use.
            prop_assert!(m.positions.len() <= 2 * mesh.positions.len());
        }
        if let MeshFormat::Ply(o) = &format {
            for (got, want) in m.positions.iter().zip(&mesh.positions) {
                prop_assert_eq!(got.to_array(), want.map(|c| o.coord.stored(c)));
            }
            let want: Vec<[u32; 3]> = mesh.fan_triangles().iter().map(|t| t.map(|i| i as u32)).collect();
            prop_assert_eq!(&m.triangles, &want);
        }
    }

    /// Any mesh file, damaged or not, under any limits: `Ok` (checked) or a clean `Err`.
    #[test]
    fn damaged_meshes_are_refused_cleanly(
        mesh in wild_mesh(),
        format in mesh_format(false),
        damage in mutations(),
        target in any::<usize>(),
        limits in limits(),
    ) {
        if let Some((name, mut files)) = mesh_files(&mesh, &format, "mesh") {
            mutate_files(&mut files, target, &damage);
            let _ = drive_mesh(&name, &files, &limits);
        }
    }
}

proptest! {
    #![proptest_config(config(64))]

    /// An OBJ over the `triangles` limit is refused, whatever whitespace separates its
    /// words.
    ///
    /// Found by this property (fixed; a regression test in the reader's module).
    #[test]
    fn obj_limits_hold_whatever_the_whitespace(mesh in sane_mesh(), odd_space in 1u8..4, opts in obj_opts()) {
        let tris = mesh.fan_triangles().len() as u64;
        prop_assume!(tris >= 2);
        let files = Files::from([("mesh.obj".to_string(), obj_bytes(&mesh, &ObjOpts { odd_space, ..opts }))]);
        let mut limits = Limits::DEFAULT;
        limits.triangles = tris - 1;
        // An accepted mesh over the limit panics in `drive_mesh` (`check_mesh_limits`).
        let r = drive_mesh("mesh.obj", &files, &limits);
        prop_assert!(r.is_err());
    }
}

proptest! {
    #![proptest_config(config(256))]

    /// A GLB whose header gives any version and length gets a clean answer from both
    /// things the page does with a mesh file: list the files it refers to
    /// (`fileset::mesh_references`, the binding's `meshFiles`) and load it.
    ///
    /// Found by this property (fixed; a regression test in the reader's module).
    #[test]
    fn glb_headers_of_any_length_get_a_clean_answer(
        mesh in sane_mesh(),
        version in prop_oneof![Just(2u32), any::<u32>()],
        length in prop_oneof![0u32..24, any::<u32>()],
    ) {
        let (name, mut files) = mesh_files(&mesh, &MeshFormat::GlbWriter, "mesh").unwrap();
        let glb = files.get_mut(&name).unwrap();
        glb[4..8].copy_from_slice(&version.to_le_bytes());
        glb[8..12].copy_from_slice(&length.to_le_bytes());
        let _ = localisebot::io::fileset::mesh_references(&name, &files[&name]);
        let _ = drive_mesh(&name, &files, &Limits::DEFAULT);
    }
}

proptest! {
    #![proptest_config(config(256))]

    /// An OBJ face corner's texture and normal indices may be relative (negative) and
    /// out of range: a clean answer either way (only positions are used).
    ///
    /// Found by this property (fixed; a regression test in the reader's module).
    #[test]
    fn obj_texture_and_normal_indices_get_a_clean_answer(
        mesh in sane_mesh(),
        corners in vec((-6i64..4, -6i64..4), 3..6),
        normals in any::<bool>(),
    ) {
        let mut text = String::from_utf8(obj_bytes(&mesh, &ObjOpts::default())).unwrap();
        text += "vt 0.5 0.5\nvn 0 0 1\n";
        let parts: Vec<String> = corners
            .iter()
            .enumerate()
            .map(|(i, (t, n))| {
                let v = i % 3 + 1;
                if normals { format!("{v}/{t}/{n}") } else { format!("{v}/{t}") }
            })
            .collect();
        text += &format!("f 1/1 2/1 3/1\nf {}\n", parts.join(" "));
        if let Ok(m) = localisebot::io::load_mesh_with("mesh.obj", text.as_bytes(), &localisebot::io::no_files, &Limits::DEFAULT) {
            check_mesh(&m);
        }
    }
}

// ---------------------------------------------------------------------------------
// PNG masks and images

fn mask(w: u32, h: u32) -> impl Strategy<Value = MaskSpec> {
    (select(PNG_KINDS.to_vec()), vec(0u8..2, 1..=(w * h) as usize)).prop_map(move |(kind, mut bits)| {
        bits[0] = 1;
        MaskSpec {
            kind,
            width: w,
            height: h,
            bits,
        }
    })
}

/// A colourful photograph (its first pixel is not grey, so it is never taken for a mask).
fn image(w: u32, h: u32) -> impl Strategy<Value = ImageSpec> {
    vec(any::<u8>(), 3..13).prop_map(move |mut rgb| {
        rgb[..3].copy_from_slice(&[10, 200, 30]);
        ImageSpec {
            width: w,
            height: h,
            rgb,
            alpha: None,
        }
    })
}

fn sized<S: Strategy, F: Fn(u32, u32) -> S>(f: F) -> impl Strategy<Value = S::Value> {
    (1u32..=17, 1u32..=17).prop_flat_map(move |(w, h)| f(w, h))
}

proptest! {
    #![proptest_config(config(2048))]

    /// A mask PNG of any pixel format reads as the pixels written; as an image, at its size.
    #[test]
    fn masks_read_as_written(m in sized(mask)) {
        let png = m.png();
        let (mask, img) = drive_png(&png, (m.width, m.height));
        let mask = mask.unwrap_or_else(|e| panic!("{:?}: {e}", m.kind));
        prop_assert_eq!(mask.data, m.pixels());
        let img = img.unwrap();
        prop_assert_eq!((img.width, img.height), (m.width, m.height));
    }

    /// Any PNG, damaged, or declaring a canvas its data does not hold: a clean answer.
    #[test]
    fn damaged_pngs_are_refused_cleanly(
        m in sized(mask),
        declared in prop::option::of((
            select(vec![0u32, 1, 2, 16384, 16385, 1 << 20, u32::MAX, 1 << 31]),
            select(vec![0u32, 1, 3, 16385, 1 << 20, u32::MAX]),
        )),
        damage in mutations(),
    ) {
        let mut png = match declared {
            None => m.png(),
            Some((w, h)) => {
                // The mask's chunks under a header of another size.
                let raw = m.png();
                let (color, depth) = m.kind.header();
                let ihdr_end = 8 + 25;
                let mut out = png_file(w, h, color, depth, None, None, &[]);
                out.truncate(ihdr_end);
                out.extend_from_slice(&raw[ihdr_end..]);
                out
            }
        };
        mutate(&mut png, &damage);
        let _ = drive_png(&png, (m.width, m.height));
    }
}

/// A JPEG photograph of 1–40 px sides (pixels repeated from a random palette), grey or
/// colour, at quality 1–100, with no EXIF block or the orientation tag 1–10 (9 and 10
/// are not valid tags); with the size it is shown at (5–8 turn it a quarter).
fn jpeg_case() -> impl Strategy<Value = (Vec<u8>, (u32, u32))> {
    (
        (1u32..=40, 1u32..=40),
        vec(any::<u8>(), 1..64),
        any::<bool>(),
        1u8..=100,
        prop::option::of(1u8..=10),
    )
        .prop_map(|((w, h), px, grey, quality, orientation)| {
            let (channels, color) = match grey {
                true => (1, image::ExtendedColorType::L8),
                false => (3, image::ExtendedColorType::Rgb8),
            };
            let data: Vec<u8> = px.iter().copied().cycle().take((w * h) as usize * channels).collect();
            let bytes = crate::support::jpeg::jpeg(&data, w, h, color, quality, orientation);
            let turned = orientation.is_some_and(|o| (5..=8).contains(&o));
            (bytes, if turned { (h, w) } else { (w, h) })
        })
}

proptest! {
    #![proptest_config(config(1024))]

    /// A JPEG photograph, grey or colour, at any quality and EXIF orientation (or a tag
    /// that is not one), reads at the size it is shown at.
    #[test]
    fn jpegs_read_at_the_size_they_are_shown_at((bytes, want) in jpeg_case()) {
        prop_assert_eq!(localisebot::io::mask::dimensions(&bytes).unwrap(), want);
        let img = localisebot::io::mask::decode_image_sized(&bytes, "v", "i.jpg", want.0, want.1).unwrap();
        prop_assert_eq!((img.width, img.height), want);
        prop_assert_eq!(img.data.len(), 4 * (want.0 * want.1) as usize);
    }

    /// Any JPEG, damaged (its markers, its EXIF block, its entropy-coded data): a clean
    /// answer, never a panic.
    #[test]
    fn damaged_jpegs_are_refused_cleanly((mut bytes, shown) in jpeg_case(), damage in mutations()) {
        mutate(&mut bytes, &damage);
        let _ = drive_png(&bytes, shown);
    }
}

// ---------------------------------------------------------------------------------
// Cameras, poses, scenes

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum ViewKind {
    Mask,
    MaskIgnoreImage,
    PhotoWithBox,
}

fn sane_camera(w: u32, h: u32) -> impl Strategy<Value = CamSpec> {
    (
        5.0..200.0f64,
        5.0..200.0f64,
        0.0..w as f64,
        0.0..h as f64,
        quat(),
        prop::array::uniform3(-10.0..10.0f64),
        select(vec![CamKey::W2c, CamKey::C2w]),
        any::<bool>(),
    )
        .prop_map(move |(fx, fy, cx, cy, q, t, key, opengl)| CamSpec {
            width: w as i64,
            height: h as i64,
            fx,
            fy,
            cx,
            cy,
            matrix: rigid(q, t),
            key,
            opengl,
        })
}

/// A sane camera with some numbers at the edges, another size, or the extrinsics
/// given twice or not at all.
fn wild_camera(w: u32, h: u32) -> impl Strategy<Value = CamSpec> {
    (
        sane_camera(w, h),
        vec((0usize..21, wild()), 0..3),
        prop_oneof![6 => Just(None), 1 => select(vec![CamKey::W2c, CamKey::C2w, CamKey::Both, CamKey::Neither]).prop_map(Some)],
        prop_oneof![6 => Just(None), 1 => (wild_int(), wild_int()).prop_map(Some), 1 => Just(Some((16384, 16384)))],
    )
        .prop_map(|(mut c, edits, key, size)| {
            for (field, v) in edits {
                match field {
                    0 => c.fx = v,
                    1 => c.fy = v,
                    2 => c.cx = v,
                    3 => c.cy = v,
                    4..=19 => c.matrix[(field - 4) / 4][(field - 4) % 4] = v,
                    _ => {
                        // The rotation scaled: off SO(3) by a little or a lot.
                        for r in 0..3 {
                            for k in 0..3 {
                                c.matrix[r][k] *= 1.0 + v * 1e-3;
                            }
                        }
                    }
                }
            }
            if let Some(k) = key {
                c.key = k;
            }
            if let Some((w, h)) = size {
                c.width = w;
                c.height = h;
            }
            c
        })
}

fn sane_pose() -> impl Strategy<Value = PoseSpec> {
    (
        quat(),
        any::<u8>(),
        prop::array::uniform3(-10.0..10.0f64),
        prop::option::of(prop::array::uniform3(0.1..10.0f64)),
    )
        .prop_map(|(q, how, translation, scale)| PoseSpec {
            rotation: match how % 3 {
                0 => RotSpec::Matrix(quat_rows(q)),
                1 => RotSpec::Quaternion(q),
                _ => RotSpec::QuaternionKey(q),
            },
            translation,
            scale,
        })
}

fn wild_pose() -> impl Strategy<Value = PoseSpec> {
    (sane_pose(), vec((0usize..16, wild()), 0..3)).prop_map(|(mut p, edits)| {
        for (f, v) in edits {
            match (f, &mut p.rotation) {
                (0..=8, RotSpec::Matrix(m)) => m[f / 3][f % 3] = v,
                (0..=3, RotSpec::Quaternion(q) | RotSpec::QuaternionKey(q)) => q[f] = v,
                (9..=11, _) => p.translation[f - 9] = v,
                (12..=14, _) => p.scale.get_or_insert([1.0; 3])[f - 12] = v,
                _ => p.scale = Some([v; 3]),
            }
        }
        p
    })
}

fn grasp(sane: bool) -> impl Strategy<Value = GraspSpec> {
    (
        prop::array::uniform3(-1.0..1.0f64),
        0.01..1.0f64,
        0.01..1.0f64,
        vec((0usize..12, wild()), 0..(if sane { 1 } else { 3 })),
    )
        .prop_map(|(centre, width, depth, edits)| {
            let mut g = GraspSpec {
                centre,
                approach: [0.0, 0.0, 1.0],
                closing: [1.0, 0.0, 0.0],
                width,
                depth,
                score: Some(0.5),
            };
            for (f, v) in edits {
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
        })
}

fn sane_view(i: usize, w: u32, h: u32) -> impl Strategy<Value = ViewSpec> {
    (
        sane_camera(w, h),
        mask(w, h),
        image(w, h),
        select(vec![ViewKind::Mask, ViewKind::MaskIgnoreImage, ViewKind::PhotoWithBox]),
        (0..w, 0..h),
    )
        .prop_flat_map(move |(camera, mask, image, kind, (x0, y0))| {
            (Just((camera, mask, image, kind, x0, y0)), (x0 + 1..=w, y0 + 1..=h))
        })
        .prop_map(move |((camera, mask, image, kind, x0, y0), (x1, y1))| {
            let ignore = MaskSpec {
                bits: mask.pixels().iter().map(|&b| 1 - b).collect(),
                ..mask.clone()
            };
            ViewSpec {
                name: format!("v{i}"),
                camera,
                mask: (kind != ViewKind::PhotoWithBox).then_some(mask),
                image: (kind != ViewKind::Mask).then_some(image),
                ignore: (kind == ViewKind::MaskIgnoreImage).then_some(ignore),
                hint: (kind == ViewKind::PhotoWithBox).then_some([x0 as f64, y0 as f64, x1 as f64, y1 as f64]),
            }
        })
}

fn dirs() -> impl Strategy<Value = String> {
    select(vec!["", "scene/", "a/b/"]).prop_map(String::from)
}

fn sane_scene() -> impl Strategy<Value = SceneSpec> {
    (
        vec((1u32..=12, 1u32..=12), 1..=4),
        sane_mesh(),
        mesh_format(true),
        dirs(),
        select(vec!["", "meshes/"]),
        prop::option::of(sane_pose()),
        prop::option::of(sane_pose()),
        vec(grasp(true), 0..2),
    )
        .prop_flat_map(
            |(sizes, mesh, format, dir, mesh_dir, initial_pose, ground_truth, grasps)| {
                let views: Vec<_> = sizes
                    .iter()
                    .enumerate()
                    .map(|(i, &(w, h))| sane_view(i, w, h))
                    .collect();
                (
                    views,
                    Just(SceneSpec {
                        dir,
                        mesh_dir: mesh_dir.into(),
                        version: None,
                        views: vec![],
                        mesh,
                        format,
                        initial_pose,
                        ground_truth,
                        grasps,
                    }),
                )
            },
        )
        .prop_map(|(views, s)| SceneSpec { views, ..s })
}

/// A sane scene made wild in places: cameras, poses, grasps, names, boxes, masks of
/// another size or missing, the version, the mesh.
fn wild_scene() -> impl Strategy<Value = SceneSpec> {
    (
        sane_scene(),
        vec((any::<usize>(), 0usize..8), 0..3),
        wild_camera(8, 6),
        prop::option::of(wild_pose()),
        vec(grasp(false), 0..2),
        wild_mesh(),
        mesh_format(false),
        prop_oneof![9 => Just(None), 1 => wild_int().prop_map(Some)],
        prop::array::uniform4(wild()),
    )
        .prop_map(|(mut s, edits, cam, pose, grasps, mesh, format, version, hint)| {
            let n = s.views.len();
            for (v, what) in edits {
                let view = &mut s.views[v % n];
                match what {
                    0 => view.camera = cam.clone(),
                    1 => view.name = "v0".into(),
                    2 => view.name = "\u{0}é\"/..\\".into(),
                    3 => view.mask = None,
                    4 => view.hint = Some(hint),
                    5 => {
                        if let Some(m) = &mut view.mask {
                            m.width += 1;
                        }
                    }
                    6 => {
                        view.mask = Some(MaskSpec {
                            bits: vec![0],
                            ..view.mask.clone().unwrap_or(MaskSpec {
                                kind: PngKind::Gray8,
                                width: 1,
                                height: 1,
                                bits: vec![],
                            })
                        })
                    }
                    _ => view.image = None,
                }
            }
            if pose.is_some() {
                s.initial_pose = pose;
            }
            s.grasps.extend(grasps);
            if version.is_some() {
                s.version = version;
            }
            if s.views.len() % 2 == 0 {
                s.mesh = mesh;
                s.format = format;
            }
            s
        })
}

proptest! {
    #![proptest_config(config(1536))]

    /// A valid scene of 1–4 views loads: each view with a mask is a view, each with a
    /// photograph and a box a photo view, the mesh as written, the poses given.
    #[test]
    fn scenes_load_as_written(s in sane_scene()) {
        let files = scene_files(&s);
        let scene = drive_scene(&files, &Limits::DEFAULT).unwrap_or_else(|e| panic!("{e}\n{}", files.text));
        let masked = s.views.iter().filter(|v| v.mask.is_some()).count();
        prop_assert_eq!(scene.views.len(), masked);
        prop_assert_eq!(scene.photos.len(), s.views.len() - masked);
        prop_assert_eq!(scene.mesh.triangles.len(), expected_counts(&s.mesh, &s.format).1);
        prop_assert_eq!(scene.initial_pose.is_some(), s.initial_pose.is_some());
        prop_assert_eq!(scene.ground_truth_pose.is_some(), s.ground_truth.is_some());
        prop_assert_eq!(scene.grasps.len(), s.grasps.len());
        for (v, spec) in scene.views.iter().zip(s.views.iter().filter(|v| v.mask.is_some())) {
            prop_assert_eq!(&v.mask().data, &spec.mask.as_ref().unwrap().pixels());
            // serde_json reads decimals to within an ulp or so.
            prop_assert!((v.camera().fx - spec.camera.fx).abs() <= 1e-14 * spec.camera.fx);
        }
    }

    /// Any scene, its text or one of its files damaged, under any limits: a clean answer.
    #[test]
    fn damaged_scenes_are_refused_cleanly(
        s in wild_scene(),
        damage in mutations(),
        target in any::<usize>(),
        limits in limits(),
    ) {
        let mut files = scene_files(&s);
        if target % 3 == 0 {
            let mut text = files.text.into_bytes();
            mutate(&mut text, &damage);
            files.text = text_of(&text);
        } else {
            mutate_files(&mut files.files, target, &damage);
        }
        let _ = drive_scene(&files, &limits);
    }

    /// A camera's JSON: a valid one converts (to a rotation and finite numbers); any
    /// other, damaged or not, is a clean answer.
    #[test]
    fn cameras_convert_or_are_refused(
        sane in sized(sane_camera),
        wild in wild_camera(8, 6),
        damage in mutations(),
    ) {
        let c = drive_camera(&camera_json(&sane)).unwrap_or_else(|e| panic!("{e}\n{}", camera_json(&sane)));
        prop_assert_eq!((c.width as i64, c.height as i64), (sane.width, sane.height));
        let mut text = camera_json(&wild).into_bytes();
        mutate(&mut text, &damage);
        let _ = drive_camera(&text_of(&text));
    }
}

// ---------------------------------------------------------------------------------
// The page's file sets

fn sane_fileset() -> impl Strategy<Value = FilesetSpec> {
    (
        sane_scene(),
        prop_oneof![
            Just(Layout::Folder),
            Just(Layout::Bare),
            (any::<bool>(), 0u8..4, 0u8..3).prop_map(|(wrapped, mask_style, image_style)| Layout::PerView {
                wrapped,
                mask_style,
                image_style
            }),
        ],
        select(vec!["", "data/", "My Scene/"]),
        any::<usize>(),
    )
        .prop_map(|(mut scene, layout, prefix, rotate)| {
            if let Layout::PerView { wrapped, .. } = layout {
                per_view_ready(&mut scene, wrapped);
            }
            FilesetSpec {
                scene,
                layout,
                prefix: prefix.into(),
                junk: vec![],
                twice: vec![],
                rotate,
            }
        })
}

fn junk_name() -> impl Strategy<Value = String> {
    (
        select(vec![
            "", "a/", "../", "./", "A/", "masks/", "images/", "x\\y/", "/abs/", "é/",
        ]),
        select(vec![
            "scene", "v0", "V0", "mesh", "model", "mask_v0", "v0_mask", "v1_image", "", ".", "..",
        ]),
        select(vec![
            ".json", ".png", ".PNG", ".glb", ".gltf", ".obj", ".ply", ".bin", "", ".JSON",
        ]),
    )
        .prop_map(|(d, s, e)| format!("{d}{s}{e}"))
}

fn junk_bytes() -> impl Strategy<Value = Vec<u8>> {
    prop_oneof![
        vec(any::<u8>(), 0..32),
        Just(b"{\"mesh\": \"mesh.ply\", \"views\": []}".to_vec()),
        Just(b"{\"fx\": 1}".to_vec()),
        Just(b"{\"camera\": null, \"name\": \"v0\"}".to_vec()),
        Just(b"[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[".to_vec()),
        sized(mask).prop_map(|m| m.png()),
    ]
}

fn wild_fileset() -> impl Strategy<Value = FilesetSpec> {
    (
        sane_fileset(),
        wild_scene(),
        any::<bool>(),
        prop_oneof![2 => Just(vec![]), 1 => vec((junk_name(), junk_bytes()), 1..3)],
        vec(any::<usize>(), 0..3),
    )
        .prop_map(|(mut f, wild, use_wild, junk, twice)| {
            if use_wild {
                f.scene = wild;
            }
            f.junk = junk;
            f.twice = twice;
            f
        })
}

proptest! {
    #![proptest_config(config(1024))]

    /// The files of a valid scene, however a page hands them over (the folder, bare
    /// names, one camera file per view), make that scene.
    #[test]
    fn file_sets_make_their_scene(f in sane_fileset()) {
        let files = fileset_files(&f);
        let (scene, _, _) = drive_fileset(&files, &Limits::DEFAULT).unwrap_or_else(|e| {
            let names: Vec<&String> = files.iter().map(|(p, _)| p).collect();
            panic!("{:?}: {e}\n{names:?}", f.layout)
        });
        prop_assert_eq!(scene.views.len() + scene.photos.len(), f.scene.views.len());
        prop_assert_eq!(scene.mesh.triangles.len(), expected_counts(&f.scene.mesh, &f.scene.format).1);
    }

    /// Any set of files — junk among them, files given twice, one damaged — under any
    /// limits: a clean answer from every call the binding makes.
    #[test]
    fn any_file_set_gets_a_clean_answer(
        f in wild_fileset(),
        damage in mutations(),
        target in any::<usize>(),
        limits in limits(),
    ) {
        let mut files = fileset_files(&f);
        if !files.is_empty() {
            let n = files.len();
            mutate(&mut files[target % n].1, &damage);
        }
        let _ = drive_fileset(&files, &limits);
    }
}

// ---------------------------------------------------------------------------------
// BOP and NeRF

fn sane_bop() -> impl Strategy<Value = BopSpec> {
    (
        vec(
            (
                quat(),
                prop::array::uniform3(-500.0..500.0f64),
                1u32..=10,
                1u32..=10,
                any::<bool>(),
            ),
            1..=3,
        ),
        quat(),
        prop::array::uniform3(-500.0..500.0f64),
        any::<bool>(),
        sane_mesh(),
        ply_opts(true),
        prop::array::uniform4(any::<bool>()),
        0u32..3,
    )
        .prop_flat_map(|(ims, w2c_q, w2c_t, with_w2c, model, model_ply, flags, scene_id)| {
            let masks: Vec<_> = ims.iter().map(|&(_, _, w, h, _)| (mask(w, h), image(w, h))).collect();
            (
                Just((ims, w2c_q, w2c_t, with_w2c, model, model_ply, flags, scene_id)),
                masks,
            )
        })
        .prop_map(
            |((ims, w2c_q, w2c_t, with_w2c, model, model_ply, flags, scene_id), masks)| {
                let images = ims
                    .iter()
                    .zip(masks)
                    .enumerate()
                    .map(|(i, (&(q, t, _, _, rgb), (m, im)))| BopImage {
                        id: i as i64,
                        listed: true,
                        k: Some([
                            500.0,
                            0.0,
                            m.width as f64 / 2.0,
                            0.0,
                            500.0,
                            m.height as f64 / 2.0,
                            0.0,
                            0.0,
                            1.0,
                        ]),
                        w2c: with_w2c.then_some((rot9(w2c_q), w2c_t)),
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
                                r: rot9(q),
                                t,
                                mask: Some(m.clone()),
                                visib: Some(m),
                            },
                        ],
                        rgb: rgb.then_some(im),
                    })
                    .collect();
                BopSpec {
                    scene_id,
                    object_id: 1,
                    images,
                    model,
                    model_ply,
                    image_ids: None,
                    instance: 0,
                    visible: flags[0],
                    metres: flags[1],
                    ignore_others: flags[2],
                    boxes: None,
                }
            },
        )
}

fn wild_bop() -> impl Strategy<Value = BopSpec> {
    (
        sane_bop(),
        vec((any::<usize>(), 0usize..24, wild()), 0..3),
        vec((any::<usize>(), 0usize..6), 0..3),
        prop_oneof![3 => Just(None), 1 => vec(0u32..4, 0..3).prop_map(Some)],
        prop_oneof![4 => Just(0usize), 1 => 1usize..3],
        prop::option::of((0.0..0.5f64, 0.0..0.25f64, any::<u64>(), 0usize..3)),
        wild_mesh(),
    )
        .prop_map(|(mut s, numbers, edits, image_ids, instance, boxes, model)| {
            let n = s.images.len();
            for (i, f, v) in numbers {
                let im = &mut s.images[i % n];
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
            for (i, what) in edits {
                let im = &mut s.images[i % n];
                match what {
                    0 => im.listed = false,
                    1 => im.k = None,
                    2 => im.instances[1].mask = None,
                    3 => im.instances[1].obj_id = -1,
                    4 => {
                        im.instances[1]
                            .mask
                            .as_mut()
                            .unwrap_or(&mut MaskSpec {
                                kind: PngKind::Gray8,
                                width: 1,
                                height: 1,
                                bits: vec![],
                            })
                            .bits = vec![0]
                    }
                    _ => im.w2c = None,
                }
            }
            s.image_ids = image_ids;
            s.instance = instance;
            s.boxes = boxes.map(|(margin, jitter, seed, views_with_box)| BoxHints {
                margin,
                jitter,
                seed,
                views_with_box,
            });
            if n == 2 {
                s.model = model;
            }
            s
        })
}

fn sane_nerf() -> impl Strategy<Value = NerfSpec> {
    (
        vec(
            (
                quat(),
                prop::array::uniform3(-5.0..5.0f64),
                2u32..=10,
                1u32..=10,
                any::<bool>(),
                any::<bool>(),
            ),
            1..=3,
        ),
        0.3..2.0f64,
        dirs(),
    )
        .prop_flat_map(|(frames, angle, dir)| {
            let alphas: Vec<_> = frames
                .iter()
                .map(|&(_, _, w, h, _, _)| (vec(0u8..2, (w * h) as usize), image(w, h)))
                .collect();
            (Just((frames, angle, dir)), alphas)
        })
        .prop_map(|((frames, angle, dir), alphas)| NerfSpec {
            dir,
            intrinsics: NerfIntrinsics {
                camera_angle_x: Some(angle),
                ..Default::default()
            },
            frames: frames
                .iter()
                .zip(alphas)
                .enumerate()
                .map(|(i, (&(q, t, w, h, with_ext, with_mask), (mut alpha, mut im)))| {
                    // Some object, some background.
                    alpha[0] = 1;
                    *alpha.last_mut().unwrap() = 0;
                    let mask = with_mask.then(|| MaskSpec {
                        kind: PngKind::Gray8,
                        width: w,
                        height: h,
                        bits: alpha.clone(),
                    });
                    im.alpha = Some(alpha);
                    NerfFrame {
                        file_path: format!("./train/r_{i}"),
                        with_ext,
                        matrix: rigid(q, t),
                        intrinsics: NerfIntrinsics::default(),
                        image: Some(im),
                        mask,
                    }
                })
                .collect(),
        })
}

fn wild_intrinsics() -> impl Strategy<Value = NerfIntrinsics> {
    prop::array::uniform9(prop::option::weighted(0.3, wild())).prop_map(|v| NerfIntrinsics {
        camera_angle_x: v[0],
        camera_angle_y: v[1],
        fl_x: v[2],
        fl_y: v[3],
        cx: v[4],
        cy: v[5],
        w: v[6],
        h: v[7],
        k1: v[8],
    })
}

fn wild_nerf() -> impl Strategy<Value = NerfSpec> {
    (
        sane_nerf(),
        vec((any::<usize>(), 0usize..8, wild()), 0..3),
        prop_oneof![3 => Just(None), 1 => wild_intrinsics().prop_map(Some)],
        prop_oneof![3 => Just(None), 1 => wild_intrinsics().prop_map(Some)],
    )
        .prop_map(|(mut s, edits, top, frame)| {
            let n = s.frames.len();
            let first = s.frames[0].file_path.clone();
            for (i, what, v) in edits {
                let f = &mut s.frames[i % n];
                match what {
                    0 => f.image = None,
                    1 => f.file_path = "".into(),
                    2 => f.file_path = first.clone(),
                    3 => {
                        if let Some(m) = &mut f.mask {
                            m.width += 1
                        }
                    }
                    4 => {
                        if let Some(im) = &mut f.image {
                            im.alpha = None
                        }
                    }
                    _ => f.matrix[what % 3][(what + 1) % 4] = v,
                }
            }
            if let Some(t) = top {
                s.intrinsics = t;
            }
            if let Some(k) = frame {
                s.frames[0].intrinsics = k;
            }
            s
        })
}

proptest! {
    #![proptest_config(config(1024))]

    /// A valid BOP scene imports one view per image, and the imported scene loads.
    #[test]
    fn bop_scenes_import_and_load(s in sane_bop()) {
        let (files, opts) = bop_files(&s);
        let im = drive_bop(&files, &opts).unwrap_or_else(|e| panic!("{e}"));
        prop_assert_eq!(im.scene.views.len(), s.images.len());
        prop_assert!(im.scene.ground_truth_pose.is_some());
        let scene = load_imported(&im, None).unwrap_or_else(|e| panic!("the imported scene: {e}"));
        prop_assert_eq!(scene.views.len(), s.images.len());
        prop_assert_eq!(scene.mesh.triangles.len(), s.model.fan_triangles().len());
    }

    /// Any BOP folder, damaged or not, with any options: a clean answer; an import
    /// is checked and loaded.
    #[test]
    fn damaged_bop_scenes_are_refused_cleanly(s in wild_bop(), damage in mutations(), target in any::<usize>()) {
        let (mut files, opts) = bop_files(&s);
        mutate_files(&mut files, target, &damage);
        if let Ok(im) = drive_bop(&files, &opts) {
            let _ = load_imported(&im, None);
        }
    }

    /// A valid NeRF folder imports one view per frame, and the imported scene loads.
    #[test]
    fn nerf_folders_import_and_load(s in sane_nerf(), mesh in sane_mesh()) {
        let (file, text, files) = nerf_files(&s);
        let im = drive_nerf(&file, &text, &files).unwrap_or_else(|e| panic!("{e}\n{text}"));
        prop_assert_eq!(im.scene.views.len(), s.frames.len());
        let ply = ply_bytes(&mesh, &PlyOpts::plain(PlyEncoding::Ascii));
        let scene = load_imported(&im, Some(("mesh.ply", ply))).unwrap_or_else(|e| panic!("the imported scene: {e}"));
        prop_assert_eq!(scene.views.len(), s.frames.len());
    }

    /// Any NeRF folder, damaged or not: a clean answer; an import is checked and loaded.
    #[test]
    fn damaged_nerf_folders_are_refused_cleanly(s in wild_nerf(), damage in mutations(), target in any::<usize>()) {
        let (file, text, mut files) = nerf_files(&s);
        let mut text = text.into_bytes();
        if target % 2 == 0 {
            mutate(&mut text, &damage);
        } else {
            mutate_files(&mut files, target / 2, &damage);
        }
        if let Ok(im) = drive_nerf(&file, &text_of(&text), &files) {
            let mesh = ply_bytes(&MeshSpec::with_base(&[], &[]), &PlyOpts::plain(PlyEncoding::Ascii));
            let _ = load_imported(&im, Some(("mesh.ply", mesh)));
        }
    }
}

/// The writers' own output, undamaged, for one fixed mesh: a guard that the shared
/// serialisers above stay readable (if this fails, the properties test nothing).
#[test]
fn the_serialisers_write_what_the_readers_read() {
    let mesh = MeshSpec::with_base(&[[0.0, 0.0, 1.0]], &[vec![0, 1, 3], vec![1, 2, 3, 0]]);
    let formats = [
        MeshFormat::Ply(PlyOpts::plain(PlyEncoding::Ascii)),
        MeshFormat::Ply(PlyOpts::plain(PlyEncoding::BinaryLe)),
        MeshFormat::Ply(PlyOpts::plain(PlyEncoding::BinaryBe)),
        MeshFormat::Obj(ObjOpts::default()),
        MeshFormat::Gltf(GltfOpts::plain(Container::Glb)),
        MeshFormat::Gltf(GltfOpts::plain(Container::DataUri)),
        MeshFormat::Gltf(GltfOpts::plain(Container::External)),
        MeshFormat::PlyWriter,
        MeshFormat::GlbWriter,
        MeshFormat::GltfWriter,
    ];
    for f in &formats {
        let (name, files) = mesh_files(&mesh, f, "m").unwrap();
        let m = drive_mesh(&name, &files, &Limits::DEFAULT).unwrap_or_else(|e| panic!("{f:?}: {e}"));
        assert_eq!(m.triangles.len(), 4, "{f:?}");
    }
    for kind in PNG_KINDS {
        let m = MaskSpec {
            kind,
            width: 9,
            height: 3,
            bits: vec![1, 0, 0, 1, 1],
        };
        assert_eq!(drive_png(&m.png(), (9, 3)).0.unwrap().data, m.pixels(), "{kind:?}");
    }
}
