//! The 3D view's getters (`src/wasm/scene_view.rs`): the display mesh (capped at
//! 200k triangles), the cameras in scene-file form, each view's picture, the cameras'
//! frames (and those of any cameras, `framesOfCameras`) and a finished fit's ghosts.

use super::{file_set, js_get, js_message, toy_example};
use glam::{DMat4, DVec3};
use localisebot::app::shapes::toy_plane;
use localisebot::wasm::{display_mesh, frames_of_cameras, Session, MAX_DISPLAY_TRIANGLES};
use localisebot::{mat4_from_rows, CameraJson, Mesh};
use serde_json::Value;
use wasm_bindgen::{JsCast, JsValue};
use wasm_bindgen_test::wasm_bindgen_test;

fn json(v: JsValue) -> Value {
    serde_wasm_bindgen::from_value(v).unwrap()
}

fn v3(v: &Value) -> DVec3 {
    DVec3::from_array(serde_json::from_value(v.clone()).unwrap())
}

fn m4(v: &Value) -> DMat4 {
    mat4_from_rows(serde_json::from_value(v.clone()).unwrap())
}

/// Every number in a JSON value, in order.
fn numbers(v: &Value) -> Vec<f64> {
    match v {
        Value::Array(a) => a.iter().flat_map(numbers).collect(),
        v => vec![v.as_f64().unwrap()],
    }
}

/// A row-major 16-number matrix.
fn m16(v: &Value) -> DMat4 {
    let a: [f64; 16] = serde_json::from_value(v.clone()).unwrap();
    DMat4::from_cols_array(&a).transpose()
}

/// A flat (rows × rows × 2)-triangle grid over the unit square, gently curved.
fn grid(rows: u32) -> Mesh {
    let n = rows + 1;
    let positions = (0..n * n)
        .map(|i| {
            let (x, y) = ((i % n) as f64 / rows as f64, (i / n) as f64 / rows as f64);
            glam::DVec3::new(x, y, 0.1 * (x * 6.0).sin() * (y * 5.0).cos())
        })
        .collect();
    let mut triangles = Vec::new();
    for r in 0..rows {
        for c in 0..rows {
            let a = r * n + c;
            triangles.push([a, a + 1, a + n + 1]);
            triangles.push([a, a + n + 1, a + n]);
        }
    }
    Mesh { positions, triangles }
}

#[wasm_bindgen_test]
fn the_display_mesh_is_the_mesh_up_to_the_cap_and_clustered_above() {
    let toy = toy_plane();
    assert_eq!(display_mesh(&toy, MAX_DISPLAY_TRIANGLES), toy);
    let big = grid(330); // 217,800 triangles
    assert!(big.triangle_count() > MAX_DISPLAY_TRIANGLES);
    let shown = display_mesh(&big, MAX_DISPLAY_TRIANGLES);
    assert!(
        shown.triangle_count() <= MAX_DISPLAY_TRIANGLES && shown.triangle_count() > 20_000,
        "{} triangles",
        shown.triangle_count()
    );
    let (a, b) = (big.bounds().unwrap(), shown.bounds().unwrap());
    assert!((a.size() - b.size()).abs().max_element() < 0.02, "{a:?} vs {b:?}");
    assert!(shown
        .triangles
        .iter()
        .flatten()
        .all(|&i| (i as usize) < shown.positions.len()));
}

#[wasm_bindgen_test]
fn geometry_cameras_and_pictures_are_what_the_session_fits() {
    let ex = toy_example();
    let session = Session::from_files(&file_set(&ex, false)).unwrap();
    let mesh = session.estimator().mesh().clone();

    let g = session.geometry().unwrap();
    let positions: js_sys::Float32Array = js_get(&g, "positions").dyn_into().unwrap();
    let indices: js_sys::Uint32Array = js_get(&g, "indices").dyn_into().unwrap();
    assert_eq!(positions.length() as usize, 3 * mesh.positions.len());
    assert_eq!(indices.length() as usize, 3 * mesh.triangle_count());
    let (p, ix) = (positions.to_vec(), indices.to_vec());
    for (k, v) in mesh.positions.iter().enumerate() {
        assert_eq!(
            [p[3 * k], p[3 * k + 1], p[3 * k + 2]],
            [v.x as f32, v.y as f32, v.z as f32]
        );
    }
    assert_eq!(ix, mesh.triangles.iter().flatten().copied().collect::<Vec<u32>>());
    assert_eq!(js_get(&g, "decimated").as_bool(), Some(false));
    assert_eq!(js_get(&g, "triangles").as_f64(), Some(mesh.triangle_count() as f64));

    // Cameras: the scene file's form, OpenCV world_to_camera rows, in view order.
    let cams: serde_json::Value = serde_wasm_bindgen::from_value(session.cameras().unwrap()).unwrap();
    let cams = cams.as_array().unwrap();
    assert_eq!(cams.len(), 4);
    for (c, v) in cams.iter().zip(session.estimator().views()) {
        assert_eq!(c["name"], v.name());
        let json: CameraJson = serde_json::from_value(c.clone()).unwrap();
        assert_eq!(json, CameraJson::from_camera(v.camera()), "exactly the view's camera");
        // Read back as a scene file would be (its rotation re-projected onto SO(3)).
        let back = json.to_camera(v.name()).unwrap();
        assert!(back.rotation.abs_diff_eq(v.camera().rotation, 1e-12));
        assert_eq!(back.translation, v.camera().translation);
        let keys: Vec<&String> = c.as_object().unwrap().keys().collect();
        assert_eq!(keys.len(), 8, "{keys:?}");
    }

    // Pictures: the photograph, reduced by a whole factor; the mask without one.
    let pic = session.view_picture(0, 100).unwrap();
    assert_eq!(js_get(&pic, "kind").as_string().unwrap(), "image");
    let (w, h) = (
        js_get(&pic, "width").as_f64().unwrap(),
        js_get(&pic, "height").as_f64().unwrap(),
    );
    assert_eq!((w, h), (86.0, 86.0), "256 px by a factor 3, rounded up");
    let rgba: js_sys::Uint8ClampedArray = js_get(&pic, "rgba").dyn_into().unwrap();
    assert_eq!(rgba.length() as f64, w * h * 4.0);
    let full = session.view_picture(1, 0).unwrap();
    assert_eq!(js_get(&full, "width").as_f64(), Some(256.0));
    let image = session.estimator().views()[1].image().unwrap();
    let data: js_sys::Uint8ClampedArray = js_get(&full, "rgba").dyn_into().unwrap();
    assert_eq!(data.to_vec(), image.data);
    assert!(session.view_picture(4, 0).is_err());

    let masks_only: Vec<_> = ex.iter().filter(|(p, _)| !p.contains("images/")).cloned().collect();
    let session = Session::from_files(&file_set(&masks_only, false)).unwrap();
    let pic = session.view_picture(2, 0).unwrap();
    assert_eq!(js_get(&pic, "kind").as_string().unwrap(), "mask");
    let data: js_sys::Uint8ClampedArray = js_get(&pic, "rgba").dyn_into().unwrap();
    let mask = session.estimator().views()[2].mask();
    for (px, &m) in data.to_vec().chunks_exact(4).zip(&mask.data) {
        assert_eq!(
            px,
            if m != 0 {
                [255, 255, 255, 255]
            } else {
                [40, 40, 40, 255]
            }
        );
    }
}

#[wasm_bindgen_test]
fn camera_frames_are_the_views_cameras_looking_at_the_object() {
    let ex = toy_example();
    let mut session = Session::from_files(&file_set(&ex, false)).unwrap();
    let s = json(session.camera_frames(Some(1.5)).unwrap());
    let frames = s["frames"].as_array().unwrap();
    let views = session.estimator().views();
    assert_eq!(frames.len(), views.len());
    let target = v3(&s["target"]);
    assert_eq!(v3(&s["meet"]), target, "the synthetic views' axes meet");
    let depth = s["depth"].as_f64().unwrap();
    let mut dists: Vec<f64> = views.iter().map(|v| v.camera().centre().distance(target)).collect();
    dists.sort_by(f64::total_cmp);
    assert!((depth - 0.3 * dists[dists.len() / 2]).abs() < 1e-9, "{depth}");
    // The views look at the object: its centre near the target (synth aims at it).
    let truth = session.estimator().mesh().bounds().unwrap().centre();
    let gt: Value = serde_json::from_slice(&ex[0].1).unwrap();
    let pose =
        localisebot::PoseJson::to_pose(&serde_json::from_value(gt["ground_truth_pose"].clone()).unwrap()).unwrap();
    assert!(
        pose.apply(truth).distance(target) < 0.1 * dists[0],
        "{target} vs {}",
        pose.apply(truth)
    );
    let up = v3(&s["up"]);
    let mean_y: DVec3 = views.iter().map(|v| v.camera().rotation.row(1)).sum();
    assert!(up.abs_diff_eq(-mean_y.normalize(), 1e-12), "minus the mean y axis");
    for (f, v) in frames.iter().zip(views) {
        let cam = v.camera();
        assert!((m4(&f["camera_to_world"]) * cam.world_to_camera_matrix()).abs_diff_eq(DMat4::IDENTITY, 1e-12));
        assert!(v3(&f["centre"]).abs_diff_eq(cam.centre(), 1e-12));
        assert!(v3(&f["z"]).abs_diff_eq(cam.rotation.row(2), 1e-15));
        // The image plane's bottom-right corner lies on the last pixel's outer edge.
        let corner = m4(&f["camera_to_world"]).transform_point3(v3(&f["corners"][2]));
        let uv = cam.project(cam.to_camera(corner));
        assert!((uv.x - (cam.width as f64 - 0.5)).abs() < 1e-6 && (uv.y - (cam.height as f64 - 0.5)).abs() < 1e-6);
        assert!((v3(&f["corners"][0]).z - depth).abs() < 1e-12);
        // Looking through it: OpenGL axes, orbiting a point on its axis.
        let gl = m4(&f["viewer_to_world"]);
        assert!((-gl.z_axis.truncate()).abs_diff_eq(cam.rotation.row(2), 1e-15));
        let look = v3(&f["look_at"]);
        assert!((look - cam.centre()).normalize().abs_diff_eq(cam.rotation.row(2), 1e-9));
    }
    let home = &s["home"];
    assert!(v3(&home["position"]).is_finite() && (v3(&home["position"]) - target).dot(up) > 0.0);
    assert_eq!(home["fov_deg"].as_f64(), Some(45.0));
    assert!(home["near"].as_f64().unwrap() > 0.0);

    // The frames of the same cameras as JSON (the suggestions' way): the same (up to
    // the rotation's re-projection onto SO(3) as a camera is read), without `look_at`.
    let again = json(frames_of_cameras(session.cameras().unwrap(), depth).unwrap());
    for (a, f) in again.as_array().unwrap().iter().zip(frames) {
        let mut f = f.clone();
        f.as_object_mut().unwrap().remove("look_at");
        let (a, f) = (a.as_object().unwrap(), f.as_object().unwrap());
        assert_eq!(a.keys().collect::<Vec<_>>(), f.keys().collect::<Vec<_>>());
        for (key, value) in a {
            let (x, y) = (numbers(value), numbers(&f[key]));
            assert_eq!(x.len(), y.len(), "{key}");
            assert!(
                x.iter().zip(&y).all(|(p, q)| (p - q).abs() < 1e-12),
                "{key}: {x:?} vs {y:?}"
            );
        }
    }
    // Plain JavaScript objects, as the page has them; the second camera is not valid.
    let bad = js_sys::JSON::parse(
        r#"[{ "name": "ok", "width": 8, "height": 8, "fx": 8, "fy": 8, "cx": 4, "cy": 4,
              "world_to_camera": [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 1], [0, 0, 0, 1]] },
            { "width": 8, "height": 8, "fx": -1, "fy": 8, "cx": 4, "cy": 4,
              "world_to_camera": [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 1], [0, 0, 0, 1]] }]"#,
    )
    .unwrap();
    let one = js_sys::Array::of1(&js_sys::Array::from(&bad).get(0));
    assert_eq!(
        json(frames_of_cameras(one.into(), 1.0).unwrap())
            .as_array()
            .unwrap()
            .len(),
        1
    );
    let msg = js_message(frames_of_cameras(bad, 1.0).err().unwrap());
    assert!(msg.contains("camera 1") && msg.contains("focal"), "{msg}");
    let msg = js_message(frames_of_cameras(js_sys::Array::new().into(), 0.0).err().unwrap());
    assert!(msg.contains("depth"), "{msg}");
    assert!(frames_of_cameras(JsValue::from_str("no"), 1.0).is_err());

    // No ghosts before the fit is done; the progress carries the pose's matrix.
    assert_eq!(json(session.ghosts(12, 1).unwrap()), serde_json::json!([]));
    let progress = json(session.progress().unwrap());
    assert!(m4(&progress["matrix"]).abs_diff_eq(session.estimator().pose().matrix(), 1e-12));
}

/// Called by the fit test (`a_fit_converges_to_the_native_result`) with its finished
/// session and result: 12 ghosts about the result's matrix, spread as its standard
/// deviations say, the same for the same seed.
pub(super) fn ghosts_of_a_finished_fit(session: &mut Session, result: &Value) {
    let ghosts = json(session.ghosts(12, 1).unwrap());
    let ghosts = ghosts.as_array().unwrap();
    assert_eq!(ghosts.len(), 12);
    assert_eq!(
        json(session.ghosts(12, 1).unwrap()).as_array().unwrap(),
        ghosts,
        "seeded"
    );
    assert_ne!(json(session.ghosts(12, 2).unwrap()).as_array().unwrap(), ghosts);
    let m = m4(&result["matrix"]);
    let sd = v3(&result["std_dev"]["translation"]);
    let shifts: Vec<f64> = ghosts
        .iter()
        .map(|g| {
            let g = m16(g);
            assert!(g.is_finite());
            assert_eq!(g.row(3), glam::DVec4::W, "an affine matrix");
            (g.w_axis - m.w_axis).truncate().length()
        })
        .collect();
    assert!(shifts.iter().all(|&d| d < 6.0 * sd.length()), "{shifts:?} vs σ {sd}");
    assert!(shifts.iter().any(|&d| d > 0.0), "the ghosts spread");
    // Progress and result agree on the pose's matrix.
    let p = json(session.step(1).unwrap());
    assert!(m4(&p["matrix"]).abs_diff_eq(m, 1e-12));
}
