//! The native side of the wasm parity check, on `tests/fixtures/scenes/toy-3view`: three
//! 240×200 views of the procedural toy aeroplane (`localisebot::app::shapes::toy_plane`) made
//! by `synthesize` (seed 5). Its mesh file `toy.glb` is not kept: every test writes it
//! with `io::gltf_write::glb`. This test checks that the committed masks are what the
//! native hard rasteriser draws now, and that the native fit matches `native_fit.json`,
//! the file the WebAssembly suites (`tests/wasm_common`) compare their own fit with.
//! After a change to the shapes, `synth` or the estimator, rewrite the folder with
//! `LOCALISEBOT_BLESS=1 cargo test --test wasm_parity`.
#![cfg(not(target_arch = "wasm32"))]

use localisebot::app::shapes::toy_plane;
use localisebot::app::synth::{synthesize, SynthSettings};
use localisebot::io::gltf_write;
use localisebot::io::png::encode_gray;
use localisebot::raster::hard;
use localisebot::{load_scene, CameraJson, PoseJson, SceneJson, ViewJson};
use localisebot::{Estimator, FitSettings};
use serde_json::Value;
use std::path::PathBuf;

fn dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/scenes/toy-3view")
}

/// Writes the scene: `scene.json` (cameras, ground truth) and `masks/view*.png`.
fn bless_scene() {
    let mesh = toy_plane();
    let settings = SynthSettings {
        views: 3,
        width: 240,
        height: 200,
        seed: 5,
        ..Default::default()
    };
    let s = synthesize(&mesh, &settings, None).unwrap();
    let dir = dir();
    std::fs::create_dir_all(dir.join("masks")).unwrap();
    let mut views = Vec::new();
    for (i, v) in s.views().iter().enumerate() {
        let rel = format!("masks/view{i}.png");
        let grey: Vec<u8> = v.mask().data.iter().map(|&o| o * 255).collect();
        std::fs::write(dir.join(&rel), encode_gray(v.mask().width, v.mask().height, &grey)).unwrap();
        views.push(ViewJson {
            ignore: None,
            name: v.name().to_string(),
            image: None,
            mask: Some(rel),
            hint_box: None,
            camera: CameraJson::from_camera(v.camera()),
        });
    }
    let json = SceneJson {
        version: 1,
        mesh: "toy.glb".into(),
        views,
        initial_pose: None,
        ground_truth_pose: Some(PoseJson::from_pose(&s.pose)),
        grasps: Vec::new(),
    };
    std::fs::write(dir.join("scene.json"), json.to_json_string() + "\n").unwrap();
}

/// Equal structure and strings; numbers equal to 1e-9 relative.
fn close(a: &Value, b: &Value) -> bool {
    match (a, b) {
        (Value::Number(x), Value::Number(y)) => {
            let (x, y) = (x.as_f64().unwrap(), y.as_f64().unwrap());
            (x - y).abs() <= 1e-9 * (1.0 + y.abs())
        }
        (Value::Array(x), Value::Array(y)) => x.len() == y.len() && x.iter().zip(y).all(|(x, y)| close(x, y)),
        (Value::Object(x), Value::Object(y)) => {
            x.len() == y.len() && x.iter().all(|(k, v)| y.get(k).is_some_and(|w| close(v, w)))
        }
        _ => a == b,
    }
}

#[test]
fn the_recorded_scene_and_native_fit_are_current() {
    let bless = std::env::var_os("LOCALISEBOT_BLESS").is_some();
    if bless {
        bless_scene();
    }
    let stale = "tests/fixtures/scenes/toy-3view is stale: rewrite it with \
                 `LOCALISEBOT_BLESS=1 cargo test --test wasm_parity`";
    let dir = dir();
    let mesh = toy_plane();
    let glb = gltf_write::glb(&mesh, "toy.glb").unwrap();
    let text = std::fs::read_to_string(dir.join("scene.json")).unwrap();
    let files = |p: &str| {
        if p == "toy.glb" {
            Some(glb.clone())
        } else {
            std::fs::read(dir.join(p)).ok()
        }
    };
    let scene = load_scene("scene.json", &text, &files).unwrap();
    let truth = scene.ground_truth_pose.unwrap();
    assert_eq!(scene.views.len(), 3);
    // The masks are the hard rasteriser's at the true pose, on the mesh as written.
    for v in &scene.views {
        assert!(v.mask().area() > 500, "view {}: the aeroplane is in view", v.name());
        assert!(
            hard::render(&scene.mesh, &truth, v.camera()) == *v.mask(),
            "{stale}: view {}'s mask",
            v.name()
        );
    }

    let mut est = Estimator::new(scene.mesh, scene.views, scene.initial_pose, FitSettings::default()).unwrap();
    while !est.is_done() {
        est.step().unwrap();
    }
    let result = est.result(0.0, Some(&truth));
    let now = serde_json::to_value(&result).unwrap();
    let path = dir.join("native_fit.json");
    if bless {
        std::fs::write(&path, serde_json::to_string_pretty(&now).unwrap() + "\n").unwrap();
    }
    let recorded: Value = serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    assert!(
        close(&now["pose"], &recorded["pose"]),
        "{stale}: pose {} vs {}",
        now["pose"],
        recorded["pose"]
    );
    assert!(
        close(&now["views"], &recorded["views"]),
        "{stale}: views {} vs {}",
        now["views"],
        recorded["views"]
    );
    assert_eq!(now["iterations"], recorded["iterations"], "{stale}");
    // The recorded fit is a good one, so the wasm suites compare with a sound reference.
    assert!(
        now["mean_iou"].as_f64().unwrap() >= 0.95,
        "mean IoU {}",
        now["mean_iou"]
    );
    assert!(
        now["errors"]["rotation_deg"].as_f64().unwrap() < 2.0,
        "{}",
        now["errors"]
    );
}
