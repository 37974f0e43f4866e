//! Real photographs (`../shared/data/real/lmo`, Linemod-Occluded test scene 2: a
//! hand-held Kinect around a cluttered table, 640×480, the dataset's intrinsics and
//! annotated poses, scanned CAD models in millimetres): for each annotated object,
//! `import bop` three views, then fit from no initial pose.
//!
//! The views were chosen once from `scene_gt_info.json` (`visib_fract`, computed by
//! BOP from the real depth) and the annotated viewing directions: among the images
//! where the object is at least 90 % visible (eggbox: the best three, 0.89–0.98),
//! the three whose viewing directions are farthest apart (minimum pairwise angle
//! 22°–66°). Masks are the visible-part masks (`mask_visib/`), the other annotated
//! objects become each view's ignore mask (`--ignore others`), units metres.

use localisebot::{metrics, Estimator, FitSettings, Verdict};

/// Imports object `object` with `images` and fits it; returns (ADD, ADD-S) relative
/// to the diameter, the verdict and the seconds taken.
fn fit_real(object: u32, images: &[u32]) -> (f64, f64, Option<Verdict>, f64) {
    let scene = crate::photos::import_lmo(object, images, None, true);
    assert_eq!(scene.views.len(), 3);
    assert!(scene
        .views
        .iter()
        .all(|v| (v.camera().width, v.camera().height) == (640, 480)));
    let gt = scene.ground_truth_pose.unwrap();
    let t0 = std::time::Instant::now();
    let mut est = Estimator::new(scene.mesh.clone(), scene.views, None, FitSettings::default()).unwrap();
    est.run(usize::MAX).unwrap();
    let secs = t0.elapsed().as_secs_f64();
    let r = est.result(secs, Some(&gt));
    let e = metrics::pose_errors(&scene.mesh, &est.pose(), &gt);
    println!(
        "LM-O object {object} (views {images:?}): ADD {:.2} %, ADD-S {:.2} % of the diameter, rotation {:.2}°, \
         IoUs {:?}, verdict {:?}, {secs:.1} s",
        100.0 * e.add_rel,
        100.0 * e.add_s_rel,
        e.rotation_deg,
        r.views
            .iter()
            .map(|v| (v.iou * 1000.0).round() / 1000.0)
            .collect::<Vec<_>>(),
        r.verdict
    );
    (e.add_rel, e.add_s_rel, r.verdict, secs)
}

fn check(object: u32, images: &[u32]) {
    let (add, _, verdict, _) = fit_real(object, images);
    // Measured: ADD 0.07–0.14 % of the diameter over the six objects (the bound is 4×).
    assert!(add < 0.005, "object {object}: ADD {:.2} % of the diameter", 100.0 * add);
    assert_eq!(verdict, Some(Verdict::Ok), "object {object}");
}

fn check_symmetric(object: u32, images: &[u32]) {
    let (_, add_s, verdict, _) = fit_real(object, images);
    // Measured: ADD-S 0.09 % (eggbox) and 0.14 % (glue).
    assert!(
        add_s < 0.005,
        "object {object}: ADD-S {:.2} % of the diameter",
        100.0 * add_s
    );
    assert_ne!(verdict, Some(Verdict::Failed), "object {object}");
}

#[test]
fn real_ape() {
    check(1, &[263, 310, 819]);
}

#[test]
fn real_can() {
    check(5, &[126, 263, 362]);
}

#[test]
fn real_cat() {
    check(6, &[102, 310, 356]);
}

#[test]
fn real_driller() {
    check(8, &[310, 428, 476]);
}

#[test]
fn real_duck() {
    check(9, &[102, 362, 476]);
}

#[test]
fn real_holepuncher() {
    check(12, &[126, 362, 1087]);
}

#[test]
fn real_eggbox_symmetric() {
    check_symmetric(10, &[819, 1087, 362]);
}

#[test]
fn real_glue_symmetric() {
    check_symmetric(11, &[428, 310, 126]);
}
