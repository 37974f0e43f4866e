//! The production objective (`loss::objective::Objective`, what the fit descends),
//! with both soft rasterisers: the PyTorch3D reference case (SoftRas: silhouettes, IoU
//! losses, gradient), the exact gradient of λ1·IoU + λ2·contour (and of the region
//! term) against central differences (whole images, object windows, ignored pixels), the Gauss–Newton model
//! against its definition with a finite-difference Jacobian, the loss along a path to
//! the true pose, and (printed, not asserted) timings.

use crate::{data, reference};
use glam::DVec3;
use localisebot::app::synth::{blob_mesh, synthesize, SynthScene, SynthSettings};
use localisebot::loss::objective::{Objective, ObjectiveSettings};
use localisebot::raster::silhouette::SoftSettings;
use localisebot::raster::silhouette::{RasterKind, RenderMesh};
use localisebot::{so3, Mask, Pose, Scene, View};
use localisebot::{Window, WindowMode};

fn load_case(size: u32) -> (Scene, Pose) {
    let dir = reference(&format!("pytorch3d-case1/scene{size}"));
    let text = std::fs::read_to_string(dir.join("scene.json")).unwrap();
    let d2 = dir.clone();
    let resolver = move |rel: &str| std::fs::read(d2.join(rel)).ok();
    let scene = localisebot::load_scene("scene.json", &text, &resolver).unwrap();
    let init = std::fs::read_to_string(dir.join("init_pose.json")).unwrap();
    (scene, Pose::from_json_str(&init, "init_pose.json").unwrap())
}

fn reference_json() -> serde_json::Value {
    let path = reference("pytorch3d-case1/reference.json");
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

fn read_f32(size: u32, view: usize) -> Vec<f64> {
    std::fs::read(reference(&format!("pytorch3d-case1/soft_init_{size}_view{view}.f32")))
        .unwrap()
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]) as f64)
        .collect()
}

/// The pose moved by θ = [ω, t, ls] (right rotation perturbation, log-scale).
fn perturb(p: &Pose, th: &[f64; 9]) -> Pose {
    Pose {
        rotation: p.rotation * so3::exp(DVec3::new(th[0], th[1], th[2])),
        translation: p.translation + DVec3::new(th[3], th[4], th[5]),
        scale: p.scale * DVec3::new(th[6].exp(), th[7].exp(), th[8].exp()),
    }
}

/// Largest |analytic − fd| relative to the largest |analytic|.
fn rel_err(analytic: &[f64], fd: &[f64]) -> f64 {
    let scale = analytic.iter().fold(0.0f64, |m, v| m.max(v.abs())).max(1e-12);
    analytic.iter().zip(fd).fold(0.0f64, |m, (a, f)| m.max((a - f).abs())) / scale
}

const RASTERS: [RasterKind; 2] = [RasterKind::Edge, RasterKind::SoftRas];

fn settings(sigma: f64, lambda_iou: f64, lambda_contour: f64, raster: RasterKind) -> ObjectiveSettings {
    ObjectiveSettings {
        // ε tiny: the cut-off's jump of size ε in A would spoil finite differences.
        soft: SoftSettings { sigma, eps: 1e-12 },
        lambda_iou,
        lambda_contour,
        lambda_region: 0.0,
        raster,
    }
}

fn full(views: &[View]) -> Vec<Window> {
    views.iter().map(|v| Window::full(v.camera())).collect()
}

fn fd_gradient(o: &mut Objective, mesh: &RenderMesh, pose: &Pose, h: f64) -> Vec<f64> {
    (0..9)
        .map(|k| {
            let mut th = [0.0; 9];
            th[k] = h;
            let p = o.value(mesh, &perturb(pose, &th)).unwrap().total;
            th[k] = -h;
            let m = o.value(mesh, &perturb(pose, &th)).unwrap().total;
            (p - m) / (2.0 * h)
        })
        .collect()
}

/// Checks the objective's gradient at `pose` against central differences, and the
/// Gauss–Newton path's against it; returns the loss.
fn check_gradient(o: &mut Objective, mesh: &RenderMesh, pose: &Pose, label: &str) -> f64 {
    let ev = o.value_and_gradient(mesh, pose).unwrap();
    let fd = fd_gradient(o, mesh, pose, 1e-6);
    let e = rel_err(&ev.gradient, &fd);
    println!("{label}: loss {:.6}, gradient relative error {e:.2e}", ev.total);
    assert!(e < 1e-5, "{label}: {:?}\n{fd:?}", ev.gradient);
    let (_, ne) = o.normal_equations(mesh, pose).unwrap();
    assert!(
        rel_err(&ev.gradient, ne.jtr.as_slice()) < 1e-9,
        "{label}: the two paths differ"
    );
    ev.total
}

// ---------------------------------------------------------------- PyTorch3D reference

#[test]
fn objective_matches_the_pytorch3d_reference() {
    let refj = reference_json();
    for size in [128u32, 256] {
        let r = &refj["per_res"][size.to_string()];
        let (scene, init) = load_case(size);
        let s = ObjectiveSettings {
            soft: SoftSettings::from_ndc(1e-4, size, size),
            lambda_iou: 1.0,
            lambda_contour: 0.0,
            lambda_region: 0.0,
            raster: RasterKind::SoftRas,
        };
        let mut o = Objective::new(&scene.views, &full(&scene.views), size, s).unwrap();
        let model = RenderMesh::new(scene.mesh.clone());
        let ev = o.value_and_gradient(&model, &init).unwrap();
        let (mut worst_a, mut worst_l) = (0.0f64, 0.0f64);
        for i in 0..scene.views.len() {
            let want = read_f32(size, i);
            let alpha = o.alpha(i);
            let d = alpha.iter().zip(&want).fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
            let sum: f64 = alpha.iter().sum();
            let want_sum = r["soft_sum_init"][i].as_f64().unwrap();
            let want_l = r["loss_init_per_view_f64"][i].as_f64().unwrap();
            println!(
                "{size} view{i}: max|ΔA| {d:.2e}, ΣA {sum:.3} (ref {want_sum:.3}), loss {:.8} (ref {want_l:.8})",
                ev.views[i].iou
            );
            worst_a = worst_a.max(d);
            worst_l = worst_l.max((ev.views[i].iou - want_l).abs());
            assert!((sum - want_sum).abs() < 0.05, "ΣA");
        }
        let want_mean = r["loss_init_mean_f64"].as_f64().unwrap();
        // Reference tangent on the left: g_left = R_init · g_right for the rotation.
        let gl = init.rotation * DVec3::new(ev.gradient[0], ev.gradient[1], ev.gradient[2]);
        let mut ours = ev.gradient.to_vec();
        ours[..3].copy_from_slice(&gl.to_array());
        let want: Vec<f64> = (0..9).map(|k| r["grad_init_f64"][k].as_f64().unwrap()).collect();
        let ge = rel_err(&want, &ours);
        println!(
            "{size}: max|ΔA| {worst_a:.2e}, max|Δloss| per view {worst_l:.2e}, mean loss {:.8} (ref {want_mean:.8}), \
             gradient relative error {ge:.2e}\n  ours {ours:.6?}\n  ref  {want:.6?}",
            ev.total
        );
        assert!(worst_a < 1e-4, "silhouettes");
        assert!(worst_l < 1e-4 && (ev.total - want_mean).abs() < 1e-4, "losses");
        assert!(ge < 1e-3, "gradient");
        // The Gauss–Newton path computes the same loss and gradient.
        let (ev2, ne) = o.normal_equations(&model, &init).unwrap();
        assert!((ev2.total - ev.total).abs() < 1e-12 && (ne.cost - ev.total).abs() < 1e-12);
        assert!(
            rel_err(&ev.gradient, ne.jtr.as_slice()) < 1e-9,
            "{:?}\n{:?}",
            ev.gradient,
            ne.jtr
        );
    }
}

// ---------------------------------------------------------------- gradients

/// The blob in two views (with shaded photographs when `images`), and a pose off the
/// truth.
fn blob_in_two_views(width: u32, height: u32, images: bool) -> (RenderMesh, SynthScene, Pose) {
    let mesh = blob_mesh(8, 12);
    let s = synthesize(
        &mesh,
        &SynthSettings {
            views: 2,
            width,
            height,
            seed: 9,
            images,
            ..Default::default()
        },
        None,
    )
    .unwrap();
    let off = perturb(&s.pose, &[0.05, -0.08, 0.03, 0.04, -0.03, 0.02, 0.05, -0.05, 0.02]);
    (RenderMesh::new(mesh), s, off)
}

/// A small synthetic scene: the blob in two views, and a pose off the truth.
fn small_scene(width: u32, height: u32) -> (RenderMesh, Vec<View>, Pose) {
    let (mesh, s, off) = blob_in_two_views(width, height, false);
    (mesh, s.views(), off)
}

/// The views with an ignore mask over a block of the first view's object.
fn with_ignored_block(views: &[View]) -> Vec<View> {
    views
        .iter()
        .enumerate()
        .map(|(i, v)| {
            let (w, h) = (v.mask().width, v.mask().height);
            let mut ig = Mask::empty(w, h);
            if i == 0 {
                let (x0, y0, x1, y1) = v.mask().bbox().unwrap();
                for y in y0..=(y0 + y1) / 2 {
                    for x in x0..=(x0 + x1) / 2 {
                        ig.data[(y * w + x) as usize] = 1;
                    }
                }
            }
            View::new(
                v.name(),
                *v.camera(),
                v.mask().clone(),
                Some(ig),
                None,
                &Default::default(),
            )
            .unwrap()
        })
        .collect()
}

#[test]
fn objective_gradient_matches_central_differences() {
    let (mesh, views, pose) = small_scene(40, 32);
    let ignored = with_ignored_block(&views);
    for raster in RASTERS {
        for (label, views, mode, res) in [
            ("whole images", &views, WindowMode::Full, 40),
            ("object windows", &views, WindowMode::Object { margin: 0.3 }, 24),
            ("ignored pixels", &ignored, WindowMode::Object { margin: 0.3 }, 24),
        ] {
            for (l1, l2) in [(1.0, 0.0), (1.0, 0.7), (0.0, 1.0)] {
                let windows: Vec<Window> = views.iter().map(|v| Window::for_view(v, mode)).collect();
                let mut o = Objective::new(views, &windows, res, settings(1.5, l1, l2, raster)).unwrap();
                o.set_weights(&[1.0, 0.4]).unwrap();
                check_gradient(&mut o, &mesh, &pose, &format!("{raster:?}, {label}, λ = ({l1}, {l2})"));
            }
        }
    }
}

/// The blob photographed (shaded on a grey gradient) in two views, its masks
/// roughened as a segmenter's are and asking for the region term; a pose off the truth.
fn photographed_scene(width: u32, height: u32) -> (RenderMesh, Vec<View>, Pose) {
    let (mesh, s, off) = blob_in_two_views(width, height, true);
    (mesh, s.segmented_views(1.5, 6.0, 3).unwrap(), off)
}

#[test]
fn region_term_gradient_matches_central_differences() {
    let (mesh, views, pose) = photographed_scene(48, 40);
    for raster in RASTERS {
        for (mode, res) in [(WindowMode::Full, 48), (WindowMode::Object { margin: 0.3 }, 24)] {
            let windows: Vec<Window> = views.iter().map(|v| Window::for_view(v, mode)).collect();
            let without = settings(1.5, 1.0, 0.7, raster);
            let with = ObjectiveSettings {
                lambda_region: 0.8,
                ..without
            };
            let mut o = Objective::new(&views, &windows, res, with).unwrap();
            // The term is there: the loss differs from the one without it.
            let mut plain = Objective::new(&views, &windows, res, without).unwrap();
            let total = check_gradient(&mut o, &mesh, &pose, &format!("{raster:?}, {mode:?}, region term"));
            let base = plain.value(&mesh, &pose).unwrap().total;
            assert!((total - base).abs() > 1e-3, "{raster:?} {mode:?}: {total} vs {base}");
        }
    }
    // A view that does not ask for the term has none, nor has an objective without the
    // contour term it is folded into.
    let plain_views: Vec<View> = views.iter().map(|v| v.clone().without_image()).collect();
    let windows = full(&views);
    let a = Objective::new(
        &plain_views,
        &windows,
        48,
        ObjectiveSettings {
            lambda_region: 0.8,
            ..settings(1.5, 1.0, 0.7, RasterKind::Edge)
        },
    );
    let b = Objective::new(&plain_views, &windows, 48, settings(1.5, 1.0, 0.7, RasterKind::Edge));
    let (va, vb) = (
        a.unwrap().value(&mesh, &pose).unwrap(),
        b.unwrap().value(&mesh, &pose).unwrap(),
    );
    assert_eq!(va.total, vb.total);
    let no_contour = settings(1.5, 1.0, 0.0, RasterKind::Edge);
    let mut c = Objective::new(
        &views,
        &windows,
        48,
        ObjectiveSettings {
            lambda_region: 0.8,
            ..no_contour
        },
    )
    .unwrap();
    let mut d = Objective::new(&views, &windows, 48, no_contour).unwrap();
    assert_eq!(
        c.value(&mesh, &pose).unwrap().total,
        d.value(&mesh, &pose).unwrap().total
    );
}

#[test]
fn ignored_pixels_count_in_no_term() {
    // Two masks differing only inside the ignore mask give the same loss.
    let (mesh, views, pose) = small_scene(40, 32);
    let ignored = with_ignored_block(&views);
    let ig = ignored[0].ignore().unwrap().clone();
    let mut blanked = views[0].mask().clone();
    for (m, &i) in blanked.data.iter_mut().zip(&ig.data) {
        if i != 0 {
            *m = 0;
        }
    }
    let other = View::new(
        "view0",
        *views[0].camera(),
        blanked,
        Some(ig),
        None,
        &Default::default(),
    )
    .unwrap();
    let a = vec![ignored[0].clone()];
    let b = vec![other];
    for raster in RASTERS {
        let s = settings(1.0, 1.0, 0.5, raster);
        let mut oa = Objective::new(&a, &full(&a), 40, s).unwrap();
        let mut ob = Objective::new(&b, &full(&b), 40, s).unwrap();
        let (la, lb) = (oa.value(&mesh, &pose).unwrap(), ob.value(&mesh, &pose).unwrap());
        assert!(
            (la.total - lb.total).abs() < 1e-12,
            "{raster:?}: {} vs {}",
            la.total,
            lb.total
        );
        // And without the ignore mask they differ.
        let mut oc = Objective::new(&views[..1], &full(&views[..1]), 40, s).unwrap();
        assert!((oc.value(&mesh, &pose).unwrap().total - la.total).abs() > 1e-4);
    }
}

#[test]
fn gauss_newton_model_matches_its_definition() {
    // JᵀJ = Σ_p c_p·J_p J_pᵀ over known pixels, J_p = ∂A_p/∂θ by central differences,
    // c_p = λ1/(2U|A_p − M_p|) + λ2·w_p²/(2ℓ_p) (see loss::objective's doc).
    let (mesh, views, pose) = small_scene(36, 30);
    let views = with_ignored_block(&views);
    let (l1, l2) = (1.0, 0.6);
    let windows: Vec<Window> = views.iter().map(|v| Window::full(v.camera())).collect();
    for raster in RASTERS {
        let mut o = Objective::new(&views, &windows, 36, settings(1.2, l1, l2, raster)).unwrap();
        // Twice: the IoU weights' 1/U is that of the previous evaluation, here the same pose.
        o.normal_equations(&mesh, &pose).unwrap();
        let (_, ne) = o.normal_equations(&mesh, &pose).unwrap();
        let h = 1e-6;
        let n = views.len() as f64;
        let mut want = [[0.0f64; 9]; 9];
        for v in 0..views.len() {
            o.value(&mesh, &pose).unwrap();
            let alpha = o.alpha(v).to_vec();
            let t = o.targets()[v].clone();
            let cols: Vec<Vec<f64>> = (0..9)
                .map(|k| {
                    let mut th = [0.0; 9];
                    th[k] = h;
                    o.value(&mesh, &perturb(&pose, &th)).unwrap();
                    let p = o.alpha(v).to_vec();
                    th[k] = -h;
                    o.value(&mesh, &perturb(&pose, &th)).unwrap();
                    let m = o.alpha(v);
                    p.iter().zip(m).map(|(a, b)| (a - b) / (2.0 * h)).collect()
                })
                .collect();
            let known = |p: usize| t.is_known(p);
            let (mut inter, mut sum_a) = (0.0, 0.0);
            for (p, &a) in alpha.iter().enumerate() {
                if known(p) {
                    sum_a += a;
                    inter += a * t.mask[p] as f64;
                }
            }
            let union = sum_a + t.area - inter + 1e-6;
            let contour = t.contour.as_ref().unwrap();
            for p in 0..alpha.len() {
                let jp: Vec<f64> = (0..9).map(|k| cols[k][p]).collect();
                if !known(p) || jp.iter().all(|j| j.abs() < 1e-14) {
                    continue;
                }
                let a = alpha[p];
                let m = t.mask[p] as f64;
                let w = contour.gradient()[p];
                let c = l1 / (2.0 * union * (a - m).abs().max(1e-12)) + l2 * w * w / (2.0 * contour.pixel_loss(p, a));
                for i in 0..9 {
                    for j in 0..9 {
                        want[i][j] += c * jp[i] * jp[j] / n;
                    }
                }
            }
        }
        let got: Vec<f64> = (0..9).flat_map(|i| (0..9).map(move |j| ne.jtj[(i, j)])).collect();
        let want: Vec<f64> = want.iter().flatten().copied().collect();
        let e = rel_err(&got, &want);
        println!("{raster:?}: Gauss–Newton curvature: relative error {e:.2e}");
        assert!(e < 1e-4, "{raster:?}: {got:?}\n{want:?}");
        for i in 0..9 {
            assert!(ne.jtj[(i, i)] > 0.0);
        }
    }
}

// ---------------------------------------------------------------- behaviour

#[test]
fn objective_falls_along_the_path_to_the_true_pose() {
    let (scene, init) = load_case(128);
    let gt = scene.ground_truth_pose.unwrap();
    let model = RenderMesh::new(scene.mesh.clone());
    for (mode, raster) in [
        (WindowMode::Full, RasterKind::SoftRas),
        (WindowMode::Object { margin: 0.3 }, RasterKind::SoftRas),
        (WindowMode::Object { margin: 0.3 }, RasterKind::Edge),
    ] {
        let s = ObjectiveSettings {
            soft: SoftSettings::from_ndc(1e-4, 128, 128),
            lambda_iou: 1.0,
            lambda_contour: 1.0,
            lambda_region: 0.0,
            raster,
        };
        let windows: Vec<Window> = scene.views.iter().map(|v| Window::for_view(v, mode)).collect();
        let mut o = Objective::new(&scene.views, &windows, 128, s).unwrap();
        let w = so3::log(init.rotation.transpose() * gt.rotation);
        let (ls0, ls1) = (init.scale.map(f64::ln), gt.scale.map(f64::ln));
        let mut last: Option<(f64, f64)> = None;
        for k in 0..=5 {
            let a = k as f64 / 5.0;
            let ls = ls0.lerp(ls1, a);
            let pose = Pose {
                rotation: init.rotation * so3::exp(w * a),
                translation: init.translation.lerp(gt.translation, a),
                scale: ls.map(f64::exp),
            };
            let ev = o.value(&model, &pose).unwrap();
            let iou = ev.views.iter().map(|v| v.iou).sum::<f64>() / 4.0;
            let contour = ev.views.iter().map(|v| v.contour).sum::<f64>() / 4.0;
            println!("{mode:?} {raster:?} path {a:.1}: IoU loss {iou:.5}, contour {contour:.6}");
            if let Some((i0, c0)) = last {
                assert!(iou < i0 && contour < c0, "{mode:?} {raster:?} at {a}");
            }
            last = Some((iou, contour));
        }
        let (iou, contour) = last.unwrap();
        assert!(iou < 0.1 && contour < 0.01);
    }
}

// ---------------------------------------------------------------- timings (printed)

#[test]
fn objective_timings() {
    let duck = localisebot::io::load_mesh(
        "Duck.glb",
        &std::fs::read(data("gltf/Duck/glTF-Binary/Duck.glb")).unwrap(),
        &localisebot::io::no_files,
    )
    .unwrap();
    let (scene, init) = load_case(128);
    let s = synthesize(
        &duck,
        &SynthSettings {
            views: 4,
            width: 128,
            height: 128,
            seed: 3,
            ..Default::default()
        },
        None,
    )
    .unwrap();
    let duck_views = s.views();
    let near = perturb(&s.pose, &[0.02, 0.01, -0.02, 0.01, 0.0, 0.01, 0.01, 0.0, -0.01]);
    let (blob, duck) = (RenderMesh::new(scene.mesh.clone()), RenderMesh::new(duck));
    for (label, mesh, views, pose, raster) in [
        ("blob", &blob, &scene.views, init, RasterKind::SoftRas),
        ("blob", &blob, &scene.views, init, RasterKind::Edge),
        ("Duck", &duck, &duck_views, near, RasterKind::SoftRas),
        ("Duck", &duck, &duck_views, near, RasterKind::Edge),
    ] {
        let mut o = Objective::new(views, &full(views), 128, settings(0.4, 1.0, 0.1, raster)).unwrap();
        let n = 10;
        let mut best = [f64::MAX; 3];
        for _ in 0..n {
            let t = std::time::Instant::now();
            o.value(mesh, &pose).unwrap();
            let t1 = t.elapsed().as_secs_f64();
            let t = std::time::Instant::now();
            let ev = o.value_and_gradient(mesh, &pose).unwrap();
            let t2 = t.elapsed().as_secs_f64();
            assert!(ev.total > 0.0 && ev.gradient.iter().any(|g| g.abs() > 1e-9));
            let t = std::time::Instant::now();
            o.normal_equations(mesh, &pose).unwrap();
            let t3 = t.elapsed().as_secs_f64();
            best = [best[0].min(t1), best[1].min(t2), best[2].min(t3)];
        }
        println!(
            "TIMING {label} {raster:?}: {} tris, {} views 128²: value {:.2} ms, value+gradient {:.2} ms, Gauss–Newton {:.2} ms",
            mesh.mesh.triangles.len(),
            views.len(),
            best[0] * 1e3,
            best[1] * 1e3,
            best[2] * 1e3
        );
    }
}
