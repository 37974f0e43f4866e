//! How far the LM-O annotation is from its photographs, measured on the photographs
//! themselves: a pose's outline against the photograph's edges (Sobel), and the
//! annotated masks moved onto those edges — what a segmenter exact to the photographs
//! would score against the annotation, and the pose it would give. `photos.rs` measures
//! its fits with these.

use crate::photos::{import_lmo, SETS};
use localisebot::raster::hard;
use localisebot::{metrics, Camera, Estimator, FitSettings, Mask, Pose, Rgba, View, ViewSources};

/// A photograph's luminance gradient magnitude (Sobel, 0–255 scale, over 8), row-major.
pub fn gradient(im: &Rgba) -> Vec<f64> {
    let (w, h) = (im.width as i64, im.height as i64);
    let lum = |x: i64, y: i64| -> f64 {
        let (x, y) = (x.clamp(0, w - 1), y.clamp(0, h - 1));
        let i = 4 * (y * w + x) as usize;
        0.299 * f64::from(im.data[i]) + 0.587 * f64::from(im.data[i + 1]) + 0.114 * f64::from(im.data[i + 2])
    };
    let mut g = Vec::with_capacity((w * h) as usize);
    for y in 0..h {
        for x in 0..w {
            let gx = lum(x + 1, y - 1) + 2.0 * lum(x + 1, y) + lum(x + 1, y + 1)
                - lum(x - 1, y - 1)
                - 2.0 * lum(x - 1, y)
                - lum(x - 1, y + 1);
            let gy = lum(x - 1, y + 1) + 2.0 * lum(x, y + 1) + lum(x + 1, y + 1)
                - lum(x - 1, y - 1)
                - 2.0 * lum(x, y - 1)
                - lum(x + 1, y - 1);
            g.push((gx * gx + gy * gy).sqrt() / 8.0);
        }
    }
    g
}

/// How strongly a pose's outline lies on a photograph's edges, per view: the mean
/// gradient magnitude ([`gradient`]) over the silhouette's outline pixels (inside, with
/// a 4-neighbour outside), and the move within ±8 px that puts the outline on the
/// strongest edges (its length, px). An independent check of where the object is in a
/// photograph — no segmenter's mask enters it.
pub fn edges(mesh: &localisebot::Mesh, pose: &Pose, cameras: &[Camera], grads: &[Vec<f64>]) -> Vec<(f64, f64)> {
    edge_moves(mesh, pose, cameras, grads)
        .into_iter()
        .map(|(e, (dx, dy))| (e, ((dx * dx + dy * dy) as f64).sqrt()))
        .collect()
}

/// As [`edges`], with the move itself (px, x and y).
pub fn edge_moves(
    mesh: &localisebot::Mesh,
    pose: &Pose,
    cameras: &[Camera],
    grads: &[Vec<f64>],
) -> Vec<(f64, (i64, i64))> {
    const REACH: i64 = 8;
    cameras
        .iter()
        .zip(grads)
        .map(|(c, g)| {
            let (w, h) = (c.width as i64, c.height as i64);
            let sil = hard::render(mesh, pose, c);
            let inside = |x: i64, y: i64| x >= 0 && y >= 0 && x < w && y < h && sil.get(x as u32, y as u32);
            let outline: Vec<(i64, i64)> = (0..h)
                .flat_map(|y| (0..w).map(move |x| (x, y)))
                .filter(|&(x, y)| {
                    inside(x, y)
                        && [(1, 0), (-1, 0), (0, 1), (0, -1)]
                            .iter()
                            .any(|(dx, dy)| !inside(x + dx, y + dy))
                })
                .collect();
            let along = |dx: i64, dy: i64| -> f64 {
                let (mut sum, mut n) = (0.0, 0usize);
                for &(x, y) in &outline {
                    let (sx, sy) = (x + dx, y + dy);
                    if sx >= 0 && sy >= 0 && sx < w && sy < h {
                        sum += g[(sy * w + sx) as usize];
                        n += 1;
                    }
                }
                if n > 0 {
                    sum / n as f64
                } else {
                    0.0
                }
            };
            let mut best = (along(0, 0), (0, 0));
            for dy in -REACH..=REACH {
                for dx in -REACH..=REACH {
                    let e = along(dx, dy);
                    if e > best.0 {
                        best = (e, (dx, dy));
                    }
                }
            }
            (along(0, 0), best.1)
        })
        .collect()
}

/// The annotation moved onto the photographs: each view's annotated visible mask moved
/// onto the photograph's strongest edges (the move within ±8 px that [`edges`] finds for
/// the annotated pose's outline; a move to the window's edge is taken for none found, and
/// the mask stays), then fitted as given masks are (the other objects ignored). What a
/// segmenter that followed the photographs exactly would give, were the cameras right.
pub struct OnEdges {
    /// Each view's move, px.
    pub moves: Vec<(i64, i64)>,
    /// The annotated visible masks, moved.
    pub masks: Vec<Mask>,
    /// Each moved mask's IoU against the annotated one: what a mask on the photograph
    /// scores against the annotation.
    pub self_ious: Vec<f64>,
    /// The pose fitted to the moved masks.
    pub pose: Pose,
}

pub fn on_edges(object: u32, images: &[u32]) -> OnEdges {
    let scene = import_lmo(object, images, None, true);
    let truth = scene.ground_truth_pose.unwrap();
    let cameras: Vec<Camera> = scene.views.iter().map(|v| *v.camera()).collect();
    let grads: Vec<Vec<f64>> = scene.views.iter().map(|v| gradient(v.image().unwrap())).collect();
    let moves: Vec<(i64, i64)> = edge_moves(&scene.mesh, &truth, &cameras, &grads)
        .into_iter()
        .map(|(_, (dx, dy))| {
            if dx.abs() == 8 || dy.abs() == 8 {
                (0, 0)
            } else {
                (dx, dy)
            }
        })
        .collect();
    let views: Vec<View> = scene
        .views
        .iter()
        .zip(&moves)
        .map(|(v, &(dx, dy))| {
            let m = v.mask();
            let (w, h) = (m.width as i64, m.height as i64);
            let mut moved = Mask::empty(m.width, m.height);
            for y in 0..h {
                for x in 0..w {
                    let (sx, sy) = (x - dx, y - dy);
                    if sx >= 0 && sy >= 0 && sx < w && sy < h && m.get(sx as u32, sy as u32) {
                        moved.data[(y * w + x) as usize] = 1;
                    }
                }
            }
            let sources = ViewSources::files("(moved)", "ignore", "photograph");
            View::new(
                v.name(),
                *v.camera(),
                moved,
                v.ignore().cloned(),
                v.image().cloned(),
                &sources,
            )
            .unwrap()
        })
        .collect();
    let self_ious = scene
        .views
        .iter()
        .zip(&views)
        .map(|(v, m)| metrics::hard_iou(v.mask(), m.mask()))
        .collect();
    let masks = views.iter().map(|v| v.mask().clone()).collect();
    let mut est = Estimator::new(scene.mesh.clone(), views, None, FitSettings::default()).unwrap();
    est.run(usize::MAX).unwrap();
    OnEdges {
        moves,
        masks,
        self_ious,
        pose: est.pose(),
    }
}

/// How far the annotation itself is from these photographs, in the issue's own
/// measures ([`on_edges`]): the pose fitted to the annotated masks moved onto the
/// photographs' edges is the part of the "median ADD(-S) ≤ 2 % d" that the
/// annotation spends, and the moved masks' IoU against the unmoved ones the most a mask
/// that follows the photograph can score against the annotation.
#[test]
fn the_annotation_moved_onto_the_photographs_edges() {
    let (mut adds, mut self_ious) = (Vec::new(), Vec::new());
    for &(o, ims, sym) in SETS.iter() {
        let scene = import_lmo(o, &ims, None, true);
        let truth = scene.ground_truth_pose.unwrap();
        let moved = on_edges(o, &ims);
        let e = metrics::pose_errors(&scene.mesh, &moved.pose, &truth);
        let add = if sym { e.add_s_rel } else { e.add_rel };
        println!(
            "LM-O object {o} {ims:?}: the annotated masks moved by {:?} px onto the photographs' edges (IoU \
             {:?} against themselves unmoved) and fitted: ADD{} {:.2} % d from the annotated pose, rotation {:.1}°",
            moved.moves,
            moved
                .self_ious
                .iter()
                .map(|x| (x * 1000.0).round() / 1000.0)
                .collect::<Vec<_>>(),
            if sym { "-S" } else { "" },
            100.0 * add,
            e.rotation_deg
        );
        adds.push(add);
        self_ious.extend(moved.self_ious);
    }
    let (median, median_iou) = (metrics::median(&adds), metrics::median(&self_ious));
    println!(
        "the annotated masks moved onto the photographs' edges: median ADD(-S) {:.2} % d from the annotated \
         pose; their median IoU against themselves unmoved {median_iou:.3}",
        100.0 * median
    );
    // Measured: 1.35–7.40 % d, median 2.24 % d (with the moves to the window's edge
    // taken as found: median 3.61 %, two fits turned away); IoU median 0.863: a mask
    // exactly on the photograph scores about that against the annotation, below the
    // issue's 0.9.
    assert!(
        (0.015..0.04).contains(&median),
        "median ADD(-S) {:.2} % d",
        100.0 * median
    );
    assert!((0.8..0.9).contains(&median_iou), "median IoU {median_iou:.3}");
}
