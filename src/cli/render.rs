//! `localisebot render SCENE --pose POSE --out DIR`: one overlay PNG per view (the
//! image or mask, the mask outline, the contour rendered at the pose and the scene's
//! grasp rectangles), and each view's grasp rectangles as an OCID/Cornell `.txt`.

use super::files::{load_masked_scene_file, load_pose, write, CliResult};
use localisebot::app::{grasp, overlay};
use localisebot::io::png::encode_rgba;
use localisebot::{metrics, raster::hard};
use std::path::Path;

/// Runs `render`.
pub fn run(scene: &Path, pose: &Path, out: &Path) -> CliResult {
    let scene = load_masked_scene_file(scene, "render")?;
    let pose = load_pose(pose)?;
    for v in &scene.views {
        let rendered = hard::render_checked(v.name(), &scene.mesh, &pose, v.camera()).map_err(|e| e.to_string())?;
        let mut img = overlay::overlay(v, Some(&rendered));
        grasp::draw_grasps(&mut img, &scene.grasps, &pose, v.camera());
        let path = out.join(format!("{}.png", v.name()));
        write(&path, &encode_rgba(&img))?;
        if !scene.grasps.is_empty() {
            let rects = grasp::rectangles(&scene.grasps, &pose, v.camera());
            write(
                &out.join(format!("{}.grasps.txt", v.name())),
                grasp::rectangles_to_txt(&rects).as_bytes(),
            )?;
        }
        println!(
            "{}: IoU {:.4} -> {}",
            v.name(),
            metrics::hard_iou_known(&rendered, v.mask(), v.ignore()),
            path.display()
        );
    }
    Ok(())
}
