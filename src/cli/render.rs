//! `localisebot render SCENE --pose POSE --out DIR`: one overlay PNG per view (the
//! image or mask, the mask outline and the contour rendered at the pose).

use super::files::{load_pose, load_scene_file, write, CliResult};
use localisebot::io::png::encode_rgba;
use localisebot::{metrics, overlay, raster::hard};
use std::path::Path;

/// Runs `render`.
pub fn run(scene: &Path, pose: &Path, out: &Path) -> CliResult {
    let scene = load_scene_file(scene)?;
    let pose = load_pose(pose)?;
    for v in &scene.views {
        let rendered = hard::render_checked(&v.name, &scene.mesh, &pose, &v.camera).map_err(|e| e.to_string())?;
        let img = overlay::overlay(v, Some(&rendered));
        let path = out.join(format!("{}.png", v.name));
        write(&path, &encode_rgba(&img))?;
        println!("{}: IoU {:.4} -> {}", v.name, metrics::hard_iou(&rendered, &v.mask), path.display());
    }
    Ok(())
}
