//! `localisebot bench`: the speed figures of BENCHMARKS.md, for one soft rasteriser
//! (`--raster edge`, the default, or `softras`). Per configuration: the median
//! milliseconds of one evaluation of the fit's objective with its 9-gradient
//! (`fwd_bwd_ms`) and with its Gauss–Newton model (`gn_ms`, what one LM iteration
//! costs), over 4 views, on one thread; and the seconds of full fits from no initial
//! pose with [`FitSettings::default`] (views in parallel on the machine's cores; `--threads`
//! sets how many): the Duck at 256², the page's bundled example (the toy aeroplane,
//! built as `scripts/build-examples.sh` builds it) and a real 640×480 three-view scene
//! (Linemod-Occluded, imported from `../shared`); and, with the segmenter's weights, its
//! encoder per crop (alone, and three crops as one mosaic) and the box-to-pose fit of
//! the same three photographs (and of them enlarged to a phone's 11 MP). Or the same
//! evaluation on a given scene at a given pose.

use super::files::{load_masked_scene_file, load_mesh, load_pose, CliResult};
use localisebot::app::shapes;
use localisebot::app::synth::{blob_mesh, synthesize, SynthSettings};
use localisebot::io::bop::{self, BopOptions, BoxHints, MaskKind};
use localisebot::loss::objective::{Objective, ObjectiveSettings};
use localisebot::raster::silhouette::SoftSettings;
use localisebot::raster::silhouette::{RasterKind, RenderMesh};
use localisebot::segment::{self, PhotoFit, PhotoSettings, SamSegmenter};
use localisebot::Window;
use localisebot::{load_scene, Estimator, FitSettings, Mesh, Pose, Scene, View};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The shared third-party data, read at run time: `../shared/data` beside the repository.
const SHARED_DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/data");

/// Arguments of `bench`.
#[derive(clap::Args)]
pub struct BenchArgs {
    /// Print one JSON object per line instead of a table.
    #[arg(long)]
    json: bool,
    /// Time a given scene instead of the fixed configurations (needs --pose).
    #[arg(long, requires = "pose")]
    scene: Option<PathBuf>,
    /// The pose at which to time the scene.
    #[arg(long)]
    pose: Option<PathBuf>,
    /// σ in pixel² (default 1.0).
    #[arg(long, default_value_t = 1.0)]
    sigma: f64,
    /// Repetitions of each evaluation (the median is reported).
    #[arg(long, default_value_t = 30)]
    reps: usize,
    /// Skip the full fits (evaluation figures only).
    #[arg(long)]
    no_fit: bool,
    /// The shared data folder (meshes, the real scene; default `../shared/data`
    /// beside the repository).
    #[arg(long, default_value = SHARED_DATA)]
    data: PathBuf,
    /// The soft rasteriser to time (default edge, the fit's default).
    #[arg(long, value_enum, default_value = "edge")]
    raster: super::fit::RasterArg,
    /// Threads for the full fits (default: all cores; evaluations always use one).
    #[arg(long)]
    threads: Option<usize>,
    /// The segmenter's weights for the photograph rows (default: where
    /// scripts/setup.sh installs them, or $LOCALISEBOT_MODELS); without them those rows
    /// are left out, with a note.
    #[arg(long)]
    models: Option<PathBuf>,
}

/// One line of figures.
#[derive(Default)]
struct Row {
    name: String,
    raster: &'static str,
    threads: usize,
    triangles: usize,
    views: usize,
    size: String,
    fwd_bwd_ms: Option<f64>,
    gn_ms: Option<f64>,
    fit_s: Option<f64>,
    fit_add_rel: Option<f64>,
    fit_iou: Option<f64>,
    fit_verdict: Option<String>,
}

/// Runs `bench`.
pub fn run(a: &BenchArgs) -> CliResult {
    if !(a.sigma > 0.0 && a.sigma.is_finite()) {
        return Err(format!("--sigma must be a positive number, got {}", a.sigma));
    }
    let pool = |n: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .map_err(|e| format!("cannot start {n} threads: {e}"))
    };
    let one = pool(1)?;
    let all = pool(a.threads.unwrap_or(0))?;
    let raster = a.raster.kind();
    let mut rows = one.install(|| evaluations(a, raster))?;
    if a.scene.is_none() && !a.no_fit {
        rows.extend(all.install(|| fits(a, raster))?);
        let t0 = Instant::now();
        match super::segmenter::load(&super::segmenter::models_dir(a.models.as_deref())) {
            Ok(sam) => {
                let load_s = t0.elapsed().as_secs_f64();
                rows.extend(all.install(|| photos(a, sam, load_s))?)
            }
            Err(e) => eprintln!("note: the photograph rows are left out: {e}"),
        }
    }
    let name = raster_name(raster);
    let threads = all.current_num_threads();
    for r in &mut rows {
        r.raster = name;
        if r.fit_s.is_some() {
            r.threads = threads;
        } else {
            r.threads = 1;
        }
    }
    print_rows(&rows, a.json);
    Ok(())
}

fn raster_name(k: RasterKind) -> &'static str {
    match k {
        RasterKind::Edge => "edge",
        RasterKind::SoftRas => "softras",
    }
}

/// The evaluation figures (one thread), or those of `--scene`.
fn evaluations(a: &BenchArgs, raster: RasterKind) -> CliResult<Vec<Row>> {
    let reps = a.reps.max(1);
    let mut rows = Vec::new();
    if let Some(scene_path) = &a.scene {
        let scene = load_masked_scene_file(scene_path, "bench")?;
        let pose = load_pose(a.pose.as_ref().expect("clap requires --pose with --scene"))?;
        let size = scene
            .views
            .iter()
            .map(|v| v.camera().width.max(v.camera().height))
            .max()
            .unwrap_or(0);
        let (fwd_bwd, gn) = time_objective(&scene.mesh, &scene.views, &pose, size, a.sigma, reps, raster)?;
        rows.push(Row {
            name: scene_path.display().to_string(),
            triangles: scene.mesh.triangles.len(),
            views: scene.views.len(),
            size: size.to_string(),
            fwd_bwd_ms: Some(fwd_bwd),
            gn_ms: Some(gn),
            ..Row::default()
        });
        return Ok(rows);
    }
    let duck = load_mesh(&shared(a, "gltf/Duck/glTF-Binary/Duck.glb")?)?;
    let engine = load_mesh(&shared(a, "gltf/2CylinderEngine/glTF-Binary/2CylinderEngine.glb")?)?;
    let meshes = [
        ("blob500", blob_mesh(12, 25), true),
        ("blob2k", blob_mesh(22, 50), true),
        ("blob10k", blob_mesh(52, 100), true),
        ("duck", duck.clone(), true),
        ("2CylinderEngine", engine, false),
    ];
    for (name, mesh, both_sizes) in &meshes {
        for size in [128u32, 256] {
            if size == 256 && !both_sizes {
                continue;
            }
            let s = synthesize(
                mesh,
                &SynthSettings {
                    views: 4,
                    width: size,
                    height: size,
                    seed: 11,
                    ..Default::default()
                },
                None,
            )
            .map_err(|e| e.to_string())?;
            let (fwd_bwd, gn) = time_objective(mesh, &s.views(), &s.pose, size, a.sigma, reps, raster)?;
            rows.push(Row {
                name: name.to_string(),
                triangles: mesh.triangles.len(),
                views: 4,
                size: size.to_string(),
                fwd_bwd_ms: Some(fwd_bwd),
                gn_ms: Some(gn),
                ..Row::default()
            });
        }
    }
    Ok(rows)
}

/// A file of the shared data folder, or an error saying where it should be.
fn shared(a: &BenchArgs, rel: &str) -> CliResult<PathBuf> {
    let p = a.data.join(rel);
    if p.exists() {
        Ok(p)
    } else {
        Err(format!(
            "{}: not found: the benchmark reads meshes and the real scene from the shared data folder \
             (`shared/data`, beside the repository), or from --data DIR",
            p.display()
        ))
    }
}

/// The full fits (views in parallel on the pool's threads).
fn fits(a: &BenchArgs, raster: RasterKind) -> CliResult<Vec<Row>> {
    let mut rows = Vec::new();
    let duck = load_mesh(&shared(a, "gltf/Duck/glTF-Binary/Duck.glb")?)?;
    // The Duck at 256², 4 views.
    let s = synth_scene(&duck, 4, 256, 256, 11)?;
    rows.push(fit_row("fit: duck", &duck, s.views(), &s.pose, "256²", raster)?);
    // The page's bundled example, as scripts/build-examples.sh makes it.
    let toy = shapes::toy_plane();
    let s = synth_scene(&toy, 4, 256, 256, 7)?;
    rows.push(fit_row(
        "fit: bundled example (toy)",
        &toy,
        s.views(),
        &s.pose,
        "256²",
        raster,
    )?);
    // A real 640×480 three-view scene: the LM-O duck, as the page's real example.
    let real = real_scene(&shared(a, "real/lmo")?)?;
    let gt = real
        .ground_truth_pose
        .ok_or("the imported real scene has no ground truth")?;
    rows.push(fit_row(
        "fit: real LM-O duck",
        &real.mesh,
        real.views.clone(),
        &gt,
        "640×480",
        raster,
    )?);
    Ok(rows)
}

/// The LM-O scene 2's `object` in `images`, with boxes instead of masks as `import bop
/// --boxes --box-seed SEED` makes them, and its annotated pose.
fn lmo_boxes(lmo: &Path, object: u32, images: &[u32], seed: u64) -> CliResult<(Scene, Pose)> {
    let mut opts = BopOptions::new(2, object);
    opts.image_ids = Some(images.to_vec());
    opts.masks = MaskKind::Visible;
    opts.boxes = Some(BoxHints {
        margin: 0.1,
        jitter: 0.05,
        seed,
        views_with_box: usize::MAX,
    });
    let imported =
        bop::import(&|p| std::fs::read(lmo.join(p)).ok(), &opts).map_err(|e| format!("{}: {e}", lmo.display()))?;
    let text = imported.scene.to_json_string();
    let files = imported.files;
    let scene = load_scene("scene.json", &text, &|p| {
        files.iter().find(|(rel, _)| rel == p).map(|(_, b)| b.clone())
    })
    .map_err(|e| e.to_string())?;
    let truth = scene
        .ground_truth_pose
        .ok_or("the imported scene has no ground truth")?;
    Ok((scene, truth))
}

/// The box-to-pose fit of `scene` (the model loaded before the clock starts).
fn photo_row(name: &str, scene: &Scene, truth: &Pose, sam: &mut SamSegmenter) -> CliResult<Row> {
    let t0 = Instant::now();
    let mut photo =
        PhotoFit::new(scene.clone(), FitSettings::default(), PhotoSettings::default()).map_err(|e| e.to_string())?;
    let est = segment::run(&mut photo, sam, |_, _| {}).map_err(|e| e.to_string())?;
    let secs = t0.elapsed().as_secs_f64();
    let r = photo.result(&est, secs, Some(truth));
    let camera = &scene.photos.first().ok_or("a scene without photographs")?.camera;
    Ok(Row {
        name: name.into(),
        triangles: scene.mesh.triangles.len(),
        views: scene.photos.len() + scene.views.len(),
        size: format!("{}×{}", camera.width, camera.height),
        fit_s: Some(secs),
        fit_add_rel: r.errors.map(|e| e.add_rel),
        fit_iou: Some(r.mean_iou),
        fit_verdict: r.verdict.map(|v| v.as_str().to_string()),
        ..Row::default()
    })
}

/// The segmenter's encoder on the LM-O duck's crops (one crop alone, three as one
/// mosaic; medians of 3 runs, on the pool's threads), and the box-to-pose fits of three
/// views (images and boxes in, as `import bop --boxes` makes them): the duck's (`ok`
/// after the first round) and the holepuncher's (in doubt to the end: the path where
/// the second round searches afresh); `load_s`, the model's loading (files read, their
/// SHA-256 checked, both networks optimised), is a row of its own.
fn photos(a: &BenchArgs, mut sam: SamSegmenter, load_s: f64) -> CliResult<Vec<Row>> {
    let lmo = shared(a, "real/lmo")?;
    let (scene, truth) = lmo_boxes(&lmo, 9, &[102, 362, 476], 9)?;
    let mut photo = PhotoFit::prepare(scene.clone(), FitSettings::default(), PhotoSettings::default())
        .map_err(|e| e.to_string())?;
    photo.start().map_err(|e| e.to_string())?;
    let crops: Vec<(Vec<u8>, u32)> = photo
        .pending()
        .iter()
        .map(|j| (j.crop.rgb(photo.image(j.view).expect("a made view")), j.crop.side))
        .collect();
    let median3 = |f: &dyn Fn() -> CliResult| -> CliResult<f64> {
        let mut t = Vec::new();
        for _ in 0..3 {
            let t0 = Instant::now();
            f()?;
            t.push(t0.elapsed().as_secs_f64());
        }
        Ok(localisebot::metrics::median(&t))
    };
    let model = sam.model();
    let one = median3(&|| {
        model
            .embed(&crops[0].0, crops[0].1)
            .map(|_| ())
            .map_err(|e| e.to_string())
    })?;
    let tiles: Vec<(&[u8], u32)> = crops.iter().map(|(c, s)| (c.as_slice(), *s)).collect();
    let mosaic = median3(&|| model.embed_tiles(&tiles).map(|_| ()).map_err(|e| e.to_string()))?;
    let mut rows = vec![
        Row {
            name: "segmenter: load, check, optimise".into(),
            size: "28+16.5 MB".into(),
            fit_s: Some(load_s),
            ..Row::default()
        },
        Row {
            name: "encoder: 1 crop, 1024²".into(),
            views: 1,
            size: format!("{}²", crops[0].1),
            fit_s: Some(one),
            ..Row::default()
        },
        Row {
            name: "encoder: 3 crops, mosaic".into(),
            views: 3,
            size: "3×512²".into(),
            fit_s: Some(mosaic),
            ..Row::default()
        },
    ];
    rows.push(photo_row("photos: LM-O duck, 3 boxes", &scene, &truth, &mut sam)?);
    rows.push(photo_row(
        "photos: the same, enlarged 6× (a phone's 11 MP)",
        &enlarged(&scene, 6)?,
        &truth,
        &mut sam,
    )?);
    let (scene, truth) = lmo_boxes(&lmo, 12, &[126, 362, 1087], 12)?;
    rows.push(photo_row(
        "photos: LM-O holepuncher, 3 boxes",
        &scene,
        &truth,
        &mut sam,
    )?);
    Ok(rows)
}

/// `scene` with its photographs enlarged `k` times (bilinear), their cameras and boxes
/// with them: what a phone's photographs cost the photograph path.
fn enlarged(scene: &Scene, k: u32) -> CliResult<Scene> {
    let mut s = scene.clone();
    for p in &mut s.photos {
        let (w, h) = (p.camera.width, p.camera.height);
        let small = image::RgbaImage::from_raw(w, h, p.image.data.clone())
            .ok_or_else(|| format!("view {}: the photograph is not {w}×{h}", p.name))?;
        let big = image::imageops::resize(&small, k * w, k * h, image::imageops::FilterType::Triangle);
        p.image = localisebot::Rgba {
            width: k * w,
            height: k * h,
            data: big.into_raw(),
        }
        .into();
        p.camera = p.camera.scaled(k * w, k * h);
        p.ignore = None;
        p.hint = p.hint.map(|b| localisebot::PixelBox {
            x0: b.x0 * k as f64,
            y0: b.y0 * k as f64,
            x1: b.x1 * k as f64,
            y1: b.y1 * k as f64,
        });
    }
    Ok(s)
}

fn synth_scene(mesh: &Mesh, views: usize, w: u32, h: u32, seed: u64) -> CliResult<localisebot::app::synth::SynthScene> {
    synthesize(
        mesh,
        &SynthSettings {
            views,
            width: w,
            height: h,
            seed,
            ..Default::default()
        },
        None,
    )
    .map_err(|e| e.to_string())
}

/// The Linemod-Occluded duck in views 102, 362 and 476, its other objects ignored
/// (as the page's real example).
fn real_scene(lmo: &Path) -> CliResult<Scene> {
    let mut opts = BopOptions::new(2, 9);
    opts.image_ids = Some(vec![102, 362, 476]);
    opts.masks = MaskKind::Visible;
    opts.ignore_others = true;
    let imported =
        bop::import(&|p| std::fs::read(lmo.join(p)).ok(), &opts).map_err(|e| format!("{}: {e}", lmo.display()))?;
    let text = imported.scene.to_json_string();
    let files = imported.files;
    load_scene("scene.json", &text, &|p| {
        files.iter().find(|(rel, _)| rel == p).map(|(_, b)| b.clone())
    })
    .map_err(|e| e.to_string())
}

/// A full fit from no initial pose with the default settings.
fn fit_row(name: &str, mesh: &Mesh, views: Vec<View>, truth: &Pose, size: &str, raster: RasterKind) -> CliResult<Row> {
    let n = views.len();
    let start = Instant::now();
    let settings = FitSettings::for_raster(raster);
    let mut est = Estimator::new(mesh.clone(), views, None, settings).map_err(|e| e.to_string())?;
    est.run(usize::MAX).map_err(|e| e.to_string())?;
    let secs = start.elapsed().as_secs_f64();
    let r = est.result(secs, Some(truth));
    Ok(Row {
        name: name.into(),
        triangles: mesh.triangles.len(),
        views: n,
        size: size.into(),
        fit_s: Some(secs),
        fit_add_rel: r.errors.map(|e| {
            if r.symmetric == Some(true) {
                e.add_s_rel
            } else {
                e.add_rel
            }
        }),
        fit_iou: Some(r.mean_iou),
        fit_verdict: r.verdict.map(|v| v.as_str().to_string()),
        ..Row::default()
    })
}

/// Median milliseconds of one objective evaluation with gradient, and with the
/// Gauss–Newton model, at a pose slightly off `pose` (as during a fit): the fit's
/// objective with its default λ1, λ2, every view's whole image at `size`.
#[allow(clippy::too_many_arguments)]
fn time_objective(
    mesh: &Mesh,
    views: &[View],
    pose: &Pose,
    size: u32,
    sigma: f64,
    reps: usize,
    raster: RasterKind,
) -> CliResult<(f64, f64)> {
    let d = FitSettings::default();
    let settings = ObjectiveSettings {
        soft: SoftSettings { sigma, eps: 1e-4 },
        lambda_iou: d.lambda_iou,
        lambda_contour: d.lambda_contour,
        lambda_region: 0.0,
        raster,
    };
    let model = RenderMesh::new(mesh.clone());
    let windows: Vec<Window> = views.iter().map(|v| Window::full(v.camera())).collect();
    let mut objective = Objective::new(views, &windows, size, settings).map_err(|e| e.to_string())?;
    let p = Pose {
        translation: pose.translation + glam::DVec3::splat(0.01 * mesh.diameter() * pose.scale.max_element()),
        ..*pose
    };
    let median = |f: &mut dyn FnMut() -> localisebot::Result<()>| -> CliResult<f64> {
        f().map_err(|e| e.to_string())?; // warm the buffers
        let mut times = Vec::with_capacity(reps);
        for _ in 0..reps {
            let t = Instant::now();
            f().map_err(|e| e.to_string())?;
            times.push(t.elapsed().as_secs_f64() * 1e3);
        }
        Ok(localisebot::metrics::median(&times))
    };
    let fwd_bwd = median(&mut || {
        objective
            .value_and_gradient(&model, &p)
            .map(|e| drop(std::hint::black_box(e)))
    })?;
    let gn = median(&mut || {
        objective
            .normal_equations(&model, &p)
            .map(|e| drop(std::hint::black_box(e)))
    })?;
    Ok((fwd_bwd, gn))
}

fn print_rows(rows: &[Row], json: bool) {
    if json {
        for r in rows {
            let mut v = serde_json::json!({
                "name": r.name, "raster": r.raster, "threads": r.threads,
                "triangles": r.triangles, "views": r.views, "size": r.size,
            });
            let mut put = |k: &str, x: Option<f64>| {
                if let Some(x) = x {
                    v[k] = x.into();
                }
            };
            put("fwd_bwd_ms", r.fwd_bwd_ms);
            put("gn_ms", r.gn_ms);
            put("fit_s", r.fit_s);
            put("fit_add_rel", r.fit_add_rel);
            put("fit_iou", r.fit_iou);
            if let Some(s) = &r.fit_verdict {
                v["fit_verdict"] = s.as_str().into();
            }
            println!("{v}");
        }
        return;
    }
    println!(
        "rasteriser: {}; evaluations on 1 thread, fits on {}",
        rows.first().map_or("-", |r| r.raster),
        rows.iter().map(|r| r.threads).max().unwrap_or(1)
    );
    println!(
        "{:<28} {:>9} {:>5} {:>8} {:>11} {:>8} {:>7} {:>9} {:>7} {:>7}",
        "configuration", "triangles", "views", "size", "fwd+bwd ms", "GN ms", "fit s", "ADD(-S)", "IoU", "verdict"
    );
    let f = |x: Option<f64>, d: usize| x.map_or("-".to_string(), |x| format!("{x:.d$}"));
    for r in rows {
        println!(
            "{:<28} {:>9} {:>5} {:>8} {:>11} {:>8} {:>7} {:>9} {:>7} {:>7}",
            r.name,
            r.triangles,
            r.views,
            r.size,
            f(r.fwd_bwd_ms, 2),
            f(r.gn_ms, 2),
            f(r.fit_s, 2),
            r.fit_add_rel.map_or("-".to_string(), |s| format!("{:.2}%", 100.0 * s)),
            f(r.fit_iou, 4),
            r.fit_verdict.as_deref().unwrap_or("-")
        );
    }
}
