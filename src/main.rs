//! The `localisebot` command line.
fn main() {}
