//! The hard rasteriser against naive per-pixel oracles (exact on the snapped
//! vertices, and in plain f64 on the unsnapped ones), the top-left rule on shared
//! edges, near-plane clipping against a ray-cast oracle, and PyTorch3D's reference
//! silhouettes (`../shared/reference/pytorch3d-case1`).

use crate::{data, reference};
use glam::{DMat3, DVec2, DVec3};
use localisebot::raster::hard::{self, BitMask, GUARD_BAND_PX, SUBPIXEL_BITS};
use localisebot::raster::project::{project_mesh, Projected};
use localisebot::{so3, Camera, Error, Mask, Mesh, Pose};
use rand::rngs::SmallRng;
use rand::{Rng, SeedableRng};
use std::path::Path;

pub fn load(path: &Path) -> Mesh {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    localisebot::io::load_mesh(&path.to_string_lossy(), &bytes, &|_| None).unwrap()
}

pub fn duck() -> Mesh {
    load(&data("gltf/Duck/glTF-Binary/Duck.glb"))
}

fn blob() -> Mesh {
    load(&reference("pytorch3d-case1/mesh.obj"))
}

/// An axis-aligned cube [-1, 1]³, 12 triangles, mixed windings.
pub fn cube() -> Mesh {
    let positions = (0..8)
        .map(|i| DVec3::new([-1., 1.][i & 1], [-1., 1.][(i >> 1) & 1], [-1., 1.][(i >> 2) & 1]))
        .collect();
    let faces = [
        [0, 1, 3, 2],
        [4, 6, 7, 5],
        [0, 4, 5, 1],
        [2, 3, 7, 6],
        [0, 2, 6, 4],
        [1, 5, 7, 3],
    ];
    let mut triangles = Vec::new();
    for (k, f) in faces.iter().enumerate() {
        triangles.push([f[0], f[1], f[2]]);
        // Odd faces get their second triangle wound the other way round.
        triangles.push(if k % 2 == 0 {
            [f[0], f[2], f[3]]
        } else {
            [f[0], f[3], f[2]]
        });
    }
    Mesh { positions, triangles }
}

/// A random pose putting the mesh's box centre near the world origin.
pub fn random_pose(rng: &mut SmallRng, mesh: &Mesh) -> Pose {
    let b = mesh.bounds().unwrap();
    let w = DVec3::new(
        rng.gen_range(-1.0..1.0),
        rng.gen_range(-1.0..1.0),
        rng.gen_range(-1.0..1.0),
    );
    let rotation = so3::exp(w.normalize() * rng.gen_range(0.0..std::f64::consts::PI));
    let scale = DVec3::new(
        rng.gen_range(0.7..1.4),
        rng.gen_range(0.7..1.4),
        rng.gen_range(0.7..1.4),
    );
    let jitter = DVec3::new(
        rng.gen_range(-0.1..0.1),
        rng.gen_range(-0.1..0.1),
        rng.gen_range(-0.1..0.1),
    );
    let translation = -(rotation * (scale * b.centre())) + jitter * b.size().length();
    Pose {
        rotation,
        translation,
        scale,
    }
}

/// A camera on a random direction looking at the origin, the object filling about half the image.
pub fn random_camera(rng: &mut SmallRng, mesh: &Mesh, w: u32, h: u32) -> Camera {
    let d = mesh.bounds().unwrap().size().length() * 1.4;
    let dir = DVec3::new(
        rng.gen_range(-1.0..1.0),
        rng.gen_range(-1.0..1.0),
        rng.gen_range(-1.0..1.0),
    )
    .normalize();
    let f = 0.5 * w.min(h) as f64 * 6.0;
    Camera::look_at(dir * 2.5 * d, DVec3::ZERO, DVec3::Y, w, h, f)
}

fn top_left(dx: i128, dy: i128) -> bool {
    dy < 0 || (dy == 0 && dx > 0)
}

/// Naive exact test: pixel centre `p` against triangle `v`, both in 1/2^SUBPIXEL_BITS
/// units, i128 edge functions evaluated directly, top-left rule on ties.
fn inside_exact(mut v: [[i128; 2]; 3], p: [i128; 2]) -> bool {
    let cross =
        |a: [i128; 2], b: [i128; 2], c: [i128; 2]| (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
    let area = cross(v[0], v[1], v[2]);
    if area == 0 {
        return false;
    }
    if area < 0 {
        v.swap(1, 2);
    }
    (0..3).all(|i| {
        let (a, b) = (v[i], v[(i + 1) % 3]);
        let e = cross(a, b, p);
        e > 0 || (e == 0 && top_left(b[0] - a[0], b[1] - a[1]))
    })
}

/// The same in f64 on unsnapped coordinates.
fn inside_f64(mut v: [DVec2; 3], p: DVec2) -> bool {
    let cross = |a: DVec2, b: DVec2, c: DVec2| (b - a).perp_dot(c - a);
    let area = cross(v[0], v[1], v[2]);
    if area == 0.0 {
        return false;
    }
    if area < 0.0 {
        v.swap(1, 2);
    }
    (0..3).all(|i| {
        let (a, b) = (v[i], v[(i + 1) % 3]);
        let e = cross(a, b, p);
        e > 0.0 || (e == 0.0 && (b.y < a.y || (b.y == a.y && b.x > a.x)))
    })
}

fn fixed(v: f64) -> i128 {
    (v * (1u64 << SUBPIXEL_BITS) as f64).round_ties_even() as i128
}

/// Every pixel centre against every triangle (all vertices must be in front and
/// inside the guard band), exactly on the snapped vertices.
fn oracle_snapped(proj: &Projected, tris: &[[u32; 3]], w: u32, h: u32) -> Mask {
    let snapped: Vec<[[i128; 2]; 3]> = tris
        .iter()
        .map(|t| {
            t.map(|i| {
                let i = i as usize;
                assert!(proj.in_front(i) && proj.uv[i].abs().max_element() < GUARD_BAND_PX);
                [fixed(proj.uv[i].x), fixed(proj.uv[i].y)]
            })
        })
        .collect();
    let one = 1i128 << SUBPIXEL_BITS;
    let mut m = Mask::empty(w, h);
    for y in 0..h as i128 {
        for x in 0..w as i128 {
            let p = [x * one, y * one];
            // A pixel outside a triangle's vertex bounds cannot be inside it.
            let hit = snapped.iter().any(|v| {
                v.iter().any(|q| q[0] <= p[0])
                    && v.iter().any(|q| q[0] >= p[0])
                    && v.iter().any(|q| q[1] <= p[1])
                    && v.iter().any(|q| q[1] >= p[1])
                    && inside_exact(*v, p)
            });
            m.data[(y * w as i128 + x) as usize] = hit as u8;
        }
    }
    m
}

/// Every pixel centre against every triangle in f64, no snapping.
fn oracle_f64(proj: &Projected, tris: &[[u32; 3]], w: u32, h: u32) -> Mask {
    let mut m = Mask::empty(w, h);
    for y in 0..h {
        for x in 0..w {
            let p = DVec2::new(x as f64, y as f64);
            let hit = tris.iter().any(|t| inside_f64(t.map(|i| proj.uv[i as usize]), p));
            m.data[(y * w + x) as usize] = hit as u8;
        }
    }
    m
}

fn seg_dist(p: DVec2, a: DVec2, b: DVec2) -> f64 {
    let ab = b - a;
    let t = ((p - a).dot(ab) / ab.length_squared().max(1e-300)).clamp(0.0, 1.0);
    p.distance(a + ab * t)
}

/// Distance from `p` to the nearest edge of any projected triangle.
fn nearest_edge(proj: &Projected, tris: &[[u32; 3]], p: DVec2) -> f64 {
    tris.iter()
        .flat_map(|t| (0..3).map(move |k| (t[k], t[(k + 1) % 3])))
        .map(|(a, b)| seg_dist(p, proj.uv[a as usize], proj.uv[b as usize]))
        .fold(f64::INFINITY, f64::min)
}

fn differing(a: &Mask, b: &Mask) -> Vec<DVec2> {
    assert_eq!((a.width, a.height), (b.width, b.height));
    (0..a.data.len())
        .filter(|&i| a.data[i] != b.data[i])
        .map(|i| DVec2::new((i % a.width as usize) as f64, (i / a.width as usize) as f64))
        .collect()
}

/// Snapping moves a vertex by at most 2^-(SUBPIXEL_BITS+1)·√2 px, and an edge no more.
fn snap_tolerance() -> f64 {
    0.5f64.powi(SUBPIXEL_BITS as i32) * 0.75
}

fn check_against_oracles(name: &str, mesh: &Mesh, seed: u64, poses: usize, w: u32, h: u32) {
    let mut rng = SmallRng::seed_from_u64(seed);
    let mut total_f64_diffs = 0;
    for k in 0..poses {
        let pose = random_pose(&mut rng, mesh);
        let cam = random_camera(&mut rng, mesh, w, h);
        let proj = project_mesh(mesh, &pose, &cam);
        let got = hard::render_projected(&proj, &mesh.triangles, &cam);
        assert!(
            got.area() > (w * h / 40) as usize,
            "{name} pose {k}: object too small to test ({} px)",
            got.area()
        );
        assert!(
            got.area() < (w * h) as usize * 9 / 10,
            "{name} pose {k}: object fills the image"
        );
        let exact = oracle_snapped(&proj, &mesh.triangles, w, h);
        assert_eq!(
            differing(&got, &exact),
            vec![],
            "{name} pose {k}: differs from the exact oracle"
        );
        assert_eq!(hard::render(mesh, &pose, &cam), got);
        let plain = oracle_f64(&proj, &mesh.triangles, w, h);
        for p in differing(&got, &plain) {
            let d = nearest_edge(&proj, &mesh.triangles, p);
            assert!(
                d <= snap_tolerance(),
                "{name} pose {k}: pixel {p} differs from the f64 oracle {d} px from an edge"
            );
            total_f64_diffs += 1;
        }
    }
    println!("{name}: {poses} poses at {w}×{h}: identical to the snapped oracle; {total_f64_diffs} pixels differ from the unsnapped f64 oracle, all within {:.1e} px of an edge", snap_tolerance());
    assert!(
        total_f64_diffs <= poses * 3,
        "{name}: {total_f64_diffs} near-tie differences"
    );
}

#[test]
fn cube_matches_naive_oracles() {
    check_against_oracles("cube", &cube(), 1, 8, 97, 83);
}

#[test]
fn blob_matches_naive_oracles() {
    check_against_oracles("blob", &blob(), 2, 4, 128, 96);
}

#[test]
fn duck_matches_naive_oracles() {
    check_against_oracles("duck", &duck(), 3, 3, 160, 120);
}

#[test]
fn bits_equal_bytes_at_many_sizes() {
    let mesh = duck();
    let mut rng = SmallRng::seed_from_u64(4);
    let mut bits = BitMask::empty(1, 1);
    for (w, h) in [(64, 64), (70, 50), (128, 1), (1, 33), (200, 150)] {
        for _ in 0..10 {
            let pose = random_pose(&mut rng, &mesh);
            let cam = random_camera(&mut rng, &mesh, w, h);
            let proj = project_mesh(&mesh, &pose, &cam);
            let bytes = hard::render_projected(&proj, &mesh.triangles, &cam);
            hard::render_bits_into(&proj, &mesh.triangles, &cam, &mut bits);
            assert_eq!(bits, BitMask::from_mask(&bytes), "{w}×{h}");
            assert_eq!(bits.to_mask(), bytes);
            assert_eq!(bits.count(), bytes.area() as u64);
        }
    }
}

/// A flat scene: pixel coordinates `uv` as camera points (u, v, 1) seen by a unit camera.
fn flat(uv: &[DVec2], w: u32, h: u32) -> (Projected, Camera) {
    let cam = Camera {
        width: w,
        height: h,
        fx: 1.0,
        fy: 1.0,
        cx: 0.0,
        cy: 0.0,
        rotation: DMat3::IDENTITY,
        translation: DVec3::ZERO,
    };
    let proj = Projected {
        cam: uv.iter().map(|p| p.extend(1.0)).collect(),
        uv: uv.to_vec(),
        near: 1e-6,
    };
    (proj, cam)
}

fn render_flat(uv: &[DVec2], tris: &[[u32; 3]], w: u32, h: u32) -> Mask {
    let (proj, cam) = flat(uv, w, h);
    hard::render_projected(&proj, tris, &cam)
}

#[test]
fn split_triangles_neither_overlap_nor_leave_gaps() {
    // Vertices on a half-pixel lattice put many pixel centres exactly on edges.
    let mut rng = SmallRng::seed_from_u64(5);
    let (w, h) = (24, 20);
    let mut ties = 0;
    for _ in 0..3000 {
        let mut pt = || DVec2::new(rng.gen_range(-4..52) as f64 * 0.5, rng.gen_range(-4..44) as f64 * 0.5);
        let (a, b, c) = (pt(), pt(), pt());
        let m = (a + b) * 0.5;
        let pts = [a, b, c, m];
        let whole = render_flat(&pts, &[[0, 1, 2]], w, h);
        let t1 = render_flat(&pts, &[[0, 3, 2]], w, h);
        let t2 = render_flat(&pts, &[[3, 1, 2]], w, h);
        for i in 0..whole.data.len() {
            assert!(t1.data[i] + t2.data[i] <= 1, "pixel {i} covered twice: {a} {b} {c}");
            assert_eq!(whole.data[i], t1.data[i] | t2.data[i], "pixel {i}: {a} {b} {c}");
            let p = DVec2::new((i % w as usize) as f64, (i / w as usize) as f64);
            if whole.data[i] == 1 && (m - c).perp_dot(p - c) == 0.0 {
                ties += 1;
            }
        }
    }
    assert!(
        ties > 500,
        "only {ties} centres fell on a shared edge: the test would prove little"
    );
}

#[test]
fn quad_on_pixel_centres_covers_the_exact_count() {
    // Corners on pixel centres: top and left edges are in, bottom and right out.
    let pts = [(2.0, 3.0), (12.0, 3.0), (12.0, 8.0), (2.0, 8.0)].map(|(x, y)| DVec2::new(x, y));
    let want: Vec<usize> = (3..8).flat_map(|y| (2..12).map(move |x| y * 20 + x)).collect();
    for tris in [
        [[0, 1, 2], [0, 2, 3]],
        [[0, 1, 3], [1, 2, 3]],
        [[2, 1, 0], [3, 2, 0]],
        [[0, 3, 1], [1, 3, 2]],
    ] {
        let m = render_flat(&pts, &tris, 20, 12);
        let got: Vec<usize> = (0..m.data.len()).filter(|&i| m.data[i] == 1).collect();
        assert_eq!(got, want, "{tris:?}");
    }
    // Corners on half pixels: every centre is strictly inside or out (4 × 4 = 16).
    let pts = [(1.5, 2.5), (5.5, 2.5), (5.5, 6.5), (1.5, 6.5)].map(|(x, y)| DVec2::new(x, y));
    let m = render_flat(&pts, &[[0, 1, 2], [0, 2, 3]], 10, 10);
    assert_eq!(m.area(), 16);
    assert_eq!(m.bbox(), Some((2, 3, 5, 6)));
}

#[test]
fn triangle_across_the_near_plane_renders_as_its_clipped_part() {
    // Camera points: A, B in front, C behind the near plane z = 0.5. The edges A–C
    // and B–C meet z = 0.5 at (∓0.5, 0.25, 0.5), projecting to (12, 42) and (52, 42).
    let cam = Camera {
        width: 64,
        height: 64,
        fx: 20.0,
        fy: 20.0,
        cx: 32.0,
        cy: 32.0,
        rotation: DMat3::IDENTITY,
        translation: DVec3::ZERO,
    };
    let pts = [
        DVec3::new(-1., -1., 2.),
        DVec3::new(1., -1., 2.),
        DVec3::new(0., 1.5, -1.),
    ];
    let proj = Projected {
        cam: pts.to_vec(),
        uv: pts
            .iter()
            .map(|&p| if p.z >= 0.5 { cam.project(p) } else { DVec2::NAN })
            .collect(),
        near: 0.5,
    };
    let got = hard::render_projected(&proj, &[[0, 1, 2]], &cam);
    let quad = [(22., 22.), (42., 22.), (52., 42.), (12., 42.)].map(|(x, y)| DVec2::new(x, y));
    let want = render_flat(&quad, &[[0, 1, 2], [0, 2, 3]], 64, 64);
    assert!(want.area() > 500);
    assert_eq!(got, want);
    assert_eq!(hard::render_bits(&proj, &[[0, 1, 2]], &cam).to_mask(), want);
}

/// Pixel centre → does the forward ray hit the triangle (world = camera frame)?
/// `None` when within `eps` of an edge (too close to call).
fn ray_hits(cam: &Camera, tri: [DVec3; 3], x: f64, y: f64, eps: f64) -> Option<bool> {
    let d = DVec3::new((x - cam.cx) / cam.fx, (y - cam.cy) / cam.fy, 1.0);
    let (e1, e2) = (tri[1] - tri[0], tri[2] - tri[0]);
    let pv = d.cross(e2);
    let det = e1.dot(pv);
    let s = -tri[0];
    let u = s.dot(pv) / det;
    let q = s.cross(e1);
    let v = d.dot(q) / det;
    let t = e2.dot(q) / det;
    let bary = [1.0 - u - v, u, v];
    if t <= 0.0 {
        return Some(false);
    }
    if bary.iter().any(|b| b.abs() < eps) {
        return None;
    }
    Some(bary.iter().all(|&b| b > 0.0))
}

#[test]
fn floor_reaching_behind_the_camera_matches_ray_casting() {
    // A floor triangle at height h below the camera with a corner 5 units behind
    // it. With f = 600 its near-plane cut projects beyond the guard band.
    for (f, cx, cy, h, beyond_guard) in [(40.0, 39.5, 20.25, 1.0, false), (600.0, 230.0, 5.25, 0.2, true)] {
        let tri = [DVec3::new(-1., h, 4.), DVec3::new(1., h, 4.), DVec3::new(0.2, h, -5.)];
        let mesh = Mesh {
            positions: tri.to_vec(),
            triangles: vec![[0, 1, 2]],
        };
        let cam = Camera {
            width: 80,
            height: 60,
            fx: f,
            fy: f,
            cx,
            cy,
            rotation: DMat3::IDENTITY,
            translation: DVec3::ZERO,
        };
        let proj = project_mesh(&mesh, &Pose::IDENTITY, &cam);
        assert_eq!((0..3).filter(|&k| !proj.in_front(k)).count(), 1);
        // Where the edge 1–2 meets the near plane, in pixels.
        let t = (4.0 - proj.near) / 9.0;
        let cut = cam.project(DVec3::new(1.0 - 0.8 * t, h, proj.near));
        assert_eq!(cut.x > GUARD_BAND_PX, beyond_guard, "cut at {cut}");
        let got = hard::render(&mesh, &Pose::IDENTITY, &cam);
        let (mut unsure, mut inside) = (0, 0);
        for y in 0..cam.height {
            for x in 0..cam.width {
                match ray_hits(&cam, tri, x as f64, y as f64, 1e-9) {
                    None => unsure += 1,
                    Some(hit) => {
                        assert_eq!(got.get(x, y), hit, "f = {f}: pixel ({x}, {y})");
                        inside += hit as usize;
                    }
                }
            }
        }
        println!("floor, f = {f}: {inside} pixels inside, {unsure} too close to call");
        assert!(
            unsure <= 2 && inside > 300 && inside < 4000,
            "f = {f}: {unsure} undecided, {inside} inside"
        );
        // Both slanted edges cross the image: some rows are partly covered.
        let partial = (0..60)
            .filter(|&y| (1..80).any(|x| got.get(x, y) != got.get(x - 1, y)))
            .count();
        assert!(partial > 10, "f = {f}: only {partial} rows have an edge");
    }
}

#[test]
fn object_behind_the_camera_is_a_view_error() {
    let mesh = cube();
    let cam = Camera::look_at(DVec3::new(0., 0., -10.), DVec3::ZERO, DVec3::Y, 64, 48, 60.0);
    let behind = Pose {
        translation: DVec3::new(0., 0., -20.),
        ..Pose::IDENTITY
    };
    match hard::render_checked("left", &mesh, &behind, &cam) {
        Err(Error::View { view, problem }) => {
            assert_eq!(view, "left");
            assert!(problem.contains("behind"), "{problem}");
        }
        other => panic!("expected a view error, got {other:?}"),
    }
    assert_eq!(hard::render(&mesh, &behind, &cam).area(), 0);
    // Straddling the camera is not an error, and the part in front is drawn.
    let straddle = Pose {
        translation: DVec3::new(0., 0., -10.),
        ..Pose::IDENTITY
    };
    let m = hard::render_checked("left", &mesh, &straddle, &cam).unwrap();
    assert_eq!(
        m.area(),
        64 * 48,
        "the camera is inside the cube: every ray hits a face"
    );
    let m = hard::render_checked("left", &mesh, &Pose::IDENTITY, &cam).unwrap();
    // Front face z = −1 at depth 9: ±1 → ±60/9 px about (31.5, 23.5): x 25..=38, y 17..=30.
    assert_eq!(m.bbox(), Some((25, 17, 38, 30)));
    assert_eq!(m.area(), 14 * 14);
}

#[test]
fn pytorch3d_reference_silhouettes() {
    for size in [128, 256] {
        let dir = reference(&format!("pytorch3d-case1/scene{size}"));
        let file = dir.join("scene.json");
        let text = std::fs::read_to_string(&file).unwrap();
        let scene = localisebot::load_scene(&file.to_string_lossy(), &text, &|p| std::fs::read(p).ok()).unwrap();
        let gt = scene.ground_truth_pose.unwrap();
        for view in &scene.views {
            let proj = project_mesh(&scene.mesh, &gt, view.camera());
            let got = hard::render_projected(&proj, &scene.mesh.triangles, view.camera());
            let diffs = differing(&got, view.mask());
            let worst = diffs
                .iter()
                .map(|&p| nearest_edge(&proj, &scene.mesh.triangles, p))
                .fold(0.0, f64::max);
            println!(
                "pytorch3d {size} {}: area {} (reference {}), {} pixels differ, farthest {worst:.2e} px from an edge",
                view.name(),
                got.area(),
                view.mask().area(),
                diffs.len()
            );
            assert!(
                diffs.len() <= 2,
                "{size} {}: {} pixels differ",
                view.name(),
                diffs.len()
            );
            assert!(
                worst <= 2e-3,
                "{size} {}: a differing pixel is {worst} px from an edge",
                view.name()
            );
        }
    }
}

#[test]
fn huge_triangles_beyond_the_guard_band_keep_their_edges() {
    // Edges leave the guard band far past its corners: clipping must keep their lines.
    let g = GUARD_BAND_PX;
    let cases: [[(f64, f64); 3]; 4] = [
        [(40.3, -10.2), (4e5, 4e6), (-4e5, 4e6)],
        [(-3e6, 3.1e6), (20.6, 15.2), (2.5e6, -2.9e6)],
        [(-899960.0, -269970.0), (700040.0, 210030.0), (31.7, 9e6)],
        [(100040.0, -199970.0), (-299960.0, 600030.0), (g * 19.0, g * 19.0)],
    ];
    for (k, c) in cases.iter().enumerate() {
        let pts = c.map(|(x, y)| DVec2::new(x, y));
        let (proj, cam) = flat(&pts, 80, 60);
        let got = hard::render_projected(&proj, &[[0, 1, 2]], &cam);
        let want = oracle_f64(&proj, &[[0, 1, 2]], 80, 60);
        assert!(
            want.area() > 100 && want.area() < 4700,
            "case {k}: area {}",
            want.area()
        );
        let d = differing(&got, &want);
        assert!(
            d.is_empty(),
            "case {k}: {} pixels differ, first {:?}",
            d.len(),
            &d[..d.len().min(5)]
        );
    }
}
