//! `cargo +nightly fuzz run camera_json`: see fuzz/README.md and `localisebot_fuzz::targets::camera_json`.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    localisebot_fuzz::targets::camera_json(data);
});
