//! `cargo +nightly fuzz run nerf`: see fuzz/README.md and `localisebot_fuzz::targets::nerf`.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    localisebot_fuzz::targets::nerf(data);
});
