//! The 3D view's getters (`src/wasm/scene_view.rs`): the display mesh (capped at
//! 200k triangles), the cameras in scene-file form, each view's picture.

use super::{file_set, js_get, toy_example};
use localisebot::app::shapes::toy_plane;
use localisebot::wasm::{display_mesh, Session, MAX_DISPLAY_TRIANGLES};
use localisebot::{CameraJson, Mesh};
use wasm_bindgen::JsCast;
use wasm_bindgen_test::wasm_bindgen_test;

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
