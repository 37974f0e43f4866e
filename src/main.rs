//! The `localisebot` command line: a thin wrapper over the core that does the file
//! I/O, progress display and timing. `localisebot --help` lists the commands.

#[cfg(not(target_arch = "wasm32"))]
mod cli;

#[cfg(not(target_arch = "wasm32"))]
fn main() {
    std::process::exit(cli::main());
}

#[cfg(target_arch = "wasm32")]
fn main() {}
