//! How much of the edge pass could face clusters with normal cones skip? For the
//! `bench` scene of a shared glTF mesh (default the 2CylinderEngine; 4 views at 128²,
//! seed 11), faces are grouped into clusters of at most N (16…128) — chunks of the
//! faces' Morton order, or with `GROW=DEG` grown over edge adjacency while a face's
//! normal is within DEG of the seed's — and each cluster gets a bounding sphere and a
//! normal cone. Printed: the share of edges inside a cluster, and the share per view
//! inside a cluster that the conservative cone test (view direction ± the sphere's
//! angle, ± the cone) proves turned one way, whose edges could be skipped (BENCHMARKS.md,
//! "Silhouette-edge rasteriser").
//!
//!     cargo run --release --example cluster_probe -- [MESH_NAME]
use glam::DVec3;
use localisebot::app::synth::{synthesize, SynthSettings};
use localisebot::io;
use std::collections::HashMap;

fn morton(p: DVec3, lo: DVec3, hi: DVec3) -> u64 {
    let q = (p - lo) / (hi - lo).max(DVec3::splat(1e-12));
    let f = |x: f64| -> u64 {
        let mut v = ((x.clamp(0.0, 1.0)) * 1023.0) as u64;
        v = (v | (v << 16)) & 0x030000FF;
        v = (v | (v << 8)) & 0x0300F00F;
        v = (v | (v << 4)) & 0x030C30C3;
        v = (v | (v << 2)) & 0x09249249;
        v
    };
    f(q.x) | (f(q.y) << 1) | (f(q.z) << 2)
}

fn main() {
    let name = std::env::args().nth(1).unwrap_or("2CylinderEngine".into());
    let path = format!(
        "{}/../shared/data/gltf/{name}/glTF-Binary/{name}.glb",
        env!("CARGO_MANIFEST_DIR")
    );
    let bytes = std::fs::read(&path).unwrap();
    let mesh = io::load_mesh(&path, &bytes, &|_| None).unwrap();
    let s = synthesize(
        &mesh,
        &SynthSettings {
            views: 4,
            width: 128,
            height: 128,
            seed: 11,
            ..Default::default()
        },
        None,
    )
    .unwrap();
    let p = &mesh.positions;
    let t = &mesh.triangles;
    let b = mesh.bounds().unwrap();
    // welded edge -> faces
    let key = |v: DVec3| {
        (
            (v.x * 1e6).round() as i64,
            (v.y * 1e6).round() as i64,
            (v.z * 1e6).round() as i64,
        )
    };
    let mut wid: HashMap<(i64, i64, i64), u32> = HashMap::new();
    let w: Vec<u32> = p
        .iter()
        .map(|&v| {
            let n = wid.len() as u32;
            *wid.entry(key(v)).or_insert(n)
        })
        .collect();
    let mut edges: HashMap<(u32, u32), Vec<u32>> = HashMap::new();
    for (f, tri) in t.iter().enumerate() {
        for k in 0..3 {
            let (a, c) = (w[tri[k] as usize], w[tri[(k + 1) % 3] as usize]);
            if a != c {
                edges.entry((a.min(c), a.max(c))).or_default().push(f as u32);
            }
        }
    }
    println!("{} faces, {} edges", t.len(), edges.len());
    for size in [16usize, 32, 64, 128] {
        let mut order: Vec<u32> = (0..t.len() as u32).collect();
        let cent = |f: u32| {
            let q = t[f as usize];
            (p[q[0] as usize] + p[q[1] as usize] + p[q[2] as usize]) / 3.0
        };
        order.sort_by_key(|&f| morton(cent(f), b.min, b.max));
        let nrm = |f: u32| {
            let q = t[f as usize];
            (p[q[1] as usize] - p[q[0] as usize])
                .cross(p[q[2] as usize] - p[q[0] as usize])
                .normalize_or_zero()
        };
        let mut chunks: Vec<Vec<u32>> = Vec::new();
        if let Ok(deg) = std::env::var("GROW") {
            let cmax = deg.parse::<f64>().unwrap().to_radians().cos();
            let mut adj: Vec<Vec<u32>> = vec![vec![]; t.len()];
            for fs in edges.values() {
                if fs.len() == 2 {
                    adj[fs[0] as usize].push(fs[1]);
                    adj[fs[1] as usize].push(fs[0]);
                }
            }
            let mut taken = vec![false; t.len()];
            for &seed in &order {
                if taken[seed as usize] {
                    continue;
                }
                let n0 = nrm(seed);
                let mut ch = vec![seed];
                taken[seed as usize] = true;
                let mut i = 0;
                while i < ch.len() && ch.len() < size {
                    let f = ch[i];
                    i += 1;
                    for &g in &adj[f as usize] {
                        if !taken[g as usize] && ch.len() < size && nrm(g).dot(n0) >= cmax {
                            taken[g as usize] = true;
                            ch.push(g);
                        }
                    }
                }
                chunks.push(ch);
            }
        } else {
            chunks = order.chunks(size).map(|c| c.to_vec()).collect();
        }
        let mut cluster = vec![0u32; t.len()];
        let mut cones = vec![];
        for (ci, ch) in chunks.iter().enumerate() {
            let ns: Vec<DVec3> = ch
                .iter()
                .map(|&f| {
                    let q = t[f as usize];
                    (p[q[1] as usize] - p[q[0] as usize]).cross(p[q[2] as usize] - p[q[0] as usize])
                })
                .collect();
            let axis = ns
                .iter()
                .map(|n| n.normalize_or_zero())
                .sum::<DVec3>()
                .normalize_or_zero();
            let cosmin = ns
                .iter()
                .map(|n| n.normalize_or_zero().dot(axis))
                .fold(1.0f64, f64::min);
            let pts: Vec<DVec3> = ch.iter().flat_map(|&f| t[f as usize].map(|i| p[i as usize])).collect();
            let c = pts.iter().sum::<DVec3>() / pts.len() as f64;
            let r = pts.iter().map(|q| q.distance(c)).fold(0.0, f64::max);
            for &f in ch {
                cluster[f as usize] = ci as u32;
            }
            cones.push((axis, cosmin.clamp(-1.0, 1.0).acos(), c, r));
        }
        let mut skip_total = 0usize;
        for cam in &s.cameras {
            // camera centre into the model frame
            let e = cam.centre();
            let pose = s.pose;
            let em = (pose.rotation.transpose() * (e - pose.translation)) / pose.scale;
            let uniform: Vec<bool> = cones
                .iter()
                .map(|&(a, alpha, c, r)| {
                    let d = em - c;
                    let l = d.length();
                    if l <= r || a == DVec3::ZERO {
                        return false;
                    }
                    let beta = (d / l).dot(a).clamp(-1.0, 1.0).acos();
                    let g = (r / l).asin();
                    let h = std::f64::consts::FRAC_PI_2;
                    beta + alpha + g < h || beta - alpha - g > h
                })
                .collect();
            let skip = edges
                .values()
                .filter(|fs| {
                    fs.len() == 2
                        && cluster[fs[0] as usize] == cluster[fs[1] as usize]
                        && uniform[cluster[fs[0] as usize] as usize]
                })
                .count();
            skip_total += skip;
        }
        let interior = edges
            .values()
            .filter(|fs| fs.len() == 2 && cluster[fs[0] as usize] == cluster[fs[1] as usize])
            .count();
        println!("{} clusters of ≤{size}: ", chunks.len());
        println!(
            "   interior edges {:.1} %, skippable per view {:.1} %",
            100.0 * interior as f64 / edges.len() as f64,
            100.0 * skip_total as f64 / 4.0 / edges.len() as f64
        );
    }
}
