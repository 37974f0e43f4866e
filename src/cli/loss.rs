//! `localisebot loss SCENE --pose POSE [--sigma S] [--size N]`: the multi-view loss,
//! per-view losses and the 9-gradient at a pose, as JSON — the teaching and
//! debugging view of the code the fit descends.

use super::files::{load_pose, load_scene_file, to_json, CliResult};
use localisebot::refine::{RefineTarget, StageSettings};
use std::path::PathBuf;

/// Arguments of `loss`.
#[derive(clap::Args)]
pub struct LossArgs {
    /// The scene file.
    scene: PathBuf,
    /// The pose file.
    #[arg(long)]
    pose: PathBuf,
    /// σ of the soft silhouette, pixel² at the evaluated size.
    #[arg(long, default_value_t = 1.0)]
    sigma: f64,
    /// Longest image side at which to evaluate (default: the views' own size).
    #[arg(long)]
    size: Option<u32>,
    /// Weight λ1 of the IoU term.
    #[arg(long, default_value_t = 1.0)]
    lambda_iou: f64,
    /// Weight λ2 of the contour term.
    #[arg(long, default_value_t = 0.0)]
    lambda_contour: f64,
}

/// Runs `loss`.
pub fn run(a: &LossArgs) -> CliResult {
    if !(a.sigma > 0.0 && a.sigma.is_finite()) {
        return Err(format!("--sigma must be a positive number, got {}", a.sigma));
    }
    let scene = load_scene_file(&a.scene)?;
    let pose = load_pose(&a.pose)?;
    let size = a.size.unwrap_or_else(|| {
        scene
            .views
            .iter()
            .map(|v| v.camera.width.max(v.camera.height))
            .max()
            .unwrap_or(8)
    });
    if size < 8 {
        return Err(format!("--size must be at least 8, got {size}"));
    }
    let stage = StageSettings {
        resolution: size,
        sigma: a.sigma,
        iterations: 1,
        lr_start: 1.0,
        lr_end: 1.0,
        keep: 1,
        contour: a.lambda_contour > 0.0,
        optimiser: localisebot::refine::Optimiser::Adam,
    };
    let mut target = RefineTarget::new(&scene.views, &stage, a.lambda_iou, a.lambda_contour);
    let per_view: Vec<_> = (0..target.view_count())
        .map(|i| target.view_loss_and_gradient(i, &scene.mesh, &pose))
        .collect();
    let (loss, grad) = target.loss_and_gradient(&scene.mesh, &pose);
    let out = serde_json::json!({
        "loss": loss,
        "gradient": grad,
        "gradient_order": ["omega_x", "omega_y", "omega_z", "t_x", "t_y", "t_z", "log_s_x", "log_s_y", "log_s_z"],
        "gradient_meaning": "d loss / d parameter at the pose: omega is a rotation applied on the right (R <- R exp([omega]x), radians, model axes), t the world translation, log_s the log of each model-axis scale",
        "views": scene.views.iter().zip(&per_view).map(|(v, (l, g))| serde_json::json!({
            "name": v.name, "loss": l, "gradient": g,
        })).collect::<Vec<_>>(),
        "sigma_px2": a.sigma,
        "size": size,
        "lambda_iou": a.lambda_iou,
        "lambda_contour": a.lambda_contour,
    });
    println!("{}", to_json(&out));
    Ok(())
}
