//! Grasps (src/grasp): the OCID/Cornell rectangle metric on known answers, transfer
//! through a pose and back, projection into a camera, the `.txt` round trip, antipodal
//! candidates on Box and Duck checked against the surface, drawing and JSON errors.

use glam::{DVec2, DVec3};
use localisebot::app::grasp::{
    self, angle_difference_deg, antipodal_grasps, grasp_correct, grasp_rectangle, grasp_transfer_correct,
    rectangle_angle_deg, rectangle_iou, rectangles_from_txt, rectangles_to_txt, Grasp, ANTIPODAL_CLEARANCE,
    ANTIPODAL_CONE_DEG, JAW_FRACTION,
};
use localisebot::{so3, Camera, Mesh, Pose, Rgba};
use rand::rngs::SmallRng;
use rand::{Rng, SeedableRng};

fn load(rel: &str) -> Mesh {
    let path = crate::data(rel);
    let bytes = std::fs::read(&path).unwrap();
    localisebot::io::load_mesh(&path.to_string_lossy(), &bytes, &|_| None).unwrap()
}

/// An axis-aligned rectangle [x0, x0 + w] × [y0, y0 + h], p0→p1 along +x.
fn aabb(x0: f64, y0: f64, w: f64, h: f64) -> [DVec2; 4] {
    [
        DVec2::new(x0, y0),
        DVec2::new(x0 + w, y0),
        DVec2::new(x0 + w, y0 + h),
        DVec2::new(x0, y0 + h),
    ]
}

fn rotate_about_centre(r: &[DVec2; 4], deg: f64) -> [DVec2; 4] {
    let c = 0.25 * (r[0] + r[1] + r[2] + r[3]);
    let rot = DVec2::from_angle(deg.to_radians());
    r.map(|p| c + rot.rotate(p - c))
}

#[test]
fn identical_rectangles_are_correct() {
    let r = rotate_about_centre(&aabb(100.0, 50.0, 40.0, 20.0), 17.0);
    assert!((rectangle_iou(&r, &r) - 1.0).abs() < 1e-12);
    assert_eq!(
        angle_difference_deg(rectangle_angle_deg(&r), rectangle_angle_deg(&r)),
        0.0
    );
    assert!(grasp_correct(&r, &r));
}

#[test]
fn a_rectangle_turned_45_degrees_fails_on_angle() {
    let r = aabb(100.0, 50.0, 40.0, 20.0);
    let t = rotate_about_centre(&r, 45.0);
    assert!((angle_difference_deg(rectangle_angle_deg(&r), rectangle_angle_deg(&t)) - 45.0).abs() < 1e-9);
    // The overlap alone would pass: the angle is what fails it.
    assert!(rectangle_iou(&r, &t) > 0.25);
    assert!(!grasp_correct(&t, &r));
    // 29° passes, 31° does not.
    assert!(grasp_correct(&rotate_about_centre(&r, 29.0), &r));
    assert!(!grasp_correct(&rotate_about_centre(&r, 31.0), &r));
}

#[test]
fn shifted_rectangle_iou_matches_the_hand_computed_overlap() {
    let (w, h) = (40.0, 20.0);
    let gt = aabb(10.0, 10.0, w, h);
    for (dx, dy) in [
        (0.0, 0.0),
        (5.0, 0.0),
        (-12.5, 3.0),
        (30.0, -15.0),
        (39.0, 19.0),
        (41.0, 0.0),
    ] {
        let est = aabb(10.0 + dx, 10.0 + dy, w, h);
        let inter = (w - f64::abs(dx)).max(0.0) * (h - f64::abs(dy)).max(0.0);
        let expected = inter / (2.0 * w * h - inter);
        let got = rectangle_iou(&est, &gt);
        assert!(
            (got - expected).abs() < 1e-12,
            "shift ({dx}, {dy}): {got} vs {expected}"
        );
    }
    // IoU = 0.25 when the overlap is 0.4 of a rectangle: a shift of 0.6·w along x.
    let flip = 0.6 * w;
    assert!(grasp_correct(&aabb(10.0 + flip - 0.1, 10.0, w, h), &gt));
    assert!(!grasp_correct(&aabb(10.0 + flip + 0.1, 10.0, w, h), &gt));
    assert!(grasp_correct(&aabb(10.0 - flip + 0.1, 10.0, w, h), &gt));
    assert!(!grasp_correct(&aabb(10.0 - flip - 0.1, 10.0, w, h), &gt));
}

#[test]
fn angles_compare_modulo_180() {
    let r = aabb(0.0, 0.0, 40.0, 20.0);
    // Listed from the other end: p0→p1 reversed, same rectangle.
    let other_end = [r[2], r[3], r[0], r[1]];
    assert!((rectangle_angle_deg(&other_end) - rectangle_angle_deg(&r)).abs() < 1e-12);
    assert!(grasp_correct(&other_end, &r));
    // Nearly vertical openings on either side of the wrap (image y is down, so turning p0→p1
    // by +89° makes it point down-right: −89° with y flipped, 1° after +90°).
    let a = rotate_about_centre(&r, 89.0);
    let b = rotate_about_centre(&r, 91.0);
    let (ta, tb) = (rectangle_angle_deg(&a), rectangle_angle_deg(&b));
    assert!((ta - 1.0).abs() < 1e-9 && (tb - 179.0).abs() < 1e-9, "{ta} {tb}");
    assert!((angle_difference_deg(ta, tb) - 2.0).abs() < 1e-9);
    assert!(grasp_correct(&a, &b));
}

fn skewed_pose() -> Pose {
    Pose {
        rotation: so3::exp(DVec3::new(0.4, -1.1, 0.7)),
        translation: DVec3::new(0.3, -0.2, 4.0),
        scale: DVec3::new(0.6, 1.7, 1.2),
    }
}

#[test]
fn transfer_round_trips_through_a_pose() {
    let approach = DVec3::new(0.3, -0.5, 0.8).normalize();
    let closing = approach.any_orthonormal_vector();
    let g = Grasp::new(DVec3::new(0.1, -0.2, 0.05), approach, closing, 0.3, 0.12).unwrap();
    let pose = skewed_pose();
    let w = g.to_world(&pose);
    // The contacts are model points mapped by the pose.
    let [a, b] = w.contacts();
    let [ma, mb] = g.contacts();
    assert!((a - pose.apply(ma)).length() < 1e-12 && (b - pose.apply(mb)).length() < 1e-12);
    assert!((w.width - 0.3 * (pose.scale * closing).length()).abs() < 1e-12);
    assert!(w.approach.dot(w.closing).abs() < 1e-12 && (w.approach.length() - 1.0).abs() < 1e-12);
    let back = w.to_object(&pose);
    assert!((back.centre - g.centre).length() < 1e-12);
    assert!((back.approach - g.approach).length() < 1e-12);
    assert!((back.closing - g.closing).length() < 1e-12);
    assert!((back.width - g.width).abs() < 1e-12 && (back.depth - g.depth).abs() < 1e-12);
}

#[test]
fn a_grasp_facing_the_camera_projects_to_its_pixel_width() {
    let (f, z) = (500.0, 5.0);
    let cam = Camera::look_at(DVec3::new(0.0, 0.0, z), DVec3::ZERO, DVec3::Y, 640, 480, f);
    // The gripper moves along the line of sight; the fingers close along world x.
    let g = Grasp::new(DVec3::ZERO, -DVec3::Z, DVec3::X, 0.4, 0.1).unwrap();
    let pose = Pose {
        translation: DVec3::new(0.5, -0.3, 0.0),
        ..Pose::IDENTITY
    };
    let r = grasp_rectangle(&g.to_world(&pose), &cam).unwrap();
    assert!(((r[1] - r[0]).length() - 0.4 * f / z).abs() < 1e-9);
    assert!(((r[2] - r[1]).length() - JAW_FRACTION * 0.4 * f / z).abs() < 1e-9);
    // The opening is horizontal in the image and centred on the projected centre.
    assert!((rectangle_angle_deg(&r) - 90.0).abs() < 1e-9);
    let centre = cam.project(cam.to_camera(pose.translation));
    assert!((0.25 * (r[0] + r[1] + r[2] + r[3]) - centre).length() < 1e-9);
    // Behind the camera: no rectangle.
    let behind = Pose {
        translation: DVec3::new(0.0, 0.0, 2.0 * z),
        ..Pose::IDENTITY
    };
    assert!(grasp_rectangle(&g.to_world(&behind), &cam).is_none());
    // Transfer correctness: exact pose passes, a 60° turn about the line of sight fails.
    assert_eq!(grasp_transfer_correct(&g, &pose, &pose, &cam), Some(true));
    let turned = Pose {
        rotation: so3::exp(DVec3::Z * 60f64.to_radians()),
        ..pose
    };
    assert_eq!(grasp_transfer_correct(&g, &turned, &pose, &cam), Some(false));
    assert_eq!(grasp_transfer_correct(&g, &pose, &behind, &cam), None);
}

#[test]
fn txt_round_trip_is_exact() {
    let mut rng = SmallRng::seed_from_u64(5);
    let rects: Vec<[DVec2; 4]> = (0..7)
        .map(|_| [(); 4].map(|_| DVec2::new(rng.gen_range(-50.0..700.0), rng.gen_range(0.0..480.0))))
        .collect();
    let text = rectangles_to_txt(&rects);
    assert_eq!(text.lines().count(), 28);
    assert!(text.lines().all(|l| l.split(' ').count() == 2));
    assert_eq!(rectangles_from_txt(&text).unwrap(), rects);
    // The OCID layout with integer-valued corners.
    let ocid = "270 143\n310 143\n310 163\n270 163\n";
    assert_eq!(rectangles_from_txt(ocid).unwrap(), vec![aabb(270.0, 143.0, 40.0, 20.0)]);
}

fn closest_on_triangle(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> DVec3 {
    // Ericson, Real-Time Collision Detection §5.1.5.
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = 1.0 / (va + vb + vc);
    a + ab * (vb * denom) + ac * (vc * denom)
}

/// Outward (winding) normals of the triangles within `tol` of `p`.
fn normals_near(mesh: &Mesh, p: DVec3, tol: f64) -> Vec<DVec3> {
    mesh.triangles
        .iter()
        .filter_map(|t| {
            let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
            let n = (b - a).cross(c - a);
            (n.length() > 0.0 && closest_on_triangle(p, a, b, c).distance(p) <= tol).then(|| n.normalize())
        })
        .collect()
}

/// Checks every grasp against the surface: both contacts on it, normals in the cone.
fn check_antipodal(mesh: &Mesh, grasps: &[Grasp], max_width: f64) {
    let diag = mesh.bounds().unwrap().size().length();
    let cos_cone = ANTIPODAL_CONE_DEG.to_radians().cos();
    for (i, g) in grasps.iter().enumerate() {
        assert!(g.width <= max_width && g.depth > 0.0);
        assert!(g.approach.dot(g.closing).abs() < 1e-12);
        let half = 0.5 * g.width / (1.0 + ANTIPODAL_CLEARANCE);
        let (p, q) = (g.centre - half * g.closing, g.centre + half * g.closing);
        let (np, nq) = (normals_near(mesh, p, 1e-9 * diag), normals_near(mesh, q, 1e-9 * diag));
        assert!(
            !np.is_empty() && !nq.is_empty(),
            "grasp {i}: a contact is off the surface"
        );
        // Outward normals: p's points against the closing direction, q's along it.
        assert!(
            np.iter().any(|n| n.dot(g.closing) <= -cos_cone),
            "grasp {i}: p's normal outside the cone"
        );
        assert!(
            nq.iter().any(|n| n.dot(g.closing) >= cos_cone),
            "grasp {i}: q's normal outside the cone"
        );
    }
}

#[test]
fn antipodal_grasps_on_box_cross_opposite_faces() {
    let mesh = load("gltf/Box/glTF-Binary/Box.glb");
    let b = mesh.bounds().unwrap();
    let grasps = antipodal_grasps(&mesh, 2.0, 20, 7);
    assert_eq!(grasps.len(), 20);
    check_antipodal(&mesh, &grasps, 2.0);
    for g in &grasps {
        // The closing direction is a face normal and the contacts span the box along it.
        let axis = g.closing.abs().max_position();
        assert!((g.closing.abs()[axis] - 1.0).abs() < 1e-9);
        assert!((g.width / (1.0 + ANTIPODAL_CLEARANCE) - b.size()[axis]).abs() < 1e-9);
    }
    assert_eq!(antipodal_grasps(&mesh, 2.0, 20, 7), grasps);
    assert_ne!(antipodal_grasps(&mesh, 2.0, 20, 8), grasps);
    // An opening smaller than the box fits no pair.
    assert!(antipodal_grasps(&mesh, 0.5 * b.size().min_element(), 5, 7).is_empty());
}

#[test]
fn antipodal_grasps_on_duck_lie_on_the_surface() {
    let mesh = load("gltf/Duck/glTF-Binary/Duck.glb");
    let size = mesh.bounds().unwrap().size();
    let max_width = 0.6 * size.max_element();
    let grasps = antipodal_grasps(&mesh, max_width, 15, 3);
    assert!(grasps.len() >= 5, "only {} grasps", grasps.len());
    check_antipodal(&mesh, &grasps, max_width);
    assert_eq!(antipodal_grasps(&mesh, max_width, 15, 3), grasps);
}

#[test]
fn draw_grasp_marks_the_jaws_strongest() {
    let mut img = Rgba {
        width: 100,
        height: 100,
        data: vec![0; 100 * 100 * 4],
    };
    let colour = [200, 100, 40, 255];
    grasp::draw_grasp(&mut img, &aabb(20.0, 40.0, 40.0, 20.0), colour);
    let px = |x: usize, y: usize| -> [u8; 4] { img.data[(y * 100 + x) * 4..][..4].try_into().unwrap() };
    assert_eq!(px(20, 50), colour);
    assert_eq!(px(60, 50), colour);
    assert_eq!(px(19, 50), colour);
    assert_eq!(px(61, 50), colour);
    assert_eq!(px(40, 40), [100, 50, 20, 255]);
    assert_eq!(px(40, 60), [100, 50, 20, 255]);
    assert_eq!(px(40, 50), [0, 0, 0, 0]);
    assert_eq!(px(21, 50), [0, 0, 0, 0]);
}

#[test]
fn malformed_grasp_json_names_the_problem() {
    let good = serde_json::json!({"centre":[0,0,0],"approach":[0,0,1],"closing":[1,0,0],"width":0.1,"depth":0.05});
    let cases = [
        (
            serde_json::json!({"centre":[0,0],"approach":[0,0,1],"closing":[1,0,0],"width":0.1,"depth":0.05}),
            "length 2",
        ),
        (
            serde_json::json!({"centre":[0,0,0],"approach":[0,0,1],"width":0.1,"depth":0.05}),
            "closing",
        ),
        (
            serde_json::json!({"centre":[0,0,0],"approach":[0,0,1],"closing":[0,1,1],"width":0.1,"depth":0.05}),
            "closing must be a unit vector",
        ),
        (
            serde_json::json!({"centre":[0,0,0],"approach":[0,0,1],"closing":[0,0.6,0.8],"width":0.1,"depth":0.05}),
            "perpendicular",
        ),
        (
            serde_json::json!({"centre":[0,0,0],"approach":[0,0,1],"closing":[1,0,0],"width":-1,"depth":0.05}),
            "width must be positive",
        ),
        (
            serde_json::json!({"centre":[0,0,0],"approach":[0,0,1],"closing":[1,0,0],"width":0.1,"depth":0}),
            "depth must be positive",
        ),
        (
            serde_json::json!({"centre":[0,0,0],"approach":[0,0,1],"closing":[1,0,0],"width":0.1,"depth":0.05,"widht":1}),
            "widht",
        ),
    ];
    for (bad, needle) in cases {
        let e = grasp::grasps_from_json(&[good.clone(), bad], "scene.json")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("scene.json: grasps[1]: ") && e.contains(needle), "{e}");
        assert!(Grasp::from_json(&good).is_ok());
    }
    let with_center =
        serde_json::json!({"center":[1,2,3],"approach":[0,0,1],"closing":[1,0,0],"width":0.1,"depth":0.05});
    assert_eq!(
        Grasp::from_json(&with_center).unwrap().centre,
        DVec3::new(1.0, 2.0, 3.0)
    );
}
