//! `cargo +nightly fuzz run png`: see fuzz/README.md and `localisebot_fuzz::targets::png`.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    localisebot_fuzz::targets::png(data);
});
