//! `localisebot suggest-view SCENE RESULT [--candidates CAMERAS.json | --viewpoints
//! above] [--top K]`: the next photograph to take. Ranks candidate cameras (default: 64
//! viewpoints on a sphere around the object at the views' mean distance, looking at it,
//! with view 0's intrinsics; `--viewpoints above`: on the sphere's upper half, along the
//! views' mean image-up) by the predicted pose uncertainty after adding a photograph from there
//! (`localisebot::uncertainty::next_view`), prints the best K on standard output as a
//! JSON list of camera objects in the scene file's form (best first, ready to add to
//! the scene), and their predicted figures on standard error.

use super::files::{load_masked_scene_file, load_pose, read_text, to_json, CliResult};
use super::fit::ScaleArg;
use clap::Args;
use localisebot::uncertainty::Viewpoints;
use localisebot::{Camera, CameraJson, FitResult, FitSettings, FitSetup, Pose, ScaleMode};
use std::path::{Path, PathBuf};

/// `suggest-view`'s arguments.
#[derive(Args, Debug)]
pub struct SuggestArgs {
    /// The scene file that was fitted.
    pub scene: PathBuf,
    /// The fit's result file (or a pose file): the pose to plan from, with the views
    /// weighted as the fit weighted them (a view it set aside is left out) and its
    /// scale mode.
    pub result: PathBuf,
    /// Candidate cameras: a JSON list of camera objects (scene-file form), or of
    /// objects with a "camera" key, or a scene file whose views' cameras are taken.
    #[arg(long)]
    pub candidates: Option<PathBuf>,
    /// Where the default candidates lie: the whole sphere around the object (the
    /// default), or its upper half (along the views' mean image-up: a camera over a
    /// table). Not with `--candidates`.
    #[arg(long, value_enum)]
    pub viewpoints: Option<ViewpointsArg>,
    /// How many cameras to print (default 3).
    #[arg(long, default_value_t = 3)]
    pub top: usize,
    /// The scale the fit estimated, as `fit --scale` (default: the result's; a pose
    /// file's: anisotropic): a scale that was not fitted is not uncertain, and no
    /// photograph is chosen to pin it.
    #[arg(long, value_enum)]
    pub scale: Option<ScaleArg>,
}

/// `--viewpoints`.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum ViewpointsArg {
    /// The whole sphere.
    Sphere,
    /// Its upper half.
    Above,
}

/// Runs `suggest-view`.
pub fn run(a: &SuggestArgs) -> CliResult<()> {
    let scene = load_masked_scene_file(&a.scene, "suggest-view")?;
    let pose = load_pose(&a.result)?;
    let fit = fit_of(&a.result, &scene.views)?;
    if a.candidates.is_some() && a.viewpoints.is_some() {
        return Err(
            "suggest-view: --viewpoints chooses the default candidates; it cannot be used with --candidates".into(),
        );
    }
    let given = a.candidates.is_some();
    let candidates = a.candidates.as_deref().map(load_cameras).transpose()?;
    let shell = match a.viewpoints {
        None | Some(ViewpointsArg::Sphere) => Viewpoints::Sphere,
        Some(ViewpointsArg::Above) => Viewpoints::Above,
    };
    let settings = FitSettings {
        scale_mode: match a.scale {
            Some(s) => s.mode(),
            None => fit.scale_mode,
        },
        ..FitSettings::default()
    };
    let in_scene = |e: localisebot::Error| format!("{}: {e}", a.scene.display());
    let setup = FitSetup::new(scene.mesh, scene.views, settings).map_err(in_scene)?;
    let ranked = setup
        .suggest_views(&pose, &fit.weights, &fit.alternatives, candidates.as_deref(), shell)
        .map_err(in_scene)?;
    let usable: Vec<_> = ranked.iter().filter(|r| r.predicted_add_rms.is_finite()).collect();
    if usable.is_empty() {
        return Err(format!(
            "{}: none of the {} candidate cameras sees the whole object in front of it",
            a.scene.display(),
            ranked.len()
        ));
    }
    let best: Vec<_> = usable.iter().take(a.top.max(1)).collect();
    eprintln!(
        "{} candidates ({}), {} see the whole object; expected RMS ADD now {:.4e}",
        ranked.len(),
        match (given, shell) {
            (true, _) => "given",
            (false, Viewpoints::Sphere) => "sphere",
            (false, Viewpoints::Above) => "upper half-sphere",
        },
        usable.len(),
        ranked[0].current_add_rms
    );
    if !fit.alternatives.is_empty() {
        eprintln!(
            "the fit is ambiguous ({} alternative poses): the views that tell them apart come first",
            fit.alternatives.len()
        );
    }
    for (k, r) in best.iter().enumerate() {
        let telling = r.discrimination.map_or(String::new(), |d| {
            format!(
                ", silhouettes of the fit and the most alike alternative differ by {:.0}% (1 − IoU)",
                100.0 * d
            )
        });
        eprintln!(
            "  {}. candidate {}: expected RMS ADD with it {:.4e} ({:.0}% of now), outline {:.0} px{telling}",
            k + 1,
            r.index,
            r.predicted_add_rms,
            100.0 * r.predicted_add_rms / r.current_add_rms.max(f64::MIN_POSITIVE),
            r.outline_px
        );
    }
    let out: Vec<CameraJson> = best.iter().map(|r| CameraJson::from_camera(&r.camera)).collect();
    println!("{}", to_json(&out));
    Ok(())
}

/// What `suggest-view` plans with from the fit: each view's weight, the scale mode and
/// the alternatives' poses (an `ambiguous` fit: the candidates that tell them apart
/// come first).
struct FitOf {
    weights: Vec<f64>,
    scale_mode: ScaleMode,
    alternatives: Vec<Pose>,
}

/// The views' weights and the scale mode of a result file (a pose file: every view
/// weighs 1, anisotropic scale). A result names its views; a view it does not name
/// is refused, since the result is then another scene's.
fn fit_of(path: &Path, views: &[localisebot::View]) -> CliResult<FitOf> {
    let text = read_text(path)?;
    let name = path.display();
    let value: serde_json::Value = serde_json::from_str(&text).map_err(|e| format!("{name}: {e}"))?;
    if value.get("views").is_none() {
        return Ok(FitOf {
            weights: vec![1.0; views.len()],
            scale_mode: ScaleMode::Anisotropic,
            alternatives: Vec::new(),
        });
    }
    let result: FitResult = serde_json::from_value(value).map_err(|e| format!("{name}: not a result file: {e}"))?;
    let weights = views
        .iter()
        .map(|v| {
            result
                .views
                .iter()
                .find(|r| r.name == v.name())
                .map(|r| r.weight)
                .ok_or_else(|| format!("{name}: the result has no view \"{}\" of the scene", v.name()))
        })
        .collect::<CliResult<Vec<f64>>>()?;
    let alternatives = result
        .alternatives
        .iter()
        .enumerate()
        .map(|(i, a)| {
            let json = serde_json::to_string(&a.pose).expect("serialising plain data cannot fail");
            Pose::from_json_str(&json, &format!("{name}: alternative {i}")).map_err(|e| e.to_string())
        })
        .collect::<CliResult<Vec<Pose>>>()?;
    Ok(FitOf {
        weights,
        scale_mode: result.scale_mode,
        alternatives,
    })
}

/// Cameras from a JSON list (of cameras or of objects with "camera") or a scene file.
fn load_cameras(path: &Path) -> CliResult<Vec<Camera>> {
    let name = path.display().to_string();
    let text = read_text(path)?;
    let value: serde_json::Value = serde_json::from_str(&text).map_err(|e| format!("{name}: {e}"))?;
    let list = match &value {
        serde_json::Value::Array(a) => a.clone(),
        serde_json::Value::Object(o) => match o.get("views").and_then(|v| v.as_array()) {
            Some(v) => v.clone(),
            None => return Err(format!("{name}: expected a JSON list of cameras or a scene file")),
        },
        _ => return Err(format!("{name}: expected a JSON list of cameras or a scene file")),
    };
    if list.is_empty() {
        return Err(format!("{name}: no candidate cameras"));
    }
    list.iter()
        .enumerate()
        .map(|(i, item)| {
            let cam = item.get("camera").unwrap_or(item);
            let json: CameraJson =
                serde_json::from_value(cam.clone()).map_err(|e| format!("{name}: candidate {i}: {e}"))?;
            json.to_camera(&format!("candidate {i}"))
                .map_err(|e| format!("{name}: {e}"))
        })
        .collect()
}
