//! SPEC §6 figures on known answers: rotation, translation and scale errors, ADD and
//! ADD-S (against a brute-force nearest neighbour), hard IoU, contour distances and
//! the empty-mask cases.

use crate::hard_raster::{cube, duck, random_pose};
use glam::{DMat3, DVec3};
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use localisebot::metrics::{self, PoseErrors};
use localisebot::{so3, Mask, Pose};
use rand::rngs::SmallRng;
use rand::SeedableRng;

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol
}

#[test]
fn rotation_translation_and_scale_errors() {
    let mut rng = SmallRng::seed_from_u64(11);
    let gt = random_pose(&mut rng, &cube());
    let axis = DVec3::new(0.3, -0.5, 0.8).normalize();
    for deg in [10.0f64, 1.0, 90.0, 179.0] {
        let est = Pose {
            rotation: gt.rotation * so3::exp(axis * deg.to_radians()),
            ..gt
        };
        let e = metrics::rotation_error_deg(&est, &gt);
        assert!(close(e, deg, 1e-5), "{deg}° gave {e}");
        assert!(close(metrics::rotation_error_deg(&gt, &est), deg, 1e-5));
    }
    let est = Pose {
        translation: gt.translation + DVec3::new(3.0, -4.0, 0.0),
        scale: gt.scale * DVec3::new(1.1, 0.85, 1.0),
        ..gt
    };
    assert!(close(metrics::translation_error(&est, &gt), 5.0, 1e-12));
    assert!(close(metrics::scale_error(&est, &gt), 0.15, 1e-12));
    assert!(close(metrics::scale_error_mean(&est, &gt), 0.25 / 3.0, 1e-12));
}

#[test]
fn add_of_a_pure_translation_is_its_length() {
    let mesh = duck();
    let mut rng = SmallRng::seed_from_u64(12);
    let gt = random_pose(&mut rng, &mesh);
    let d = DVec3::new(0.02, -0.03, 0.06);
    let est = Pose {
        translation: gt.translation + d,
        ..gt
    };
    assert!(close(metrics::add(&mesh, &est, &gt), d.length(), 1e-12));
    assert!(metrics::add_s(&mesh, &est, &gt) <= d.length() + 1e-12);
    assert_eq!(metrics::add(&mesh, &gt, &gt), 0.0);
    assert_eq!(metrics::add_s(&mesh, &gt, &gt), 0.0);
}

#[test]
fn add_s_forgives_a_symmetry_that_add_does_not() {
    // The cube [-1, 1]³ turned 90° about z maps its corners onto each other; each
    // corner moves by |(x, y) − (−y, x)| = √2·√2 = 2.
    let mesh = cube();
    let gt = Pose::IDENTITY;
    let est = Pose {
        rotation: DMat3::from_rotation_z(std::f64::consts::FRAC_PI_2),
        ..gt
    };
    assert!(close(metrics::add(&mesh, &est, &gt), 2.0, 1e-12));
    assert!(metrics::add_s(&mesh, &est, &gt) < 1e-12);
    let e: PoseErrors = metrics::pose_errors(&mesh, &est, &gt);
    assert!(close(e.rotation_deg, 90.0, 1e-9));
    assert!(close(e.diameter, 12f64.sqrt(), 1e-12));
    assert!(close(e.add_rel, 2.0 / 12f64.sqrt(), 1e-12) && e.add_s_rel < 1e-12);
    let json = serde_json::to_value(e).unwrap();
    for key in [
        "rotation_deg",
        "translation",
        "scale",
        "scale_mean",
        "add",
        "add_s",
        "diameter",
        "add_rel",
        "add_s_rel",
    ] {
        assert!(json.get(key).is_some(), "missing {key} in {json}");
    }
}

#[test]
fn add_s_agrees_with_brute_force_on_the_duck() {
    let mesh = duck();
    let mut rng = SmallRng::seed_from_u64(13);
    for _ in 0..2 {
        let gt = random_pose(&mut rng, &mesh);
        let est = random_pose(&mut rng, &mesh);
        let pts = mesh.used_points();
        let posed: Vec<DVec3> = pts.iter().map(|&p| est.apply(p)).collect();
        let brute = pts
            .iter()
            .map(|&p| {
                let g = gt.apply(p);
                posed.iter().map(|q| q.distance(g)).fold(f64::INFINITY, f64::min)
            })
            .sum::<f64>()
            / pts.len() as f64;
        let fast = metrics::add_s(&mesh, &est, &gt);
        assert!(close(fast, brute, 1e-12), "k-d tree {fast} vs brute force {brute}");
        assert!(fast > 0.0 && fast < metrics::add(&mesh, &est, &gt));
        // The diameter is measured under the true pose, scale included.
        let e = metrics::pose_errors(&mesh, &est, &gt);
        let scaled = localisebot::Mesh {
            positions: mesh.positions.iter().map(|&p| gt.scale * p).collect(),
            triangles: mesh.triangles.clone(),
        };
        assert!(close(e.diameter, scaled.diameter(), 1e-9));
        assert!(close(e.add_s_rel * e.diameter, fast, 1e-12));
    }
}

#[test]
fn add_s_of_a_big_mesh_reads_a_strided_subset_and_agrees_with_all_of_it() {
    // 62 002 vertices: more than MAX_QUERY_POINTS, so every second one is a query.
    let mesh = localisebot::app::synth::blob_mesh(250, 250);
    let pts = mesh.used_points();
    assert!(pts.len() > metrics::MAX_QUERY_POINTS);
    let queried = metrics::strided(&pts, metrics::MAX_QUERY_POINTS).count();
    assert!(
        (metrics::MAX_QUERY_POINTS / 2..=metrics::MAX_QUERY_POINTS).contains(&queried),
        "{queried}"
    );
    assert_eq!(
        metrics::strided(&pts[..100], metrics::MAX_QUERY_POINTS).count(),
        100,
        "a small mesh: all of it"
    );
    let mut rng = SmallRng::seed_from_u64(5);
    let gt = random_pose(&mut rng, &mesh);
    assert_eq!(metrics::add_s(&mesh, &gt, &gt), 0.0);
    let est = Pose {
        rotation: gt.rotation * so3::exp(DVec3::new(0.05, -0.03, 0.02)),
        translation: gt.translation + DVec3::new(0.02, 0.0, -0.01),
        scale: gt.scale,
    };
    // ADD-S over every vertex (a k-d tree of its own).
    let posed: Vec<[f64; 3]> = pts.iter().map(|&p| est.apply(p).to_array()).collect();
    let tree: ImmutableKdTree<f64, 3> = ImmutableKdTree::new_from_slice(&posed);
    let all = pts
        .iter()
        .map(|&p| {
            tree.nearest_one::<SquaredEuclidean>(&gt.apply(p).to_array())
                .distance
                .sqrt()
        })
        .sum::<f64>()
        / pts.len() as f64;
    let fast = metrics::add_s(&mesh, &est, &gt);
    assert!(
        all > 0.0 && (fast / all - 1.0).abs() < 0.02,
        "subset {fast} vs all {all}"
    );
}

fn rect(w: u32, h: u32, x0: u32, y0: u32, x1: u32, y1: u32) -> Mask {
    let mut m = Mask::empty(w, h);
    for y in y0..=y1 {
        for x in x0..=x1 {
            m.data[(y * w + x) as usize] = 1;
        }
    }
    m
}

fn disc(w: u32, h: u32, cx: f64, cy: f64, r: f64) -> Mask {
    let mut m = Mask::empty(w, h);
    for y in 0..h {
        for x in 0..w {
            m.data[(y * w + x) as usize] = ((x as f64 - cx).powi(2) + (y as f64 - cy).powi(2) <= r * r) as u8;
        }
    }
    m
}

#[test]
fn iou_of_two_rectangles() {
    let a = rect(30, 30, 0, 0, 9, 9);
    let b = rect(30, 30, 5, 5, 14, 14);
    assert!(close(metrics::hard_iou(&a, &b), 25.0 / 175.0, 1e-15));
    assert_eq!(metrics::hard_iou(&a, &a), 1.0);
    assert_eq!(metrics::hard_iou(&a, &rect(30, 30, 20, 20, 25, 25)), 0.0);
}

#[test]
fn contour_is_the_object_border() {
    let m = rect(7, 6, 1, 1, 3, 3);
    let c = metrics::contour(&m);
    let on: Vec<(u32, u32)> = (0..42)
        .filter(|&i| c.data[i] == 1)
        .map(|i| (i as u32 % 7, i as u32 / 7))
        .collect();
    assert_eq!(on, vec![(1, 1), (2, 1), (3, 1), (1, 2), (3, 2), (1, 3), (2, 3), (3, 3)]);
    // Object pixels on the image border are contour pixels.
    let full = rect(4, 3, 0, 0, 3, 2);
    assert_eq!(metrics::contour(&full).area(), 10);
}

#[test]
fn hausdorff_of_offset_shapes_is_the_offset() {
    let a = rect(40, 30, 5, 5, 14, 14);
    let b = rect(40, 30, 8, 5, 17, 14);
    assert_eq!(metrics::hausdorff_px(&a, &b), 3.0);
    assert_eq!(metrics::hausdorff_px(&b, &a), 3.0);
    for d in [1.0, 4.0, 7.0] {
        let a = disc(64, 48, 20.0, 22.0, 10.0);
        let b = disc(64, 48, 20.0 + d, 22.0, 10.0);
        assert_eq!(metrics::hausdorff_px(&a, &b), d);
        let c = metrics::contour_distance(&a, &b);
        assert!(c.mean > 0.0 && c.mean < d, "mean {}", c.mean);
    }
    // A square ring of side 11 inside one of side 15: A's pixels are all 2 away;
    // B's are 2 (44), √5 (8, next to the corners) or 2√2 (4 corners) away.
    let a = rect(30, 30, 10, 10, 20, 20);
    let b = rect(30, 30, 8, 8, 22, 22);
    let c = metrics::contour_distance(&a, &b);
    assert!(close(c.hausdorff, 8f64.sqrt(), 1e-12));
    let want = (40.0 * 2.0 + 44.0 * 2.0 + 8.0 * 5f64.sqrt() + 4.0 * 8f64.sqrt()) / 96.0;
    assert!(close(c.mean, want, 1e-12), "{} vs {want}", c.mean);
    assert_eq!(metrics::contour_distance(&a, &a).hausdorff, 0.0);
    assert_eq!(metrics::mean_contour_distance_px(&a, &a), 0.0);
}

/// The contour distances by brute force over the whole image: every contour pixel of one
/// mask against every one of the other.
fn brute_contour_distance(a: &Mask, b: &Mask) -> (f64, f64) {
    let pixels = |m: &Mask| {
        let c = metrics::contour(m);
        (0..m.height)
            .flat_map(|y| (0..m.width).map(move |x| (x, y)))
            .filter(|&(x, y)| c.get(x, y))
            .collect::<Vec<_>>()
    };
    let (pa, pb) = (pixels(a), pixels(b));
    let nearest = |p: (u32, u32), q: &[(u32, u32)]| {
        q.iter()
            .map(|&(x, y)| (f64::from(x) - f64::from(p.0)).hypot(f64::from(y) - f64::from(p.1)))
            .fold(f64::INFINITY, f64::min)
    };
    let d: Vec<f64> = pa
        .iter()
        .map(|&p| nearest(p, &pb))
        .chain(pb.iter().map(|&p| nearest(p, &pa)))
        .collect();
    (
        d.iter().copied().fold(0.0, f64::max),
        d.iter().sum::<f64>() / d.len() as f64,
    )
}

#[test]
fn contour_distances_in_the_objects_box_equal_the_whole_images() {
    // Random pairs of shapes, some touching the image's edges (where the border makes
    // contour pixels) and some far apart (the box then spans most of the image).
    use rand::Rng;
    let mut rng = SmallRng::seed_from_u64(23);
    for case in 0..60 {
        let (w, h) = (rng.gen_range(8..48u32), rng.gen_range(8..40u32));
        let shape = |rng: &mut SmallRng| {
            let (x0, y0) = (rng.gen_range(0..w), rng.gen_range(0..h));
            let (x1, y1) = (rng.gen_range(x0..w), rng.gen_range(y0..h));
            if rng.gen_bool(0.5) {
                rect(w, h, x0, y0, x1, y1)
            } else {
                disc(w, h, f64::from(x0), f64::from(y0), 1.0 + f64::from(x1 - x0) / 2.0)
            }
        };
        let (a, b) = (shape(&mut rng), shape(&mut rng));
        if a.area() == 0 || b.area() == 0 {
            continue;
        }
        let got = metrics::contour_distance(&a, &b);
        let (hausdorff, mean) = brute_contour_distance(&a, &b);
        assert!(
            close(got.hausdorff, hausdorff, 1e-12),
            "case {case}: {} vs {hausdorff}",
            got.hausdorff
        );
        assert!(close(got.mean, mean, 1e-12), "case {case}: {} vs {mean}", got.mean);
    }
}

#[test]
fn empty_masks_have_defined_figures() {
    let e = Mask::empty(20, 10);
    let a = rect(20, 10, 2, 2, 5, 5);
    assert_eq!(metrics::hard_iou(&e, &e), 0.0);
    assert_eq!(metrics::hard_iou(&e, &a), 0.0);
    assert_eq!(metrics::hausdorff_px(&e, &e), 0.0);
    assert_eq!(metrics::hausdorff_px(&e, &a), 30.0);
    assert_eq!(metrics::hausdorff_px(&a, &e), 30.0);
    assert_eq!(metrics::mean_contour_distance_px(&a, &e), 30.0);
}

#[test]
fn the_median_is_the_middle_or_the_mean_of_the_two_middles() {
    use localisebot::metrics::median;
    assert_eq!(median(&[3.0, -1.0, 2.0]), 2.0);
    assert_eq!(median(&[4.0, 1.0, 3.0, 2.0]), 2.5);
    assert_eq!(median(&[7.0]), 7.0);
    assert!(median(&[]).is_nan());
}

#[test]
fn the_geometric_mean_is_the_nth_root_of_the_product() {
    use localisebot::metrics::geometric_mean;
    assert!((geometric_mean(&[2.0, 8.0]) - 4.0).abs() < 1e-12);
    assert!((geometric_mean(&[1.0, 10.0, 100.0]) - 10.0).abs() < 1e-12);
    assert!((geometric_mean(&[5.0]) - 5.0).abs() < 1e-12);
    assert_eq!(geometric_mean(&[0.0, 3.0]), 0.0);
    assert!(geometric_mean(&[]).is_nan());
}
