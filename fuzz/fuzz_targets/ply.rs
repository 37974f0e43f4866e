//! `cargo +nightly fuzz run ply`: see fuzz/README.md and `localisebot_fuzz::targets::ply`.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    localisebot_fuzz::targets::ply(data);
});
