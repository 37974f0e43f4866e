//! `cargo +nightly fuzz run gltf`: see fuzz/README.md and `localisebot_fuzz::targets::gltf`.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    localisebot_fuzz::targets::gltf(data);
});
