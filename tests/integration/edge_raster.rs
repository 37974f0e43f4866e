//! Silhouette-edge soft rasteriser (`raster::edge`): the tiled kernel against a naive
//! per-pixel oracle over all edges (adjacency built independently, with hash maps),
//! its gradient records against central differences (2-D and through the pose), the
//! σ → 0 limit, the closed-form soft values of a square, and hidden contours. The
//! oracle and the checks against it are `tests/oracles/edge.rs`, which the browser
//! suite (`tests/wasm.rs`) runs too.

#[path = "../oracles/edge.rs"]
mod oracle;

use crate::hard_raster::{cube, duck};
use glam::{DVec2, DVec3};
use localisebot::app::synth::blob_mesh;
use localisebot::raster::edge::{EdgeSilhouette, EdgeTopology};
use localisebot::raster::hard;
use localisebot::raster::project::{project_mesh, Projected};
use localisebot::raster::silhouette::SoftSettings;
use localisebot::{so3, Camera, Mask, Mesh, Pose};
use oracle::*;

/// A `(n+1)²`-vertex height field over [−1, 1]², an open mesh.
fn height_field(n: usize) -> Mesh {
    let mut positions = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            let (x, y) = (i as f64 / n as f64 * 2.0 - 1.0, j as f64 / n as f64 * 2.0 - 1.0);
            positions.push(DVec3::new(x, y, 0.3 * (2.0 * x).sin() * (1.5 * y).cos()));
        }
    }
    let v = |i: usize, j: usize| (j * (n + 1) + i) as u32;
    let mut triangles = Vec::new();
    for j in 0..n {
        for i in 0..n {
            triangles.push([v(i, j), v(i + 1, j), v(i + 1, j + 1)]);
            triangles.push([v(i, j), v(i + 1, j + 1), v(i, j + 1)]);
        }
    }
    Mesh { positions, triangles }
}

/// The mesh with every vertex of every other triangle replaced by a fresh copy
/// appended after the originals (so the smallest index of each position is the
/// original one), as glTF stores UV and normal seams.
fn with_seams(mesh: &Mesh) -> Mesh {
    let mut positions = mesh.positions.clone();
    let mut triangles = Vec::new();
    for (f, t) in mesh.triangles.iter().enumerate() {
        if f % 2 == 0 {
            triangles.push(*t);
        } else {
            triangles.push(t.map(|i| {
                positions.push(mesh.positions[i as usize]);
                positions.len() as u32 - 1
            }));
        }
    }
    Mesh { positions, triangles }
}

/// A box of half-size `h` centred at `c`, 12 triangles.
fn boxed(c: DVec3, h: DVec3) -> Mesh {
    let mut m = cube();
    for p in &mut m.positions {
        *p = c + *p * h;
    }
    m
}

fn concat(a: &Mesh, b: &Mesh) -> Mesh {
    let n = a.positions.len() as u32;
    Mesh {
        positions: a.positions.iter().chain(&b.positions).copied().collect(),
        triangles: a
            .triangles
            .iter()
            .copied()
            .chain(b.triangles.iter().map(|t| t.map(|i| i + n)))
            .collect(),
    }
}

/// A flat "projection": pixel positions as given, every vertex in front.
fn flat(uv: &[DVec2]) -> (Mesh, Projected) {
    let mesh = Mesh {
        positions: uv.iter().map(|p| p.extend(0.0)).collect(),
        triangles: Vec::new(),
    };
    let proj = Projected {
        cam: vec![DVec3::Z; uv.len()],
        uv: uv.to_vec(),
        near: 1e-3,
    };
    (mesh, proj)
}

/// A camera used only for its canvas size (every vertex of a flat projection is in front).
fn canvas(w: u32, h: u32) -> Camera {
    Camera::look_at(DVec3::new(0.0, 0.0, -1.0), DVec3::ZERO, DVec3::Y, w, h, 10.0)
}

fn settings(sigma: f64) -> SoftSettings {
    SoftSettings { sigma, eps: 1e-4 }
}

// ---------------------------------------------------------------- forward vs oracle

#[test]
fn edge_matches_oracle_on_the_blob() {
    let mesh = blob_mesh(22, 50);
    for (dir, sigma) in [(DVec3::new(0.3, -0.4, 2.5), 0.4096), (DVec3::new(-1.0, 0.7, 0.2), 2.0)] {
        let cam = look(&mesh, dir, 3.0, 128, 128, 150.0);
        let proj = project_mesh(&mesh, &some_pose(), &cam);
        check("blob", &mesh, &proj, &cam, &settings(sigma));
    }
}

#[test]
fn edge_matches_oracle_on_the_duck() {
    let mesh = duck();
    for (k, dir) in [DVec3::new(1.0, 0.5, 1.0), DVec3::new(-0.7, -0.4, -1.0)]
        .into_iter()
        .enumerate()
    {
        let cam = look(&mesh, dir, 3.5, 128, 128, 150.0);
        let proj = project_mesh(&mesh, &Pose::IDENTITY, &cam);
        let (sil, _) = check(&format!("duck view {k}"), &mesh, &proj, &cam, &settings(0.4096));
        // The Duck's seams: far fewer welded vertices than stored ones.
        let topo = EdgeTopology::from_mesh(&mesh);
        assert!(topo.welded_vertex_count() < mesh.positions.len());
        assert!(sil.outline_edges() < topo.edge_count() / 4);
    }
}

#[test]
fn edge_matches_oracle_on_a_cube_an_open_mesh_and_across_the_border() {
    let c = cube();
    let cam = look(&c, DVec3::new(0.6, 0.8, 1.7), 3.0, 64, 56, 60.0);
    check("cube", &c, &project_mesh(&c, &some_pose(), &cam), &cam, &settings(1.0));
    let hf = height_field(7);
    let cam = look(&hf, DVec3::new(0.4, -0.9, 1.5), 2.5, 64, 64, 70.0);
    check(
        "height field",
        &hf,
        &project_mesh(&hf, &some_pose(), &cam),
        &cam,
        &settings(1.5),
    );
    // The blob close up: its silhouette leaves the canvas on every side.
    let blob = blob_mesh(12, 24);
    let cam = look(&blob, DVec3::new(0.2, 0.1, 1.0), 1.4, 40, 36, 60.0);
    let proj = project_mesh(&blob, &Pose::IDENTITY, &cam);
    let (sil, o) = check("blob across the border", &blob, &proj, &cam, &settings(1.0));
    assert!(o
        .candidates
        .iter()
        .any(|e| e.pa.x < 0.0 || e.pa.y < 0.0 || e.pa.x > 39.0 || e.pa.y > 35.0));
    let row0 = &sil.coverage().data[..40];
    assert!(row0.contains(&1), "the silhouette should reach the canvas' top row");
}

#[test]
fn edge_matches_oracle_on_non_manifold_edges() {
    // Three triangles share the edge (20, 12)–(20, 40). Mixed sides: the shared edge
    // is no outline; all on one side: it is.
    for (thirds, shared_is_outline) in [
        (
            [DVec2::new(33.4, 25.1), DVec2::new(7.3, 22.8), DVec2::new(30.2, 41.7)],
            false,
        ),
        (
            [DVec2::new(33.4, 25.1), DVec2::new(26.9, 14.2), DVec2::new(30.2, 41.7)],
            true,
        ),
    ] {
        let mut uv = vec![DVec2::new(20.0, 12.0), DVec2::new(20.0, 40.0)];
        uv.extend(thirds);
        let (mut mesh, proj) = flat(&uv);
        mesh.triangles = vec![[0, 1, 2], [1, 0, 3], [0, 4, 1]];
        let cam = canvas(48, 52);
        let (_, o) = check("non-manifold", &mesh, &proj, &cam, &settings(1.0));
        assert_eq!(o.candidates.iter().any(|e| (e.a, e.b) == (0, 1)), shared_is_outline);
        let topo = EdgeTopology::from_mesh(&mesh);
        assert_eq!(topo.edge_count(), 7);
    }
}

#[test]
fn edge_welds_seams_to_the_welded_result() {
    for (label, mesh) in [("blob", blob_mesh(14, 30)), ("duck", duck())] {
        let seams = with_seams(&mesh);
        let cam = look(&mesh, DVec3::new(0.5, 0.6, 1.0), 3.0, 96, 96, 110.0);
        let pose = some_pose();
        let a = render(&mesh, &project_mesh(&mesh, &pose, &cam), &cam, &settings(0.8));
        let proj = project_mesh(&seams, &pose, &cam);
        let (b, _) = check(&format!("{label} with seams"), &seams, &proj, &cam, &settings(0.8));
        assert_eq!(a.coverage(), b.coverage(), "{label}");
        assert_eq!(a.outline_edges(), b.outline_edges(), "{label}");
        assert!(
            a.alpha().iter().zip(b.alpha()).all(|(x, y)| (x - y).abs() <= 1e-12),
            "{label}"
        );
        assert_records_match(label, b.records(), a.records());
    }
}

#[test]
fn edge_vertices_behind_the_camera_drop_their_faces() {
    // A camera above the middle of a height field, looking along it: the near half is
    // behind the camera, the hard coverage clips it, its faces are not present.
    let mesh = height_field(12);
    let cam = Camera::look_at(
        DVec3::new(0.1, -0.2, 0.8),
        DVec3::new(0.0, 1.0, 0.0),
        DVec3::Z,
        64,
        48,
        40.0,
    );
    let proj = project_mesh(&mesh, &Pose::IDENTITY, &cam);
    assert!(proj.cam.iter().any(|c| c.z < proj.near) && proj.cam.iter().any(|c| c.z > proj.near));
    check("height field behind the camera", &mesh, &proj, &cam, &settings(1.0));
}

#[test]
fn edge_hidden_contours_do_not_soften_the_interior() {
    let big = boxed(DVec3::ZERO, DVec3::new(1.0, 0.8, 0.6));
    let small = boxed(DVec3::new(0.1, -0.05, 1.2), DVec3::new(0.25, 0.2, 0.2));
    let both = concat(&big, &small);
    let cam = Camera::look_at(DVec3::new(0.4, 0.3, 6.0), DVec3::ZERO, DVec3::Y, 128, 112, 200.0);
    let pose = Pose {
        rotation: so3::exp(DVec3::new(0.05, -0.1, 0.3)),
        ..Pose::IDENTITY
    };
    let s = settings(1.0);
    let alone = render(&big, &project_mesh(&big, &pose, &cam), &cam, &s);
    let (sil, o) = check("boxes", &both, &project_mesh(&both, &pose, &cam), &cam, &s);
    // The small box's contours are candidates, lie well inside the big silhouette, and
    // are all rejected: the render is the big box's alone.
    assert!(sil.outline_edges() > alone.outline_edges());
    let small_edges: Vec<&Candidate> = o.candidates.iter().filter(|e| e.a >= 8).collect();
    assert!(small_edges.len() >= 4);
    assert!(small_edges.iter().all(|e| {
        let mid = ((e.pa + e.pb) * 0.5).round();
        sil.coverage().get(mid.x as u32, mid.y as u32)
    }));
    assert_eq!(sil.coverage(), alone.coverage());
    assert!(sil
        .alpha()
        .iter()
        .zip(alone.alpha())
        .all(|(a, b)| (a - b).abs() <= 1e-12));
    assert!(sil.records().iter().all(|r| r.a < 8 && r.b < 8));
    assert!(sil.alpha().iter().filter(|&&a| a == 1.0).count() > 1000);
}

// ---------------------------------------------------------------- limits and closed forms

#[test]
fn edge_tiny_sigma_gives_the_hard_raster() {
    for mesh in [blob_mesh(22, 50), duck()] {
        let cam = look(&mesh, DVec3::new(0.3, 0.2, 1.0), 3.0, 128, 128, 150.0);
        let proj = project_mesh(&mesh, &some_pose(), &cam);
        let sil = render(&mesh, &proj, &cam, &settings(1e-6));
        let hard = hard::render_projected(&proj, &mesh.triangles, &cam);
        // Pixels within 1e-2 px of any projected edge are excluded.
        let (w, h) = (cam.width as usize, cam.height as usize);
        let mut near_edge = vec![false; w * h];
        for t in &mesh.triangles {
            for k in 0..3 {
                let (a, b) = (proj.uv[t[k] as usize], proj.uv[t[(k + 1) % 3] as usize]);
                let lo = (a.min(b) - 0.01).ceil().max(DVec2::ZERO);
                let hi = (a.max(b) + 0.01)
                    .floor()
                    .min(DVec2::new(w as f64 - 1.0, h as f64 - 1.0));
                for y in lo.y as i64..=hi.y as i64 {
                    for x in lo.x as i64..=hi.x as i64 {
                        let p = DVec2::new(x as f64, y as f64);
                        let d = b - a;
                        let t = ((p - a).dot(d) / d.length_squared()).clamp(0.0, 1.0);
                        if (p - (a + d * t)).length() <= 0.01 {
                            near_edge[y as usize * w + x as usize] = true;
                        }
                    }
                }
            }
        }
        let mut checked = 0;
        for (i, (a, c)) in sil.alpha().iter().zip(&hard.data).enumerate() {
            if !near_edge[i] {
                assert_eq!(*a, f64::from(*c), "pixel {i}");
                checked += 1;
            }
        }
        assert!(checked > w * h * 9 / 10 && hard.area() > 1000, "{checked}");
    }
}

#[test]
fn edge_square_follows_the_sigmoid_of_the_squared_distance() {
    let (x0, x1, y0, y1) = (10.3, 100.7, 12.6, 90.2);
    let uv = [
        DVec2::new(x0, y0),
        DVec2::new(x1, y0),
        DVec2::new(x1, y1),
        DVec2::new(x0, y1),
    ];
    let (mut mesh, proj) = flat(&uv);
    mesh.triangles = vec![[0, 1, 2], [0, 2, 3]];
    let cam = canvas(128, 112);
    for sigma in [0.5, 2.0] {
        let s = settings(sigma);
        let m = s.cutoff_sq().sqrt();
        let sil = render(&mesh, &proj, &cam, &s);
        assert_eq!(sil.outline_edges(), 4);
        let mut soft = 0;
        // A row crossing the left and right edges, a column crossing the top and bottom.
        for x in 0..128usize {
            let inside = x as f64 > x0 && (x as f64) < x1;
            let d = (x as f64 - x0).abs().min((x as f64 - x1).abs());
            let want = match (d < m, inside) {
                (true, true) => 1.0 / (1.0 + (-d * d / sigma).exp()),
                (true, false) => 1.0 / (1.0 + (d * d / sigma).exp()),
                (false, c) => f64::from(u8::from(c)),
            };
            soft += usize::from(d < m);
            let got = sil.alpha()[50 * 128 + x];
            assert!((got - want).abs() < 1e-14, "σ {sigma} x {x}: {got} vs {want}");
        }
        for y in 0..112usize {
            let inside = y as f64 > y0 && (y as f64) < y1;
            let d = (y as f64 - y0).abs().min((y as f64 - y1).abs());
            let want = if d < m {
                1.0 / (1.0 + (if inside { -1.0 } else { 1.0 } * d * d / sigma).exp())
            } else {
                f64::from(u8::from(inside))
            };
            let got = sil.alpha()[y * 128 + 60];
            assert!((got - want).abs() < 1e-14, "σ {sigma} y {y}: {got} vs {want}");
        }
        assert!(soft >= 4);
        // Moving the left edge right by ξ lowers A at (x, 50) near it:
        // ∂A/∂ξ = −∂A/∂x, the sum of the two left vertices' u-gradients.
        for x in 9..13usize {
            let i = (50 * 128 + x) as u32;
            let r = sil.records().iter().find(|r| r.px == i).unwrap();
            assert_eq!((r.a.min(r.b), r.a.max(r.b)), (0, 3));
            let d = x as f64 - x0;
            let a = sil.alpha()[i as usize];
            let want = -(a * (1.0 - a) / sigma) * 2.0 * d.abs();
            assert!(((r.ga.x + r.gb.x) - want).abs() < 1e-12, "x {x}");
            assert!((r.ga.y + r.gb.y).abs() < 1e-12);
        }
    }
}

#[test]
fn edge_gradient_2d_matches_central_differences() {
    let blob = blob_mesh(14, 30);
    let cam = look(&blob, DVec3::new(0.3, -0.4, 2.5), 3.0, 64, 64, 75.0);
    fd_2d("blob", &blob, &project_mesh(&blob, &some_pose(), &cam), &cam, 1.0);
    let d = duck();
    let cam = look(&d, DVec3::new(1.0, 0.5, 1.0), 3.5, 128, 128, 150.0);
    fd_2d("duck", &d, &project_mesh(&d, &Pose::IDENTITY, &cam), &cam, 0.4096);
    let hf = height_field(5);
    let cam = look(&hf, DVec3::new(0.4, -0.9, 1.5), 2.5, 64, 64, 70.0);
    fd_2d("height field", &hf, &project_mesh(&hf, &some_pose(), &cam), &cam, 2.0);
}

#[test]
fn edge_gradient_through_the_pose_matches_central_differences() {
    // ∂(Σ w·A)/∂t for the translation t, chained by hand: X_c = R_c(R·sX + t) + t_c,
    // so ∂L/∂t = R_cᵀ Σ_v J_vᵀ ∂L/∂uv_v (J_v the projection Jacobian at X_c of v). The
    // gradient sits on one copy of each welded vertex, yet every copy moves: this
    // checks that any copy serves.
    let mesh = duck();
    let topo = EdgeTopology::from_mesh(&mesh);
    let cam = look(&mesh, DVec3::new(-1.0, 0.6, 0.8), 3.5, 96, 96, 110.0);
    let s = SoftSettings { sigma: 0.6, eps: 1e-15 };
    let weights = noise(96 * 96, 11);
    // A world length that moves the object by about one pixel.
    let px = mesh.diameter() * 3.5 * 0.5 / cam.fx;
    let mut pose = some_pose();
    let found = (0..20).any(|k| {
        pose.translation = some_pose().translation + DVec3::new(0.31, -0.17, 0.0) * (k as f64 * px);
        let o = oracle(
            &mesh.positions,
            &mesh.triangles,
            &project_mesh(&mesh, &pose, &cam),
            &cam,
            &s,
        );
        margin(&o, 96, 96) >= 1e-3
    });
    assert!(found, "no configuration without a pixel centre near the outline");
    let proj = project_mesh(&mesh, &pose, &cam);
    let mut sil = EdgeSilhouette::new();
    sil.render(&topo, &proj, &mesh.triangles, &cam, &s).unwrap();
    let base_structure = structure(&sil);
    let base_alpha = sil.alpha().to_vec();
    let mut g = Vec::new();
    sil.backward_2d(&weights, &mut g);
    let mut gc = DVec3::ZERO;
    for (v, gv) in g.iter().enumerate() {
        let (_, j) = cam.project_with_jacobian(proj.cam[v]);
        gc += j[0] * gv.x + j[1] * gv.y;
    }
    let analytic = cam.rotation.transpose() * gc;
    let scale = analytic.abs().max_element();
    assert!(scale > 1e-3 / px);
    let hstep = 1e-6 * px;
    for axis in 0..3 {
        let mut f = [0.0; 2];
        for (j, sign) in [1.0, -1.0].into_iter().enumerate() {
            let mut p = pose;
            p.translation[axis] += sign * hstep;
            sil.render(&topo, &project_mesh(&mesh, &p, &cam), &mesh.triangles, &cam, &s)
                .unwrap();
            assert!(structure(&sil) == base_structure, "axis {axis} changes the structure");
            f[j] = sil
                .alpha()
                .iter()
                .zip(&base_alpha)
                .zip(&weights)
                .map(|((a, b), w)| (a - b) * w)
                .sum();
        }
        let numeric = (f[0] - f[1]) / (2.0 * hstep);
        assert!(
            (numeric - analytic[axis]).abs() <= 1e-6 * scale,
            "axis {axis}: {numeric} vs {} (scale {scale})",
            analytic[axis]
        );
    }
}

#[test]
fn closed_meshes_skip_their_back_faces_yet_cover_the_same_pixels() {
    use localisebot::app::shapes::toy_plane;
    let meshes = [
        ("duck", duck()),
        ("blob", blob_mesh(22, 50)),
        ("toy", toy_plane()),
        ("cube", localisebot::app::shapes::cube_mesh(1.0)),
    ];
    for (label, mesh) in &meshes {
        let topo = EdgeTopology::from_mesh(mesh);
        let culled = topo.front_signs().iter().filter(|&&s| s != 0).count();
        assert_eq!(culled, mesh.triangles.len(), "{label}: a closed, oriented mesh");
        let b = mesh.bounds().unwrap();
        let (c, r) = (b.centre(), b.size().length() * 0.5);
        let (mut same, mut skipped) = (0, 0usize);
        for k in 0..12 {
            let dir = DVec3::new((k as f64 * 1.3).sin(), (k as f64 * 0.7).cos(), (k as f64 * 2.1).sin()).normalize();
            let cam = Camera::look_at(c + dir * r * 3.0, c, DVec3::Y, 96, 80, 90.0 + 7.0 * k as f64);
            let pose = Pose {
                rotation: so3::exp(DVec3::new(0.1 * k as f64, -0.2, 0.05)),
                ..Pose::IDENTITY
            };
            let proj = project_mesh(mesh, &pose, &cam);
            let all = hard::render_projected(&proj, &mesh.triangles, &cam);
            let mut front = Mask::empty(0, 0);
            hard::render_projected_culled_into(&proj, &mesh.triangles, &cam, topo.front_signs(), &mut front);
            same += usize::from(all == front);
            // About half the faces face away from any camera.
            let back = mesh
                .triangles
                .iter()
                .zip(topo.front_signs())
                .filter(|(t, &s)| {
                    let [a, b, c] = t.map(|i| proj.uv[i as usize]);
                    ((b - a).perp_dot(c - a)).signum() as i8 != s
                })
                .count();
            skipped += back;
        }
        assert_eq!(same, 12, "{label}: culled coverage differs");
        assert!(
            skipped > 12 * mesh.triangles.len() / 4,
            "{label}: {skipped} back faces skipped"
        );
    }
    // Open or inconsistently wound meshes are never culled.
    let mut open = cube();
    open.triangles.pop();
    assert!(EdgeTopology::from_mesh(&open).front_signs().iter().all(|&s| s == 0));
}
