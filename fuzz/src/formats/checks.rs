//! What every accepted input must give: finite numbers, indices in range,
//! rotations that are rotations.

use localisebot::io::nerf::Imported;
use localisebot::io::scene::{Scene, SceneJson};
use localisebot::limits::{FOCAL_RANGE_PX, MAX_LENGTH};
use localisebot::{Camera, Mesh, Pose};

// ---------------------------------------------------------------------------------
// What every accepted input must give

fn finite(what: &str, v: &[f64]) {
    assert!(v.iter().all(|x| x.is_finite()), "{what}: not finite: {v:?}");
}

pub fn check_mesh(m: &Mesh) {
    assert!(!m.triangles.is_empty(), "an accepted mesh has triangles");
    let n = m.positions.len() as u32;
    for t in &m.triangles {
        assert!(t.iter().all(|&i| i < n), "triangle {t:?} past the {n} vertices");
    }
    for p in &m.positions {
        finite("mesh vertex", &p.to_array());
        assert!(
            p.abs().max_element() <= MAX_LENGTH,
            "mesh vertex {p} beyond ±{MAX_LENGTH:e}"
        );
    }
}

fn check_rotation(what: &str, r: glam::DMat3) {
    finite(what, &r.to_cols_array());
    let e = (r.transpose() * r - glam::DMat3::IDENTITY)
        .to_cols_array()
        .iter()
        .fold(0.0f64, |a, v| a.max(v.abs()));
    assert!(
        e < 1e-6 && (r.determinant() - 1.0).abs() < 1e-6,
        "{what}: not a rotation: {r:?}"
    );
}

pub fn check_camera(c: &Camera) {
    finite("camera intrinsics", &[c.fx, c.fy, c.cx, c.cy]);
    let (lo, hi) = FOCAL_RANGE_PX;
    assert!(
        (lo..=hi).contains(&c.fx) && (lo..=hi).contains(&c.fy),
        "focal lengths {} {}",
        c.fx,
        c.fy
    );
    assert!(c.width >= 1 && c.height >= 1 && c.width <= localisebot::MAX_SIDE && c.height <= localisebot::MAX_SIDE);
    check_rotation("camera rotation", c.rotation);
    finite("camera translation", &c.translation.to_array());
    assert!(
        c.translation.abs().max_element() <= 2.0 * MAX_LENGTH,
        "camera translation {}",
        c.translation
    );
}

pub fn check_pose(p: &Pose) {
    check_rotation("pose rotation", p.rotation);
    finite("pose translation", &p.translation.to_array());
    finite("pose scale", &p.scale.to_array());
    assert!(p.scale.min_element() > 0.0, "pose scale {}", p.scale);
}

pub fn check_scene(s: &Scene) {
    check_mesh(&s.mesh);
    assert!(
        !s.views.is_empty() || !s.photos.is_empty(),
        "an accepted scene has views"
    );
    for v in &s.views {
        let c = v.camera();
        check_camera(c);
        let m = v.mask();
        assert_eq!((m.width, m.height), (c.width, c.height));
        assert_eq!(m.data.len(), (c.width * c.height) as usize);
        assert!(v.known_area() > 0);
        if let Some(ig) = v.ignore() {
            assert_eq!(ig.data.len(), m.data.len());
        }
        if let Some(im) = v.image() {
            assert_eq!(im.data.len(), 4 * m.data.len());
        }
    }
    for p in &s.photos {
        check_camera(&p.camera);
        assert_eq!(p.image.data.len(), 4 * (p.camera.width * p.camera.height) as usize);
        if let Some(b) = &p.hint {
            finite("box", &b.to_array());
        }
    }
    for p in s.initial_pose.iter().chain(&s.ground_truth_pose) {
        check_pose(p);
    }
    for g in &s.grasps {
        finite(
            "grasp",
            &[g.centre.to_array(), g.approach.to_array(), g.closing.to_array()].concat(),
        );
        finite("grasp size", &[g.width, g.depth, g.score.unwrap_or(0.0)]);
    }
}

/// An import's scene: cameras that convert, finite poses.
pub fn check_imported(im: &Imported) {
    check_scene_json(&im.scene);
    for v in &im.scene.views {
        for f in [&v.mask, &v.image, &v.ignore].into_iter().flatten() {
            assert!(
                im.files.iter().any(|(p, _)| p == f),
                "view '{}': {f} is not among the files",
                v.name
            );
        }
    }
}

pub fn check_scene_json(s: &SceneJson) {
    for v in &s.views {
        let c = v
            .camera
            .to_camera(&v.name)
            .unwrap_or_else(|e| panic!("an imported camera is refused: {e}"));
        check_camera(&c);
        if let Some(b) = v.hint_box {
            finite("box", &b);
        }
    }
    for p in s.initial_pose.iter().chain(&s.ground_truth_pose) {
        let mut all: Vec<f64> = p.translation.iter().chain(&p.scale).copied().collect();
        match &p.rotation {
            Some(localisebot::RotationJson::Matrix(m)) => all.extend(m.iter().flatten()),
            Some(localisebot::RotationJson::Quaternion(q)) => all.extend(q),
            None => {}
        }
        all.extend(p.quaternion.iter().flatten());
        finite("imported pose", &all);
    }
}
