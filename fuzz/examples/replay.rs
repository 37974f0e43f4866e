//! Runs inputs through a target as libFuzzer does, and says what each gave:
//!
//! ```text
//! LOCALISEBOT_FUZZ_DUMP=/tmp/files cargo run --release --example replay -- ply artifacts/ply/crash-…
//! ```
//!
//! With `LOCALISEBOT_FUZZ_DUMP` set, the files the input made are written there.

use localisebot_fuzz::targets::TARGETS;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some((target, inputs)) = args.split_first() else {
        eprintln!("usage: replay TARGET INPUT…");
        std::process::exit(2);
    };
    let Some((_, run)) = TARGETS.iter().find(|(n, _)| n == target) else {
        eprintln!("no target {target}");
        std::process::exit(2);
    };
    for path in inputs {
        let data = std::fs::read(path).expect("readable input");
        let t = std::time::Instant::now();
        let outcome = run(&data);
        println!("{path}: {} ({:?})", outcome.label, t.elapsed());
    }
}
