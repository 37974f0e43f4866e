//! The silhouette-edge rasteriser's naive oracle and the checks against it, shared by
//! the native tests (`tests/integration/edge_raster.rs`) and the browser's
//! (`tests/wasm.rs`, the same kernel compiled to wasm32 with simd128): the definition
//! of `raster::edge`'s module doc computed literally (hash-map weld and adjacency,
//! every pixel against every candidate edge), the comparison of a render with it, and
//! the gradient check against central differences.
#![allow(dead_code)] // each suite uses its part

use glam::{DVec2, DVec3};
use localisebot::raster::edge::{EdgeRecord, EdgeSilhouette, EdgeTopology, WELD_TOLERANCE};
use localisebot::raster::hard;
use localisebot::raster::project::Projected;
use localisebot::raster::silhouette::SoftSettings;
use localisebot::{so3, Camera, Mask, Mesh, Pose};
use std::collections::HashMap;

// ---------------------------------------------------------------- the naive oracle

/// A candidate outline edge as the oracle sees it.
pub struct Candidate {
    pub a: u32,
    pub b: u32,
    pub pa: DVec2,
    pub pb: DVec2,
    pub out: DVec2,
}

/// What the oracle computes.
pub struct Oracle {
    pub alpha: Vec<f64>,
    pub records: Vec<EdgeRecord>,
    pub coverage: Mask,
    pub candidates: Vec<Candidate>,
}

pub fn sigmoid(x: f64) -> f64 {
    1.0 / (1.0 + (-x).exp())
}

/// The definition of the module doc, literally: weld with a hash map over grid keys,
/// adjacency with a hash map over welded pairs, then every pixel against every
/// candidate.
pub fn oracle(positions: &[DVec3], tris: &[[u32; 3]], proj: &Projected, cam: &Camera, s: &SoftSettings) -> Oracle {
    // Weld: grid step WELD_TOLERANCE × box diagonal, from the box's minimum corner;
    // each vertex represented by the smallest index with its key.
    let lo = positions.iter().fold(DVec3::INFINITY, |m, p| m.min(*p));
    let hi = positions.iter().fold(DVec3::NEG_INFINITY, |m, p| m.max(*p));
    let step = (hi - lo).length() * WELD_TOLERANCE;
    let key = |p: DVec3| {
        let g = ((p - lo) / step).round();
        (g.x as i64, g.y as i64, g.z as i64)
    };
    let mut first: HashMap<(i64, i64, i64), u32> = HashMap::new();
    for (i, p) in positions.iter().enumerate() {
        first.entry(key(*p)).or_insert(i as u32);
    }
    let rep: Vec<u32> = positions.iter().map(|p| first[&key(*p)]).collect();
    // Adjacency: welded pair → (face, third vertex).
    let mut adj: HashMap<(u32, u32), Vec<(usize, u32)>> = HashMap::new();
    for (f, t) in tris.iter().enumerate() {
        for k in 0..3 {
            let (u, v) = (rep[t[k] as usize], rep[t[(k + 1) % 3] as usize]);
            if u != v {
                adj.entry((u.min(v), u.max(v))).or_default().push((f, t[(k + 2) % 3]));
            }
        }
    }
    let uv = &proj.uv;
    // Present: the welded vertices in front and within the guard band, and the doubled
    // area of the face snapped to 1/1024 px non-zero; sides from the snapped positions.
    let snapped = |i: u32| -> Option<[i64; 2]> {
        let p = uv[i as usize];
        (proj.cam[i as usize].z >= proj.near && p.x.abs() <= hard::GUARD_BAND_PX && p.y.abs() <= hard::GUARD_BAND_PX)
            .then(|| [p.x, p.y].map(|v| (v * f64::from(1u32 << hard::SUBPIXEL_BITS)).round_ties_even() as i64))
    };
    let cross = |a: [i64; 2], b: [i64; 2], c: [i64; 2]| {
        ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])).signum()
    };
    let present = |f: usize| {
        let w = tris[f].map(|i| snapped(rep[i as usize]));
        matches!(w, [Some(a), Some(b), Some(c)] if cross(a, b, c) != 0)
    };
    let mut keys: Vec<(u32, u32)> = adj.keys().copied().collect();
    keys.sort();
    let mut candidates = Vec::new();
    for (a, b) in keys {
        let (pa, pb) = (uv[a as usize], uv[b as usize]);
        let sides: Vec<f64> = adj[&(a, b)]
            .iter()
            .filter(|(f, _)| present(*f))
            .map(|(_, c)| {
                let [sa, sb, sc] = [a, b, rep[*c as usize]].map(|i| snapped(i).unwrap());
                cross(sa, sb, sc) as f64
            })
            .collect();
        if sides.is_empty() || sides.iter().any(|&x| x != sides[0]) {
            continue;
        }
        let d = pb - pa;
        let left = DVec2::new(-d.y, d.x) / d.length();
        candidates.push(Candidate {
            a,
            b,
            pa,
            pb,
            out: -sides[0] * left,
        });
    }
    // The hard raster of the welded triangles.
    let welded: Vec<[u32; 3]> = tris.iter().map(|t| t.map(|i| rep[i as usize])).collect();
    let coverage = hard::render_projected(proj, &welded, cam);
    let (w, h) = (cam.width as i64, cam.height as i64);
    let c_at = |x: i64, y: i64| x >= 0 && y >= 0 && x < w && y < h && coverage.data[(y * w + x) as usize] != 0;
    let m2 = s.cutoff_sq();
    let mut alpha = Vec::new();
    let mut records = Vec::new();
    for y in 0..h {
        for x in 0..w {
            let p = DVec2::new(x as f64, y as f64);
            let inside = c_at(x, y);
            let mut best: Option<(f64, f64, DVec2, &Candidate)> = None;
            for e in &candidates {
                let d = e.pb - e.pa;
                let t = ((p - e.pa).dot(d) / d.length_squared()).clamp(0.0, 1.0);
                let q = if t == 0.0 {
                    e.pa
                } else if t == 1.0 {
                    e.pb
                } else {
                    e.pa + d * t
                };
                let d2 = (p - q).length_squared();
                let r = q + e.out;
                let accepted = !c_at((r.x + 0.5).floor() as i64, (r.y + 0.5).floor() as i64);
                if d2 < m2 && accepted && best.as_ref().is_none_or(|b| d2 < b.0) {
                    best = Some((d2, t, q, e));
                }
            }
            let Some((d2, t, q, e)) = best else {
                alpha.push(f64::from(u8::from(inside)));
                continue;
            };
            let delta = if inside { 1.0 } else { -1.0 };
            let a = sigmoid(delta * d2 / s.sigma);
            alpha.push(a);
            let da = delta * a * (1.0 - a) / s.sigma;
            records.push(EdgeRecord {
                px: (y * w + x) as u32,
                a: e.a,
                b: e.b,
                ga: (p - q) * (-2.0 * (1.0 - t) * da),
                gb: (p - q) * (-2.0 * t * da),
            });
        }
    }
    Oracle {
        alpha,
        records,
        coverage,
        candidates,
    }
}

// ---------------------------------------------------------------- helpers

pub fn render(mesh: &Mesh, proj: &Projected, cam: &Camera, s: &SoftSettings) -> EdgeSilhouette {
    let topo = EdgeTopology::from_mesh(mesh);
    let mut sil = EdgeSilhouette::new();
    sil.render(&topo, proj, &mesh.triangles, cam, s).unwrap();
    sil
}

/// Records match when they name the same pixels, in increasing order, and give each
/// pixel the same vertex gradients to 1e-12. The edge named may differ where two edges
/// are equally near (a pixel nearest to the vertex they share, where both give all of
/// the gradient to that vertex): rounding decides the tie differently in the two.
pub fn assert_records_match(label: &str, got: &[EdgeRecord], want: &[EdgeRecord]) {
    assert!(
        got.windows(2).all(|r| r[0].px < r[1].px),
        "{label}: records out of order"
    );
    assert_eq!(got.len(), want.len(), "{label}: record count");
    let mut relabelled = 0;
    for (g, w) in got.iter().zip(want) {
        assert_eq!(g.px, w.px, "{label}: record {g:?} vs {w:?}");
        let tol = 1e-12 * (1.0 + w.ga.length() + w.gb.length());
        if (g.a, g.b) == (w.a, w.b) {
            assert!(
                (g.ga - w.ga).length() <= tol && (g.gb - w.gb).length() <= tol,
                "{label}: gradient {g:?} vs {w:?}"
            );
            continue;
        }
        relabelled += 1;
        // Per-vertex gradients, dropping vanishing ones.
        let per_vertex = |r: &EdgeRecord| {
            let mut v: Vec<(u32, DVec2)> = vec![(r.a, r.ga), (r.b, r.gb)];
            v.retain(|(_, g)| g.length() > tol);
            v.sort_by_key(|(i, _)| *i);
            v
        };
        let (pg, pw) = (per_vertex(g), per_vertex(w));
        assert_eq!(pg.len(), pw.len(), "{label}: {g:?} vs {w:?}");
        for ((ig, gg), (iw, gw)) in pg.iter().zip(&pw) {
            assert!(ig == iw && (*gg - *gw).length() <= tol, "{label}: {g:?} vs {w:?}");
        }
    }
    assert!(
        relabelled * 20 <= got.len().max(20),
        "{label}: {relabelled} ties of {}",
        got.len()
    );
}

/// Renders with the kernel and the oracle and compares everything; returns the
/// kernel's silhouette and the oracle for further checks.
pub fn check(label: &str, mesh: &Mesh, proj: &Projected, cam: &Camera, s: &SoftSettings) -> (EdgeSilhouette, Oracle) {
    let sil = render(mesh, proj, cam, s);
    let o = oracle(&mesh.positions, &mesh.triangles, proj, cam, s);
    assert_eq!(sil.coverage(), &o.coverage, "{label}: coverage");
    assert_eq!(sil.outline_edges(), o.candidates.len(), "{label}: candidate count");
    let worst = sil
        .alpha()
        .iter()
        .zip(&o.alpha)
        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
    assert!(worst <= 1e-12, "{label}: alpha differs by {worst}");
    assert_records_match(label, sil.records(), &o.records);
    assert!(
        !o.records.is_empty(),
        "{label}: nothing soft: the scene misses the canvas"
    );
    (sil, o)
}

pub fn look(mesh: &Mesh, dir: DVec3, dist: f64, w: u32, h: u32, f: f64) -> Camera {
    let b = mesh.bounds().unwrap();
    let c = b.centre();
    let r = b.size().length() * 0.5;
    Camera::look_at(c + dir.normalize() * r * dist, c, DVec3::Y, w, h, f)
}

pub fn some_pose() -> Pose {
    Pose {
        rotation: so3::exp(DVec3::new(0.3, -0.5, 0.2)),
        translation: DVec3::new(0.05, -0.02, 0.1),
        scale: DVec3::new(1.0, 0.8, 1.2),
    }
}

// ---------------------------------------------------------------- gradients vs central differences

/// Deterministic pseudo-random numbers in [−1, 1].
pub fn noise(n: usize, seed: u64) -> Vec<f64> {
    let mut s = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
    (0..n)
        .map(|_| {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((s >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        })
        .collect()
}

/// Smallest distance from a pixel centre to a candidate outline segment.
pub fn margin(o: &Oracle, w: u32, h: u32) -> f64 {
    let mut best = f64::INFINITY;
    for e in &o.candidates {
        let lo = (e.pa.min(e.pb) - 1.0).ceil().max(DVec2::ZERO);
        let hi = (e.pa.max(e.pb) + 1.0)
            .floor()
            .min(DVec2::new(w as f64 - 1.0, h as f64 - 1.0));
        for y in lo.y as i64..=hi.y as i64 {
            for x in lo.x as i64..=hi.x as i64 {
                let p = DVec2::new(x as f64, y as f64);
                let d = e.pb - e.pa;
                let t = ((p - e.pa).dot(d) / d.length_squared()).clamp(0.0, 1.0);
                best = best.min((p - (e.pa + d * t)).length());
            }
        }
    }
    best
}

/// The structure the finite differences must not change: the coverage, and per soft
/// pixel the vertices its gradient reaches (the edge named may switch between two whose
/// closest point is the vertex they share: the same function there).
pub fn structure(sil: &EdgeSilhouette) -> (Mask, Vec<(u32, Vec<u32>)>) {
    let reached = |r: &EdgeRecord| {
        let mut v: Vec<u32> = [(r.a, r.ga), (r.b, r.gb)]
            .iter()
            .filter(|(_, g)| *g != DVec2::ZERO)
            .map(|(i, _)| *i)
            .collect();
        v.sort();
        v
    };
    (
        sil.coverage().clone(),
        sil.records().iter().map(|r| (r.px, reached(r))).collect(),
    )
}

/// ∂(Σ w·A)/∂uv against central differences, moving every copy of a vertex together.
///
/// Configurations: the whole projection is shifted by pseudo-random sub-pixel offsets
/// until no pixel centre lies within 1e-3 px of a candidate outline segment (the hard
/// coverage, snapped to 1/1024 px, then cannot change under a 1e-6 px step); ε = 1e-15
/// makes the cut-off's jump negligible. Each ±h render must then have the base's
/// coverage and pixel-to-edge assignment (asserted), so the function is smooth there.
#[allow(clippy::needless_range_loop)] // `axis` indexes DVec2 components
pub fn fd_2d(label: &str, mesh: &Mesh, base: &Projected, cam: &Camera, sigma: f64) {
    let s = SoftSettings { sigma, eps: 1e-15 };
    let topo = EdgeTopology::from_mesh(mesh);
    let (w, h) = (cam.width, cam.height);
    let weights = noise(w as usize * h as usize, 7);
    let offsets = noise(40, 3);
    let mut proj = base.clone();
    let mut found = false;
    for k in 0..20 {
        let shift = DVec2::new(offsets[2 * k], offsets[2 * k + 1]) * 0.5;
        proj.uv = base.uv.iter().map(|p| *p + shift).collect();
        if margin(&oracle(&mesh.positions, &mesh.triangles, &proj, cam, &s), w, h) >= 1e-3 {
            found = true;
            break;
        }
    }
    assert!(
        found,
        "{label}: no configuration without a pixel centre near the outline"
    );
    let mut sil = EdgeSilhouette::new();
    sil.render(&topo, &proj, &mesh.triangles, cam, &s).unwrap();
    let base_structure = structure(&sil);
    let base_alpha = sil.alpha().to_vec();
    let mut grad = Vec::new();
    sil.backward_2d(&weights, &mut grad);
    // Vertices to test: spread over the outline, and one on no outline edge.
    let mut on_outline: Vec<u32> = sil.records().iter().flat_map(|r| [r.a, r.b]).collect();
    on_outline.sort();
    on_outline.dedup();
    assert!(on_outline.len() >= 6, "{label}");
    let mut chosen: Vec<u32> = (0..6).map(|i| on_outline[i * on_outline.len() / 6]).collect();
    let outline_pos: Vec<DVec3> = on_outline.iter().map(|&v| mesh.positions[v as usize]).collect();
    chosen.extend((0..mesh.positions.len() as u32).find(|&v| !outline_pos.contains(&mesh.positions[v as usize])));
    let hstep = 1e-6;
    let (mut analytic, mut numeric) = (Vec::new(), Vec::new());
    for &v in &chosen {
        let copies: Vec<usize> = (0..mesh.positions.len())
            .filter(|&i| mesh.positions[i] == mesh.positions[v as usize])
            .collect();
        for axis in 0..2 {
            let mut sum = [0.0; 2];
            for (j, sign) in [1.0, -1.0].into_iter().enumerate() {
                let mut p = proj.clone();
                for &c in &copies {
                    p.uv[c][axis] += sign * hstep;
                }
                sil.render(&topo, &p, &mesh.triangles, cam, &s).unwrap();
                assert!(
                    structure(&sil) == base_structure,
                    "{label}: vertex {v} axis {axis} changes the structure"
                );
                sum[j] = sil
                    .alpha()
                    .iter()
                    .zip(&base_alpha)
                    .zip(&weights)
                    .map(|((a, b), w)| (a - b) * w)
                    .sum();
            }
            numeric.push((sum[0] - sum[1]) / (2.0 * hstep));
            analytic.push(copies.iter().map(|&c| grad[c][axis]).sum::<f64>());
        }
    }
    let scale = analytic.iter().fold(0.0f64, |m, g| m.max(g.abs()));
    let err = analytic
        .iter()
        .zip(&numeric)
        .fold(0.0f64, |m, (a, n)| m.max((a - n).abs()));
    assert!(scale > 1e-3, "{label}: no gradient");
    assert!(
        err <= 1e-6 * scale,
        "{label}: error {err} of {scale}\n{analytic:?}\n{numeric:?}"
    );
    // The vertex on no outline edge has no gradient, analytically or numerically.
    assert_eq!(analytic[analytic.len() - 2..], [0.0, 0.0]);
    assert!(numeric[numeric.len() - 2..].iter().all(|n| n.abs() < 1e-6 * scale));
}
