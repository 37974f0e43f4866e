//! Build a scene in code and fit it: three cameras placed around a table, the masks a
//! perfect segmenter would give, then the fit from no initial pose.
//!
//! ```text
//! cargo run --release --example build_scene
//! ```
//!
//! With your own data, each view is a [`Camera`] (intrinsics and `world_to_camera`, as
//! in a scene file's camera object) and a [`Mask`] of the same size (object pixels 1);
//! the mesh is any [`Mesh`] — here the project's toy aeroplane.

use glam::{DMat3, DVec3};
use localisebot::app::{shapes, synth};
use localisebot::{metrics, Camera, CameraJson, Estimator, FitSettings, Pose, View, ViewSources};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mesh = shapes::toy_plane(); // 0.32 m long, model frame, metres
                                    // Where the object really is (the fit does not see this).
    let truth = Pose {
        rotation: DMat3::from_rotation_z(0.6) * DMat3::from_rotation_x(-0.3),
        translation: DVec3::new(0.05, -0.02, 0.0),
        scale: DVec3::ONE,
    };
    // Cameras 0.9 m from the table's centre, looking at it, 640×480, f = 600 px.
    let eyes = [
        DVec3::new(0.9, 0.0, 0.4),
        DVec3::new(-0.4, 0.8, 0.5),
        DVec3::new(-0.3, -0.8, 0.6),
    ];
    let mut views = Vec::new();
    for (i, eye) in eyes.iter().enumerate() {
        let camera = Camera::look_at(*eye, DVec3::ZERO, DVec3::Z, 640, 480, 600.0);
        // The camera in the scene file's form: what you would write in `scene.json`.
        if i == 0 {
            println!(
                "view0's camera: {}",
                serde_json::to_string(&CameraJson::from_camera(&camera))?
            );
        }
        let mask = synth::render_mask(&mesh, &truth, &camera);
        views.push(View::new(
            &format!("view{i}"),
            camera,
            mask,
            None,
            None,
            &ViewSources::default(),
        )?);
    }

    let mut fit = Estimator::new(mesh.clone(), views, None, FitSettings::default())?;
    let progress = fit.run(usize::MAX)?;
    let result = fit.result(0.0, Some(&truth));
    let errors = metrics::pose_errors(&mesh, &fit.pose(), &truth);
    println!(
        "{} after {} iterations: verdict {}, rotation error {:.3}°, ADD {:.3} % of the diameter",
        progress.termination.map_or("not finished", |t| t.describe()),
        progress.iteration,
        result.verdict.map_or("none", |v| v.as_str()),
        errors.rotation_deg,
        100.0 * errors.add_rel
    );
    println!(
        "translation {:?} (true {:?})",
        fit.pose().translation.to_array(),
        truth.translation.to_array()
    );
    if errors.add_rel > 0.01 {
        return Err(format!("the fit is off by {:.2} % of the diameter", 100.0 * errors.add_rel).into());
    }
    Ok(())
}
