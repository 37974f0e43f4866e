//! `localisebot loss SCENE --pose POSE [--sigma S] [--size N]`: the multi-view loss,
//! per-view losses and the 9-gradient at a pose, as JSON — the teaching and
//! debugging view of the objective the fit descends (the same `Objective`, the
//! same defaults for λ1 and λ2).

use super::files::{load_pose, load_scene_file, to_json, CliResult};
use localisebot::loss::objective::{Objective, ObjectiveSettings};
use localisebot::raster::silhouette::RenderMesh;
use localisebot::raster::silhouette::SoftSettings;
use localisebot::FitSettings;
use localisebot::Window;
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
    /// Weight λ1 of the soft IoU term (default: the fit's, 1).
    #[arg(long)]
    lambda_iou: Option<f64>,
    /// Weight λ2 of the contour (chamfer-type mean distance) term (default: the fit's, 1).
    #[arg(long)]
    lambda_contour: Option<f64>,
    /// The soft rasteriser (default: the fit's, edge).
    #[arg(long, value_enum)]
    raster: Option<super::fit::RasterArg>,
}

/// Runs `loss`.
pub fn run(a: &LossArgs) -> CliResult {
    let scene = load_scene_file(&a.scene)?;
    let pose = load_pose(&a.pose)?;
    let size = a.size.unwrap_or_else(|| {
        scene
            .views
            .iter()
            .map(|v| v.camera().width.max(v.camera().height))
            .max()
            .unwrap_or(8)
    });
    if size < 8 {
        return Err(format!("--size must be at least 8, got {size}"));
    }
    let defaults = FitSettings::default();
    let settings = ObjectiveSettings {
        soft: SoftSettings {
            sigma: a.sigma,
            eps: 1e-4,
        },
        lambda_iou: a.lambda_iou.unwrap_or(defaults.lambda_iou),
        lambda_contour: a.lambda_contour.unwrap_or(defaults.lambda_contour),
        lambda_region: 0.0,
        raster: a.raster.map_or(defaults.raster, |r| r.kind()),
    };
    let windows: Vec<Window> = scene.views.iter().map(|v| Window::full(v.camera())).collect();
    let mut objective = Objective::new(&scene.views, &windows, size, settings).map_err(|e| e.to_string())?;
    let model = RenderMesh::new(scene.mesh.clone());
    let ev = objective.value_and_gradient(&model, &pose).map_err(|e| e.to_string())?;
    let out = serde_json::json!({
        "loss": ev.total,
        "gradient": ev.gradient,
        "gradient_order": ["omega_x", "omega_y", "omega_z", "t_x", "t_y", "t_z", "log_s_x", "log_s_y", "log_s_z"],
        "gradient_meaning": "d loss / d parameter at the pose: omega is a rotation applied on the right (R <- R exp([omega]x), radians, model axes), t the world translation, log_s the log of each model-axis scale",
        "loss_meaning": "mean over views of lambda_iou * (1 - soft IoU) + lambda_contour * contour, the contour term a chamfer-type mean distance to the mask's contour (see src/loss/contour.rs)",
        "views": scene.views.iter().zip(&ev.views).map(|(v, l)| serde_json::json!({
            "name": v.name(), "loss": l.total, "iou_loss": l.iou, "contour": l.contour,
        })).collect::<Vec<_>>(),
        "raster": settings.raster,
        "sigma_px2": a.sigma,
        "size": size,
        "lambda_iou": settings.lambda_iou,
        "lambda_contour": settings.lambda_contour,
    });
    println!("{}", to_json(&out));
    Ok(())
}
