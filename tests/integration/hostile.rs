//! Numbers that are not numbers, and shapes that are not objects (issue 23, item 4):
//! NaN, ±∞, 1e300, denormals and −0 in cameras, poses, mesh vertices and box hints;
//! degenerate meshes; an object smaller than a pixel or larger than the view; a mask
//! that is all object. Each gets a clear error or a fit whose result holds no NaN —
//! never a panic, never a hang (every fit here has a bounded schedule).

use glam::DVec3;
use localisebot::io::png::{encode_gray, encode_rgba};
use localisebot::{load_scene, Camera, CameraJson, Estimator, FitSettings, Mask, Mesh, Pose, PoseJson, Rgba, View};
use serde_json::{json, Value};

/// Three cameras 4 units from the origin, 64×48 pixels.
fn cameras() -> Vec<Camera> {
    [
        DVec3::new(0.3, 0.2, 1.0),
        DVec3::new(1.0, 0.4, 0.1),
        DVec3::new(-0.2, 1.0, 0.5),
    ]
    .iter()
    .map(|d| Camera::look_at(4.0 * d.normalize(), DVec3::ZERO, DVec3::Y, 64, 48, 60.0))
    .collect()
}

fn cube() -> Mesh {
    Mesh::cuboid(DVec3::new(1.0, 0.7, 0.5))
}

fn obj_text(mesh: &Mesh) -> String {
    let mut s = String::new();
    for p in &mesh.positions {
        s += &format!("v {:e} {:e} {:e}\n", p.x, p.y, p.z);
    }
    for t in &mesh.triangles {
        s += &format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1);
    }
    s
}

/// A scene file's JSON for `cams` with masks `m0.png`, … and the mesh `mesh.obj`.
fn scene_json(cams: &[Camera]) -> Value {
    let views: Vec<Value> = cams
        .iter()
        .enumerate()
        .map(|(i, c)| {
            json!({"name": format!("v{i}"), "mask": format!("m{i}.png"), "image": "photo.png",
                   "camera": serde_json::to_value(CameraJson::from_camera(c)).unwrap()})
        })
        .collect();
    json!({"mesh": "mesh.obj", "views": views})
}

/// Loads `scene` (JSON) with `mesh` as `mesh.obj`, masks rendered of the cube at the
/// identity (or `mask` for every view when given), and fits it when it loads.
fn load_and_fit(scene: &Value, mesh_file: &[u8], mask: Option<&Mask>) -> Result<localisebot::FitResult, String> {
    let cams = cameras();
    let masks: Vec<Vec<u8>> = cams
        .iter()
        .map(|c| {
            let m = mask
                .cloned()
                .unwrap_or_else(|| localisebot::raster::hard::render(&cube(), &Pose::IDENTITY, c));
            encode_gray(m.width, m.height, &m.data.iter().map(|&v| v * 255).collect::<Vec<u8>>())
        })
        .collect();
    let photo = encode_rgba(&Rgba {
        width: 64,
        height: 48,
        data: vec![90; 64 * 48 * 4],
    });
    let mesh_file = mesh_file.to_vec();
    let files = move |p: &str| -> Option<Vec<u8>> {
        match p {
            "mesh.obj" => Some(mesh_file.clone()),
            "photo.png" => Some(photo.clone()),
            _ => p
                .strip_prefix('m')
                .and_then(|r| r.strip_suffix(".png"))
                .and_then(|i| i.parse::<usize>().ok())
                .and_then(|i| masks.get(i).cloned()),
        }
    };
    let s = load_scene("scene.json", &scene.to_string(), &files).map_err(|e| e.to_string())?;
    fit(s.mesh, s.views, s.initial_pose)
}

fn quick() -> FitSettings {
    let mut s = FitSettings::default();
    s.search.sampling = localisebot::Sampling::Uniform(64);
    s.search.keep = 4;
    s
}

fn fit(mesh: Mesh, views: Vec<View>, start: Option<Pose>) -> Result<localisebot::FitResult, String> {
    let mut est = Estimator::new(mesh, views, start, quick()).map_err(|e| e.to_string())?;
    est.run(100_000).map_err(|e| e.to_string())?;
    let r = est.result(0.0, None);
    assert_no_nan(&serde_json::to_value(&r).unwrap(), "result");
    Ok(r)
}

/// Fields of a result that may be null (absent figures); any other null is a NaN that
/// serde_json wrote as null.
const MAY_BE_NULL: [&str; 9] = [
    "termination",
    "verdict",
    "covariance",
    "std_dev",
    "uncertainty_error",
    "camera_corrections",
    "camera_correction_error",
    "camera_test",
    "errors",
];

fn assert_no_nan(v: &Value, path: &str) {
    match v {
        Value::Null => panic!("{path} is null: a NaN or infinity in the result"),
        Value::Number(n) => assert!(n.as_f64().is_some_and(f64::is_finite), "{path} = {n}"),
        Value::Array(a) => a
            .iter()
            .enumerate()
            .for_each(|(i, x)| assert_no_nan(x, &format!("{path}[{i}]"))),
        Value::Object(o) => {
            for (k, x) in o {
                if !(x.is_null() && MAY_BE_NULL.contains(&k.as_str())) {
                    assert_no_nan(x, &format!("{path}.{k}"));
                }
            }
        }
        _ => {}
    }
}

/// `f(scene)` edits the scene JSON; the load must fail with a message containing each of `says`.
fn refused(edit: impl Fn(&mut Value), says: &[&str]) {
    let mut scene = scene_json(&cameras());
    edit(&mut scene);
    match load_and_fit(&scene, obj_text(&cube()).as_bytes(), None) {
        Ok(r) => panic!("accepted ({:?}): {scene}", r.verdict),
        Err(e) => assert!(says.iter().all(|s| e.contains(s)), "{e}\n  expected {says:?}"),
    }
}

#[test]
fn the_untouched_scene_fits() {
    let r = load_and_fit(&scene_json(&cameras()), obj_text(&cube()).as_bytes(), None).unwrap();
    assert!(r.mean_iou > 0.9, "{}", r.mean_iou);
}

#[test]
fn absurd_intrinsics_are_refused_naming_the_view() {
    for (key, value, says) in [
        ("fx", json!(1e300), "fx"),
        ("fy", json!(1e-310), "fy"),
        ("fx", json!(-0.0), "focal lengths must be positive"),
        ("cx", json!(1e300), "cx"),
        ("cy", json!(-1e300), "cy"),
    ] {
        refused(|s| s["views"][1]["camera"][key] = value.clone(), &["view 'v1'", says]);
    }
}

#[test]
fn absurd_extrinsics_are_refused_naming_the_view() {
    refused(
        |s| s["views"][0]["camera"]["world_to_camera"][0][3] = json!(1e300),
        &["view 'v0'", "world_to_camera"],
    );
    refused(
        |s| s["views"][2]["camera"]["world_to_camera"][1][1] = json!(1e300),
        &["view 'v2'", "world_to_camera"],
    );
    refused(
        |s| s["views"][2]["camera"]["world_to_camera"][0][0] = json!(5e-324),
        &["view 'v2'", "rotation"],
    );
    // JSON has no NaN or infinity: numbers out of range are the parser's error.
    let mut scene = scene_json(&cameras()).to_string();
    scene = scene.replacen("\"fx\":60.0", "\"fx\":1e999", 1);
    let e = load_scene("scene.json", &scene, &|_| None).unwrap_err().to_string();
    assert!(e.starts_with("scene.json:") && e.contains("number out of range"), "{e}");
}

#[test]
fn non_finite_cameras_from_the_binding_are_refused() {
    // serde-wasm-bindgen hands NaN and ±∞ through: the camera itself refuses them.
    let good = CameraJson::from_camera(&cameras()[0]);
    for (i, v) in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY].into_iter().enumerate() {
        let mut c = good.clone();
        match i {
            0 => c.fx = v,
            1 => c.cy = v,
            _ => c.world_to_camera.as_mut().unwrap()[2][3] = v,
        }
        let e = c.to_camera("v").unwrap_err().to_string();
        assert!(e.starts_with("view 'v': camera:") && e.contains("finite"), "{e}");
    }
    // −0 is zero: a translation of −0 is a camera like any other.
    let mut c = good.clone();
    c.world_to_camera.as_mut().unwrap()[0][3] = -0.0;
    c.to_camera("v").unwrap();
}

#[test]
fn signed_zeros_in_a_scene_are_numbers_like_any_other() {
    let mut scene = scene_json(&cameras());
    scene["initial_pose"] =
        json!({"translation": [-0.0, 0.0, -0.0], "rotation": [[1, -0.0, 0], [0, 1, 0], [-0.0, 0, 1]]});
    let r = load_and_fit(&scene, obj_text(&cube()).as_bytes(), None).unwrap();
    assert!(r.mean_iou > 0.9, "{}", r.mean_iou);
}

#[test]
fn absurd_initial_poses_are_refused() {
    for (pose, says) in [
        (json!({"translation": [1e300, 0, 0]}), "translation"),
        (json!({"translation": [0, 0, 0], "scale": [1e300, 1, 1]}), "scale"),
        (json!({"translation": [0, 0, 0], "scale": [5e-324, 1, 1]}), "scale"),
        (
            json!({"translation": [0, 0, 0], "scale": [-0.0, 1, 1]}),
            "scale must be positive",
        ),
        (
            json!({"translation": [0, 0, 0], "quaternion": [1e300, 0, 0, 0]}),
            "quaternion",
        ),
    ] {
        refused(
            |s| s["initial_pose"] = pose.clone(),
            &["scene.json", "initial_pose", says],
        );
    }
    // From the binding, NaN reaches the pose check itself.
    let p = PoseJson {
        translation: [0.0, f64::NAN, 0.0],
        ..PoseJson::from_pose(&Pose::IDENTITY)
    };
    assert!(p.to_pose().unwrap_err().to_string().contains("non-finite"));
}

#[test]
fn absurd_box_hints_are_refused_naming_the_view() {
    for (b, says) in [
        (json!([1e300, 0, 10, 10]), "box"),
        (json!([0, 0, 1e300, 1e300]), "box"),
        (json!([5e-324, 5e-324, 1e-310, 1e-310]), "box"),
        (json!([-0.0, -0.0, -0.0, 10]), "box"),
    ] {
        refused(
            |s| {
                let v = &mut s["views"][1];
                v.as_object_mut().unwrap().remove("mask");
                v["box"] = b.clone();
            },
            &["view 'v1'", says],
        );
    }
}

/// A mesh file `text` is refused with a message containing `says`.
fn mesh_refused(file: &str, bytes: &[u8], says: &str) {
    let e = localisebot::io::load_mesh(file, bytes, &localisebot::io::no_files)
        .unwrap_err()
        .to_string();
    assert!(e.contains(file) && e.contains(says), "{e}\n  expected: {says}");
}

fn binary_ply(points: &[[f64; 3]], faces: &[[u32; 3]]) -> Vec<u8> {
    let mut b = format!(
        "ply\nformat binary_little_endian 1.0\nelement vertex {}\nproperty double x\nproperty double y\nproperty double z\n\
         element face {}\nproperty list uchar int vertex_indices\nend_header\n",
        points.len(),
        faces.len()
    )
    .into_bytes();
    for p in points {
        p.iter().for_each(|v| b.extend(v.to_le_bytes()));
    }
    for f in faces {
        b.push(3);
        f.iter().for_each(|&i| b.extend((i as i32).to_le_bytes()));
    }
    b
}

#[test]
fn non_numbers_in_mesh_vertices_are_refused() {
    let tri = [[0u32, 1, 2]];
    for (v, says) in [
        (f64::NAN, "non-finite"),
        (f64::INFINITY, "non-finite"),
        (1e300, "coordinate"),
        (-1e300, "coordinate"),
    ] {
        mesh_refused(
            "m.ply",
            &binary_ply(&[[0.0; 3], [1.0, 0.0, 0.0], [0.0, v, 0.0]], &tri),
            says,
        );
    }
    // glTF floats: written as any exporter would, with a NaN among them.
    // (the writer refuses them, so a marked value is patched in its binary chunk).
    for v in [f32::NAN, f32::INFINITY, 1e38] {
        let mut m = cube();
        m.positions[3].y = 0.123_456_7;
        let mut glb = localisebot::io::gltf_write::glb(&m, "m.glb").unwrap();
        let mark = 0.123_456_7f32.to_le_bytes();
        let at = glb
            .windows(4)
            .position(|w| w == mark)
            .expect("the marked float is in the buffer");
        glb[at..at + 4].copy_from_slice(&v.to_le_bytes());
        let says = if v.is_finite() { "coordinate" } else { "non-finite" };
        mesh_refused("m.glb", &glb, says);
    }
    // Denormal coordinates make a mesh of no size.
    mesh_refused(
        "d.ply",
        &binary_ply(&[[0.0; 3], [1e-310, 0.0, 0.0], [0.0, 1e-310, 0.0]], &tri),
        "no extent",
    );
}

fn cube_views() -> Vec<View> {
    cameras()
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let m = localisebot::raster::hard::render(&cube(), &Pose::IDENTITY, c);
            View::new(&format!("v{i}"), *c, m, None, None, &Default::default()).unwrap()
        })
        .collect()
}

#[test]
fn degenerate_meshes_are_refused() {
    let p = |x: f64, y: f64, z: f64| DVec3::new(x, y, z);
    for (positions, triangles, says) in [
        (vec![p(1., 2., 3.); 4], vec![[0, 1, 2], [1, 2, 3]], "no extent"),
        (
            vec![p(0., 0., 0.), p(1., 1., 1.), p(2., 2., 2.), p(3., 3., 3.)],
            vec![[0, 1, 2], [1, 2, 3]],
            "no area",
        ),
        (
            vec![p(0., 0., 0.), p(1., 0., 0.), p(0., 1., 0.)],
            vec![[0, 0, 1], [2, 2, 2]],
            "no area",
        ),
    ] {
        let m = Mesh { positions, triangles };
        mesh_refused("bad.obj", obj_text(&m).as_bytes(), says);
        // The library's own door refuses it too (a mesh built in code, not read).
        match Estimator::new(m, cube_views(), None, quick()) {
            Ok(_) => panic!("a degenerate mesh was accepted by Estimator::new ({says})"),
            Err(e) => assert!(e.to_string().contains(says), "{e}"),
        }
    }
}

#[test]
fn a_single_triangle_is_fitted_or_fails_without_nan() {
    let tri = Mesh {
        positions: vec![
            DVec3::new(-0.5, -0.4, 0.0),
            DVec3::new(0.6, -0.3, 0.1),
            DVec3::new(0.0, 0.5, -0.1),
        ],
        triangles: vec![[0, 1, 2]],
    };
    let views: Vec<View> = cameras()
        .iter()
        .enumerate()
        .map(|(i, c)| {
            View::new(
                &format!("v{i}"),
                *c,
                localisebot::raster::hard::render(&tri, &Pose::IDENTITY, c),
                None,
                None,
                &Default::default(),
            )
            .unwrap()
        })
        .collect();
    fit(tri, views, None).unwrap();
}

#[test]
fn an_object_under_a_pixel_or_over_the_whole_view_fails_without_nan() {
    // A mask of one pixel: the object is far smaller than the views.
    let mut dot = Mask::empty(64, 48);
    dot.data[24 * 64 + 32] = 1;
    match load_and_fit(&scene_json(&cameras()), obj_text(&cube()).as_bytes(), Some(&dot)) {
        Ok(r) => assert_ne!(r.verdict, Some(localisebot::Verdict::Ok), "{:?}", r.verdict_reasons),
        Err(e) => assert!(e.contains("view"), "{e}"),
    }
    // A mask that is all object: the object fills (at least) every view.
    let full = Mask {
        width: 64,
        height: 48,
        data: vec![1; 64 * 48],
    };
    match load_and_fit(&scene_json(&cameras()), obj_text(&cube()).as_bytes(), Some(&full)) {
        Ok(r) => assert_ne!(r.verdict, Some(localisebot::Verdict::Ok), "{:?}", r.verdict_reasons),
        Err(e) => assert!(e.contains("view"), "{e}"),
    }
    // The cube a thousandth of its size, seen from where the masks were made.
    let tiny = Mesh {
        positions: cube().positions.iter().map(|p| *p * 1e-3).collect(),
        triangles: cube().triangles,
    };
    match load_and_fit(&scene_json(&cameras()), obj_text(&tiny).as_bytes(), Some(&dot)) {
        Ok(_) => {}
        Err(e) => assert!(e.contains("view") || e.contains("mesh"), "{e}"),
    }
}
