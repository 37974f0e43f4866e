//! Where to look next: candidate cameras ranked by how much a photograph from there
//! is predicted to shrink the pose uncertainty.
//!
//! A candidate's outline at the fitted pose gives its information `H_c`
//! ([`outline_information`]); assuming its mask carries the views' mean noise power
//! `p` (σ²λ, module doc of `crate::uncertainty`), the covariance with it added is
//! `Σ' = κ (H + H_c)⁻¹ (B + p·H_c) (H + H_c)⁻¹` and the candidate's score is the
//! expected squared ADD under Σ', `tr(W Σ')` (W the ADD metric, [`add_metric`]):
//! the smaller, the better. Candidates that do not see the whole object in front of
//! them are ranked last (an object cut by the frame gives a truncated outline).

use super::{add_metric, outline_information, sandwich, Mat9, NoiseModel, Uncertainty};
use crate::camera::Camera;
use crate::error::{Error, Result};
use crate::pose::Pose;
use crate::raster::hard;
use crate::raster::silhouette::RenderMesh;
use crate::view::{PixelBox, View};
use crate::window::Window;
use glam::DVec3;

/// Margin of a candidate's object window, as a fraction of the silhouette's box.
const MARGIN: f64 = 0.3;
/// The long side of a candidate's canvas, at most.
const RESOLUTION: u32 = 512;

/// A candidate camera with its predicted effect.
#[derive(Debug, Clone, PartialEq)]
pub struct RankedView {
    /// Index of the candidate in the list given.
    pub index: usize,
    /// The camera (OpenCV axes, the candidate's intrinsics).
    pub camera: Camera,
    /// The expected RMS ADD after adding a photograph from here, scene units
    /// (infinite when the candidate does not see the object whole).
    pub predicted_add_rms: f64,
    /// The expected RMS ADD now, scene units, for comparison.
    pub current_add_rms: f64,
    /// The object's outline length in the candidate's window, pixels.
    pub outline_px: f64,
    /// When the fit has alternatives (`ambiguous`): how well a photograph from here
    /// tells them apart from the fit — `1 − IoU` between the fit's silhouette and the
    /// most alike alternative's, seen from here ([`discriminate`]); `None` otherwise.
    pub discrimination: Option<f64>,
}

/// Re-ranks `ranked` (of the fit at `pose`) for a fit with `alternatives`: by how well
/// a photograph from each candidate would tell them apart — the smallest `1 − IoU`
/// between the fit's silhouette and an alternative's there, in steps of 0.05 (so that
/// views about as telling are ranked by their predicted ADD, as before), most telling
/// first. A candidate that does not see the object keeps its infinite ADD, last.
pub fn discriminate(mesh: &crate::mesh::Mesh, pose: &Pose, alternatives: &[Pose], ranked: &mut [RankedView]) {
    if alternatives.is_empty() {
        return;
    }
    for r in ranked.iter_mut() {
        if !r.predicted_add_rms.is_finite() {
            continue;
        }
        // Both silhouettes on one canvas around the two: at most RESOLUTION across,
        // not the whole image (the IoU is read in steps of 0.05).
        let fit_box = projected_box(mesh, pose, &r.camera);
        let d = alternatives
            .iter()
            .map(|a| {
                let (Some(f), Some(g)) = (fit_box, projected_box(mesh, a, &r.camera)) else {
                    return 1.0; // the alternative is behind the camera: nothing alike
                };
                let both = [f[0].min(g[0]), f[1].min(g[1]), f[2].max(g[2]), f[3].max(g[3])];
                let canvas = canvas_around(&r.camera, both, 0.05);
                1.0 - crate::metrics::hard_iou(&hard::render(mesh, pose, &canvas), &hard::render(mesh, a, &canvas))
            })
            .fold(f64::INFINITY, f64::min);
        r.discrimination = Some(d);
    }
    let step = |r: &RankedView| r.discrimination.map_or(-1, |d| (d / 0.05).floor() as i64);
    ranked.sort_by(|a, b| {
        step(b)
            .cmp(&step(a))
            .then(a.predicted_add_rms.total_cmp(&b.predicted_add_rms))
            .then(a.index.cmp(&b.index))
    });
}

/// Where the default candidate viewpoints lie.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Viewpoints {
    /// The whole sphere around the object, its poles along view 0's image-up.
    #[default]
    Sphere,
    /// The half of the sphere above the object: on the side the views' mean image-up
    /// points to (a camera on an arm over a table cannot look from under it).
    Above,
}

/// `count` viewpoints evenly spread over `shell` (a Fibonacci lattice; see
/// [`Viewpoints`]) around the object at `pose`, at the views' mean distance from it,
/// looking at it, with the intrinsics of view 0. Image-up is the lattice's axis: view
/// 0's image-up for the sphere, the views' mean image-up for the upper half (view 0's
/// when they cancel out).
///
/// Errors: no views.
pub fn candidate_viewpoints(
    model: &RenderMesh,
    views: &[View],
    pose: &Pose,
    count: usize,
    shell: Viewpoints,
) -> Result<Vec<Camera>> {
    let first = views
        .first()
        .ok_or_else(|| Error::Settings("next view: the scene has no views".into()))?
        .camera();
    let centre = model.mesh.bounds().map_or(pose.translation, |b| pose.apply(b.centre()));
    let distance = views.iter().map(|v| v.camera().centre().distance(centre)).sum::<f64>() / views.len() as f64;
    // A view's image-up in the world: −y of its camera axes.
    let image_up = |c: &Camera| -(c.rotation.transpose() * DVec3::Y);
    let up = match shell {
        Viewpoints::Sphere => image_up(first),
        Viewpoints::Above => {
            let sum = views.iter().map(|v| image_up(v.camera())).sum::<DVec3>();
            // Views whose ups (nearly) cancel out say nothing of "up": view 0's then.
            if sum.length() > 1e-3 * views.len() as f64 {
                sum.normalize()
            } else {
                image_up(first)
            }
        }
    };
    // The lattice's heights along `up`: the whole of [−1, 1], or (0, 1].
    let (top, span) = match shell {
        Viewpoints::Sphere => (1.0, 2.0),
        Viewpoints::Above => (1.0, 1.0),
    };
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    let n = count.max(1);
    let (e1, e2) = up.any_orthonormal_pair();
    Ok((0..n)
        .map(|i| {
            let z = top - span * (i as f64 + 0.5) / n as f64;
            let r = (1.0 - z * z).max(0.0).sqrt();
            let a = golden * i as f64;
            // A lattice about `up`, so that its pole is above the object.
            let dir = up * z + (e1 * a.cos() + e2 * a.sin()) * r;
            let eye = centre + dir * distance;
            let mut cam = Camera::look_at(eye, centre, up, first.width, first.height, first.fx);
            cam.fy = first.fy;
            cam.cx = first.cx;
            cam.cy = first.cy;
            cam
        })
        .collect())
}

/// Ranks `candidates` for the fit at `pose` whose uncertainty is `u` (module doc),
/// best first.
///
/// Errors: the fit's information constrains nothing, or a render fails.
pub fn rank_views(
    model: &RenderMesh,
    pose: &Pose,
    u: &Uncertainty,
    candidates: &[Camera],
    noise: &NoiseModel,
) -> Result<Vec<RankedView>> {
    let w = add_metric(&model.mesh, pose);
    let expected = |cov: &Mat9| (w * cov).trace().max(0.0).sqrt();
    let current = expected(&u.covariance);
    let mut ranked = Vec::with_capacity(candidates.len());
    for (index, cam) in candidates.iter().enumerate() {
        let mut out = RankedView {
            index,
            camera: *cam,
            predicted_add_rms: f64::INFINITY,
            current_add_rms: current,
            outline_px: 0.0,
            discrimination: None,
        };
        if let Some(canvas) = object_canvas(model, pose, cam) {
            let (hc, length) = outline_information(model, pose, &canvas, noise)?;
            let cov = sandwich(&(u.information + hc), &(u.noise + hc * u.noise_power), u.mode, noise)?;
            out.predicted_add_rms = expected(&cov);
            out.outline_px = length;
        }
        ranked.push(out);
    }
    ranked.sort_by(|a, b| {
        a.predicted_add_rms
            .total_cmp(&b.predicted_add_rms)
            .then(a.index.cmp(&b.index))
    });
    Ok(ranked)
}

/// The default number of sphere candidates.
pub const SPHERE: usize = 64;

/// The image box `[x_min, x_max] × [y_min, y_max]` (continuous pixel coordinates, pixel
/// centres at integers) of the mesh's vertices at `pose` seen by `cam` — the
/// silhouette's extent, whose extremes are vertices — or `None` when a vertex is not in
/// front of the camera. One pass over the vertices, where rendering the whole image
/// would cost a pass over all its pixels (12 MP for a phone's photograph).
fn projected_box(mesh: &crate::mesh::Mesh, pose: &Pose, cam: &Camera) -> Option<[f64; 4]> {
    let mut b = [f64::INFINITY, f64::INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY];
    for &p in &mesh.positions {
        let pc = cam.to_camera(pose.apply(p));
        if pc.z.is_nan() || pc.z <= 1e-9 {
            return None;
        }
        let q = cam.project(pc);
        b = [b[0].min(q.x), b[1].min(q.y), b[2].max(q.x), b[3].max(q.y)];
    }
    b.iter().all(|v| v.is_finite()).then_some(b)
}

/// The canvas camera (at most [`RESOLUTION`] across) of a square window around the
/// image box `b` ([`projected_box`]) with `margin`.
fn canvas_around(cam: &Camera, b: [f64; 4], margin: f64) -> Camera {
    // A PixelBox covering [x0, x1) spans [x0 − ½, x1 − ½] in continuous coordinates.
    let pixels = PixelBox {
        x0: b[0] + 0.5,
        y0: b[1] + 0.5,
        x1: b[2] + 0.5,
        y1: b[3] + 0.5,
    };
    let window = Window::around_box(&pixels, margin);
    let (w, h) = window.canvas(RESOLUTION);
    window.camera(cam, w, h)
}

/// The canvas camera of `cam`'s object window at `pose`, or `None` when the object is
/// not whole and in front of the camera: a vertex behind it, or the silhouette's box
/// less than a pixel across or reaching the image's border pixels (as a rendered mask
/// touching the border would).
fn object_canvas(model: &RenderMesh, pose: &Pose, cam: &Camera) -> Option<Camera> {
    let b = projected_box(&model.mesh, pose, cam)?;
    let (w, h) = (cam.width as f64, cam.height as f64);
    let seen = b[2] - b[0] >= 1.0 && b[3] - b[1] >= 1.0;
    let inside = b[0] > 0.5 && b[1] > 0.5 && b[2] < w - 1.5 && b[3] < h - 1.5;
    (seen && inside).then(|| canvas_around(cam, b, MARGIN))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::app::synth::{synthesize, SynthSettings};
    use crate::optim::params::ScaleMode;
    use crate::uncertainty::fit_uncertainty;

    /// A blob seen by `views` synthetic cameras: its render mesh, views and true pose.
    fn blob_scene(views: usize) -> (RenderMesh, Vec<View>, Pose) {
        let mesh = crate::app::synth::blob_mesh(10, 14);
        let settings = SynthSettings {
            views,
            ..Default::default()
        };
        let s = synthesize(&mesh, &settings, None).unwrap();
        (RenderMesh::new(mesh), s.views(), s.pose)
    }

    #[test]
    fn sphere_viewpoints_look_at_the_object_from_the_views_distance() {
        let (model, views, pose) = blob_scene(2);
        let cams = candidate_viewpoints(&model, &views, &pose, 32, Viewpoints::Sphere).unwrap();
        assert_eq!(cams.len(), 32);
        let c = pose.apply(model.mesh.bounds().unwrap().centre());
        let d0 = views.iter().map(|v| v.camera().centre().distance(c)).sum::<f64>() / 2.0;
        for cam in &cams {
            assert!((cam.centre().distance(c) - d0).abs() < 1e-9 * d0);
            let p = cam.project(cam.to_camera(c));
            assert!((p - glam::DVec2::new(cam.cx, cam.cy)).length() < 1e-6, "{p:?}");
        }
        // Spread: no two candidates closer than a third of the lattice's spacing.
        let spacing = (4.0 * std::f64::consts::PI / 32.0).sqrt();
        for (i, a) in cams.iter().enumerate() {
            for b in &cams[i + 1..] {
                let (da, db) = ((a.centre() - c).normalize(), (b.centre() - c).normalize());
                assert!(da.angle_between(db) > spacing / 3.0);
            }
        }
    }

    #[test]
    fn viewpoints_above_cover_the_upper_half_about_the_views_mean_up() {
        let (model, views, pose) = blob_scene(3);
        let n = 40;
        let cams = candidate_viewpoints(&model, &views, &pose, n, Viewpoints::Above).unwrap();
        assert_eq!(cams.len(), n);
        let c = pose.apply(model.mesh.bounds().unwrap().centre());
        let d0 = views.iter().map(|v| v.camera().centre().distance(c)).sum::<f64>() / 3.0;
        let up = views
            .iter()
            .map(|v| -(v.camera().rotation.transpose() * DVec3::Y))
            .sum::<DVec3>()
            .normalize();
        let heights: Vec<f64> = cams.iter().map(|k| (k.centre() - c).normalize().dot(up)).collect();
        for (k, h) in cams.iter().zip(&heights) {
            assert!(*h > 0.0, "a candidate below the object: height {h}");
            assert!((k.centre().distance(c) - d0).abs() < 1e-9 * d0);
            let p = k.project(k.to_camera(c));
            assert!((p - glam::DVec2::new(k.cx, k.cy)).length() < 1e-6, "{p:?}");
            // Image-up is the lattice's axis: the object's "up" is up in every picture.
            let k_up = -(k.rotation.transpose() * DVec3::Y);
            assert!(k_up.dot(up) > 0.0);
        }
        // The whole upper half: from near the pole to near the horizon, evenly.
        let (lo, hi) = heights.iter().fold((1.0f64, 0.0f64), |(l, h), &z| (l.min(z), h.max(z)));
        assert!(lo < 0.05 && hi > 0.95, "heights {lo}..{hi}");
        let spacing = (2.0 * std::f64::consts::PI / n as f64).sqrt();
        for (i, a) in cams.iter().enumerate() {
            for b in &cams[i + 1..] {
                let (da, db) = ((a.centre() - c).normalize(), (b.centre() - c).normalize());
                assert!(da.angle_between(db) > spacing / 3.0);
            }
        }
        // The sphere: both halves, about view 0's up.
        let sphere = candidate_viewpoints(&model, &views, &pose, n, Viewpoints::Sphere).unwrap();
        let up0 = -(views[0].camera().rotation.transpose() * DVec3::Y);
        let below = sphere.iter().filter(|k| (k.centre() - c).dot(up0) < 0.0).count();
        assert_eq!(below, n / 2);
        // Views whose ups cancel out (view 0 and itself turned upside down about its
        // axis): the upper half is view 0's.
        let mut flipped = *views[0].camera();
        flipped.rotation = glam::DMat3::from_diagonal(DVec3::new(-1.0, -1.0, 1.0)) * flipped.rotation;
        flipped.translation = glam::DMat3::from_diagonal(DVec3::new(-1.0, -1.0, 1.0)) * flipped.translation;
        assert!(flipped.centre().distance(views[0].camera().centre()) < 1e-9);
        let mask = views[0].mask().clone();
        let pair = [
            views[0].clone(),
            View::new("upside down", flipped, mask, None, None, &Default::default()).unwrap(),
        ];
        let cams = candidate_viewpoints(&model, &pair, &pose, n, Viewpoints::Above).unwrap();
        assert!(cams.iter().all(|k| (k.centre() - c).dot(up0) > 0.0));
    }

    #[test]
    fn a_view_along_the_existing_one_helps_less_than_a_view_across_it() {
        // One view constrains depth (and scale) poorly; a second view at 90° fixes it,
        // a second view beside the first hardly does.
        let (model, views, pose) = blob_scene(1);
        let windows = [Window::for_view(
            &views[0],
            crate::window::WindowMode::Object { margin: 0.3 },
        )];
        let noise = NoiseModel::default();
        let u = fit_uncertainty(&model, &views, &windows, &pose, &[1.0], ScaleMode::Anisotropic, &noise).unwrap();
        let c = pose.apply(model.mesh.bounds().unwrap().centre());
        let cam0 = views[0].camera();
        let eye0 = cam0.centre() - c;
        let up = -(cam0.rotation.transpose() * DVec3::Y);
        let beside = glam::DQuat::from_axis_angle(up, 5f64.to_radians()) * eye0;
        let across = glam::DQuat::from_axis_angle(up, 90f64.to_radians()) * eye0;
        let make = |e: DVec3| {
            let mut k = Camera::look_at(c + e, c, up, cam0.width, cam0.height, cam0.fx);
            k.cx = cam0.cx;
            k.cy = cam0.cy;
            k
        };
        let behind = Camera::look_at(c + eye0, c + eye0 * 2.0, up, cam0.width, cam0.height, cam0.fx);
        let ranked = rank_views(&model, &pose, &u, &[make(beside), make(across), behind], &noise).unwrap();
        assert_eq!(ranked[0].index, 1, "{ranked:?}");
        assert_eq!(ranked[1].index, 0);
        assert!(
            ranked[0].predicted_add_rms < 0.5 * ranked[1].predicted_add_rms,
            "{ranked:?}"
        );
        assert!(
            ranked[1].predicted_add_rms <= ranked[1].current_add_rms * 1.0001,
            "{ranked:?}"
        );
        // The camera looking away from the object is last and marked unusable.
        assert_eq!(ranked[2].index, 2);
        assert!(ranked[2].predicted_add_rms.is_infinite());
    }

    #[test]
    fn the_object_canvas_is_the_rendered_silhouettes_box_and_none_when_the_border_cuts_it() {
        let (model, views, pose) = blob_scene(1);
        let cam = *views[0].camera();
        let mask = hard::render(&model.mesh, &pose, &cam);
        let (x0, y0, x1, y1) = mask.bbox().unwrap();
        let b = projected_box(&model.mesh, &pose, &cam).unwrap();
        // The vertices' box holds every covered pixel centre, and hardly more.
        assert!(
            b[0] <= x0 as f64 && b[1] <= y0 as f64 && b[2] >= x1 as f64 && b[3] >= y1 as f64,
            "{b:?}"
        );
        assert!(b[0] > x0 as f64 - 1.0 && b[1] > y0 as f64 - 1.0 && b[2] < x1 as f64 + 1.0 && b[3] < y1 as f64 + 1.0);
        // Its canvas is the window a mask-based one would be, to a pixel of the image.
        let canvas = object_canvas(&model, &pose, &cam).unwrap();
        let window = Window::around_mask(&mask, MARGIN).unwrap();
        let (w, h) = window.canvas(RESOLUTION);
        let expect = window.camera(&cam, w, h);
        let px = cam.fx / expect.fx; // image pixels per canvas pixel
        assert!((canvas.cx - expect.cx).abs() * px < 2.0 && (canvas.cy - expect.cy).abs() * px < 2.0);
        assert!(
            (canvas.fx / expect.fx - 1.0).abs() < 0.02,
            "{} {}",
            canvas.fx,
            expect.fx
        );
        // Moved so that the silhouette reaches past the left edge: not whole, no canvas.
        let mut cut = cam;
        cut.cx -= (b[0] + b[2]) / 2.0;
        assert!(hard::render(&model.mesh, &pose, &cut).touches_border());
        assert!(object_canvas(&model, &pose, &cut).is_none());
        // Behind the camera: none either.
        let mut behind = cam;
        behind.translation.z = -behind.translation.z - 10.0;
        assert!(projected_box(&model.mesh, &pose, &behind).is_none());
        assert!(object_canvas(&model, &pose, &behind).is_none());
    }
}
