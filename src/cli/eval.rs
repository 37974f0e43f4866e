//! `localisebot eval DIR… --out REPORT_DIR [--jobs N]`: fits every scene that has a
//! `ground_truth_pose`, re-fits each with its first 1…N views, and writes the paper's
//! figures — `report.md`, `report.json` and SVG plots (plotters).

use super::files::{load_masked_scene_file, to_json, write, CliResult};
use super::fit::FitOptions;
use indicatif::{ProgressBar, ProgressStyle};
use localisebot::app::eval::{accuracy_measure, report_markdown, summarise, SceneOutcome, Summary};
use localisebot::app::grasp;
use localisebot::symmetry::{closest_equivalent, symmetries};
use localisebot::{Estimator, FitSettings};
use localisebot::{Pose, Scene};
use plotters::prelude::*;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::Instant;

/// Arguments of `eval`.
#[derive(clap::Args)]
pub struct EvalArgs {
    /// Scene folders, or folders of scene folders.
    #[arg(required = true)]
    dirs: Vec<PathBuf>,
    /// Output folder for report.md, report.json and the plots.
    #[arg(long)]
    out: PathBuf,
    /// Scenes fitted in parallel.
    #[arg(long, default_value_t = 1)]
    jobs: usize,
    /// Skip the re-fits with 1…N views (the loss-against-views figure).
    #[arg(long)]
    no_views_curve: bool,
    #[command(flatten)]
    options: FitOptions,
}

/// Runs `eval`.
pub fn run(a: &EvalArgs) -> CliResult {
    let settings = a.options.settings()?;
    let scenes = discover(&a.dirs)?;
    if scenes.is_empty() {
        return Err("no scene.json found in the given folders".into());
    }
    let bar = ProgressBar::new(scenes.len() as u64);
    bar.set_style(
        ProgressStyle::with_template("{spinner} {elapsed_precise} [{bar:30}] {pos}/{len} {msg}")
            .expect("the template is valid")
            .progress_chars("=> "),
    );
    let next = AtomicUsize::new(0);
    let results: Mutex<Vec<Option<CliResult<Option<SceneOutcome>>>>> = Mutex::new(vec![None; scenes.len()]);
    std::thread::scope(|s| {
        for _ in 0..a.jobs.clamp(1, 64) {
            s.spawn(|| loop {
                let i = next.fetch_add(1, Ordering::SeqCst);
                if i >= scenes.len() {
                    break;
                }
                let r = evaluate_scene(&scenes[i], &settings, !a.no_views_curve);
                bar.inc(1);
                bar.set_message(scenes[i].display().to_string());
                results.lock().expect("no worker panics while holding the lock")[i] = Some(r);
            });
        }
    });
    bar.finish_and_clear();
    let mut outcomes = Vec::new();
    for (path, r) in scenes.iter().zip(results.into_inner().expect("workers are done")) {
        match r.expect("every scene was evaluated") {
            Ok(Some(o)) => outcomes.push(o),
            Ok(None) => eprintln!("warning: {}: no ground_truth_pose; skipped", path.display()),
            Err(e) => return Err(e),
        }
    }
    if outcomes.is_empty() {
        return Err("none of the scenes has a ground_truth_pose".into());
    }
    let summary = summarise(&outcomes);
    let md = report_markdown(&summary, &outcomes);
    write(&a.out.join("report.md"), md.as_bytes())?;
    let json = serde_json::json!({ "summary": summary, "scenes": outcomes });
    write(&a.out.join("report.json"), to_json(&json).as_bytes())?;
    plot_views(&summary, &a.out.join("loss_vs_views.svg"))?;
    plot_errors(&outcomes, &a.out.join("errors.svg"))?;
    print_table(&summary);
    eprintln!("wrote {}", a.out.join("report.md").display());
    Ok(())
}

/// Scene files: each folder holding scene.json, or each sub-folder that does.
fn discover(dirs: &[PathBuf]) -> CliResult<Vec<PathBuf>> {
    let mut out = Vec::new();
    for d in dirs {
        if d.is_file() {
            out.push(d.clone());
        } else if d.join("scene.json").is_file() {
            out.push(d.join("scene.json"));
        } else {
            let mut subs: Vec<PathBuf> = std::fs::read_dir(d)
                .map_err(|e| format!("{}: cannot list: {e}", d.display()))?
                .filter_map(|e| Some(e.ok()?.path().join("scene.json")))
                .filter(|p| p.is_file())
                .collect();
            subs.sort();
            if subs.is_empty() {
                return Err(format!("{}: no scene.json in it or in its sub-folders", d.display()));
            }
            out.extend(subs);
        }
    }
    Ok(out)
}

fn scene_name(path: &Path) -> String {
    path.parent()
        .and_then(|p| p.file_name())
        .map_or_else(|| path.display().to_string(), |n| n.to_string_lossy().into())
}

fn fit(scene: &Scene, views: usize, settings: &FitSettings) -> CliResult<(Estimator, f64)> {
    let start = Instant::now();
    let mut est = Estimator::new(
        scene.mesh.clone(),
        scene.views[..views].to_vec(),
        scene.initial_pose,
        settings.clone(),
    )
    .map_err(|e| e.to_string())?;
    est.run(usize::MAX).map_err(|e| e.to_string())?;
    Ok((est, start.elapsed().as_secs_f64()))
}

fn evaluate_scene(path: &Path, settings: &FitSettings, curve: bool) -> CliResult<Option<SceneOutcome>> {
    let scene = load_masked_scene_file(path, "eval")?;
    let Some(gt) = scene.ground_truth_pose else {
        return Ok(None);
    };
    let n = scene.views.len();
    let (est, secs) = fit(&scene, n, settings).map_err(|e| format!("{}: {e}", path.display()))?;
    // Errors allow for the object's symmetries (the result does it); grasps are
    // checked against the same equivalent of the truth.
    let result = est.result(secs, Some(&gt));
    let symmetric = result.symmetric == Some(true);
    let gt_eq = closest_equivalent(&scene.mesh, &symmetries(&scene.mesh), &est.pose(), &gt);
    let predicted_area = est
        .view_figures(&est.pose())
        .iter()
        .map(|f| f.rendered.area())
        .collect();
    let (grasps_correct, grasps_total) = grasp_accuracy(&scene, &est.pose(), &gt_eq);
    let mut loss_by_views = Vec::new();
    let mut add_rel_by_views = Vec::new();
    if curve {
        for k in 1..=n {
            let refit = if k == n { None } else { Some(fit(&scene, k, settings)?) };
            let r = match &refit {
                Some((est_k, s)) => est_k.result(*s, Some(&gt)),
                None => result.clone(),
            };
            loss_by_views.push(r.loss_history.last().copied().unwrap_or(f64::NAN));
            let tmp = SceneOutcome {
                name: String::new(),
                views: k,
                symmetric,
                result: r,
                predicted_area: vec![],
                grasps_correct: 0,
                grasps_total: 0,
                loss_by_views: vec![],
                add_rel_by_views: vec![],
            };
            add_rel_by_views.push(accuracy_measure(&tmp));
        }
    }
    Ok(Some(SceneOutcome {
        name: scene_name(path),
        views: n,
        symmetric,
        result,
        predicted_area,
        grasps_correct,
        grasps_total,
        loss_by_views,
        add_rel_by_views,
    }))
}

/// Grasps transferred with the estimated pose vs the true pose, checked in every view
/// where the true grasp's rectangle is in front of the camera: (correct, checked).
fn grasp_accuracy(scene: &Scene, est: &Pose, gt: &Pose) -> (usize, usize) {
    let mut correct = 0;
    let mut total = 0;
    for g in &scene.grasps {
        for v in &scene.views {
            if let Some(ok) = grasp::grasp_transfer_correct(g, est, gt, v.camera()) {
                total += 1;
                correct += ok as usize;
            }
        }
    }
    (correct, total)
}

fn print_table(s: &Summary) {
    println!("IoU >  precision  recall     F1");
    for r in &s.prf {
        println!("{:5}  {:9.3}  {:6.3}  {:5.3}", r.threshold, r.precision, r.recall, r.f1);
    }
    println!(
        "ADD(-S) < 10% of diameter: {:.1}% of {} scenes",
        100.0 * s.add_accuracy,
        s.scenes
    );
    println!(
        "median rotation {:.2} deg, scale error {:.2}%, ADD(-S) {:.2}% of diameter",
        s.median_rotation_deg,
        100.0 * s.median_scale_error,
        100.0 * s.median_add_rel
    );
    if let Some(g) = s.grasp_accuracy {
        println!("grasp accuracy: {:.1}%", 100.0 * g);
    }
}

fn plot_err<E: std::fmt::Debug>(path: &Path) -> impl Fn(E) -> String + '_ {
    move |e| format!("{}: cannot draw the plot: {e:?}", path.display())
}

fn plot_views(s: &Summary, path: &Path) -> CliResult {
    let pts: Vec<(f64, f64)> = s
        .loss_by_views
        .iter()
        .filter(|p| p.1.is_finite())
        .map(|p| (p.0 as f64, p.1))
        .collect();
    let add: Vec<(f64, f64)> = s
        .add_rel_by_views
        .iter()
        .filter(|p| p.1.is_finite())
        .map(|p| (p.0 as f64, 100.0 * p.1))
        .collect();
    let e = plot_err(path);
    let root = SVGBackend::new(path, (720, 360)).into_drawing_area();
    root.fill(&WHITE).map_err(&e)?;
    let (left, right) = root.split_horizontally(360);
    let max_v = pts.iter().map(|p| p.0).fold(1.0, f64::max) + 0.5;
    let max_l = pts.iter().map(|p| p.1).fold(1e-6, f64::max) * 1.1;
    let mut c = ChartBuilder::on(&left)
        .caption("Final loss against views", ("sans-serif", 16))
        .margin(10)
        .x_label_area_size(35)
        .y_label_area_size(55)
        .build_cartesian_2d(0.5..max_v, 0.0..max_l)
        .map_err(&e)?;
    c.configure_mesh()
        .x_desc("views used")
        .y_desc("mean final loss")
        .draw()
        .map_err(&e)?;
    c.draw_series(LineSeries::new(pts.clone(), &BLUE)).map_err(&e)?;
    c.draw_series(pts.iter().map(|p| Circle::new(*p, 4, BLUE.filled())))
        .map_err(&e)?;
    let max_a = add.iter().map(|p| p.1).fold(1.0, f64::max) * 1.1;
    let mut c = ChartBuilder::on(&right)
        .caption("ADD(-S) against views", ("sans-serif", 16))
        .margin(10)
        .x_label_area_size(35)
        .y_label_area_size(55)
        .build_cartesian_2d(0.5..max_v, 0.0..max_a)
        .map_err(&e)?;
    c.configure_mesh()
        .x_desc("views used")
        .y_desc("mean ADD(-S), % of diameter")
        .draw()
        .map_err(&e)?;
    c.draw_series(LineSeries::new(add.clone(), &RED)).map_err(&e)?;
    c.draw_series(add.iter().map(|p| Circle::new(*p, 4, RED.filled())))
        .map_err(&e)?;
    root.present().map_err(&e)?;
    Ok(())
}

/// Cumulative accuracy curves: the fraction of scenes whose error is below x.
fn plot_errors(outcomes: &[SceneOutcome], path: &Path) -> CliResult {
    let e = plot_err(path);
    let cumulative = |mut v: Vec<f64>| -> Vec<(f64, f64)> {
        v.retain(|x| x.is_finite());
        v.sort_by(f64::total_cmp);
        let n = v.len().max(1) as f64;
        v.iter().enumerate().map(|(i, x)| (*x, (i + 1) as f64 / n)).collect()
    };
    let add = cumulative(outcomes.iter().map(|o| 100.0 * accuracy_measure(o)).collect());
    let rot = cumulative(
        outcomes
            .iter()
            .filter_map(|o| o.result.errors.as_ref().map(|e| e.rotation_deg))
            .collect(),
    );
    let root = SVGBackend::new(path, (720, 360)).into_drawing_area();
    root.fill(&WHITE).map_err(&e)?;
    let (left, right) = root.split_horizontally(360);
    for (area, data, title, xdesc, xmax) in [
        (&left, &add, "ADD(-S) accuracy", "ADD(-S), % of diameter", 20.0),
        (&right, &rot, "Rotation accuracy", "rotation error, degrees", 20.0),
    ] {
        let mut c = ChartBuilder::on(area)
            .caption(title, ("sans-serif", 16))
            .margin(10)
            .x_label_area_size(35)
            .y_label_area_size(45)
            .build_cartesian_2d(0.0..xmax, 0.0..1.0)
            .map_err(&e)?;
        c.configure_mesh()
            .x_desc(xdesc)
            .y_desc("fraction of scenes")
            .draw()
            .map_err(&e)?;
        let mut steps = vec![(0.0, 0.0)];
        for (x, y) in data.iter() {
            let x = x.min(xmax);
            steps.push((x, steps.last().map_or(0.0, |p| p.1)));
            steps.push((x, *y));
        }
        steps.push((xmax, steps.last().map_or(0.0, |p| p.1)));
        c.draw_series(LineSeries::new(steps, &BLUE)).map_err(&e)?;
    }
    root.present().map_err(&e)?;
    Ok(())
}
