//! A fit the photographs cannot settle says so. A box with a bump on its front face,
//! photographed from the front twice: the bump hides inside the box's outline, and the
//! box turned round (bump at the back) casts the same two silhouettes. The fit must be
//! `ambiguous`, list the other pose, widen its ADD bound to cover it and suggest a view
//! that tells the two apart; from the side the bump shows, and the fit is `ok`.

use glam::DVec3;
use localisebot::app::synth::{blob_mesh, synthesize, SynthSettings};
use localisebot::raster::hard;
use localisebot::uncertainty::Viewpoints;
use localisebot::{metrics, symmetry, Camera, Estimator, FitSettings, Mesh, Pose, ScaleMode, Verdict, View};

/// A 1 × 0.6 × 0.4 box with a 0.3 × 0.2 × 0.15 bump centred on its +z face.
fn bumped_box() -> Mesh {
    let mut mesh = Mesh::cuboid(DVec3::new(1.0, 0.6, 0.4));
    let bump = Mesh::cuboid(DVec3::new(0.3, 0.2, 0.15));
    let base = mesh.positions.len() as u32;
    let lift = DVec3::new(0.0, 0.0, 0.2 + 0.075);
    mesh.positions.extend(bump.positions.iter().map(|p| *p + lift));
    mesh.triangles
        .extend(bump.triangles.iter().map(|t| [t[0] + base, t[1] + base, t[2] + base]));
    mesh
}

/// A camera 4 units from the origin along `dir`, looking at it.
fn camera(dir: DVec3) -> Camera {
    Camera::look_at(4.0 * dir.normalize(), DVec3::ZERO, DVec3::Y, 160, 120, 220.0)
}

fn views(mesh: &Mesh, truth: &Pose, dirs: &[DVec3]) -> Vec<View> {
    dirs.iter()
        .enumerate()
        .map(|(i, &d)| {
            let cam = camera(d);
            let mask = hard::render(mesh, truth, &cam);
            View::new(&format!("view{i}"), cam, mask, None, None, &Default::default()).unwrap()
        })
        .collect()
}

/// ADD over the diameter, allowing for the mesh's symmetries.
fn error(mesh: &Mesh, est: &Pose, truth: &Pose) -> f64 {
    let syms = symmetry::symmetries(mesh);
    metrics::pose_errors(mesh, est, &symmetry::closest_equivalent(mesh, &syms, est, truth)).add_rel
}

fn fit(mesh: &Mesh, views: Vec<View>) -> Estimator {
    let settings = FitSettings {
        scale_mode: ScaleMode::Fixed,
        ..FitSettings::default()
    };
    let mut est = Estimator::new(mesh.clone(), views, None, settings).unwrap();
    est.run(usize::MAX).unwrap();
    est
}

const FRONT: [DVec3; 2] = [DVec3::new(-0.45, 0.15, 1.0), DVec3::new(0.45, -0.1, 1.0)];

#[test]
fn two_views_that_cannot_tell_the_box_s_front_from_its_back_make_the_fit_ambiguous() {
    let mesh = bumped_box();
    assert!(
        symmetry::symmetries(&mesh).len() == 2,
        "the bumped box's only symmetry is the half-turn about z"
    );
    let truth = Pose::IDENTITY;
    let est = fit(&mesh, views(&mesh, &truth, &FRONT));
    let r = est.result(0.0, Some(&truth));
    assert_eq!(r.verdict, Some(Verdict::Ambiguous), "{:?}", r.verdict_reasons);
    assert!(
        r.views.iter().all(|v| v.iou > 0.98),
        "the fit explains both masks: {:?}",
        r.views
    );
    let alts = est.alternatives();
    assert!(!alts.is_empty() && alts.len() <= 2, "{} alternatives", alts.len());
    // One of the two is the truth, the other the box turned round (bump at the back).
    let mut errors: Vec<f64> = std::iter::once(est.pose())
        .chain(alts.iter().map(|a| a.pose))
        .map(|p| error(&mesh, &p, &truth))
        .collect();
    errors.sort_by(f64::total_cmp);
    assert!(errors[0] < 0.02, "no pose near the truth: errors {errors:?}");
    assert!(errors[1] > 0.1, "the alternative is distinct: errors {errors:?}");
    let a = &alts[0];
    assert!(a.rotation_deg > 150.0, "the box turned round: {:.1}°", a.rotation_deg);
    assert!(
        a.mean_iou > 0.98 && a.add_rel >= 0.1,
        "{:.3} {:.3}",
        a.mean_iou,
        a.add_rel
    );
    assert!(
        r.verdict_reasons.iter().any(|s| s.contains("alternative 1")),
        "{:?}",
        r.verdict_reasons
    );
    assert_eq!(r.alternatives.len(), alts.len(), "the result lists them");
    assert!(r.alternatives[0].errors.is_some() && r.alternatives[0].covariance.is_some());
    // The ADD bound is a mixture's: it reaches the alternative, which one Gaussian does not.
    let sd = r.std_dev.as_ref().unwrap();
    assert!(sd.add_95_alone < a.add, "{} vs {}", sd.add_95_alone, a.add);
    assert!(
        sd.add_95 >= a.add,
        "the 95 % bound {} does not reach the alternative {}",
        sd.add_95,
        a.add
    );
    let syms = symmetry::symmetries(&mesh);
    let nearest = symmetry::closest_equivalent(&mesh, &syms, &est.pose(), &truth);
    let truth_add = metrics::add(&mesh, &est.pose(), &nearest);
    assert!(
        truth_add <= sd.add_95,
        "the truth ({truth_add}) is inside the bound ({})",
        sd.add_95
    );

    // The next view: the candidates that tell the two poses apart come first.
    let ranked = est.suggest_views(None, Viewpoints::Sphere).unwrap();
    let telling: Vec<f64> = ranked.iter().filter_map(|r| r.discrimination).collect();
    assert!(telling.len() > 10, "candidates measured: {}", telling.len());
    let best = telling.iter().cloned().fold(0.0, f64::max);
    let top = ranked[0].discrimination.unwrap();
    assert!(top > best - 0.05 && top > 0.03, "top {top:.3}, best {best:.3}");
    let median = metrics::median(&telling);
    assert!(
        top > 2.0 * median,
        "top {top:.3} against the median candidate's {median:.3}"
    );
}

#[test]
fn a_view_from_the_side_settles_it() {
    let mesh = bumped_box();
    let truth = Pose::IDENTITY;
    let dirs = [FRONT[0], FRONT[1], DVec3::new(1.0, 0.2, 0.1)];
    let est = fit(&mesh, views(&mesh, &truth, &dirs));
    let r = est.result(0.0, Some(&truth));
    assert_eq!(r.verdict, Some(Verdict::Ok), "{:?}", r.verdict_reasons);
    assert!(est.alternatives().is_empty() && r.alternatives.is_empty());
    assert!(error(&mesh, &est.pose(), &truth) < 0.01);
    let sd = r.std_dev.unwrap();
    assert_eq!(sd.add_95, sd.add_95_alone, "no alternative: one Gaussian's bound");
}

#[test]
fn a_shape_the_views_pin_down_has_no_alternatives() {
    let mesh = blob_mesh(12, 25);
    let scene = synthesize(
        &mesh,
        &SynthSettings {
            views: 3,
            width: 128,
            height: 96,
            seed: 4,
            ..Default::default()
        },
        None,
    )
    .unwrap();
    let mut est = Estimator::new(mesh.clone(), scene.views(), None, FitSettings::default()).unwrap();
    est.run(usize::MAX).unwrap();
    assert_eq!(est.judgement().unwrap().verdict, Verdict::Ok);
    assert!(est.alternatives().is_empty());
    assert!(metrics::add(&mesh, &est.pose(), &scene.pose) / mesh.diameter() < 0.01);
}

#[test]
fn the_command_line_says_ambiguous_exits_3_when_strict_and_suggests_a_telling_view() {
    use crate::cli::{bin, stderr, tmp};
    let d = tmp("ambiguous");
    let mesh = bumped_box();
    let mut obj = String::new();
    for p in &mesh.positions {
        obj += &format!("v {} {} {}\n", p.x, p.y, p.z);
    }
    for t in &mesh.triangles {
        obj += &format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1);
    }
    std::fs::write(d.join("box.obj"), obj).unwrap();
    std::fs::create_dir_all(d.join("masks")).unwrap();
    let views: Vec<serde_json::Value> = views(&mesh, &Pose::IDENTITY, &FRONT)
        .iter()
        .map(|v| {
            let m = v.mask();
            let img = image::GrayImage::from_fn(m.width, m.height, |x, y| {
                image::Luma([if m.get(x, y) { 255 } else { 0 }])
            });
            img.save(d.join(format!("masks/{}.png", v.name()))).unwrap();
            serde_json::json!({
                "name": v.name(),
                "mask": format!("masks/{}.png", v.name()),
                "camera": localisebot::CameraJson::from_camera(v.camera()),
            })
        })
        .collect();
    let scene = serde_json::json!({"version": 1, "mesh": "box.obj", "views": views});
    std::fs::write(d.join("scene.json"), scene.to_string()).unwrap();
    let path = |f: &str| d.join(f).display().to_string();
    let o = bin()
        .args([
            "fit",
            &path("scene.json"),
            "--out",
            &path("result.json"),
            "--scale",
            "fixed",
            "--strict",
        ])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(
        err.contains("verdict ambiguous") && err.contains("alternative 1"),
        "{err}"
    );
    assert!(err.contains("covers the 1 alternative pose"), "{err}");
    let r: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(d.join("result.json")).unwrap()).unwrap();
    assert_eq!(r["verdict"], "ambiguous");
    assert_eq!(
        r["alternatives"].as_array().map(|a| a.len()),
        Some(1),
        "{}",
        r["alternatives"]
    );
    let o = bin()
        .args(["suggest-view", &path("scene.json"), &path("result.json"), "--top", "1"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(
        err.contains("the fit is ambiguous") && err.contains("differ by"),
        "{err}"
    );
}
