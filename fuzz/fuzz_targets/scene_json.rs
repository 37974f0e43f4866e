//! `cargo +nightly fuzz run scene_json`: see fuzz/README.md and `localisebot_fuzz::targets::scene_json`.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    localisebot_fuzz::targets::scene_json(data);
});
