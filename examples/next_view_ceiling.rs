//! How well can any ranking do on the next-best-view check? For synthetic Duck scenes
//! (seeds FIRST..LAST; two stops 45° apart, 160×120, masks roughened by 1 px, as the
//! test), every usable candidate is refitted with DRAWS noise draws of its mask
//! (default 3). Printed: the variance of log ADD between noise draws of one candidate
//! and between candidates; the rate of the check for the suggested view; the same rate
//! for a "cross-validated oracle" that picks, with hindsight, the candidate whose other
//! draws were best (what a perfect ranking could hope for, slightly pessimistic); and the
//! rate when each candidate's ADD is the mean over its draws (BENCHMARKS.md "Next best
//! view").
//!
//!     cargo run --release --example next_view_ceiling -- FIRST LAST
//!
//! Environment: `DRAWS` (noise draws per candidate, default 3, at least 2), `DUMP`
//! (set: also print `logs SEED CANDIDATE ln(ADD)…` per candidate, best-ranked first,
//! for offline analysis).

use localisebot::app::coverage::{CoverageScenes, NextViewSetup};
use localisebot::io;
use localisebot::metrics::median;
use localisebot::uncertainty::Viewpoints;
use rand::seq::SliceRandom;
use rand::{Rng, SeedableRng};

/// Trials of the random draw of 5 candidates per scene.
const TRIALS: usize = 400;

/// The chance that `pick(top)` beats the median of `pick` over 5 random others.
fn rate(
    rng: &mut rand::rngs::SmallRng,
    top: usize,
    all: &[usize],
    pick: &mut dyn FnMut(&mut rand::rngs::SmallRng, usize) -> f64,
) -> f64 {
    let others: Vec<usize> = all.iter().copied().filter(|&i| i != top).collect();
    let mut wins = 0;
    for _ in 0..TRIALS {
        let a = pick(rng, top);
        let five: Vec<usize> = others.choose_multiple(rng, 5).copied().collect();
        let m = median(&five.iter().map(|&i| pick(rng, i)).collect::<Vec<_>>());
        wins += usize::from(a < m);
    }
    wins as f64 / TRIALS as f64
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let first: u64 = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(500);
    let last: u64 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(539);
    let draws: u64 = std::env::var("DRAWS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(3)
        .max(2);
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../shared/data/gltf/Duck/glTF-Binary/Duck.glb"
    );
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{path}: {e}"));
    let mesh = io::load_mesh(path, &bytes, &|_| None).expect("the Duck loads");
    let scenes = CoverageScenes {
        width: 160,
        height: 120,
        noise_px: 1.0,
        correlation_px: 12.0,
    };
    let mut rng = rand::rngs::SmallRng::seed_from_u64(7);
    let (mut suggested, mut oracle, mut means, mut within, mut between) = (vec![], vec![], vec![], vec![], vec![]);
    for seed in first..=last {
        let setup = match NextViewSetup::new(&mesh, seed, &scenes, 64, Viewpoints::Sphere, Some(45.0)) {
            Ok(Some(s)) => s,
            Ok(None) => continue,
            Err(e) => panic!("seed {seed}: {e}"),
        };
        // log ADD of every usable candidate under every draw.
        let mut logs: Vec<(usize, Vec<f64>)> = Vec::new();
        for &i in &setup.ranked {
            let adds: Vec<f64> = (0..draws)
                .filter_map(|d| setup.refit(i, d).expect("the refit runs"))
                .map(f64::ln)
                .collect();
            if adds.len() == draws as usize {
                logs.push((i, adds));
            }
        }
        if logs.len() < 6 {
            continue;
        }
        if std::env::var_os("DUMP").is_some() {
            for (i, v) in &logs {
                let v: Vec<String> = v.iter().map(|x| format!("{x:.5}")).collect();
                println!("logs {seed} {i} {}", v.join(" "));
            }
        }
        let all: Vec<usize> = (0..logs.len()).collect();
        let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
        let mut single = |r: &mut rand::rngs::SmallRng, k: usize| logs[k].1[r.gen_range(0..draws as usize)];
        // The suggested view is the first of `ranked` still in `logs`.
        let top = 0;
        suggested.push(rate(&mut rng, top, &all, &mut single));
        means.push(rate(&mut rng, top, &all, &mut |_, k| mean(&logs[k].1)));
        for hold in 0..draws as usize {
            let rest = |k: usize| {
                mean(
                    &logs[k]
                        .1
                        .iter()
                        .enumerate()
                        .filter(|(d, _)| *d != hold)
                        .map(|(_, x)| *x)
                        .collect::<Vec<_>>(),
                )
            };
            let best = (0..logs.len())
                .min_by(|&a, &b| rest(a).total_cmp(&rest(b)))
                .unwrap_or(0);
            oracle.push(rate(&mut rng, best, &all, &mut |r, k| {
                if k == best {
                    logs[k].1[hold]
                } else {
                    logs[k].1[r.gen_range(0..draws as usize)]
                }
            }));
        }
        let mu: Vec<f64> = logs.iter().map(|(_, v)| mean(v)).collect();
        let w = logs
            .iter()
            .zip(&mu)
            .map(|((_, v), m)| v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (draws - 1) as f64)
            .sum::<f64>()
            / logs.len() as f64;
        let grand = mean(&mu);
        let b = mu.iter().map(|m| (m - grand) * (m - grand)).sum::<f64>() / (mu.len() - 1) as f64 - w / draws as f64;
        within.push(w);
        between.push(b);
        println!(
            "seed {seed}: {} candidates; suggested view wins {:.0} % of draws, the oracle {:.0} %",
            logs.len(),
            100.0 * suggested.last().unwrap(),
            100.0 * oracle[oracle.len() - draws as usize..].iter().sum::<f64>() / draws as f64
        );
    }
    let avg = |v: &[f64]| v.iter().sum::<f64>() / v.len().max(1) as f64;
    println!("{} scenes, {draws} noise draws per candidate", suggested.len());
    println!(
        "variance of log ADD: between noise draws of one candidate {:.3}, between candidates {:.3}",
        avg(&within),
        avg(&between)
    );
    println!(
        "expected rate of the check: suggested view {:.0} %, cross-validated oracle {:.0} %",
        100.0 * avg(&suggested),
        100.0 * avg(&oracle)
    );
    println!(
        "with each candidate's ADD averaged over its draws: suggested view {:.0} %",
        100.0 * avg(&means)
    );
}
