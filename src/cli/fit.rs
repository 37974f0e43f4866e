//! `localisebot fit SCENE --out RESULT [--overlays DIR]`: the whole pipeline on a
//! scene file, with a progress bar on a terminal (quiet otherwise).

use super::files::{load_pose, load_scene_file, to_json, write, CliResult};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use localisebot::estimator::{Estimator, FitSettings, Phase, ScaleMode};
use localisebot::io::png::encode_rgba;
use localisebot::optim::search::Sampling;
use localisebot::overlay;
use localisebot::refine::Optimiser;
use std::path::PathBuf;
use std::time::Instant;

/// Options shared by `fit` and `eval`.
#[derive(Args, Clone, Debug)]
pub struct FitOptions {
    /// Orientation candidates: `uniform:N` (default uniform:512) or the paper's grid `euler:K` (K³ candidates).
    #[arg(long, default_value = "uniform:512")]
    pub search: String,
    /// How many of the best search candidates to refine.
    #[arg(long, default_value_t = 4)]
    pub keep: usize,
    /// Weight λ1 of the IoU loss (stages using Adam; LM stages fit the pixel residuals).
    #[arg(long, default_value_t = 1.0)]
    pub lambda_iou: f64,
    /// Weight λ2 of the contour (Hausdorff) loss (stages using Adam).
    #[arg(long)]
    pub lambda_contour: Option<f64>,
    /// Optimiser of the refinement stages: adam, or lm (Levenberg–Marquardt).
    #[arg(long)]
    pub optimiser: Option<String>,
    /// Scale: anisotropic (9-DoF), isotropic, or fixed (the CAD model is to scale).
    #[arg(long, default_value = "anisotropic")]
    pub scale: String,
}

impl FitOptions {
    /// The core settings these options describe.
    pub fn settings(&self) -> CliResult<FitSettings> {
        let mut s = FitSettings::default();
        let (kind, n) = self.search.split_once(':').ok_or_else(|| bad_search(&self.search))?;
        let n: usize = n.parse().map_err(|_| bad_search(&self.search))?;
        s.search.sampling = match kind {
            "uniform" if (1..=100_000).contains(&n) => Sampling::Uniform(n),
            "euler" if (1..=64).contains(&n) => Sampling::EulerGrid(n),
            _ => return Err(bad_search(&self.search)),
        };
        s.search.keep = self.keep.max(1);
        s.lambda_iou = self.lambda_iou;
        if let Some(l) = self.lambda_contour {
            s.lambda_contour = l;
        }
        s.scale_mode = match self.scale.as_str() {
            "anisotropic" => ScaleMode::Anisotropic,
            "isotropic" => ScaleMode::Isotropic,
            "fixed" => ScaleMode::Fixed,
            o => return Err(format!("--scale: expected anisotropic, isotropic or fixed, got '{o}'")),
        };
        if let Some(o) = &self.optimiser {
            let o = match o.as_str() {
                "adam" => Optimiser::Adam,
                "lm" => Optimiser::LevenbergMarquardt,
                o => return Err(format!("--optimiser: expected adam or lm, got '{o}'")),
            };
            s.stages.iter_mut().for_each(|st| st.optimiser = o);
        }
        s.validate().map_err(|e| e.to_string())?;
        Ok(s)
    }
}

fn bad_search(s: &str) -> String {
    format!("--search: expected uniform:N (1..100000) or euler:K (1..64), got '{s}'")
}

/// Arguments of `fit`.
#[derive(Args)]
pub struct FitArgs {
    /// The scene file.
    scene: PathBuf,
    /// Where to write the result JSON.
    #[arg(long)]
    out: PathBuf,
    /// Folder for one overlay PNG per view at the estimated pose.
    #[arg(long)]
    overlays: Option<PathBuf>,
    /// Start from this pose instead of searching (overrides the scene's initial_pose).
    #[arg(long)]
    initial_pose: Option<PathBuf>,
    #[command(flatten)]
    options: FitOptions,
}

/// Runs `fit`.
pub fn run(a: &FitArgs) -> CliResult {
    let settings = a.options.settings()?;
    let scene = load_scene_file(&a.scene)?;
    if scene.views.len() == 1 {
        eprintln!(
            "warning: {}: only one view: depth and scale cannot be told apart from one view",
            a.scene.display()
        );
    }
    let initial = match &a.initial_pose {
        Some(p) => Some(load_pose(p)?),
        None => scene.initial_pose,
    };
    let start = Instant::now();
    let mut est = Estimator::new(scene.mesh.clone(), scene.views.clone(), initial, settings)
        .map_err(|e| format!("{}: {e}", a.scene.display()))?;
    let bar = ProgressBar::new(100);
    bar.set_style(
        ProgressStyle::with_template("{spinner} {elapsed_precise} [{bar:30}] {msg}")
            .expect("the template is valid")
            .progress_chars("=> "),
    );
    let mut search_s = 0.0;
    let mut stage_s = vec![0.0; est.settings().stages.len()];
    let mut last = Instant::now();
    while !est.is_done() {
        let before = est.progress_phase();
        let p = est.step();
        let now = Instant::now();
        match before {
            (Phase::Search, _) => search_s += (now - last).as_secs_f64(),
            (_, stage) => stage_s[stage] += (now - last).as_secs_f64(),
        }
        last = now;
        match p.phase {
            Phase::Search => {
                bar.set_position((30 * p.searched / p.search_total.max(1)) as u64);
                bar.set_message(format!("search {}/{}", p.searched, p.search_total));
            }
            Phase::Refine | Phase::Done => {
                let stages = est.settings().stages.len();
                bar.set_position(30 + (70 * p.stage / stages.max(1)) as u64);
                bar.set_message(format!(
                    "refine stage {}/{} candidate {} iter {} loss {:.5}",
                    p.stage + 1,
                    stages,
                    p.candidate + 1,
                    p.iteration,
                    p.loss
                ));
            }
        }
    }
    let seconds = start.elapsed().as_secs_f64();
    bar.finish_and_clear();
    // A symmetric object's pose is known up to its symmetries: errors are measured
    // against the equivalent of the truth closest to the estimate.
    let truth = scene.ground_truth_pose.map(|gt| {
        let syms = localisebot::eval::symmetries(&scene.mesh);
        localisebot::eval::closest_equivalent(&scene.mesh, &syms, &est.pose(), &gt)
    });
    let result = est.result(seconds, truth.as_ref());
    write(&a.out, to_json(&result).as_bytes())?;
    if let Some(dir) = &a.overlays {
        let pose = est.pose();
        for (v, (_, _, m)) in scene.views.iter().zip(est.view_figures(&pose)) {
            let mut img = overlay::overlay(v, Some(&m));
            localisebot::grasp::draw_grasps(&mut img, &scene.grasps, &pose, &v.camera);
            write(&dir.join(format!("{}.png", v.name)), &encode_rgba(&img))?;
        }
    }
    let mut line = format!(
        "{}: mean IoU {:.4} in {:.2} s (search {:.2} s, stages {} s; {} iterations, {:?})",
        a.out.display(),
        result.mean_iou,
        seconds,
        search_s,
        stage_s.iter().map(|s| format!("{s:.2}")).collect::<Vec<_>>().join("/"),
        result.iterations,
        result.termination
    );
    if let Some(e) = &result.errors {
        line += &format!(
            "; rotation error {:.2}°, ADD {:.2}% of diameter",
            e.rotation_deg,
            100.0 * e.add_rel
        );
    }
    eprintln!("{line}");
    Ok(())
}
