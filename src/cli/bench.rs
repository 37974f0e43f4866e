//! `localisebot bench`: the speed figures of BENCHMARKS.md — median milliseconds of
//! one forward + backward (multi-view loss and its 9-gradient) on fixed synthetic
//! configurations, and seconds of a full fit from no initial pose; or the same
//! forward + backward on a given scene at a given pose.

use super::files::{load_mesh, load_pose, load_scene_file, CliResult};
use localisebot::app::synth::{blob_mesh, synthesize, SynthSettings};
use localisebot::loss::objective::{Objective, ObjectiveSettings};
use localisebot::loss::target::Window;
use localisebot::raster::soft::SoftSettings;
use localisebot::{Estimator, FitSettings};
use localisebot::{Mesh, Pose, View};
use std::path::PathBuf;
use std::time::Instant;

/// The benchmark's Duck (Khronos sample), read at run time where the shared
/// third-party data sits: `../shared` beside the repository.
const DUCK: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../shared/data/gltf/Duck/glTF-Binary/Duck.glb"
);

/// Arguments of `bench`.
#[derive(clap::Args)]
pub struct BenchArgs {
    /// Print one JSON object per line instead of a table.
    #[arg(long)]
    json: bool,
    /// Time a given scene instead of the fixed configurations (needs --pose).
    #[arg(long, requires = "pose")]
    scene: Option<PathBuf>,
    /// The pose at which to time the scene.
    #[arg(long)]
    pose: Option<PathBuf>,
    /// σ in pixel² (default 1.0).
    #[arg(long, default_value_t = 1.0)]
    sigma: f64,
    /// Repetitions of the forward + backward (the median is reported).
    #[arg(long, default_value_t = 30)]
    reps: usize,
    /// Skip the full fits (forward + backward figures only).
    #[arg(long)]
    no_fit: bool,
    /// The Duck mesh of the fixed configurations (default: the shared data's
    /// `Duck.glb`, in `../shared` beside the repository).
    #[arg(long, default_value = DUCK)]
    duck: PathBuf,
}

struct Row {
    mesh: String,
    triangles: usize,
    views: usize,
    size: u32,
    sigma: f64,
    fwd_bwd_ms: f64,
    fit_s: Option<f64>,
    fit_add_rel: Option<f64>,
    fit_iou: Option<f64>,
}

/// Runs `bench`.
pub fn run(a: &BenchArgs) -> CliResult {
    if !(a.sigma > 0.0 && a.sigma.is_finite()) {
        return Err(format!("--sigma must be a positive number, got {}", a.sigma));
    }
    let reps = a.reps.max(1);
    let mut rows = Vec::new();
    if let Some(scene_path) = &a.scene {
        let scene = load_scene_file(scene_path)?;
        let pose = load_pose(a.pose.as_ref().expect("clap requires --pose with --scene"))?;
        let size = scene
            .views
            .iter()
            .map(|v| v.camera().width.max(v.camera().height))
            .max()
            .unwrap_or(0);
        let ms = time_fwd_bwd(&scene.mesh, &scene.views, &pose, size, a.sigma, reps);
        rows.push(Row {
            mesh: scene_path.display().to_string(),
            triangles: scene.mesh.triangles.len(),
            views: scene.views.len(),
            size,
            sigma: a.sigma,
            fwd_bwd_ms: ms,
            fit_s: None,
            fit_add_rel: None,
            fit_iou: None,
        });
    } else {
        if !a.duck.is_file() {
            return Err(format!(
                "{}: not found: the benchmark's Duck is read from the shared data folder `shared`, \
                 which must sit beside the repository, or from --duck PATH",
                a.duck.display()
            ));
        }
        let duck = load_mesh(&a.duck)?;
        let meshes = [
            ("blob500".to_string(), blob_mesh(12, 25)),
            ("blob2k".to_string(), blob_mesh(22, 50)),
            ("blob10k".to_string(), blob_mesh(52, 100)),
            ("duck".to_string(), duck),
        ];
        for (name, mesh) in &meshes {
            for size in [128u32, 256] {
                let synth = SynthSettings {
                    views: 4,
                    width: size,
                    height: size,
                    seed: 11,
                    ..Default::default()
                };
                let s = synthesize(mesh, &synth, None).map_err(|e| e.to_string())?;
                let views = s.views();
                let ms = time_fwd_bwd(mesh, &views, &s.pose, size, a.sigma, reps);
                let (fit_s, fit_add_rel, fit_iou) = if a.no_fit || size != 256 {
                    (None, None, None)
                } else {
                    let start = Instant::now();
                    let mut est = Estimator::new(mesh.clone(), views.clone(), None, FitSettings::default())
                        .map_err(|e| e.to_string())?;
                    est.run(usize::MAX).map_err(|e| e.to_string())?;
                    let secs = start.elapsed().as_secs_f64();
                    let r = est.result(secs, Some(&s.pose));
                    (Some(secs), r.errors.map(|e| e.add_rel), Some(r.mean_iou))
                };
                rows.push(Row {
                    mesh: name.clone(),
                    triangles: mesh.triangles.len(),
                    views: 4,
                    size,
                    sigma: a.sigma,
                    fwd_bwd_ms: ms,
                    fit_s,
                    fit_add_rel,
                    fit_iou,
                });
            }
        }
    }
    print_rows(&rows, a.json);
    Ok(())
}

/// Median milliseconds of one multi-view loss + 9-gradient at `pose` (the fit's
/// objective with its default λ1, λ2; every view's whole image at `size`).
fn time_fwd_bwd(mesh: &Mesh, views: &[View], pose: &Pose, size: u32, sigma: f64, reps: usize) -> f64 {
    let d = FitSettings::default();
    let settings = ObjectiveSettings {
        soft: SoftSettings { sigma, eps: 1e-4 },
        lambda_iou: d.lambda_iou,
        lambda_contour: d.lambda_contour,
    };
    let windows: Vec<Window> = views.iter().map(|v| Window::full(v.camera())).collect();
    let Ok(mut objective) = Objective::new(views, &windows, size, settings) else {
        return f64::NAN;
    };
    // A pose slightly off the truth, as during a fit.
    let p = Pose {
        translation: pose.translation + glam::DVec3::splat(0.01),
        ..*pose
    };
    let _ = objective.value_and_gradient(mesh, &p); // warm the buffers
    let mut times: Vec<f64> = (0..reps)
        .map(|_| {
            let t = Instant::now();
            let _ = std::hint::black_box(objective.value_and_gradient(mesh, &p));
            t.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    times.sort_by(f64::total_cmp);
    times[times.len() / 2]
}

fn print_rows(rows: &[Row], json: bool) {
    if json {
        for r in rows {
            let mut v = serde_json::json!({
                "mesh": r.mesh, "triangles": r.triangles, "views": r.views, "size": r.size,
                "sigma": r.sigma, "fwd_bwd_ms": r.fwd_bwd_ms,
            });
            if let Some(s) = r.fit_s {
                v["fit_s"] = s.into();
            }
            if let Some(s) = r.fit_add_rel {
                v["fit_add_rel"] = s.into();
            }
            if let Some(s) = r.fit_iou {
                v["fit_iou"] = s.into();
            }
            println!("{v}");
        }
        return;
    }
    println!(
        "{:<28} {:>9} {:>5} {:>6} {:>7} {:>12} {:>8} {:>9}",
        "mesh", "triangles", "views", "size", "sigma", "fwd+bwd ms", "fit s", "fit ADD"
    );
    for r in rows {
        let fit = r.fit_s.map_or("-".to_string(), |s| format!("{s:.2}"));
        let add = r.fit_add_rel.map_or("-".to_string(), |s| format!("{:.2}%", 100.0 * s));
        let iou = r.fit_iou.map_or("-".to_string(), |s| format!("{s:.4}"));
        println!(
            "{:<28} {:>9} {:>5} {:>6} {:>7.3} {:>12.3} {:>8} {:>9} {:>8}",
            r.mesh, r.triangles, r.views, r.size, r.sigma, r.fwd_bwd_ms, fit, add, iou
        );
    }
}
