//! The file set's tests: what a drop or a folder holds, and how each is read.

use super::*;
use crate::app::shapes::blob_mesh;
use crate::app::synth::{synthesize, SynthSettings};
use crate::io::gltf_write;
use crate::io::png::{encode_gray, encode_rgba};
use crate::{CameraJson, PoseJson, ViewJson};

#[test]
fn glb_headers_too_short_for_their_own_length_list_no_references() {
    // "glTF", version 2, a length of 0..11 (the gltf crate subtracted 12 from it;
    // found by fuzzing), then zeros.
    for length in [0u32, 11, 12, 19] {
        let mut glb = b"glTF".to_vec();
        glb.extend(2u32.to_le_bytes());
        glb.extend(length.to_le_bytes());
        glb.extend([0u8; 8]);
        assert!(mesh_references("m.glb", &glb).is_empty(), "length {length}");
    }
}

/// A 3-view scene of a small blob, as files: (mesh bytes, per-view (camera JSON,
/// mask PNG, image PNG), scene JSON naming `mesh` and `masks/…`, `images/…`).
struct Parts {
    glb: Vec<u8>,
    views: Vec<(String, Vec<u8>, Vec<u8>)>,
    scene: String,
}

fn parts() -> Parts {
    let mesh = blob_mesh(7, 11);
    let settings = SynthSettings {
        views: 3,
        width: 48,
        height: 40,
        seed: 2,
        images: true,
        ..Default::default()
    };
    let s = synthesize(&mesh, &settings, None).unwrap();
    let mut views = Vec::new();
    let mut json_views = Vec::new();
    for (i, v) in s.views().iter().enumerate() {
        let grey: Vec<u8> = v.mask().data.iter().map(|&o| o * 255).collect();
        let camera = CameraJson::from_camera(v.camera());
        views.push((
            serde_json::to_string(&camera).unwrap(),
            encode_gray(v.mask().width, v.mask().height, &grey),
            encode_rgba(&s.images[i]),
        ));
        json_views.push(ViewJson {
            ignore: None,
            name: v.name().to_string(),
            image: Some(format!("images/{}.png", v.name())),
            mask: Some(format!("masks/{}.png", v.name())),
            hint_box: None,
            camera,
        });
    }
    let scene = SceneJson {
        version: 1,
        mesh: "blob.glb".into(),
        views: json_views,
        initial_pose: None,
        ground_truth_pose: Some(PoseJson::from_pose(&s.pose)),
        grasps: vec![],
    };
    Parts {
        glb: gltf_write::glb(&mesh, "blob.glb").unwrap(),
        views,
        scene: scene.to_json_string(),
    }
}

/// The scene folder as dropped: `dir/scene.json`, `dir/blob.glb`, `dir/masks/…`, `dir/images/…`.
fn folder(p: &Parts, dir: &str) -> FileSet {
    let mut set = FileSet::new();
    set.add(&format!("{dir}/scene.json"), p.scene.clone().into_bytes());
    set.add(&format!("{dir}/blob.glb"), p.glb.clone());
    for (i, (_, mask, image)) in p.views.iter().enumerate() {
        set.add(&format!("{dir}/masks/view{i}.png"), mask.clone());
        set.add(&format!("{dir}/images/view{i}.png"), image.clone());
    }
    set
}

fn message<T: std::fmt::Debug>(r: Result<T>) -> String {
    r.unwrap_err().to_string()
}

#[test]
fn a_scene_json_and_its_files_load_from_a_folder_or_from_bare_names() {
    let p = parts();
    let set = folder(&p, "scene");
    assert_eq!(
        set.plan().unwrap(),
        Plan::Scene {
            file: "scene/scene.json".into(),
            text: p.scene.clone()
        }
    );
    let (scene, warnings, file) = set.load().unwrap();
    assert_eq!(file, "scene/scene.json");
    assert!(warnings.is_empty(), "{warnings:?}");
    assert_eq!(scene.views.len(), 3);
    assert!(scene.views.iter().all(|v| v.image().is_some() && v.mask().area() > 20));
    // A file chooser gives bare names: masks/view0.png and images/view0.png are both view0.png.
    let mut flat = FileSet::new();
    for name in set.names() {
        let bytes = set.find(&name, FileRole::Other).unwrap().unwrap().to_vec();
        flat.add(base_name(&name), bytes);
    }
    let (flat_scene, warnings, _) = flat.load().unwrap();
    assert!(warnings.is_empty(), "{warnings:?}");
    for (a, b) in flat_scene.views.iter().zip(&scene.views) {
        assert!(
            a.mask() == b.mask() && a.image() == b.image(),
            "view {}: mask and image in their places",
            a.name()
        );
    }
    // Masks only: the scene loads, with a warning per missing image.
    let mut masks_only = FileSet::new();
    for name in set.names().into_iter().filter(|n| !n.contains("images/")) {
        masks_only.add(&name, set.find(&name, FileRole::Other).unwrap().unwrap().to_vec());
    }
    let (_, warnings, _) = masks_only.load().unwrap();
    assert_eq!(warnings.len(), 3);
    assert!(warnings[1].contains("view 'view1'") && warnings[1].contains("images/view1.png"));
    // set_masks_only: the images given are left out (no warning), the masks the same.
    let mut flat_masks = flat.clone();
    flat_masks.set_masks_only(true);
    let (lean, warnings, _) = flat_masks.load().unwrap();
    assert!(warnings.is_empty(), "{warnings:?}");
    for (a, b) in lean.views.iter().zip(&scene.views) {
        assert!(a.image().is_none() && a.mask() == b.mask(), "view {}", a.name());
    }
}

#[test]
fn a_mesh_under_another_name_serves_the_scene_when_it_is_the_only_one() {
    let p = parts();
    let mut set = FileSet::new();
    set.add("scene.json", p.scene.clone().into_bytes());
    set.add("models/my-blob.glb", p.glb.clone());
    for (i, (_, mask, _)) in p.views.iter().enumerate() {
        set.add(&format!("masks/view{i}.png"), mask.clone());
    }
    let Plan::Scene { text, .. } = set.plan().unwrap() else {
        panic!("a scene")
    };
    assert!(text.contains("\"mesh\":\"models/my-blob.glb\""), "{text}");
    assert_eq!(set.load().unwrap().0.views.len(), 3);
    // With two meshes, neither named by the scene, nothing is guessed.
    set.add("other.ply", crate::io::ply::write_ascii(&blob_mesh(5, 5), "x"));
    let e = message(set.load());
    assert!(e.contains("blob.glb") && e.contains("not found"), "{e}");
}

#[test]
fn per_view_camera_files_find_their_masks_and_images_by_name() {
    let p = parts();
    let mut set = FileSet::new();
    set.add("blob.glb", p.glb.clone());
    // view0: masks/ and images/ folders; view1: NAME_mask.png, NAME_rgb.png; view2: a lone NAME.png.
    let [v0, v1, v2] = [&p.views[0], &p.views[1], &p.views[2]];
    set.add("cams/view0.json", v0.0.clone().into_bytes());
    set.add("masks/view0.png", v0.1.clone());
    set.add("images/view0.png", v0.2.clone());
    set.add("view1.json", v1.0.clone().into_bytes());
    set.add("view1_mask.png", v1.1.clone());
    set.add("view1_rgb.png", v1.2.clone());
    set.add("view2.json", v2.0.clone().into_bytes());
    set.add("View2.PNG", v2.1.clone());
    set.add("notes.txt", b"ignored".to_vec());
    let Plan::Scene { file, text } = set.plan().unwrap() else {
        panic!("a scene")
    };
    assert_eq!(file, "cameras.json");
    let v: Value = serde_json::from_str(&text).unwrap();
    assert_eq!(v["mesh"], "blob.glb");
    let views = v["views"].as_array().unwrap();
    let get = |i: usize, k: &str| views[i][k].as_str().map(str::to_string);
    assert_eq!(get(0, "mask").as_deref(), Some("masks/view0.png"));
    assert_eq!(get(0, "image").as_deref(), Some("images/view0.png"));
    assert_eq!(get(1, "mask").as_deref(), Some("view1_mask.png"));
    assert_eq!(get(1, "image").as_deref(), Some("view1_rgb.png"));
    assert_eq!(get(2, "mask").as_deref(), Some("View2.PNG"));
    assert_eq!(get(2, "image"), None);
    let (scene, warnings, _) = set.load().unwrap();
    assert!(warnings.is_empty());
    assert_eq!(scene.views[2].name(), "view2");
    assert!(scene.views[0].image().is_some() && scene.views[2].image().is_none());
}

#[test]
fn jpeg_photographs_are_found_by_name_and_decoded() {
    use image::ImageEncoder;
    let p = parts();
    let jpeg = |png: &[u8]| {
        let rgb = image::load_from_memory(png).unwrap().to_rgb8();
        let mut out = Vec::new();
        image::codecs::jpeg::JpegEncoder::new_with_quality(&mut out, 95)
            .write_image(rgb.as_raw(), rgb.width(), rgb.height(), image::ExtendedColorType::Rgb8)
            .unwrap();
        out
    };
    let mut set = FileSet::new();
    set.add("blob.glb", p.glb.clone());
    // view0: images/NAME.jpg; view1: a lone NAME.JPEG beside a lone NAME.png (the
    // mask); view2: NAME_rgb.jpg.
    let names = ["images/view0.jpg", "view1.JPEG", "view2_rgb.jpg"];
    let masks = ["masks/view0.png", "view1.png", "view2_mask.png"];
    for (i, (camera, mask, image)) in p.views.iter().enumerate() {
        set.add(&format!("view{i}.json"), camera.clone().into_bytes());
        set.add(masks[i], mask.clone());
        set.add(names[i], jpeg(image));
    }
    let Plan::Scene { text, .. } = set.plan().unwrap() else {
        panic!("a scene")
    };
    let v: Value = serde_json::from_str(&text).unwrap();
    for i in 0..3 {
        assert_eq!(v["views"][i]["image"], names[i], "{text}");
        assert_eq!(v["views"][i]["mask"], masks[i], "{text}");
    }
    let (scene, warnings, _) = set.load().unwrap();
    assert!(warnings.is_empty(), "{warnings:?}");
    let pngs = folder(&p, "s").load().unwrap().0;
    for (a, b) in scene.views.iter().zip(&pngs.views) {
        let (a, b) = (a.image().unwrap(), b.image().unwrap());
        assert_eq!((a.width, a.height), (b.width, b.height));
        let diff: f64 = a
            .data
            .iter()
            .zip(&b.data)
            .map(|(x, y)| (*x as f64 - *y as f64).abs())
            .sum::<f64>()
            / a.data.len() as f64;
        assert!(
            diff < 4.0,
            "the JPEG's pixels are the photograph's: mean difference {diff}"
        );
    }
    // A JPEG alone is a photograph, never a mask: a view with nothing else is named.
    let mut alone = FileSet::new();
    alone.add("blob.glb", p.glb.clone());
    alone.add("view0.json", p.views[0].0.clone().into_bytes());
    alone.add("view0.jpg", jpeg(&p.views[0].2));
    let Plan::Scene { text, .. } = alone.plan().unwrap() else {
        panic!("a scene")
    };
    let v: Value = serde_json::from_str(&text).unwrap();
    assert_eq!(v["views"][0]["image"], "view0.jpg");
    assert!(v["views"][0].get("mask").is_none(), "{text}");
}

#[test]
fn a_mask_and_an_image_of_the_same_name_are_told_apart_by_their_pixels() {
    let p = parts();
    let mut set = FileSet::new();
    set.add("blob.glb", p.glb.clone());
    for (i, (camera, mask, image)) in p.views.iter().enumerate() {
        set.add(&format!("view{i}.json"), camera.clone().into_bytes());
        set.add(&format!("view{i}.png"), image.clone());
        set.add(&format!("view{i}.png"), mask.clone());
    }
    let (scene, warnings, _) = set.load().unwrap();
    assert!(warnings.is_empty(), "{warnings:?}");
    let from_folder = folder(&p, "s").load().unwrap().0;
    for (a, b) in scene.views.iter().zip(&from_folder.views) {
        assert!(
            a.mask() == b.mask(),
            "view {}: the black-and-white file is the mask",
            a.name()
        );
        assert!(a.image() == b.image(), "view {}: the other one is the image", a.name());
    }
    // Two images of one name cannot be told apart.
    let mut two = FileSet::new();
    two.add("a/x.png", p.views[0].2.clone());
    two.add("b/x.png", p.views[1].2.clone());
    let e = two.find("x.png", FileRole::Image).unwrap_err();
    assert!(
        e.contains("ambiguous") && e.contains("a/x.png") && e.contains("b/x.png"),
        "{e}"
    );
}

#[test]
fn views_are_in_natural_order_and_may_carry_their_own_names_and_masks() {
    let p = parts();
    let mut set = FileSet::new();
    set.add("blob.ply", crate::io::ply::write_ascii(&blob_mesh(7, 11), "blob"));
    for (i, n) in [10, 2, 1].iter().enumerate() {
        // A scene view entry: a name, a mask path, the camera under "camera".
        let camera: Value = serde_json::from_str(&p.views[i].0).unwrap();
        let entry = json!({ "name": format!("cam{n}"), "mask": format!("m/{n}.png"), "camera": camera });
        set.add(&format!("c{n}.json"), entry.to_string().into_bytes());
        set.add(&format!("m/{n}.png"), p.views[i].1.clone());
    }
    let (scene, _, _) = set.load().unwrap();
    let names: Vec<&str> = scene.views.iter().map(|v| v.name()).collect();
    assert_eq!(names, ["cam1", "cam2", "cam10"]);
    assert_eq!(natural_cmp("view2", "view10"), Ordering::Less);
    assert_eq!(natural_cmp("View2", "view02"), Ordering::Less);
    assert_eq!(natural_cmp("b", "A"), Ordering::Greater);
}

#[test]
fn what_is_missing_or_ambiguous_is_named() {
    let p = parts();
    let camera = p.views[0].0.clone().into_bytes();
    let mut no_mesh = FileSet::new();
    no_mesh.add("view0.json", camera.clone());
    no_mesh.add("view0.png", p.views[0].1.clone());
    assert!(message(no_mesh.plan()).starts_with("no mesh: add a .glb, .gltf (with its .bin), .obj or .ply"));
    let mut two = no_mesh.clone();
    two.add("a.glb", p.glb.clone());
    two.add("b.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n".to_vec());
    assert_eq!(message(two.plan()), "several meshes (a.glb, b.obj): choose one");
    let mut no_mask = FileSet::new();
    no_mask.add("a.glb", p.glb.clone());
    no_mask.add("left.json", camera);
    assert_eq!(
        message(no_mask.plan()),
        "view 'left' (left.json): no mask and no photograph: add left.png (a mask or the photograph), \
         masks/left.png or images/left.png"
    );
    let mut scenes = folder(&p, "a");
    scenes.add("b/scene.json", p.scene.clone().into_bytes());
    let e = message(scenes.plan());
    assert!(e.starts_with("several scene files (a/scene.json, b/scene.json)"), "{e}");
    let mut bad = FileSet::new();
    bad.add("scene.json", b"{ nope".to_vec());
    assert!(message(bad.plan()).starts_with("scene.json: not valid JSON"));
    let mut nothing = FileSet::new();
    nothing.add("masks/a.png", p.views[0].1.clone());
    nothing.add("readme.txt", vec![]);
    let e = message(nothing.plan());
    assert!(
        e.starts_with("no scene.json or camera .json among masks/a.png, readme.txt"),
        "{e}"
    );
    assert_eq!(message(FileSet::new().plan()), "no files were given");
}

#[test]
fn a_mesh_alone_of_each_type_is_checked_and_said_to_lack_a_scene() {
    let mesh = blob_mesh(7, 11);
    let n = mesh.triangles.len();
    let (gltf, bin) = gltf_write::gltf_and_bin(&mesh, "m.gltf", "m.bin").unwrap();
    let obj: String = mesh
        .positions
        .iter()
        .map(|p| format!("v {} {} {}\n", p.x, p.y, p.z))
        .chain(
            mesh.triangles
                .iter()
                .map(|t| format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1)),
        )
        .collect();
    type Files<'a> = Vec<(&'a str, Vec<u8>)>;
    let cases: [(&str, Files); 4] = [
        ("m.glb", vec![("m.glb", gltf_write::glb(&mesh, "m.glb").unwrap())]),
        (
            "dir/m.gltf",
            vec![("dir/m.gltf", gltf.into_bytes()), ("dir/m.bin", bin)],
        ),
        ("m.obj", vec![("m.obj", obj.into_bytes())]),
        ("M.PLY", vec![("M.PLY", crate::io::ply::write_ascii(&mesh, "m"))]),
    ];
    for (file, files) in cases {
        let mut set = FileSet::new();
        for (p, b) in files {
            set.add(p, b);
        }
        assert_eq!(set.plan().unwrap(), Plan::MeshOnly { file: file.into() });
        let e = message(set.load());
        assert_eq!(
            e,
            format!(
                "{file}: a valid mesh ({n} triangles), but there is no scene: add a scene.json \
                 (or one camera .json per view) and the masks"
            )
        );
    }
    let mut broken = FileSet::new();
    broken.add("broken.glb", b"glTF\x02\x00\x00\x00garbage".to_vec());
    let e = message(broken.load());
    assert!(e.starts_with("mesh 'broken.glb'"), "{e}");
    assert!(is_mesh_file("a/B.Ply") && !is_mesh_file("a.bin"));
}

#[test]
fn find_goes_by_path_then_suffix_then_case() {
    let mut set = FileSet::new();
    set.add("scene/masks/a.png", vec![1]);
    set.add("scene/images/a.png", vec![2]);
    set.add("Models/Duck.GLB", vec![3]);
    assert_eq!(
        set.find("scene/masks/a.png", FileRole::Other).unwrap(),
        Some(&[1u8][..])
    );
    assert_eq!(
        set.find("./masks/../images/a.png", FileRole::Other).unwrap(),
        Some(&[2u8][..])
    );
    assert_eq!(set.find("masks/a.png", FileRole::Other).unwrap(), Some(&[1u8][..]));
    assert_eq!(set.find("duck.glb", FileRole::Other).unwrap(), Some(&[3u8][..]));
    assert!(set.find("a.png", FileRole::Other).unwrap_err().contains("ambiguous"));
    assert_eq!(set.find("other/a.png", FileRole::Other).unwrap(), None);
    set.add("scene/masks/a.png", vec![1]);
    assert_eq!(set.len(), 3, "an exact duplicate is ignored");
}

#[test]
fn the_files_a_scene_and_a_gltf_name_are_listed() {
    let text = r#"{"mesh": "../models/m.gltf", "views": [
        {"name": "a", "mask": "masks/a.png", "image": "images/a.png", "ignore": "masks/a_ignore.png", "camera": {}},
        {"name": "b", "mask": "masks/b.png", "image": "masks/b.png", "camera": {}}]}"#;
    assert_eq!(
        scene_references("ex/toy/scene.json", text).unwrap(),
        [
            "ex/models/m.gltf",
            "ex/toy/masks/a.png",
            "ex/toy/images/a.png",
            "ex/toy/masks/a_ignore.png",
            "ex/toy/masks/b.png"
        ]
    );
    assert!(message(scene_references("s.json", "{\"views\": []}")).contains("\"mesh\""));
    let mesh = blob_mesh(5, 5);
    let (gltf, _) = gltf_write::gltf_and_bin(&mesh, "m.gltf", "bufs/m.bin").unwrap();
    assert_eq!(
        mesh_references("ex/models/m.gltf", gltf.as_bytes()),
        ["ex/models/bufs/m.bin"]
    );
    assert!(mesh_references("m.glb", &gltf_write::glb(&mesh, "m.glb").unwrap()).is_empty());
    assert!(mesh_references("m.ply", b"ply\n").is_empty());
}
