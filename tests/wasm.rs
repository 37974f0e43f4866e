//! The WebAssembly suite in headless Chromium (`tests/wasm_common`): run with
//! `wasm-pack test --headless --chrome`, or `cargo test --target wasm32-unknown-unknown
//! --test wasm` with `CARGO_TARGET_WASM32_UNKNOWN_UNKNOWN_RUNNER=wasm-bindgen-test-runner`.
//! Here only: the silhouette-edge rasteriser as the browser runs it (wasm32 with
//! simd128, `.cargo/config.toml`) against the native suite's naive oracle
//! (`tests/oracles/edge.rs`) and central differences, through `raster::silhouette` —
//! whose per-pixel Jacobians and pose gradients use `wide`'s f64x2 lanes.
#![cfg(target_arch = "wasm32")]

wasm_bindgen_test::wasm_bindgen_test_configure!(run_in_browser);

mod wasm_common;

#[path = "oracles/edge.rs"]
mod oracle;

use glam::DVec3;
use localisebot::app::shapes::{cube_mesh, toy_plane};
use localisebot::app::synth::blob_mesh;
use localisebot::raster::edge::EdgeSilhouette;
use localisebot::raster::project::{project_mesh, POSE_DIM};
use localisebot::raster::silhouette::SoftSettings;
use localisebot::raster::silhouette::{RasterKind, RenderMesh, SilhouetteRenderer};
use localisebot::{so3, Camera, Mesh, Pose};
use oracle::{check, fd_2d, look, margin, noise, oracle, some_pose, structure};
use wasm_bindgen_test::wasm_bindgen_test;

// The SIMD path is the one under test: a build without simd128 does not compile.
const _: () = assert!(
    cfg!(target_feature = "simd128"),
    "wasm32 builds enable simd128 (.cargo/config.toml)"
);

/// The render of `raster::silhouette` (RasterKind::Edge): the edge kernel's own.
fn silhouette_alpha(mesh: &Mesh, pose: &Pose, cam: &Camera, s: &SoftSettings) -> Vec<f64> {
    let m = RenderMesh::exact(mesh.clone());
    let mut r = SilhouetteRenderer::new(RasterKind::Edge);
    r.render(&m, pose, cam, s).unwrap().to_vec()
}

#[wasm_bindgen_test]
fn edge_silhouettes_match_the_oracle_in_the_browser() {
    let s = |sigma| SoftSettings { sigma, eps: 1e-4 };
    let blob = blob_mesh(22, 50);
    let toy = toy_plane();
    let cube = cube_mesh(1.0);
    let cases: [(&str, &Mesh, DVec3, f64, Pose, u32, f64); 5] = [
        ("blob", &blob, DVec3::new(0.3, -0.4, 2.5), 3.0, some_pose(), 128, 0.4096),
        (
            "blob, σ 2",
            &blob,
            DVec3::new(-1.0, 0.7, 0.2),
            3.0,
            some_pose(),
            128,
            2.0,
        ),
        ("toy", &toy, DVec3::new(0.8, 0.6, 1.0), 2.5, Pose::IDENTITY, 128, 0.5),
        (
            "toy, another side",
            &toy,
            DVec3::new(-0.2, -1.0, 0.4),
            2.5,
            some_pose(),
            96,
            1.0,
        ),
        ("cube", &cube, DVec3::new(0.6, 0.8, 1.7), 3.0, some_pose(), 64, 1.0),
    ];
    for (label, mesh, dir, dist, pose, size, sigma) in cases {
        let cam = look(mesh, dir, dist, size, size, size as f64 * 1.2);
        let proj = project_mesh(mesh, &pose, &cam);
        let (sil, o) = check(label, mesh, &proj, &cam, &s(sigma));
        assert!(o.records.len() > 50, "{label}: {} soft pixels", o.records.len());
        // Through raster::silhouette, the loss's entry point: the same values.
        assert_eq!(silhouette_alpha(mesh, &pose, &cam, &s(sigma)), sil.alpha(), "{label}");
    }
}

#[wasm_bindgen_test]
fn edge_vertex_gradients_match_central_differences_in_the_browser() {
    let blob = blob_mesh(14, 30);
    let cam = look(&blob, DVec3::new(0.3, -0.4, 2.5), 3.0, 64, 64, 75.0);
    fd_2d("blob", &blob, &project_mesh(&blob, &some_pose(), &cam), &cam, 1.0);
    let toy = toy_plane();
    let cam = look(&toy, DVec3::new(0.8, 0.6, 1.0), 2.5, 96, 96, 110.0);
    fd_2d("toy", &toy, &project_mesh(&toy, &Pose::IDENTITY, &cam), &cam, 0.6);
}

/// The pose moved by θ = [ω, t, ls] (right rotation perturbation, log-scale).
fn perturb(p: &Pose, th: &[f64; POSE_DIM]) -> Pose {
    Pose {
        rotation: p.rotation * so3::exp(DVec3::new(th[0], th[1], th[2])),
        translation: p.translation + DVec3::new(th[3], th[4], th[5]),
        scale: p.scale * DVec3::new(th[6].exp(), th[7].exp(), th[8].exp()),
    }
}

/// `raster::silhouette`'s 9-gradient of `Σ w·A` (the weight-field sweep) and the sum of
/// its per-pixel Jacobians `Σ w·∂A/∂θ` (Gauss–Newton's) against central differences
/// in every pose parameter, at a pose where no pixel centre is within 1e-3 px of the
/// outline (steps move the silhouette by about 1e-6 px: the coverage cannot change).
#[wasm_bindgen_test]
fn edge_pose_gradients_and_jacobians_match_central_differences_in_the_browser() {
    for (label, mesh, dir) in [
        ("toy", toy_plane(), DVec3::new(-1.0, 0.6, 0.8)),
        ("blob", blob_mesh(14, 30), DVec3::new(0.3, -0.4, 2.5)),
    ] {
        let m = RenderMesh::exact(mesh.clone());
        let cam = look(&mesh, dir, 3.0, 96, 96, 110.0);
        let s = SoftSettings { sigma: 0.6, eps: 1e-15 };
        let w = noise(96 * 96, 11);
        let radius = mesh.diameter() * 0.5;
        let px = radius * 3.0 / cam.fx; // a world length of about one pixel
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
        assert!(
            found,
            "{label}: no configuration without a pixel centre near the outline"
        );
        let mut r = SilhouetteRenderer::new(RasterKind::Edge);
        let [grad] = r.render_with_gradients(&m, &pose, &cam, &s, |p| [w[p]]).unwrap();
        let mut jac_sum = [0.0; POSE_DIM];
        r.render_with_jacobians(&m, &pose, &cam, &s, |p, _, j| {
            for (a, b) in jac_sum.iter_mut().zip(j) {
                *a += w[p] * b;
            }
        })
        .unwrap();
        let base = r.render(&m, &pose, &cam, &s).unwrap().to_vec();
        let base_structure = {
            let mut e = EdgeSilhouette::new();
            e.render(
                m.topology(),
                &project_mesh(&mesh, &pose, &cam),
                &mesh.triangles,
                &cam,
                &s,
            )
            .unwrap();
            structure(&e)
        };
        let scale = grad.iter().fold(0.0f64, |a, g| a.max(g.abs()));
        assert!(scale > 0.0, "{label}: no gradient");
        for k in 0..POSE_DIM {
            // ~1e-6 px of motion: rotations and log-scales move points by ~radius·h.
            let h = if (3..6).contains(&k) {
                1e-6 * px
            } else {
                1e-6 * px / radius
            };
            let mut f = [0.0; 2];
            for (j, sign) in [1.0, -1.0].into_iter().enumerate() {
                let mut th = [0.0; POSE_DIM];
                th[k] = sign * h;
                let p = perturb(&pose, &th);
                let mut e = EdgeSilhouette::new();
                e.render(m.topology(), &project_mesh(&mesh, &p, &cam), &mesh.triangles, &cam, &s)
                    .unwrap();
                assert!(structure(&e) == base_structure, "{label}: θ{k} changes the structure");
                let a = r.render(&m, &p, &cam, &s).unwrap();
                f[j] = a.iter().zip(&base).zip(&w).map(|((a, b), w)| (a - b) * w).sum();
            }
            let numeric = (f[0] - f[1]) / (2.0 * h);
            // Per-parameter scale: the rotations' and log-scales' gradients are larger.
            let tol = 1e-5 * (grad[k].abs() + numeric.abs()).max(1e-3 * scale);
            assert!(
                (numeric - grad[k]).abs() <= tol,
                "{label} θ{k}: gradient {} vs central difference {numeric}",
                grad[k]
            );
            assert!(
                (jac_sum[k] - grad[k]).abs() <= 1e-9 * (grad[k].abs() + scale),
                "{label} θ{k}: Σ w·J {} vs gradient {}",
                jac_sum[k],
                grad[k]
            );
        }
    }
}
