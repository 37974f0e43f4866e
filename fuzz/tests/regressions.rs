//! Every input kept in `regressions/<target>/` (crashes the fuzzer found, minimised)
//! and every seed in `corpus/<target>/` must give a clean answer through the very
//! function the target runs. `cargo test` in `fuzz/` (stable Rust is enough).

use localisebot_fuzz::targets::TARGETS;
use std::path::Path;

fn run_all(folder: &str) -> usize {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join(folder);
    let mut n = 0;
    for (name, run) in TARGETS {
        let Ok(dir) = std::fs::read_dir(root.join(name)) else {
            continue;
        };
        let mut paths: Vec<_> = dir.map(|e| e.unwrap().path()).collect();
        paths.sort();
        for path in paths {
            let data = std::fs::read(&path).unwrap();
            let outcome = std::panic::catch_unwind(|| run(&data));
            assert!(outcome.is_ok(), "{name}: {} panics", path.display());
            n += 1;
        }
    }
    n
}

#[test]
fn regressions_give_clean_answers() {
    run_all("regressions");
}

#[test]
fn seeds_give_clean_answers() {
    assert!(
        run_all("corpus") > 0,
        "no seed corpora: run `cargo run --release --example gen_corpus`"
    );
}
