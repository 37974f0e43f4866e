//! Calibrates and checks the uncertainty: fits synthetic Duck scenes (seeds FIRST..LAST,
//! 2–4 views, 160×120) with clean and roughened masks and prints each scene's squared
//! Mahalanobis distance, the coverage of the 95 % bounds, and the κ that would put the
//! 95th percentile of the distances on χ²(9, 0.95) (the calibration of
//! `NoiseModel::inflation`; BENCHMARKS.md "Uncertainty").
//!
//!     cargo run --release --example uncertainty_coverage -- FIRST LAST [NOISE_PX]

use localisebot::app::coverage::{coverage, coverage_case, CoverageScenes};
use localisebot::io;
use localisebot::uncertainty::{NoiseModel, CHI2_9_95};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let first: u64 = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(1000);
    let last: u64 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(1019);
    let noise: f64 = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(0.0);
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../shared/data/gltf/Duck/glTF-Binary/Duck.glb"
    );
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{path}: {e}"));
    let mesh = io::load_mesh(path, &bytes, &|_| None).expect("the Duck loads");
    let scenes = CoverageScenes {
        width: 160,
        height: 120,
        noise_px: noise,
        correlation_px: 12.0,
    };
    let mut cases = Vec::new();
    for seed in first..=last {
        match coverage_case(&mesh, seed, &scenes) {
            Ok(Some(c)) => {
                println!(
                    "seed {seed} views {} m² {:.2} add {:.5} add95 {:.5} rot {:.3}° sd {:.3}°",
                    c.views, c.mahalanobis_sq, c.add, c.add_95, c.rotation_deg, c.rotation_sd_deg
                );
                cases.push(c);
            }
            Ok(None) => println!("seed {seed}: failed fit, not counted"),
            Err(e) => println!("seed {seed}: error {e}"),
        }
    }
    let (ell, add) = coverage(&cases);
    let mut m: Vec<f64> = cases.iter().map(|c| c.mahalanobis_sq).collect();
    m.sort_by(f64::total_cmp);
    let q95 = m
        .get((m.len() * 95 / 100).min(m.len().saturating_sub(1)))
        .copied()
        .unwrap_or(f64::NAN);
    let kappa = NoiseModel::default().inflation;
    println!(
        "{} scenes: 95% ellipsoid coverage {:.1}%, ADD bound coverage {:.1}%; κ now {kappa}, κ for 95%: {:.2}",
        cases.len(),
        100.0 * ell,
        100.0 * add,
        kappa * q95 / CHI2_9_95
    );
}
