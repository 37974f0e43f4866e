//! The next-best-view check: for synthetic Duck scenes (seeds FIRST..LAST, 2 views,
//! 160×120, masks roughened by 1 px), how often adding the top-ranked of 64 sphere
//! candidates reduces the true ADD more than the median of 5 random candidates
//! (BENCHMARKS.md "Next best view").
//!
//!     cargo run --release --example next_view_rate -- FIRST LAST
//!
//! Environment: `SPREAD` (degrees between the two stops; default the synthetic
//! scene's cameras), `NOISE` (px, default 1), `NV` (candidates, default 64), `MESH` (a
//! mesh file or a shape name of `synth --shape`, default the shared Duck), `W`, `H`
//! (image size, default 160×120), `ABOVE` (set: candidates on the upper half-sphere),
//! `DRAWS` (noise draws of the new view's mask each candidate's ADD is the geometric
//! mean of; default 6, as the test; 1 = a single photograph).

use localisebot::app::coverage::{next_view_case, CoverageScenes};
use localisebot::io;
use localisebot::uncertainty::Viewpoints;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let first: u64 = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(300);
    let last: u64 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(319);
    let default = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../shared/data/gltf/Duck/glTF-Binary/Duck.glb"
    );
    let path = std::env::var("MESH").unwrap_or_else(|_| default.to_string());
    let path = path.as_str();
    let mesh = match localisebot::app::shapes::by_name(path) {
        Some(m) => m,
        None => {
            let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{path}: {e}"));
            io::load_mesh(path, &bytes, &|_| None).expect("the mesh loads")
        }
    };
    let scenes = CoverageScenes {
        width: std::env::var("W").ok().and_then(|s| s.parse().ok()).unwrap_or(160),
        height: std::env::var("H").ok().and_then(|s| s.parse().ok()).unwrap_or(120),
        noise_px: std::env::var("NOISE").ok().and_then(|s| s.parse().ok()).unwrap_or(1.0),
        correlation_px: 12.0,
    };
    let (mut wins, mut n) = (0, 0);
    for seed in first..=last {
        match next_view_case(
            &mesh,
            seed,
            &scenes,
            std::env::var("NV").ok().and_then(|s| s.parse().ok()).unwrap_or(64),
            if std::env::var("ABOVE").is_ok() {
                Viewpoints::Above
            } else {
                Viewpoints::Sphere
            },
            5,
            std::env::var("DRAWS").ok().and_then(|s| s.parse().ok()).unwrap_or(6),
            std::env::var("SPREAD").ok().and_then(|s| s.parse().ok()),
        ) {
            Ok(Some(c)) => {
                n += 1;
                wins += usize::from(c.top_wins());
                println!(
                    "seed {seed}: ADD 2 views {:.5}, + top {:.5}, + random median {:.5} {:?}",
                    c.add_before,
                    c.add_top,
                    c.median_random(),
                    c.add_random.iter().map(|a| format!("{a:.5}")).collect::<Vec<_>>()
                );
            }
            Ok(None) => println!("seed {seed}: failed fit, not counted"),
            Err(e) => println!("seed {seed}: error {e}"),
        }
    }
    println!(
        "top candidate beat the median random one in {wins} of {n} scenes ({:.0}%)",
        100.0 * wins as f64 / n.max(1) as f64
    );
}
