//! Occlusion (SPEC §4; the real-photographs issue's done-when): in three-view synthetic
//! scenes (256², the Duck and the Avocado of `../shared/data`: objects whose per-axis
//! scale their silhouettes pin down), 30 % of view 1's object is hidden behind a
//! rectangular occluder (`app::synth::occlude`). With its ignore mask the fit must be as
//! accurate as on the unoccluded scene; without it, at least as accurate as the fit with
//! that view left out, and the view must be named.

use crate::data;
use localisebot::app::synth::{occlude, synthesize, SynthScene, SynthSettings};
use localisebot::{io, metrics, Estimator, FitResult, FitSettings, Mesh, Pose, View};

/// (mesh file under `../shared/data/gltf`, seed).
const SCENES: [(&str, u64); 6] = [
    ("Duck/glTF-Binary/Duck.glb", 1),
    ("Duck/glTF-Binary/Duck.glb", 2),
    ("Duck/glTF-Binary/Duck.glb", 3),
    ("Avocado-kaolin/avocado.gltf", 4),
    ("Avocado-kaolin/avocado.gltf", 5),
    ("Avocado-kaolin/avocado.gltf", 6),
];

fn mesh(rel: &str) -> Mesh {
    let path = data(&format!("gltf/{rel}"));
    let dir = path.parent().unwrap().to_path_buf();
    io::load_mesh(&path.to_string_lossy(), &std::fs::read(&path).unwrap(), &|u| {
        std::fs::read(dir.join(u)).ok()
    })
    .unwrap()
}

fn scene(mesh: &Mesh, seed: u64) -> SynthScene {
    synthesize(
        mesh,
        &SynthSettings {
            views: 3,
            seed,
            ..Default::default()
        },
        None,
    )
    .unwrap()
}

/// The scene's views with view 1 occluded; with `ignore`, the occluder as its ignore mask.
fn occluded(s: &SynthScene, seed: u64, ignore: bool) -> Vec<View> {
    s.views()
        .iter()
        .enumerate()
        .map(|(i, v)| {
            if i != 1 {
                return v.clone();
            }
            let (cut, occluder) = occlude(v.mask(), 0.3, seed);
            let hidden = 1.0 - cut.area() as f64 / v.mask().area() as f64;
            assert!((hidden - 0.3).abs() < 0.05, "{hidden}");
            View::new(
                v.name(),
                *v.camera(),
                cut,
                ignore.then_some(occluder),
                None,
                &Default::default(),
            )
            .unwrap()
        })
        .collect()
}

/// (rotation error °, scale error, result).
fn fit(mesh: &Mesh, views: Vec<View>, truth: &Pose) -> (f64, f64, FitResult) {
    let mut est = Estimator::new(mesh.clone(), views, None, FitSettings::default()).unwrap();
    est.run(usize::MAX).unwrap();
    let e = metrics::pose_errors(mesh, &est.pose(), truth);
    (e.rotation_deg, e.scale, est.result(0.0, Some(truth)))
}

#[test]
fn with_its_ignore_mask_an_occluded_view_costs_no_accuracy() {
    let (mut clean, mut ignored) = (vec![], vec![]);
    for (rel, seed) in SCENES {
        let mesh = mesh(rel);
        let s = scene(&mesh, seed);
        let c = fit(&mesh, s.views(), &s.pose);
        let i = fit(&mesh, occluded(&s, seed, true), &s.pose);
        println!(
            "{rel} seed {seed}: unoccluded {:.2}° {:.2} %, ignore mask {:.2}° {:.2} %",
            c.0,
            100.0 * c.1,
            i.0,
            100.0 * i.1
        );
        assert!(i.2.doubted_views.is_empty(), "an ignored occluder is no disagreement");
        clean.push(c);
        ignored.push(i);
    }
    let m = |v: &[(f64, f64, FitResult)], k: usize| {
        localisebot::metrics::median(&v.iter().map(|r| if k == 0 { r.0 } else { r.1 }).collect::<Vec<_>>())
    };
    println!(
        "median: unoccluded {:.2}° {:.2} %, with the ignore mask {:.2}° {:.2} %",
        m(&clean, 0),
        100.0 * m(&clean, 1),
        m(&ignored, 0),
        100.0 * m(&ignored, 1)
    );
    // Measured: median rotation 0.03°, scale 0.03 %.
    assert!(m(&ignored, 0) < 0.2 && m(&ignored, 1) < 0.002);
    assert!(m(&ignored, 0) <= m(&clean, 0) + 0.1 && m(&ignored, 1) <= m(&clean, 1) + 0.002);
}

#[test]
fn without_an_ignore_mask_the_occluded_view_is_named_and_costs_no_more_than_leaving_it_out() {
    let (mut alone, mut dropped, mut named) = (vec![], vec![], 0);
    for (rel, seed) in SCENES {
        let mesh = mesh(rel);
        let s = scene(&mesh, seed);
        let views = occluded(&s, seed, false);
        let a = fit(&mesh, views.clone(), &s.pose);
        let d = fit(&mesh, vec![views[0].clone(), views[2].clone()], &s.pose);
        println!(
            "{rel} seed {seed}: no ignore mask {:.2}° {:.2} % (doubted {:?}), view left out {:.2}° {:.2} %",
            a.0,
            100.0 * a.1,
            a.2.doubted_views,
            d.0,
            100.0 * d.1
        );
        named += usize::from(a.2.doubted_views == ["view1"]);
        alone.push(a);
        dropped.push(d);
    }
    let m = |v: &[(f64, f64, FitResult)], k: usize| {
        localisebot::metrics::median(&v.iter().map(|r| if k == 0 { r.0 } else { r.1 }).collect::<Vec<_>>())
    };
    println!(
        "median: no ignore mask {:.2}° {:.2} %, the view left out {:.2}° {:.2} %; named in {named}/{}",
        m(&alone, 0),
        100.0 * m(&alone, 1),
        m(&dropped, 0),
        100.0 * m(&dropped, 1),
        SCENES.len()
    );
    assert!(named >= SCENES.len() - 1, "the occluded view is named");
    assert!(m(&alone, 0) <= m(&dropped, 0) * 1.5 + 0.2, "rotation");
    assert!(m(&alone, 1) <= m(&dropped, 1) * 1.5 + 0.005, "scale");
}
