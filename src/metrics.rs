//! Pose errors and silhouette figures (SPEC §6), all pure functions.
//!
//! Pose figures compare an estimated [`Pose`] with the true one: rotation error
//! (geodesic angle, degrees), translation error (scene units), scale error
//! (relative, per axis), ADD and ADD-S (Hinterstoisser et al., ACCV 2012: the mean
//! distance of the model's points under the two poses; ADD-S pairs each point with
//! the closest one, for symmetric objects; nearest neighbours through a `kiddo` k-d
//! tree) and both relative to the object's diameter.
//! Silhouette figures compare two binary [`Mask`]s of one size: hard IoU, and the
//! Hausdorff / mean distance in pixels between their contours, through the exact
//! Euclidean distance transform of [`crate::loss::edt`].

use crate::loss::edt;
use crate::mask::Mask;
use crate::mesh::Mesh;
use crate::pose::Pose;
use crate::so3;
use glam::DVec3;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use serde::{Deserialize, Serialize};

/// Geodesic angle between the two rotations, degrees in [0, 180].
pub fn rotation_error_deg(est: &Pose, gt: &Pose) -> f64 {
    so3::geodesic_deg(est.rotation, gt.rotation)
}

/// Euclidean distance between the two translations, scene units.
pub fn translation_error(est: &Pose, gt: &Pose) -> f64 {
    est.translation.distance(gt.translation)
}

/// Relative scale error, the worst axis: `max_i |s_est,i / s_gt,i − 1|` (0.1 = 10 %).
pub fn scale_error(est: &Pose, gt: &Pose) -> f64 {
    (est.scale / gt.scale - DVec3::ONE).abs().max_element()
}

/// Relative scale error averaged over the three axes: `mean_i |s_est,i / s_gt,i − 1|`.
pub fn scale_error_mean(est: &Pose, gt: &Pose) -> f64 {
    (est.scale / gt.scale - DVec3::ONE).abs().element_sum() / 3.0
}

/// ADD: the mean over the mesh's used vertices `p` of `|est(p) − gt(p)|`, scene
/// units; 0 for a mesh with no used vertex.
pub fn add(mesh: &Mesh, est: &Pose, gt: &Pose) -> f64 {
    let pts = mesh.used_points();
    if pts.is_empty() {
        return 0.0;
    }
    pts.iter().map(|&p| est.apply(p).distance(gt.apply(p))).sum::<f64>() / pts.len() as f64
}

/// At most this many vertices are the queries of a nearest-neighbour figure (ADD-S,
/// [`crate::symmetry::symmetries`]): a bigger mesh is read through an evenly strided
/// subset of them ([`strided`]), as BOP's evaluation reads a model's points — the
/// 1 M-triangle meshes a scanner makes would otherwise cost seconds per figure (a
/// Linemod model, up to 23 k vertices, is read whole).
pub const MAX_QUERY_POINTS: usize = 50_000;

/// Every k-th of `pts`, k the smallest step leaving at most `max` of them (all of
/// them when there are no more than `max`).
pub fn strided(pts: &[DVec3], max: usize) -> impl Iterator<Item = &DVec3> {
    pts.iter().step_by(pts.len().div_ceil(max.max(1)).max(1))
}

/// ADD-S: the mean over the used vertices `p` of the distance from `gt(p)` to the
/// nearest of the points `est(q)` (all of them, in a k-d tree), scene units; over at
/// most [`MAX_QUERY_POINTS`] of the `p` ([`strided`]); 0 for a mesh with no used
/// vertex.
pub fn add_s(mesh: &Mesh, est: &Pose, gt: &Pose) -> f64 {
    let pts = mesh.used_points();
    if pts.is_empty() {
        return 0.0;
    }
    let posed: Vec<[f64; 3]> = pts.iter().map(|&p| est.apply(p).to_array()).collect();
    let tree: ImmutableKdTree<f64, 3> = ImmutableKdTree::new_from_slice(&posed);
    let (sum, n) = strided(&pts, MAX_QUERY_POINTS).fold((0.0, 0usize), |(sum, n), &p| {
        let d = tree.nearest_one::<SquaredEuclidean>(&gt.apply(p).to_array()).distance;
        (sum + d.sqrt(), n + 1)
    });
    sum / n as f64
}

/// The pose figures of SPEC §6 for one scene.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub struct PoseErrors {
    /// Geodesic rotation error, degrees ([`rotation_error_deg`]).
    pub rotation_deg: f64,
    /// Translation error, scene units ([`translation_error`]).
    pub translation: f64,
    /// Worst-axis relative scale error ([`scale_error`]).
    pub scale: f64,
    /// Mean-axis relative scale error ([`scale_error_mean`]).
    pub scale_mean: f64,
    /// ADD, scene units ([`add`]).
    pub add: f64,
    /// ADD-S, scene units ([`add_s`]).
    pub add_s: f64,
    /// The object's diameter under the true pose (scale applied), scene units.
    pub diameter: f64,
    /// `add / diameter` (the usual success threshold is 0.1).
    pub add_rel: f64,
    /// `add_s / diameter`.
    pub add_s_rel: f64,
}

/// All pose figures of `est` against `gt`; the diameter is that of the mesh's
/// vertices placed by `gt` (see [`Mesh::diameter`]).
pub fn pose_errors(mesh: &Mesh, est: &Pose, gt: &Pose) -> PoseErrors {
    let posed = Mesh {
        positions: mesh.positions.iter().map(|&p| gt.apply(p)).collect(),
        triangles: mesh.triangles.clone(),
    };
    let diameter = posed.diameter();
    let (a, s) = (add(mesh, est, gt), add_s(mesh, est, gt));
    let rel = |v: f64| if diameter > 0.0 { v / diameter } else { 0.0 };
    PoseErrors {
        rotation_deg: rotation_error_deg(est, gt),
        translation: translation_error(est, gt),
        scale: scale_error(est, gt),
        scale_mean: scale_error_mean(est, gt),
        add: a,
        add_s: s,
        diameter,
        add_rel: rel(a),
        add_s_rel: rel(s),
    }
}

fn assert_same_size(a: &Mask, b: &Mask) {
    assert!(
        a.width == b.width && a.height == b.height,
        "masks differ in size: {}×{} and {}×{}",
        a.width,
        a.height,
        b.width,
        b.height
    );
}

/// Hard intersection over union of two masks, |A ∩ B| / |A ∪ B|; 0 when both are empty.
///
/// # Panics
/// If the sizes differ.
pub fn hard_iou(a: &Mask, b: &Mask) -> f64 {
    assert_same_size(a, b);
    let (mut inter, mut union) = (0usize, 0usize);
    for (&x, &y) in a.data.iter().zip(&b.data) {
        let (x, y) = (x != 0, y != 0);
        inter += (x && y) as usize;
        union += (x || y) as usize;
    }
    if union == 0 {
        0.0
    } else {
        inter as f64 / union as f64
    }
}

/// Hard IoU of `a` (a render) against `b` (a mask) counting only the pixels not set
/// in `ignore` (SPEC §2: ignored pixels count in no IoU); [`hard_iou`] without one.
///
/// # Panics
/// If the sizes differ.
pub fn hard_iou_known(a: &Mask, b: &Mask, ignore: Option<&Mask>) -> f64 {
    let Some(ig) = ignore else { return hard_iou(a, b) };
    assert_same_size(a, b);
    assert_same_size(a, ig);
    let (mut inter, mut union) = (0usize, 0usize);
    for ((&x, &y), &i) in a.data.iter().zip(&b.data).zip(&ig.data) {
        if i != 0 {
            continue;
        }
        let (x, y) = (x != 0, y != 0);
        inter += (x && y) as usize;
        union += (x || y) as usize;
    }
    if union == 0 {
        0.0
    } else {
        inter as f64 / union as f64
    }
}

/// The contour of a mask: its object pixels with a 4-neighbour that is background
/// or outside the image.
pub fn contour(mask: &Mask) -> Mask {
    let (w, h) = (mask.width as usize, mask.height as usize);
    let mut out = Mask::empty(mask.width, mask.height);
    let on = |x: usize, y: usize| mask.data[y * w + x] != 0;
    for y in 0..h {
        for x in 0..w {
            if on(x, y)
                && (x == 0
                    || y == 0
                    || x + 1 == w
                    || y + 1 == h
                    || !on(x - 1, y)
                    || !on(x + 1, y)
                    || !on(x, y - 1)
                    || !on(x, y + 1))
            {
                out.data[y * w + x] = 1;
            }
        }
    }
    out
}

/// Distances in pixels between the contours of two masks (see [`contour`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub struct ContourDistance {
    /// Symmetric Hausdorff distance: the largest distance from a contour pixel of
    /// either mask to the nearest contour pixel of the other.
    pub hausdorff: f64,
    /// Average symmetric contour distance: the mean of those nearest distances over
    /// the contour pixels of both masks together.
    pub mean: f64,
}

/// Contour distances between `a` and `b`. Both empty: 0 and 0. One empty: both
/// figures are `width + height`, more than any distance between two pixels.
///
/// The work is done in the bounding box of both masks' object pixels (a pixel next to
/// it is background or outside the image, so the contours there are the same), so its
/// cost follows the object, not the image: a small object in a 12-MP photograph costs
/// what it would in a small image.
///
/// # Panics
/// If the sizes differ.
pub fn contour_distance(a: &Mask, b: &Mask) -> ContourDistance {
    assert_same_size(a, b);
    let (w, h) = (a.width as usize, a.height as usize);
    let union = match (a.bbox(), b.bbox()) {
        (Some(p), Some(q)) => (p.0.min(q.0), p.1.min(q.1), p.2.max(q.2), p.3.max(q.3)),
        (None, None) => {
            return ContourDistance {
                hausdorff: 0.0,
                mean: 0.0,
            }
        }
        _ => {
            let v = (w + h) as f64;
            return ContourDistance { hausdorff: v, mean: v };
        }
    };
    let (sa, sb) = (contour_in(a, union), contour_in(b, union));
    let (na, nb) = (sa.iter().filter(|&&s| s).count(), sb.iter().filter(|&&s| s).count());
    let (cw, ch) = ((union.2 - union.0 + 1) as usize, (union.3 - union.1 + 1) as usize);
    let (da, db) = (edt::squared_distance(cw, ch, &sa), edt::squared_distance(cw, ch, &sb));
    let (mut max2, mut sum) = (0.0f64, 0.0f64);
    for i in 0..cw * ch {
        if sa[i] {
            max2 = max2.max(db[i]);
            sum += db[i].sqrt();
        }
        if sb[i] {
            max2 = max2.max(da[i]);
            sum += da[i].sqrt();
        }
    }
    ContourDistance {
        hausdorff: max2.sqrt(),
        mean: sum / (na + nb) as f64,
    }
}

/// [`contour`] of `mask` within the inclusive box `(x0, y0, x1, y1)`, which holds every
/// object pixel: row-major over the box, `true` on the contour. A neighbour outside the
/// box is background (or outside the image), as it is in the whole mask.
fn contour_in(mask: &Mask, (x0, y0, x1, y1): (u32, u32, u32, u32)) -> Vec<bool> {
    let w = mask.width as usize;
    let (x0, y0, x1, y1) = (x0 as usize, y0 as usize, x1 as usize, y1 as usize);
    let on = |x: usize, y: usize| mask.data[y * w + x] != 0;
    let mut out = Vec::with_capacity((x1 - x0 + 1) * (y1 - y0 + 1));
    for y in y0..=y1 {
        for x in x0..=x1 {
            out.push(
                on(x, y)
                    && (x == x0
                        || y == y0
                        || x == x1
                        || y == y1
                        || !on(x - 1, y)
                        || !on(x + 1, y)
                        || !on(x, y - 1)
                        || !on(x, y + 1)),
            );
        }
    }
    out
}

/// Symmetric Hausdorff distance in pixels between the two masks' contours
/// ([`contour_distance`]`.hausdorff`; `width + height` when exactly one is empty).
pub fn hausdorff_px(a: &Mask, b: &Mask) -> f64 {
    contour_distance(a, b).hausdorff
}

/// Average symmetric contour distance in pixels ([`contour_distance`]`.mean`).
pub fn mean_contour_distance_px(a: &Mask, b: &Mask) -> f64 {
    contour_distance(a, b).mean
}

/// The median of `v` (the mean of the two middle values for an even count), NaN for
/// an empty slice.
pub fn median(v: &[f64]) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    match s.len() {
        0 => f64::NAN,
        n if n % 2 == 1 => s[n / 2],
        n => 0.5 * (s[n / 2 - 1] + s[n / 2]),
    }
}

/// The geometric mean `exp(mean(ln x))` of positive values (0 when one is 0), NaN for
/// an empty slice.
pub fn geometric_mean(x: &[f64]) -> f64 {
    if x.is_empty() {
        return f64::NAN;
    }
    (x.iter().map(|v| v.ln()).sum::<f64>() / x.len() as f64).exp()
}
