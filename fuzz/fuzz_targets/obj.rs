//! `cargo +nightly fuzz run obj`: see fuzz/README.md and `localisebot_fuzz::targets::obj`.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    localisebot_fuzz::targets::obj(data);
});
