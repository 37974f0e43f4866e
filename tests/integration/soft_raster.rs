//! The SoftRas kernel: forward against a naive all-pairs oracle, every backward
//! stage against central finite differences. (The objective built on it — the
//! PyTorch3D reference, loss gradients, the Gauss–Newton model — is in `objective.rs`.)

use glam::{DVec2, DVec3};
use localisebot::loss::contour::ContourTarget;
use localisebot::loss::iou::{soft_iou_loss, soft_iou_loss_grad};
use localisebot::raster::silhouette::SoftSettings;
use localisebot::raster::softras::{render, SoftRasterizer, SoftSilhouette, DEGENERATE_DOUBLE_AREA};
use localisebot::{so3, Camera, Mask, Mesh, Pose, Scene};

// ---------------------------------------------------------------- helpers

fn load_case(size: u32) -> (Scene, Pose) {
    let dir = crate::reference(&format!("pytorch3d-case1/scene{size}"));
    let text = std::fs::read_to_string(dir.join("scene.json")).unwrap();
    let d2 = dir.clone();
    let resolver = move |rel: &str| std::fs::read(d2.join(rel)).ok();
    let scene = localisebot::load_scene("scene.json", &text, &resolver).unwrap();
    let init = std::fs::read_to_string(dir.join("init_pose.json")).unwrap();
    (scene, Pose::from_json_str(&init, "init_pose.json").unwrap())
}

/// The pose moved by θ = [ω, t, ls] (right rotation perturbation, log-scale).
fn perturb(p: &Pose, th: &[f64; 9]) -> Pose {
    Pose {
        rotation: p.rotation * so3::exp(DVec3::new(th[0], th[1], th[2])),
        translation: p.translation + DVec3::new(th[3], th[4], th[5]),
        scale: p.scale * DVec3::new(th[6].exp(), th[7].exp(), th[8].exp()),
    }
}

/// Deterministic pseudo-random weights in [−1, 1].
fn weights(n: usize, seed: u64) -> Vec<f64> {
    let mut s = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
    (0..n)
        .map(|_| {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((s >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        })
        .collect()
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Largest |analytic − fd| relative to the largest |analytic| (plus a floor).
fn rel_err(analytic: &[f64], fd: &[f64]) -> f64 {
    let scale = analytic.iter().fold(0.0f64, |m, v| m.max(v.abs())).max(1e-12);
    analytic.iter().zip(fd).fold(0.0f64, |m, (a, f)| m.max((a - f).abs())) / scale
}

/// What the naive oracle computes per pixel.
struct Naive {
    /// A with outside pairs at d² ≥ σ·ln(1/ε − 1) dropped, as the renderer does.
    same_rule: Vec<f64>,
    /// A with every pair.
    exact: Vec<f64>,
    /// Σ D_j over the dropped pairs: a bound on |exact − same_rule|.
    dropped: Vec<f64>,
}

/// The naive oracle: every pixel × every triangle in f64, inside by barycentric
/// coordinates, distance as the minimum over the three closed segments.
fn naive(uv: &[DVec2], tris: &[[u32; 3]], w: u32, h: u32, s: &SoftSettings) -> Naive {
    let m2 = s.sigma * (1.0 / s.eps - 1.0).ln();
    let seg = |p: DVec2, a: DVec2, b: DVec2| {
        let d = b - a;
        let t = ((p - a).dot(d) / d.dot(d)).clamp(0.0, 1.0);
        (p - a - d * t).length_squared()
    };
    let n = (w * h) as usize;
    let mut out = Naive {
        same_rule: vec![0.0; n],
        exact: vec![0.0; n],
        dropped: vec![0.0; n],
    };
    for y in 0..h {
        for x in 0..w {
            let i = (y * w + x) as usize;
            let p = DVec2::new(x as f64, y as f64);
            let (mut t_rule, mut t_exact) = (1.0, 1.0);
            for tri in tris {
                let [a, b, c] = tri.map(|i| uv[i as usize]);
                if !(a.is_finite() && b.is_finite() && c.is_finite()) {
                    continue;
                }
                let area = (b - a).perp_dot(c - a);
                if area.abs() <= DEGENERATE_DOUBLE_AREA {
                    continue;
                }
                let l0 = (c - b).perp_dot(p - b) / area;
                let l1 = (a - c).perp_dot(p - c) / area;
                let l2 = 1.0 - l0 - l1;
                let inside = l0 > 0.0 && l1 > 0.0 && l2 > 0.0;
                let d2 = seg(p, a, b).min(seg(p, b, c)).min(seg(p, c, a));
                let z = if inside { d2 / s.sigma } else { -d2 / s.sigma };
                let d = 1.0 / (1.0 + (-z).exp());
                t_exact *= 1.0 - d;
                if !inside && d2 >= m2 {
                    out.dropped[i] += d;
                } else {
                    t_rule *= 1.0 - d;
                }
            }
            out.same_rule[i] = 1.0 - t_rule;
            out.exact[i] = 1.0 - t_exact;
        }
    }
    out
}

/// Checks a render against the oracle: equal under the same rule; and, per pixel,
/// within the dropped pairs' Σ D (each D < ε) of the untruncated product.
fn check_against_oracle(label: &str, alpha: &[f64], o: &Naive, eps: f64) {
    let d_rule = max_abs_diff(alpha, &o.same_rule);
    let d_exact = max_abs_diff(alpha, &o.exact);
    let max_dropped = o.dropped.iter().fold(0.0f64, |m, v| m.max(*v));
    println!(
        "{label}: max|ΔA| vs same-rule oracle {d_rule:.2e}, vs untruncated {d_exact:.2e} \
         (largest Σ D of the pairs dropped at one pixel, each D < ε = {eps:.0e}: {max_dropped:.2e})"
    );
    assert!(d_rule < 1e-8, "{d_rule}");
    for ((a, e), bound) in alpha.iter().zip(&o.exact).zip(&o.dropped) {
        assert!((a - e).abs() <= bound + 1e-8);
    }
    assert!(d_exact > 0.0 && d_exact <= max_dropped + 1e-8);
}

fn max_abs_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
}

/// A small closed mesh: an irregular octahedron.
fn octahedron() -> Mesh {
    Mesh {
        positions: vec![
            DVec3::new(0.5, 0.0, 0.0),
            DVec3::new(-0.4, 0.05, 0.0),
            DVec3::new(0.0, 0.6, 0.1),
            DVec3::new(0.05, -0.45, 0.0),
            DVec3::new(0.0, 0.0, 0.55),
            DVec3::new(0.1, 0.0, -0.5),
        ],
        triangles: vec![
            [0, 2, 4],
            [2, 1, 4],
            [1, 3, 4],
            [3, 0, 4],
            [2, 0, 5],
            [1, 2, 5],
            [3, 1, 5],
            [0, 3, 5],
        ],
    }
}

fn test_camera(w: u32, h: u32) -> Camera {
    Camera::look_at(DVec3::new(0.3, -0.4, 2.5), DVec3::ZERO, DVec3::Y, w, h, 60.0)
}

fn some_pose() -> Pose {
    Pose {
        rotation: so3::exp(DVec3::new(0.3, -0.5, 0.2)),
        translation: DVec3::new(0.05, -0.02, 0.1),
        scale: DVec3::new(1.0, 0.8, 1.2),
    }
}

/// Settings with a negligible truncation, so that no pair jumps in or out of the
/// cut-off band within a finite-difference step (ε's jumps are of size ε).
fn fd_settings(sigma: f64) -> SoftSettings {
    SoftSettings { sigma, eps: 1e-12 }
}

// ---------------------------------------------------------------- forward

#[test]
fn soft_forward_matches_naive_oracle_on_a_small_mesh() {
    let mesh = octahedron();
    let cam = test_camera(48, 40);
    for (pose, sigma) in [(some_pose(), 1.0), (Pose::IDENTITY, 0.3), (some_pose(), 4.0)] {
        let s = SoftSettings { sigma, eps: 1e-4 };
        let mut r = SoftRasterizer::new();
        let sil = r.render(&mesh, &pose, &cam, &s).unwrap().clone();
        assert!(sil.alpha.iter().any(|&a| a > 0.99) && sil.alpha.contains(&0.0));
        let o = naive(r.uv(), &mesh.triangles, 48, 40, &s);
        check_against_oracle(&format!("octahedron σ={sigma}"), &sil.alpha, &o, s.eps);
        for (a, t) in sil.alpha.iter().zip(&sil.transmittance) {
            assert!((a + t - 1.0).abs() < 1e-15);
        }
    }
}

#[test]
fn soft_forward_matches_naive_oracle_on_the_blob() {
    let (scene, init) = load_case(128);
    let s = SoftSettings::from_ndc(1e-4, 128, 128);
    assert!((s.sigma - 0.4096).abs() < 1e-12);
    for view in &scene.views[..2] {
        let mut r = SoftRasterizer::new();
        let sil = r.render(&scene.mesh, &init, view.camera(), &s).unwrap().clone();
        let o = naive(r.uv(), &scene.mesh.triangles, 128, 128, &s);
        check_against_oracle(&format!("blob {}", view.name()), &sil.alpha, &o, s.eps);
    }
}

#[test]
fn soft_triangles_behind_the_camera_are_skipped_and_bad_settings_named() {
    let mesh = octahedron();
    let cam = test_camera(32, 32);
    // Moved behind the camera: nothing is drawn.
    let pose = Pose {
        translation: DVec3::new(0.6, -0.8, 5.0),
        ..Pose::IDENTITY
    };
    let sil = render(&mesh, &pose, &cam, &SoftSettings::default()).unwrap();
    assert!(sil.alpha.iter().all(|&a| a == 0.0));
    let e = render(&mesh, &Pose::IDENTITY, &cam, &SoftSettings { sigma: 0.0, eps: 1e-4 }).unwrap_err();
    assert!(e.to_string().contains("sigma"), "{e}");
    let e = SoftSilhouette::new()
        .render_2d(&[DVec2::ZERO; 2], &[[0, 1, 2]], 8, 8, &SoftSettings::default())
        .unwrap_err();
    assert!(e.to_string().contains("beyond the 2 vertices"), "{e}");
}

// ---------------------------------------------------------------- backward

#[test]
fn soft_backward_2d_matches_finite_differences() {
    // Triangles crossing the canvas edge, overlapping, one thin and nearly degenerate.
    let uv = vec![
        DVec2::new(-3.2, 4.1),
        DVec2::new(14.3, 2.2),
        DVec2::new(6.1, 15.7),
        DVec2::new(9.4, 6.3),
        DVec2::new(22.8, 13.1),
        DVec2::new(12.2, 19.9),
        DVec2::new(3.3, 18.2),
        DVec2::new(20.1, 18.9),
    ];
    let tris = [[0, 1, 2], [3, 4, 5], [2, 5, 3], [6, 7, 5]];
    let (w, h) = (20, 18);
    let s = fd_settings(1.3);
    let g = weights((w * h) as usize, 7);
    let f = |uv: &[DVec2]| {
        let mut sil = SoftSilhouette::new();
        sil.render_2d(uv, &tris, w, h, &s).unwrap();
        dot(&sil.alpha, &g)
    };
    let mut sil = SoftSilhouette::new();
    sil.render_2d(&uv, &tris, w, h, &s).unwrap();
    let mut grad = Vec::new();
    sil.backward_2d(&g, &mut grad);
    let (mut an, mut fd) = (vec![], vec![]);
    let step = 1e-6;
    for i in 0..uv.len() {
        for c in 0..2 {
            let (mut p, mut m) = (uv.clone(), uv.clone());
            p[i][c] += step;
            m[i][c] -= step;
            an.push(grad[i][c]);
            fd.push((f(&p) - f(&m)) / (2.0 * step));
        }
    }
    let e = rel_err(&an, &fd);
    println!("2-D vertex gradient: relative error {e:.2e}");
    assert!(e < 1e-6, "{an:?}\n{fd:?}");
}

#[test]
fn soft_backward_camera_frame_matches_finite_differences() {
    let mesh = octahedron();
    let cam = test_camera(40, 36);
    let s = fd_settings(0.8);
    let pose = some_pose();
    let pts: Vec<DVec3> = mesh.positions.iter().map(|p| cam.to_camera(pose.apply(*p))).collect();
    let g = weights(40 * 36, 3);
    let mut r = SoftRasterizer::new();
    let mut f = |pts: &[DVec3]| {
        let sil = r.render_camera_frame(pts, 1e-6, &mesh.triangles, &cam, &s).unwrap();
        dot(&sil.alpha, &g)
    };
    let (mut an, mut fd) = (vec![], vec![]);
    let step = 1e-7;
    for i in 0..pts.len() {
        for c in 0..3 {
            let (mut p, mut m) = (pts.clone(), pts.clone());
            p[i][c] += step;
            m[i][c] -= step;
            fd.push((f(&p) - f(&m)) / (2.0 * step));
        }
    }
    let mut r = SoftRasterizer::new();
    r.render_camera_frame(&pts, 1e-6, &mesh.triangles, &cam, &s).unwrap();
    let gc = r.backward_camera_frame(&g).to_vec();
    for v in &gc {
        an.extend([v.x, v.y, v.z]);
    }
    let e = rel_err(&an, &fd);
    println!("camera-frame vertex gradient: relative error {e:.2e}");
    assert!(e < 1e-5, "{an:?}\n{fd:?}");
}

/// ∂(Σ g·A)/∂θ at `pose`, analytic and by central differences.
fn pose_gradients(
    mesh: &Mesh,
    pose: &Pose,
    cam: &Camera,
    s: &SoftSettings,
    seed: u64,
    step: f64,
) -> (Vec<f64>, Vec<f64>) {
    let g = weights((cam.width * cam.height) as usize, seed);
    let mut r = SoftRasterizer::new();
    r.render(mesh, pose, cam, s).unwrap();
    let an = r.backward(&g).to_vec();
    let fd = (0..9)
        .map(|k| {
            let mut th = [0.0; 9];
            th[k] = step;
            let p = dot(&render(mesh, &perturb(pose, &th), cam, s).unwrap().alpha, &g);
            th[k] = -step;
            let m = dot(&render(mesh, &perturb(pose, &th), cam, s).unwrap().alpha, &g);
            (p - m) / (2.0 * step)
        })
        .collect();
    (an, fd)
}

#[test]
fn soft_backward_pose_matches_finite_differences() {
    let mesh = octahedron();
    let cam = test_camera(48, 40);
    let s = fd_settings(0.9);
    let crossing = Pose {
        translation: DVec3::new(0.62, 0.1, 0.0),
        ..some_pose()
    };
    for (name, pose) in [("general", some_pose()), ("crossing the canvas edge", crossing)] {
        let (an, fd) = pose_gradients(&mesh, &pose, &cam, &s, 11, 1e-6);
        let e = rel_err(&an, &fd);
        println!("pose gradient ({name}): relative error {e:.2e}\n  analytic {an:.5?}\n  fd       {fd:.5?}");
        assert!(e < 1e-5, "{name}");
        assert!(
            an.iter().all(|v| v.abs() > 1e-9),
            "{name}: every parameter moves the silhouette"
        );
    }
    // A single square seen nearly edge-on (its normal 88° from the view direction).
    let square = Mesh {
        positions: vec![
            DVec3::new(-0.4, -0.4, 0.0),
            DVec3::new(0.4, -0.4, 0.0),
            DVec3::new(0.4, 0.4, 0.0),
            DVec3::new(-0.4, 0.4, 0.0),
        ],
        triangles: vec![[0, 1, 2], [0, 2, 3]],
    };
    let cam = Camera::look_at(DVec3::new(0.0, 0.0, 3.0), DVec3::ZERO, DVec3::Y, 40, 40, 70.0);
    let pose = Pose {
        rotation: so3::exp(DVec3::new(0.0, 88f64.to_radians(), 0.0)) * so3::exp(DVec3::new(0.2, 0.0, 0.0)),
        ..Pose::IDENTITY
    };
    let (an, fd) = pose_gradients(&square, &pose, &cam, &s, 5, 1e-6);
    let e = rel_err(&an, &fd);
    println!("pose gradient (nearly edge-on face): relative error {e:.2e}");
    assert!(e < 1e-5);
}

#[test]
fn soft_backward_pose_on_the_blob_matches_finite_differences() {
    let (scene, init) = load_case(128);
    let s = fd_settings(0.4096);
    // d² is a minimum over edges, with kinks where the closest edge changes: with
    // thousands of triangles a larger step straddles some (h = 1e-5 gives 2.5e-3,
    // 1e-6 gives 8e-4), so the step is small.
    let (an, fd) = pose_gradients(&scene.mesh, &init, scene.views[1].camera(), &s, 17, 1e-7);
    let e = rel_err(&an, &fd);
    println!("pose gradient (blob, view1): relative error {e:.2e}");
    assert!(e < 1e-4, "{an:?}\n{fd:?}");
}

#[test]
fn soft_contour_loss_gives_a_signal_when_disjoint() {
    // A render entirely beside its mask: the IoU loss is flat (1), the contour loss
    // still pulls the render towards the mask.
    let mesh = octahedron();
    let cam = Camera::look_at(DVec3::new(0.3, -0.4, 2.5), DVec3::ZERO, DVec3::Y, 64, 64, 30.0);
    let s = SoftSettings::default();
    let pose = Pose {
        translation: DVec3::new(1.5, 0.0, 0.0),
        ..Pose::IDENTITY
    };
    let target = render(&mesh, &Pose::IDENTITY, &cam, &s).unwrap();
    let mask = Mask {
        width: 64,
        height: 64,
        data: target.alpha.iter().map(|&a| (a > 0.5) as u8).collect(),
    };
    let mut r = SoftRasterizer::new();
    let alpha = r.render(&mesh, &pose, &cam, &s).unwrap().alpha.clone();
    let m = &mask.data;
    assert!(soft_iou_loss(&alpha, m) > 0.999);
    let ct = ContourTarget::new(&mask, "v").unwrap();
    let mut g = vec![0.0; alpha.len()];
    ct.loss_grad(&alpha, 1.0, &mut g);
    let grad = r.backward(&g);
    // Descending the contour loss moves the render back (−x in the world).
    assert!(grad[3] > 0.0, "{grad:?}");
    let mut g2 = vec![0.0; alpha.len()];
    soft_iou_loss_grad(&alpha, m, 1.0, &mut g2);
    assert!(r.backward(&g2)[3].abs() < 1e-3 * grad[3]);
}
