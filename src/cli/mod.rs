//! Command-line parsing (clap) and dispatch. Each command lives in its own file;
//! every error reaches the user as one line on stderr and a non-zero exit status.

mod bench;
mod eval;
mod files;
mod fit;
mod import;
mod info;
mod loss;
mod render;
mod segment;
mod segmenter;
mod suggest;
mod synth;

use clap::{Parser, Subcommand};
use std::path::PathBuf;

/// Multi-view 9-DoF object localisation by differentiable silhouette rendering.
#[derive(Parser)]
#[command(name = "localisebot", version, about, long_about = None)]
struct Cli {
    /// Raise or lower an input limit, NAME=VALUE (repeatable): file_bytes, view_pixels,
    /// total_pixels, views, vertices, triangles (defaults in README, "Limits").
    #[arg(long = "limit", global = true, value_name = "NAME=VALUE")]
    limits: Vec<String>,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Print a mesh's vertex and triangle counts and bounds (after node transforms) as JSON.
    Info {
        /// Mesh file (.glb, .gltf, .obj, .ply).
        mesh: PathBuf,
    },
    /// Make a synthetic scene: cameras around the mesh, masks rendered at a (random) pose.
    Synth(synth::SynthArgs),
    /// Estimate the object's pose in a scene (search, then refine); write the result JSON
    /// (exit status 3 with --strict unless the verdict is ok).
    Fit(fit::FitArgs),
    /// Print the multi-view loss, per-view losses and the 9-gradient at a pose, as JSON.
    Loss(loss::LossArgs),
    /// Time the forward + backward pass and full fits (see BENCHMARKS.md).
    Bench(bench::BenchArgs),
    /// Rank candidate cameras by how much a photograph from there would shrink the pose
    /// uncertainty of a fit; print the best as a JSON list of scene-form cameras.
    SuggestView(suggest::SuggestArgs),
    /// Fit every scene of some folders and write the paper's tables and plots.
    Eval(eval::EvalArgs),
    /// Import a dataset folder (NeRF, BOP) as a scene folder.
    #[command(subcommand)]
    Import(import::ImportCommand),
    /// Make the masks of a scene's photographs (views with an image and a box, or only an
    /// image) and write a scene with masks: DIR/scene.json and DIR/masks/<view>.png.
    Segment(segment::SegmentArgs),
    /// Draw overlays (mask outline and rendered contour over each view) for a pose.
    Render {
        /// The scene file.
        scene: PathBuf,
        /// The pose file (SPEC §3 pose form, or a result file with a "pose" key).
        #[arg(long)]
        pose: PathBuf,
        /// Output folder for one PNG per view.
        #[arg(long)]
        out: PathBuf,
    },
}

/// The process's peak resident memory in bytes (`VmHWM` of `/proc/self/status`), where
/// the system says it (Linux); `None` elsewhere.
pub(crate) fn peak_memory_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    parse_vm_hwm(&status)
}

/// `VmHWM:   123456 kB` of a `/proc/<pid>/status` text, in bytes.
fn parse_vm_hwm(status: &str) -> Option<u64> {
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let mut words = line["VmHWM:".len()..].split_whitespace();
    let n: u64 = words.next()?.parse().ok()?;
    match words.next()? {
        "kB" => n.checked_mul(1024),
        _ => None,
    }
}

/// Runs the command line; returns the process exit status.
pub fn main() -> i32 {
    let cli = Cli::parse();
    if let Err(e) = files::set_limits(&cli.limits) {
        eprintln!("error: {e}");
        return 2;
    }
    let result = match cli.command {
        Command::Info { mesh } => info::run(&mesh).map(|_| 0),
        Command::Synth(args) => synth::run(&args).map(|_| 0),
        Command::Fit(args) => fit::run(&args),
        Command::Loss(args) => loss::run(&args).map(|_| 0),
        Command::Import(cmd) => import::run(&cmd).map(|_| 0),
        Command::Eval(args) => eval::run(&args).map(|_| 0),
        Command::Bench(args) => bench::run(&args).map(|_| 0),
        Command::SuggestView(args) => suggest::run(&args).map(|_| 0),
        Command::Segment(args) => segment::run(&args).map(|_| 0),
        Command::Render { scene, pose, out } => render::run(&scene, &pose, &out).map(|_| 0),
    };
    match result {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e}");
            1
        }
    }
}

#[cfg(test)]
mod tests {
    use super::parse_vm_hwm;

    #[test]
    fn the_peak_memory_is_read_from_vm_hwm() {
        let status = "Name:\tlocalisebot\nVmPeak:\t  900 kB\nVmHWM:\t  1329024 kB\nVmRSS:\t 12 kB\n";
        assert_eq!(parse_vm_hwm(status), Some(1_329_024 * 1024));
        assert_eq!(parse_vm_hwm("VmRSS:\t 12 kB\n"), None);
        assert_eq!(parse_vm_hwm("VmHWM:\t twelve kB\n"), None);
        assert_eq!(parse_vm_hwm("VmHWM:\t 12 MB\n"), None);
        // The process's own: some memory, read back on Linux.
        #[cfg(target_os = "linux")]
        assert!(super::peak_memory_bytes().is_some_and(|b| b > 1024 * 1024));
    }
}
