//! Times what the end of a fit adds: the uncertainty (`fit_uncertainty`) and the
//! next-view ranking (64 sphere candidates), on a scene file at a pose file.
//!
//!     cargo run --release --example uncertainty_timing -- SCENE POSE

use localisebot::loss::target::Window;
use localisebot::optim::lm::Free;
use localisebot::raster::silhouette::RenderMesh;
use localisebot::uncertainty::{fit_uncertainty, rank_views, sphere_candidates, NoiseModel};
use localisebot::{load_scene, FitSettings, Pose};
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let text = std::fs::read_to_string(&args[1]).expect("the scene file");
    let scene = load_scene(&args[1], &text, &|p| std::fs::read(p).ok()).expect("the scene loads");
    let pose_text = std::fs::read_to_string(&args[2]).expect("the pose file");
    let v: serde_json::Value = serde_json::from_str(&pose_text).expect("JSON");
    let pose = Pose::from_json_str(&v.get("pose").unwrap_or(&v).to_string(), &args[2]).expect("a pose");
    let settings = FitSettings::default();
    let windows: Vec<Window> = scene
        .views
        .iter()
        .map(|w| Window::for_view(w, settings.window))
        .collect();
    let model = RenderMesh::new(scene.mesh.clone());
    let weights = vec![1.0; scene.views.len()];
    let noise = NoiseModel::default();
    let reps = 10;
    let t0 = Instant::now();
    let mut u = None;
    for _ in 0..reps {
        u = Some(
            fit_uncertainty(&model, &scene.views, &windows, &pose, &weights, Free::All, &noise).expect("measured"),
        );
    }
    let t_unc = t0.elapsed().as_secs_f64() / reps as f64;
    let u = u.expect("measured");
    let cams = sphere_candidates(&model, &scene.views, &pose, 64).expect("candidates");
    let t1 = Instant::now();
    let ranked = rank_views(&model, &pose, &u, &cams, &noise).expect("ranked");
    let t_nbv = t1.elapsed().as_secs_f64();
    println!(
        "{}: {} views, {} triangles: uncertainty {:.1} ms, ranking 64 candidates {:.1} ms (best: candidate {})",
        args[1],
        scene.views.len(),
        scene.mesh.triangles.len(),
        1e3 * t_unc,
        1e3 * t_nbv,
        ranked[0].index
    );
}
