//! Fit a scene file from Rust, as `localisebot fit` does, printing each stage as it
//! starts and the result's pose, figures and uncertainty.
//!
//! ```text
//! cargo run --release --example fit_scene -- www/examples/toy/scene.json
//! ```
//!
//! The library reads no files itself: [`load_scene`] takes the scene's text and a
//! resolver that returns the bytes of each file the scene names (the path as written,
//! joined onto the scene file's folder).

use localisebot::{load_scene, Estimator, FitSettings, Phase};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = std::env::args().nth(1).ok_or("usage: fit_scene SCENE.json")?;
    let text = std::fs::read_to_string(&path).map_err(|e| format!("{path}: {e}"))?;
    // The resolver is asked for paths already joined onto the scene file's folder.
    let scene = load_scene(&path, &text, &|p| std::fs::read(p).ok())?;
    println!(
        "{path}: {} views, mesh of {} triangles",
        scene.views.len(),
        scene.mesh.triangles.len()
    );

    let mut fit = Estimator::new(scene.mesh, scene.views, scene.initial_pose, FitSettings::default())?;
    let started = std::time::Instant::now();
    let mut shown = None;
    while !fit.is_done() {
        let p = fit.step()?;
        if shown != Some((p.phase, p.stage)) && p.phase != Phase::Done {
            println!("  {:?} stage {} (iteration {})", p.phase, p.stage, p.iteration);
            shown = Some((p.phase, p.stage));
        }
    }
    let r = fit.result(started.elapsed().as_secs_f64(), scene.ground_truth_pose.as_ref());
    println!(
        "verdict {} in {:.2} s, {} iterations; mean IoU {:.4}",
        r.verdict.map_or("none", |v| v.as_str()),
        r.seconds,
        r.iterations,
        r.mean_iou
    );
    println!(
        "translation {:?}, euler XYZ {:?}°",
        r.pose.translation, r.pose.euler_xyz_deg
    );
    if let Some(s) = &r.std_dev {
        println!(
            "95 % of poses within ADD {:.3e} (diameter {:.3e})",
            s.add_95, s.diameter
        );
    }
    if let Some(e) = &r.errors {
        println!(
            "against the ground truth: rotation {:.3}°, ADD {:.3} % of the diameter",
            e.rotation_deg,
            100.0 * e.add_rel
        );
    }
    Ok(())
}
