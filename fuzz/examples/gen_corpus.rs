//! Writes the seed corpora, `fuzz/corpus/<target>/`, from this project's own writers:
//! raw-mode seeds (`targets::raw_seeds`: the reference scene, meshes, PNGs, BOP and
//! NeRF files) and structured-mode seeds (pseudo-random bytes, fixed seed, kept when
//! they reach an outcome not yet seen — a few that load, a couple per kind of refusal).
//! Deterministic; run from `fuzz/` on stable Rust:
//!
//! ```text
//! cargo run --release --example gen_corpus
//! ```
//!
//! An input that panics is not kept: it is written to `fuzz/regressions/<target>/`
//! and reported (the run then exits with an error).

use localisebot_fuzz::targets::{raw_seeds, TARGETS};
use std::collections::BTreeMap;
use std::path::Path;

fn fnv(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, &b| {
        (h ^ b as u64).wrapping_mul(0x100_0000_01b3)
    })
}

fn next(state: &mut u64) -> u64 {
    *state ^= *state << 13;
    *state ^= *state >> 7;
    *state ^= *state << 17;
    *state
}

const PER_TARGET: usize = 40;

fn main() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let only: Vec<String> = std::env::args().skip(1).collect();
    let mut panics = 0;
    for (name, run) in TARGETS {
        if !only.is_empty() && !only.iter().any(|o| o == name) {
            continue;
        }
        let mut kept: Vec<Vec<u8>> = raw_seeds(name);
        let mut seen: BTreeMap<String, usize> = BTreeMap::new();
        for seed in &kept {
            let label = run(seed).label;
            *seen.entry(format!("raw {label}")).or_default() += 1;
        }
        let mut rng = 0x9E37_79B9_7F4A_7C15u64 ^ fnv(name.as_bytes());
        for attempt in 0..6000usize {
            if kept.len() >= PER_TARGET {
                break;
            }
            let len = [4, 16, 48, 128, 400, 1200][attempt % 6];
            let zeros = [0, 50, 80, 95][attempt / 6 % 4];
            let mut data = vec![1u8];
            for _ in 0..len {
                let r = next(&mut rng);
                data.push(if r % 100 < zeros { 0 } else { (r >> 32) as u8 });
            }
            let outcome = std::panic::catch_unwind(|| run(&data));
            let label = match outcome {
                Ok(o) => o.label,
                Err(_) => {
                    panics += 1;
                    let dir = root.join("regressions").join(name);
                    std::fs::create_dir_all(&dir).unwrap();
                    let path = dir.join(format!("panic-{:016x}", fnv(&data)));
                    std::fs::write(&path, &data).unwrap();
                    eprintln!("{name}: PANIC, input written to {}", path.display());
                    continue;
                }
            };
            let cap = if label == "ok" { 10 } else { 2 };
            let count = seen.entry(label).or_default();
            if *count < cap {
                *count += 1;
                kept.push(data);
            }
        }
        let dir = root.join("corpus").join(name);
        if dir.exists() {
            std::fs::remove_dir_all(&dir).unwrap();
        }
        std::fs::create_dir_all(&dir).unwrap();
        let mut bytes = 0;
        for data in &kept {
            bytes += data.len();
            std::fs::write(dir.join(format!("seed-{:016x}", fnv(data))), data).unwrap();
        }
        println!("{name}: {} seeds, {bytes} bytes; outcomes:", kept.len());
        for (label, n) in &seen {
            println!("    {n:3}  {label}");
        }
    }
    if panics > 0 {
        eprintln!("{panics} inputs panicked");
        std::process::exit(1);
    }
}
