//! Importers: NeRF `transforms_train.json` (the lego scene of `../shared/data/multiview`, values from
//! `../shared/data/SOURCES.md`) and BOP (the hand-made `tests/fixtures/bop_mini`, whose
//! numbers `generate.py` there documents), each loaded end to end as a scene.

use crate::{data, fixture};
use glam::{DMat3, DMat4, DVec2, DVec3};
use localisebot::io::bop::{self, BopOptions, Units};
use localisebot::io::mask::decode_mask;
use localisebot::io::nerf::{self, Imported};
use localisebot::{load_scene, metrics, raster, Scene};
use localisebot::{mat3_from_rows, mat4_from_rows};
use std::collections::HashMap;

/// Loads an imported scene through `load_scene`, from memory: the scene file
/// `out/scene.json`, the files the importer produced, plus `extra` ones.
fn load_imported(imp: &Imported, extra: &[(&str, Vec<u8>)]) -> Scene {
    let mut files: HashMap<String, Vec<u8>> = imp.files.iter().map(|(p, b)| (format!("out/{p}"), b.clone())).collect();
    for (p, b) in extra {
        files.insert(format!("out/{p}"), b.clone());
    }
    load_scene("out/scene.json", &imp.scene.to_json_string(), &|p| {
        files.get(p).cloned()
    })
    .unwrap()
}

fn file<'a>(imp: &'a Imported, path: &str) -> &'a [u8] {
    &imp.files
        .iter()
        .find(|(p, _)| p == path)
        .unwrap_or_else(|| panic!("{path} not written"))
        .1
}

#[test]
fn nerf_lego_six_views() {
    let dir = data("multiview/nerf_synthetic_lego");
    let text = std::fs::read_to_string(dir.join("transforms_train.json")).unwrap();
    let imp = nerf::import(
        "transforms_train.json",
        &text,
        &|p| std::fs::read(dir.join(p)).ok(),
        "box.glb",
    )
    .unwrap();
    let names: Vec<&str> = imp.scene.views.iter().map(|v| v.name.as_str()).collect();
    assert_eq!(names, ["r_0", "r_2", "r_4", "r_5", "r_6", "r_18"]);
    assert_eq!(imp.warnings.len(), 94);
    assert!(imp.warnings.iter().all(|w| w.contains("image not found")));
    assert!(imp.warnings[0].contains("./train/r_1"), "{}", imp.warnings[0]);
    let areas = [149690, 189434, 188094, 223626, 226206, 201314];
    for (v, area) in imp.scene.views.iter().zip(areas) {
        let cam = v.camera.to_camera(&v.name).unwrap();
        assert!((cam.fx - 1111.111).abs() < 1e-3 && cam.fx == cam.fy, "{}", cam.fx);
        assert_eq!((cam.width, cam.height, cam.cx, cam.cy), (800, 800, 399.5, 399.5));
        assert!(
            (cam.centre().length() - 4.031).abs() < 1e-3,
            "{}: {}",
            v.name,
            cam.centre().length()
        );
        let pc = cam.to_camera(DVec3::ZERO);
        assert!(pc.z > 0.0);
        let uv = cam.project(pc);
        assert!((uv - DVec2::splat(399.5)).length() < 0.01, "{}: origin at {uv}", v.name);
        let mask_file = v.mask.as_deref().unwrap();
        let mask = decode_mask(file(&imp, mask_file), &v.name, mask_file).unwrap();
        assert!(
            (mask.area() as f64 - area as f64).abs() <= 0.01 * area as f64,
            "{}: {}",
            v.name,
            mask.area()
        );
        assert_eq!(
            mask.area(),
            area,
            "{}: alpha ≥ 128 is the same rule as alpha > 127",
            v.name
        );
        for (x, y) in [(399, 399), (400, 399), (399, 400), (400, 400)] {
            assert!(
                mask.get(x, y),
                "{}: the origin's pixel ({x}, {y}) is not object",
                v.name
            );
        }
        // The written image is the original file.
        let image = v.image.as_deref().unwrap();
        assert_eq!(
            file(&imp, image),
            std::fs::read(dir.join("train").join(format!("{}.png", v.name))).unwrap()
        );
    }
    // End to end: the scene file loads (with Box as a stand-in mesh).
    let boxed = std::fs::read(data("gltf/Box/glTF-Binary/Box.glb")).unwrap();
    let scene = load_imported(&imp, &[("box.glb", boxed)]);
    assert_eq!(scene.views.len(), 6);
    assert_eq!(scene.mesh.triangle_count(), 12);
    for (v, area) in scene.views.iter().zip(areas) {
        assert_eq!(v.mask().area(), area);
        assert_eq!(v.image().map(|i| (i.width, i.height)), Some((800, 800)));
        assert!((v.camera().project(v.camera().to_camera(DVec3::ZERO)) - DVec2::splat(399.5)).length() < 0.01);
    }
}

// ---- BOP -------------------------------------------------------------------

fn bop_files() -> impl Fn(&str) -> Option<Vec<u8>> {
    let dir = fixture("bop_mini");
    move |p: &str| std::fs::read(dir.join(p)).ok()
}

/// `scene_camera.json` / `scene_gt.json` of the fixture, as rigid transforms in mm.
fn fixture_poses(
    scene: &str,
    file: &str,
    r: &str,
    t: &str,
    pick: fn(&serde_json::Value) -> &serde_json::Value,
) -> Vec<DMat4> {
    let text = std::fs::read_to_string(fixture(&format!("bop_mini/test/{scene}/{file}"))).unwrap();
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    ["1", "4", "9"]
        .iter()
        .map(|id| {
            let e = pick(&v[id]);
            let n = |k: &str, i: usize| e[k][i].as_f64().unwrap();
            let rot = mat3_from_rows([
                [n(r, 0), n(r, 1), n(r, 2)],
                [n(r, 3), n(r, 4), n(r, 5)],
                [n(r, 6), n(r, 7), n(r, 8)],
            ]);
            DMat4::from_cols(
                rot.x_axis.extend(0.),
                rot.y_axis.extend(0.),
                rot.z_axis.extend(0.),
                DVec3::new(n(t, 0), n(t, 1), n(t, 2)).extend(1.),
            )
        })
        .collect()
}

fn scaled(m: DMat4, unit: f64) -> DMat4 {
    let mut m = m;
    m.w_axis = (m.w_axis.truncate() * unit).extend(1.0);
    m
}

fn close(a: DMat4, b: DMat4, tol: f64) -> bool {
    a.abs_diff_eq(b, tol)
}

/// Every view: the hard render of the mesh at the ground truth matches the mask.
fn assert_renders_match(scene: &Scene) {
    let gt = scene.ground_truth_pose.unwrap();
    for v in &scene.views {
        let rendered = raster::hard::render(&scene.mesh, &gt, v.camera());
        let iou = metrics::hard_iou(&rendered, v.mask());
        assert!(iou > 0.95, "view {}: IoU {iou}", v.name());
        // The object's centre projects where BOP's own annotation puts it.
        let c = v.camera().project(v.camera().to_camera(gt.translation));
        assert!(v.mask().get(c.x.round() as u32, c.y.round() as u32));
    }
}

#[test]
fn bop_with_world_extrinsics_in_metres_and_mm() {
    let files = bop_files();
    let imp = bop::import(&files, &BopOptions::new(1, 1)).unwrap();
    assert!(imp.warnings.is_empty(), "{:?}", imp.warnings);
    let names: Vec<&str> = imp.scene.views.iter().map(|v| v.name.as_str()).collect();
    assert_eq!(names, ["000001", "000004", "000009"]);
    // Image 1 lists a distractor first: object 1's mask there is GT id 1.
    assert_eq!(
        file(&imp, "masks/000001.png"),
        files("test/000001/mask/000001_000001.png").unwrap()
    );
    // Ground truth: Rz(30°), (10, −20, 40) mm, in metres.
    let gt = imp.scene.ground_truth_pose.as_ref().unwrap().to_pose().unwrap();
    assert!(gt
        .rotation
        .abs_diff_eq(DMat3::from_rotation_z(30f64.to_radians()), 1e-9));
    assert!((gt.translation - DVec3::new(0.010, -0.020, 0.040)).length() < 1e-12);
    assert_eq!(gt.scale, DVec3::ONE);
    // Cameras: the dataset's cam_R_w2c, cam_t_w2c × 0.001.
    let w2c = fixture_poses("000001", "scene_camera.json", "cam_R_w2c", "cam_t_w2c", |e| e);
    for (v, expected) in imp.scene.views.iter().zip(&w2c) {
        let cam = v.camera.to_camera(&v.name).unwrap();
        assert!(
            close(cam.world_to_camera_matrix(), scaled(*expected, 0.001), 1e-12),
            "{}",
            v.name
        );
        assert_eq!((cam.fx, cam.fy, cam.cx, cam.cy), (410.0, 405.0, 98.2, 76.4));
        assert_eq!((cam.width, cam.height), (200, 150));
    }
    assert_eq!(imp.scene.mesh, "obj_000001_m.ply");
    let scene = load_imported(&imp, &[]);
    let b = scene.mesh.bounds().unwrap();
    assert!((b.max - DVec3::new(0.02, 0.03, 0.04)).length() < 1e-12 && (b.min + b.max).length() < 1e-12);
    assert_renders_match(&scene);

    // Millimetres: the same numbers × 1000 and the model copied as it is.
    let mut opts = BopOptions::new(1, 1);
    opts.units = Units::Millimetres;
    let imp = bop::import(&files, &opts).unwrap();
    let gt = imp.scene.ground_truth_pose.as_ref().unwrap().to_pose().unwrap();
    assert!((gt.translation - DVec3::new(10.0, -20.0, 40.0)).length() < 1e-9);
    assert_eq!(imp.scene.mesh, "obj_000001.ply");
    assert_eq!(file(&imp, "obj_000001.ply"), files("models/obj_000001.ply").unwrap());
    let cam = imp.scene.views[2].camera.to_camera("000009").unwrap();
    assert!(close(cam.world_to_camera_matrix(), w2c[2], 1e-9));
    assert_renders_match(&load_imported(&imp, &[]));
}

#[test]
fn bop_without_extrinsics_uses_the_first_camera_as_world() {
    let files = bop_files();
    let imp = bop::import(&files, &BopOptions::new(2, 1)).unwrap();
    assert!(imp.warnings.is_empty(), "{:?}", imp.warnings);
    let w2c = fixture_poses("000001", "scene_camera.json", "cam_R_w2c", "cam_t_w2c", |e| e);
    let m2c = fixture_poses("000002", "scene_gt.json", "cam_R_m2c", "cam_t_m2c", |l| {
        l.as_array().unwrap().iter().find(|e| e["obj_id"] == 1).unwrap()
    });
    // Ground truth: image 1's own annotation T_m2c, in metres.
    let gt = imp.scene.ground_truth_pose.as_ref().unwrap().to_pose().unwrap();
    assert!(close(gt.matrix(), scaled(m2c[0], 0.001), 1e-9));
    // Cameras: the first is the identity; the others are placed relative to it exactly
    // as the dataset's world extrinsics place them: T_w2c(i) · T_w2c(1)⁻¹.
    for (i, v) in imp.scene.views.iter().enumerate() {
        let cam = v.camera.to_camera(&v.name).unwrap();
        let expected = scaled(w2c[i] * w2c[0].inverse(), 0.001);
        assert!(close(cam.world_to_camera_matrix(), expected, 1e-9), "{}", v.name);
    }
    assert!(close(
        mat4_from_rows(imp.scene.views[0].camera.world_to_camera.unwrap()),
        DMat4::IDENTITY,
        1e-12
    ));
    assert_renders_match(&load_imported(&imp, &[]));
}

#[test]
fn bop_image_choice_and_errors() {
    let files = bop_files();
    let mut opts = BopOptions::new(1, 1);
    opts.image_ids = Some(vec![9, 5, 4]);
    let imp = bop::import(&files, &opts).unwrap();
    let names: Vec<&str> = imp.scene.views.iter().map(|v| v.name.as_str()).collect();
    assert_eq!(names, ["000009", "000004"]);
    assert_eq!(imp.warnings.len(), 1);
    assert!(imp.warnings[0].contains("image 000005"), "{}", imp.warnings[0]);
    // The ground truth does not depend on which image comes first.
    let gt = imp.scene.ground_truth_pose.as_ref().unwrap().to_pose().unwrap();
    assert!((gt.translation - DVec3::new(0.010, -0.020, 0.040)).length() < 1e-9);
    // Object 2 (the distractor) has neither masks nor a model.
    let e = bop::import(&files, &BopOptions::new(1, 2)).unwrap_err().to_string();
    assert!(e.contains("no image of scene 1 shows object 2"), "{e}");
    let e = bop::import(&files, &BopOptions::new(7, 1)).unwrap_err().to_string();
    assert!(
        e.contains("test/000007/scene_camera.json") && e.contains("not found"),
        "{e}"
    );
    opts.models_dir = "models_eval".into();
    let e = bop::import(&files, &opts).unwrap_err().to_string();
    assert!(e.contains("models_eval/obj_000001.ply"), "{e}");
}
