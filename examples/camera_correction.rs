//! The camera-correction check: synthetic Duck scenes (seeds FIRST..LAST, 3–4 views,
//! 160×120, clean masks) fitted with every camera off by ROT° and DIST of its distance
//! (defaults 0.7 and 0.01), without and with `refine_cameras`; prints the median
//! rotation, scale and ADD errors (BENCHMARKS.md "Camera correction").
//!
//!     cargo run --release --example camera_correction -- FIRST LAST [ROT DIST]

use localisebot::app::coverage::{camera_case, CameraCase, CoverageScenes};
use localisebot::io;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    if v.is_empty() {
        f64::NAN
    } else {
        v[v.len() / 2]
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let num = |i: usize, d: f64| args.get(i).and_then(|s| s.parse().ok()).unwrap_or(d);
    let (first, last) = (num(1, 700.0) as u64, num(2, 711.0) as u64);
    let (rot, dist) = (num(3, 0.7), num(4, 0.01));
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../shared/data/gltf/Duck/glTF-Binary/Duck.glb"
    );
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{path}: {e}"));
    let mesh = io::load_mesh(path, &bytes, &|_| None).expect("the Duck loads");
    let scenes = CoverageScenes {
        width: 160,
        height: 120,
        noise_px: 0.0,
        correlation_px: 12.0,
    };
    for (r, d, refine) in [
        (rot, dist, false),
        (rot, dist, true),
        (0.0, 0.0, false),
        (0.0, 0.0, true),
    ] {
        let cases: Vec<CameraCase> = (first..=last)
            .filter_map(|seed| camera_case(&mesh, seed, &scenes, r, d, refine).unwrap_or_else(|e| panic!("{e}")))
            .collect();
        println!(
            "cameras off by {r}° / {}%, refine {refine}: {} fits, median rotation {:.3}°, scale {:.2}%, ADD {:.3}%",
            100.0 * d,
            cases.len(),
            median(cases.iter().map(|c| c.rotation_deg).collect()),
            100.0 * median(cases.iter().map(|c| c.scale).collect()),
            100.0 * median(cases.iter().map(|c| c.add_rel).collect()),
        );
    }
}
