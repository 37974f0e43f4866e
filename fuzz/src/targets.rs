//! The fuzz targets' bodies (each `fuzz_targets/NAME.rs` calls `targets::NAME`), here
//! so that the corpus generator (`examples/gen_corpus.rs`) and a regression test can
//! run exactly what libFuzzer runs.
//!
//! Every target has two modes, chosen by the first byte: odd, the rest decodes as an
//! `arbitrary` structure ([`crate::arb`]) that is serialised to the format and damaged
//! as it says; even, the rest is the raw file (for the readers that need more files —
//! the scene's masks and mesh, a BOP or NeRF folder, a file set — the others come from
//! a fixed reference set, [`reference`]). The answer is an [`Outcome`] whose label
//! ("ok", or the error's kind and first words) lets the corpus generator keep inputs
//! that reach different places.

use crate::arb::*;
use crate::formats::*;
use arbitrary::{Arbitrary, Unstructured};
use localisebot::{io, Limits};
use std::sync::OnceLock;

/// What a run gave: `"ok"` or the error's kind and first words (digits dropped).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Outcome {
    pub label: String,
}

fn label<T>(r: &localisebot::Result<T>) -> Outcome {
    let label = match r {
        Ok(_) => "ok".to_string(),
        Err(e) => {
            let debug = format!("{e:?}");
            let kind = debug
                .split(|c: char| !c.is_alphanumeric())
                .next()
                .unwrap_or("")
                .to_string();
            let text: String = e.to_string().chars().filter(|c| !c.is_ascii_digit()).collect();
            let words: Vec<&str> = text.split_whitespace().skip(1).take(4).collect();
            format!("{kind}: {}", words.join(" "))
        }
    };
    Outcome { label }
}

fn undecodable() -> Outcome {
    Outcome {
        label: "undecodable".into(),
    }
}

/// `Some(structure)` in structured mode (odd first byte), `None` in raw mode.
fn structured<'a, T: Arbitrary<'a>>(data: &'a [u8]) -> Option<arbitrary::Result<T>> {
    match data.first() {
        Some(b) if b & 1 == 1 => Some(T::arbitrary(&mut Unstructured::new(&data[1..]))),
        _ => None,
    }
}

fn raw(data: &[u8]) -> &[u8] {
    data.get(1..).unwrap_or(&[])
}

// ---------------------------------------------------------------------------------
// The reference files of the raw modes

/// The fixed files raw inputs are read against.
pub struct Reference {
    /// A scene of four 8×6 views (`masks/m0.png` …, `images/i1.png` …), its mesh as
    /// `mesh.ply`, `mesh.obj`, `mesh.glb` and `mesh.gltf` with `mesh.bin`.
    pub scene: SceneSpec,
    pub scene_files: Files,
    /// The scene's files as a page drops them (its folder).
    pub fileset: Vec<(String, Vec<u8>)>,
    /// A BOP scene of two 8×6 images.
    pub bop: BopSpec,
    pub bop_files: Files,
    /// A NeRF folder of three 8×6 frames, and its `transforms.json` text.
    pub nerf: NerfSpec,
    pub nerf_text: String,
    pub nerf_files: Files,
}

pub fn reference_mesh() -> MeshSpec {
    MeshSpec::with_base(
        &[[0.0, 0.0, 1.0], [1.0, 1.0, 0.5]],
        &[vec![0, 1, 3], vec![1, 2, 4, 3], vec![0, 2, 3]],
    )
}

fn reference_view(i: usize) -> ViewSpec {
    let (w, h) = (8, 6);
    let camera = default_of::<ACamera>().spec(w, h);
    let mask = MaskSpec {
        kind: PNG_KINDS[i % PNG_KINDS.len()],
        width: w,
        height: h,
        bits: vec![1, 1, 0, 0, 1, 0, 1],
    };
    let image = ImageSpec {
        width: w,
        height: h,
        rgb: vec![10, 200, 30, 40, 50, 60],
        alpha: None,
    };
    ViewSpec {
        name: format!("v{i}"),
        camera: CamSpec {
            fx: 20.0 + i as f64,
            ..camera
        },
        mask: (i != 3).then(|| mask.clone()),
        image: (i != 0).then_some(image),
        ignore: (i == 2).then(|| MaskSpec {
            bits: mask.pixels().iter().map(|b| 1 - b).collect(),
            ..mask
        }),
        hint: (i == 3).then_some([1.0, 1.0, 6.0, 5.0]),
    }
}

pub fn reference_scene(views: usize, format: MeshFormat) -> SceneSpec {
    SceneSpec {
        dir: String::new(),
        mesh_dir: String::new(),
        version: Some(1),
        views: (0..views).map(reference_view).collect(),
        mesh: reference_mesh(),
        format,
        initial_pose: Some(default_of::<APose>().spec()),
        ground_truth: None,
        grasps: vec![default_of::<AGrasp>().spec()],
    }
}

pub fn reference() -> &'static Reference {
    static R: OnceLock<Reference> = OnceLock::new();
    R.get_or_init(|| {
        let scene = reference_scene(4, MeshFormat::PlyWriter);
        let mut scene_files = scene_files(&scene).files;
        let mesh = reference_mesh();
        for f in [
            MeshFormat::Obj(ObjOpts::default()),
            MeshFormat::GlbWriter,
            MeshFormat::GltfWriter,
        ] {
            scene_files.extend(mesh_files(&mesh, &f, "mesh").expect("the reference mesh is valid").1);
        }
        let fileset = fileset_files(&FilesetSpec {
            scene: scene.clone(),
            layout: Layout::Folder,
            prefix: "scene/".into(),
            junk: vec![],
            twice: vec![],
            rotate: 0,
        });
        let mut bop_arb: ABop = default_of();
        bop_arb.images = vec![
            ABopImage {
                q: [3, 1, 0, -1],
                t: [10, -20, 4000],
                size: (7, 5),
                mask: AMask {
                    kind: 1,
                    bits: vec![1, 0, 1, 1],
                },
                rgb: Some(AImage { rgb: vec![1, 2, 3] }),
            },
            ABopImage {
                q: [3, -1, 1, 0],
                t: [-10, 20, 5000],
                size: (7, 5),
                mask: AMask {
                    kind: 4,
                    bits: vec![0, 1, 1],
                },
                rgb: None,
            },
        ];
        bop_arb.model.extra = vec![[0, 0, 10]];
        bop_arb.model.faces = vec![[0, 0, 1, 3, 0, 0]];
        let bop = bop_arb.spec();
        let (bop_files, _) = bop_files(&bop);
        let mut nerf_arb: ANerf = default_of();
        nerf_arb.frames = (0..3)
            .map(|i| ANerfFrame {
                q: [2, i, 1, -1],
                t: [0, 0, 40],
                size: (6, 5),
                alpha: vec![1, 1, 0, 1, 0],
                rgb: AImage { rgb: vec![i as u8; 3] },
                with_ext: i == 1,
                with_mask: i == 2,
            })
            .collect();
        let nerf = nerf_arb.spec();
        let (_, nerf_text, nerf_files) = nerf_files(&nerf);
        Reference {
            scene,
            scene_files,
            fileset,
            bop,
            bop_files,
            nerf,
            nerf_text,
            nerf_files,
        }
    })
}

/// A small JPEG (quality 90; pixels from a fixed formula) tagged EXIF orientation `o`
/// (no EXIF block when 0).
fn jpeg_seed(w: u32, h: u32, grey: bool, o: u8) -> Vec<u8> {
    let (channels, color) = match grey {
        true => (1, image::ExtendedColorType::L8),
        false => (3, image::ExtendedColorType::Rgb8),
    };
    let data: Vec<u8> = (0..w * h * channels).map(|k| (k * 37 % 251) as u8).collect();
    crate::jpeg_support::jpeg(&data, w, h, color, 90, (o > 0).then_some(o))
}

/// Raw-mode inputs made from the reference files (for the seed corpora).
pub fn raw_seeds(target: &str) -> Vec<Vec<u8>> {
    let r = reference();
    let with = |prefix: &[u8], bytes: &[u8]| [prefix, bytes].concat();
    let mesh = reference_mesh();
    match target {
        "scene_json" => [1, 2, 4]
            .iter()
            .flat_map(|&n| {
                [
                    MeshFormat::PlyWriter,
                    MeshFormat::GlbWriter,
                    MeshFormat::Obj(ObjOpts::default()),
                ]
                .into_iter()
                .map(move |f| reference_scene(n, f))
            })
            .map(|s| with(&[0], scene_files(&s).text.as_bytes()))
            .collect(),
        "camera_json" => r
            .scene
            .views
            .iter()
            .map(|v| with(&[0], crate::formats::camera_json(&v.camera).as_bytes()))
            .collect(),
        "fileset" => (0..r.fileset.len())
            .map(|k| with(&[0, k as u8], &r.fileset[k].1))
            .collect(),
        "gltf" => {
            let mut out = Vec::new();
            for (i, f) in [MeshFormat::GlbWriter, MeshFormat::GltfWriter].iter().enumerate() {
                let (name, files) = mesh_files(&mesh, f, "mesh").expect("valid");
                out.push(with(&[0, i as u8], &files[&name]));
            }
            for c in [Container::Glb, Container::DataUri] {
                let (name, files) = gltf_files(&mesh, &GltfOpts::plain(c), "mesh");
                out.push(with(&[0, (c == Container::DataUri) as u8], &files[&name]));
            }
            out
        }
        "obj" => vec![
            with(&[0], &obj_bytes(&mesh, &ObjOpts::default())),
            with(&[0], &obj_bytes(&mesh, &default_of::<AObj>().opts())),
        ],
        "ply" => [PlyEncoding::Ascii, PlyEncoding::BinaryLe, PlyEncoding::BinaryBe]
            .iter()
            .map(|&e| with(&[0], &ply_bytes(&mesh, &PlyOpts::plain(e))))
            .chain([with(
                &[0],
                &localisebot::io::ply::write_ascii(&mesh.mesh().expect("valid"), "seed"),
            )])
            .collect(),
        "png" => PNG_KINDS
            .iter()
            .map(|&kind| {
                let m = MaskSpec {
                    kind,
                    width: 8,
                    height: 6,
                    bits: vec![1, 0, 0, 1, 1],
                };
                with(&[0], &m.png())
            })
            // JPEG photographs, shown 8×6: colour as stored, colour stored sideways
            // (EXIF 6), grey with no EXIF block.
            .chain([(8, 6, false, 1), (6, 8, false, 6), (8, 6, true, 0)].map(|(w, h, grey, o)| {
                with(&[0], &jpeg_seed(w, h, grey, o))
            }))
            .collect(),
        "bop" => r
            .bop_files
            .values()
            .enumerate()
            .map(|(k, b)| with(&[0, k as u8], b))
            .collect(),
        "nerf" => vec![with(&[0], r.nerf_text.as_bytes())],
        _ => vec![],
    }
}

// ---------------------------------------------------------------------------------
// The targets

/// Scene JSON (`load_scene_with`): the scene's text and every file it names.
pub fn scene_json(data: &[u8]) -> Outcome {
    match structured::<(AScene, ADamage)>(data) {
        None => {
            let sf = SceneFiles {
                scene_file: "scene.json".into(),
                text: text_of(raw(data)),
                files: reference().scene_files.clone(),
            };
            label(&drive_scene(&sf, &Limits::DEFAULT))
        }
        Some(Err(_)) => undecodable(),
        Some(Ok((scene, damage))) => {
            let mut sf = scene_files(&scene.spec());
            let ms = damage.mutations();
            if damage.target % 3 == 0 {
                let mut text = sf.text.into_bytes();
                mutate(&mut text, &ms);
                sf.text = text_of(&text);
            } else {
                mutate_files(&mut sf.files, damage.target as usize / 3, &ms);
            }
            label(&drive_scene(&sf, &damage.limits()))
        }
    }
}

/// A camera's JSON (as a scene's view or a page's per-view file holds it).
pub fn camera_json(data: &[u8]) -> Outcome {
    match structured::<(ACamera, (u8, u8), ADamage)>(data) {
        None => label(&drive_camera(&text_of(raw(data)))),
        Some(Err(_)) => undecodable(),
        Some(Ok((camera, (w, h), damage))) => {
            let spec = camera.spec(1 + w as u32 % 64, 1 + h as u32 % 64);
            let mut text = crate::formats::camera_json(&spec).into_bytes();
            mutate(&mut text, &damage.mutations());
            label(&drive_camera(&text_of(&text)))
        }
    }
}

/// A page's file set (`FileSet`: every call the wasm binding makes, then `load`).
pub fn fileset(data: &[u8]) -> Outcome {
    match structured::<(AFileset, ADamage)>(data) {
        None => {
            let mut files = reference().fileset.clone();
            let k = *data.get(1).unwrap_or(&0) as usize % files.len();
            files[k].1 = data.get(2..).unwrap_or(&[]).to_vec();
            label(&drive_fileset(&files, &Limits::DEFAULT))
        }
        Some(Err(_)) => undecodable(),
        Some(Ok((set, damage))) => {
            let mut files = fileset_files(&set.spec());
            if !files.is_empty() {
                let n = files.len();
                mutate(&mut files[damage.target as usize % n].1, &damage.mutations());
            }
            label(&drive_fileset(&files, &damage.limits()))
        }
    }
}

/// glTF: `.glb`, `.gltf` with a data URI or an external `.bin` (by hand, or by the
/// project's writers).
pub fn gltf(data: &[u8]) -> Outcome {
    match structured::<(AMesh, AGltf, u8, ADamage)>(data) {
        None => {
            let name = if data.get(1).is_some_and(|b| b & 1 == 1) {
                "mesh.gltf"
            } else {
                "mesh.glb"
            };
            let mut files = Files::new();
            files.insert(name.into(), data.get(2..).unwrap_or(&[]).to_vec());
            files.insert("mesh.bin".into(), reference().scene_files["mesh.bin"].clone());
            let _ = io::fileset::mesh_references(name, &files[name]);
            label(&drive_mesh(name, &files, &Limits::DEFAULT))
        }
        Some(Err(_)) => undecodable(),
        Some(Ok((mesh, gltf, writer, damage))) => {
            let format = match writer % 4 {
                1 => MeshFormat::GlbWriter,
                2 => MeshFormat::GltfWriter,
                _ => MeshFormat::Gltf(gltf.opts()),
            };
            let Some((name, mut files)) = mesh_files(&mesh.spec(), &format, "mesh") else {
                return Outcome {
                    label: "refused by the writer".into(),
                };
            };
            mutate_files(&mut files, damage.target as usize, &damage.mutations());
            let _ = io::fileset::mesh_references(&name, &files[&name]);
            label(&drive_mesh(&name, &files, &damage.limits()))
        }
    }
}

/// OBJ.
pub fn obj(data: &[u8]) -> Outcome {
    match structured::<(AMesh, AObj, ADamage)>(data) {
        None => label(&drive_mesh(
            "mesh.obj",
            &Files::from([("mesh.obj".into(), raw(data).to_vec())]),
            &Limits::DEFAULT,
        )),
        Some(Err(_)) => undecodable(),
        Some(Ok((mesh, obj, damage))) => {
            let mut bytes = obj_bytes(&mesh.spec(), &obj.opts());
            mutate(&mut bytes, &damage.mutations());
            label(&drive_mesh(
                "mesh.obj",
                &Files::from([("mesh.obj".into(), bytes)]),
                &damage.limits(),
            ))
        }
    }
}

/// PLY, ASCII and binary (by hand, or by `io::ply::write_ascii`).
pub fn ply(data: &[u8]) -> Outcome {
    match structured::<(AMesh, APly, bool, ADamage)>(data) {
        None => label(&drive_mesh(
            "mesh.ply",
            &Files::from([("mesh.ply".into(), raw(data).to_vec())]),
            &Limits::DEFAULT,
        )),
        Some(Err(_)) => undecodable(),
        Some(Ok((mesh, ply, writer, damage))) => {
            let format = if writer {
                MeshFormat::PlyWriter
            } else {
                MeshFormat::Ply(ply.opts())
            };
            let Some((name, mut files)) = mesh_files(&mesh.spec(), &format, "mesh") else {
                return Outcome {
                    label: "refused by the writer".into(),
                };
            };
            mutate_files(&mut files, 0, &damage.mutations());
            label(&drive_mesh(&name, &files, &damage.limits()))
        }
    }
}

/// PNG masks and images (`decode_mask`, `decode_image`, sized and not).
pub fn png(data: &[u8]) -> Outcome {
    let outcome = |r: (
        localisebot::Result<localisebot::Mask>,
        localisebot::Result<localisebot::Rgba>,
    )| {
        let (m, i) = r;
        Outcome {
            label: format!("{} / {}", label(&m).label, label(&i).label),
        }
    };
    match structured::<(APng, ADamage)>(data) {
        None => outcome(drive_png(raw(data), (8, 6))),
        Some(Err(_)) => undecodable(),
        Some(Ok((p, damage))) => {
            let (w, h) = (1 + (p.size.0 % 16) as u32, 1 + (p.size.1 % 16) as u32);
            let mask = p.mask.spec(w, h);
            let mut bytes = match &p.photo {
                Some((image, alpha)) => {
                    let mut im = image.spec(w, h);
                    if *alpha {
                        im.alpha = Some(mask.bits.clone());
                    }
                    im.png()
                }
                None => mask.png(),
            };
            if let Some((dw, dh)) = p.declared {
                // The same chunks under a header of another size.
                let ihdr_end = 8 + 25;
                let mut head = png_file(dw.i() as u32, dh.i() as u32, bytes[25], bytes[24], None, None, &[]);
                head.truncate(ihdr_end);
                head.extend_from_slice(&bytes[ihdr_end..]);
                bytes = head;
            }
            mutate(&mut bytes, &damage.mutations());
            outcome(drive_png(&bytes, (w, h)))
        }
    }
}

/// The BOP importer (`io::bop::import`), and the scene it makes loaded.
pub fn bop(data: &[u8]) -> Outcome {
    let run = |files: &Files, opts: &localisebot::io::bop::BopOptions| {
        let r = drive_bop(files, opts);
        if let Ok(im) = &r {
            return label(&load_imported(im, None));
        }
        label(&r)
    };
    match structured::<(ABop, ADamage)>(data) {
        None => {
            let r = reference();
            let mut files = r.bop_files.clone();
            let k = *data.get(1).unwrap_or(&0) as usize % files.len();
            let key = files.keys().nth(k).cloned().expect("in range");
            files.insert(key, data.get(2..).unwrap_or(&[]).to_vec());
            let (_, opts) = bop_files(&r.bop);
            run(&files, &opts)
        }
        Some(Err(_)) => undecodable(),
        Some(Ok((b, damage))) => {
            let (mut files, opts) = bop_files(&b.spec());
            mutate_files(&mut files, damage.target as usize, &damage.mutations());
            run(&files, &opts)
        }
    }
}

/// The NeRF importer (`io::nerf::import`), and the scene it makes loaded.
pub fn nerf(data: &[u8]) -> Outcome {
    let run = |file: &str, text: &str, files: &Files| {
        let r = drive_nerf(file, text, files);
        if let Ok(im) = &r {
            let mesh = ply_bytes(&reference_mesh(), &PlyOpts::plain(PlyEncoding::Ascii));
            return label(&load_imported(im, Some(("mesh.ply", mesh))));
        }
        label(&r)
    };
    match structured::<(ANerf, ADamage)>(data) {
        None => run("transforms.json", &text_of(raw(data)), &reference().nerf_files),
        Some(Err(_)) => undecodable(),
        Some(Ok((n, damage))) => {
            let (file, text, mut files) = nerf_files(&n.spec());
            let ms = damage.mutations();
            let mut text = text.into_bytes();
            if damage.target % 2 == 0 {
                mutate(&mut text, &ms);
            } else {
                mutate_files(&mut files, damage.target as usize / 2, &ms);
            }
            run(&file, &text_of(&text), &files)
        }
    }
}

/// The targets by name.
pub const TARGETS: [(&str, fn(&[u8]) -> Outcome); 9] = [
    ("scene_json", scene_json),
    ("camera_json", camera_json),
    ("fileset", fileset),
    ("gltf", gltf),
    ("obj", obj),
    ("ply", ply),
    ("png", png),
    ("bop", bop),
    ("nerf", nerf),
];
