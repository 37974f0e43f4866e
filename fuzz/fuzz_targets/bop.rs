//! `cargo +nightly fuzz run bop`: see fuzz/README.md and `localisebot_fuzz::targets::bop`.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    localisebot_fuzz::targets::bop(data);
});
