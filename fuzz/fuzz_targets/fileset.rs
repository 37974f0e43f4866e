//! `cargo +nightly fuzz run fileset`: see fuzz/README.md and `localisebot_fuzz::targets::fileset`.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    localisebot_fuzz::targets::fileset(data);
});
