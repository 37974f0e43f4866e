//! Coarse orientation search (paper §3.1.3; SPEC §4 step 3): candidate rotations —
//! a uniform SO(3) sampling (default) or the paper's k³ Euler grid — each scored
//! cheaply by hard-silhouette IoU (over known pixels, bit masks and popcount) in the
//! views' windows at low resolution, after re-fitting the translation (and, unless
//! the scale is fixed, an isotropic scale) to the masks' centroids and areas; the n
//! best distinct candidates are kept for refinement. The views are the search
//! [`Objective`](crate::loss::objective::Objective)'s targets.

use crate::loss::target::ViewTarget;
use crate::mesh::Mesh;
use crate::pose::Pose;
use crate::raster::hard::{render_bits_into, BitMask};
use crate::raster::project::project_mesh;
use crate::so3;
use glam::{DMat3, DVec3};

/// Which rotations to try.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Sampling {
    /// `n` rotations spread uniformly over SO(3) (super-Fibonacci spiral).
    Uniform(usize),
    /// The paper's grid: `k` bins per intrinsic-XYZ Euler axis, `k³` rotations.
    EulerGrid(usize),
}

/// Search settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SearchSettings {
    /// Candidate rotations (default `Uniform(512)`).
    pub sampling: Sampling,
    /// How many of the best distinct candidates to keep (default 12: with 4, two-view
    /// real scenes lost the true basin — LM-O holepuncher, eggbox, ape — to a flipped one).
    pub keep: usize,
    /// Canvas pixels across each view's window at which candidates are scored (default 64).
    pub resolution: u32,
    /// Two kept candidates are at least this far apart, degrees (default 30).
    pub min_separation_deg: f64,
    /// Translation/scale re-fit rounds per candidate (default 2).
    pub refit_rounds: usize,
}

impl Default for SearchSettings {
    fn default() -> Self {
        SearchSettings {
            sampling: Sampling::Uniform(512),
            keep: 12,
            resolution: 64,
            min_separation_deg: 30.0,
            refit_rounds: 2,
        }
    }
}

impl Sampling {
    /// The candidate rotations.
    pub fn rotations(&self) -> Vec<DMat3> {
        match *self {
            Sampling::Uniform(n) => so3::uniform_samples(n),
            Sampling::EulerGrid(k) => so3::euler_grid(k),
        }
    }
}

/// A scored candidate.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Candidate {
    /// Its pose after the translation/scale re-fit.
    pub pose: Pose,
    /// Mean hard IoU over the views at low resolution.
    pub score: f64,
    /// Each view's hard IoU.
    pub ious: Vec<f64>,
}

/// Re-fits the translation (and with `refit_scale` an isotropic scale) of `pose` to
/// the targets' mask centroids and areas, `rounds` times, then scores it by the mean
/// hard IoU over the views. `centre` is the mesh's model-frame centre; `bits` scratch.
///
/// With three views or more the re-fit is robust to one view that disagrees (an
/// occluded mask's centroid and area are off): the translation is the
/// iteratively re-weighted least-squares solution over the views' centroid shifts
/// (weights `1/(1 + (e_v/2ẽ)²)`, e_v a view's residual, ẽ their median), and the
/// scale follows the median of the views' area ratios.
pub fn score_candidate(
    mesh: &Mesh,
    targets: &[ViewTarget],
    mut pose: Pose,
    centre: DVec3,
    rounds: usize,
    refit_scale: bool,
    bits: &mut BitMask,
) -> Candidate {
    let robust = targets.len() >= 3;
    for _ in 0..rounds {
        // Per view: the two camera-axis rows and the wanted camera-frame shift.
        let mut rows = Vec::with_capacity(targets.len());
        let mut ratios = Vec::with_capacity(targets.len());
        let (mut area_r, mut area_m) = (0.0, 0.0);
        for t in targets {
            let proj = project_mesh(mesh, &pose, &t.camera);
            render_bits_into(&proj, &mesh.triangles, &t.camera, bits);
            t.keep_known(bits);
            let (ar, cr) = bits.area_and_centroid();
            area_r += ar;
            area_m += t.area;
            if ar == 0.0 || t.area == 0.0 {
                continue;
            }
            ratios.push(t.area / ar);
            // Shift the object so its rendered centroid moves onto the mask's:
            // a camera-frame move (Δx, Δy) at the object's depth z.
            let z = t.camera.to_camera(pose.apply(centre)).z.max(1e-9);
            let d = t.centroid - cr;
            let r = t.camera.rotation;
            rows.push((r.row(0), r.row(1), d.x * z / t.camera.fx, d.y * z / t.camera.fy));
        }
        if area_r == 0.0 {
            break;
        }
        let solve = |w: &[f64]| {
            // Least squares over views of w·|P·R·Δt − target|², P dropping the z row.
            let mut a = DMat3::ZERO;
            let mut b = DVec3::ZERO;
            for (&(rx, ry, tx, ty), &w) in rows.iter().zip(w) {
                a += (DMat3::from_cols(rx * rx.x, rx * rx.y, rx * rx.z)
                    + DMat3::from_cols(ry * ry.x, ry * ry.y, ry * ry.z))
                    * w;
                b += (rx * tx + ry * ty) * w;
            }
            // A little damping keeps one-view (depth-blind) fits well posed.
            let damp = 1e-6 * (a.x_axis.x + a.y_axis.y + a.z_axis.z);
            (a + DMat3::IDENTITY * damp).inverse() * b
        };
        let mut w = vec![1.0; rows.len()];
        let mut dt = solve(&w);
        if robust && rows.len() >= 3 {
            for _ in 0..3 {
                let e: Vec<f64> = rows
                    .iter()
                    .map(|&(rx, ry, tx, ty)| ((rx.dot(dt) - tx).powi(2) + (ry.dot(dt) - ty).powi(2)).sqrt())
                    .collect();
                let med = median(&e).max(1e-12);
                w = e.iter().map(|&e| 1.0 / (1.0 + (e / (2.0 * med)).powi(2))).collect();
                dt = solve(&w);
            }
        }
        let ds = if !refit_scale {
            1.0
        } else if robust && ratios.len() >= 3 {
            median(&ratios).sqrt().clamp(0.5, 2.0)
        } else {
            (area_m / area_r).sqrt().clamp(0.5, 2.0)
        };
        // Scale about the object's centre, so the centre stays where it was moved to.
        let c_world = pose.apply(centre) + if dt.is_finite() { dt } else { DVec3::ZERO };
        pose.scale *= ds;
        pose.translation = c_world - pose.rotation * (pose.scale * centre);
    }
    let ious: Vec<f64> = targets
        .iter()
        .map(|t| {
            let proj = project_mesh(mesh, &pose, &t.camera);
            render_bits_into(&proj, &mesh.triangles, &t.camera, bits);
            t.hard_iou(bits)
        })
        .collect();
    let score = ious.iter().sum::<f64>() / ious.len().max(1) as f64;
    Candidate { pose, score, ious }
}

/// The median of a non-empty slice (0 for an empty one).
fn median(v: &[f64]) -> f64 {
    if v.is_empty() {
        0.0
    } else {
        crate::metrics::median(v)
    }
}

/// The `keep` best candidates, at least `min_sep_deg` apart in rotation, best first.
pub fn select_best(mut all: Vec<Candidate>, keep: usize, min_sep_deg: f64) -> Vec<Candidate> {
    all.sort_by(|a, b| b.score.total_cmp(&a.score));
    let mut out: Vec<Candidate> = Vec::with_capacity(keep);
    for c in all {
        if out.len() >= keep {
            break;
        }
        if out
            .iter()
            .all(|o| so3::geodesic_deg(o.pose.rotation, c.pose.rotation) >= min_sep_deg)
        {
            out.push(c);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keeps_distinct_candidates() {
        let c = |deg: f64, score: f64| Candidate {
            pose: Pose {
                rotation: DMat3::from_rotation_z(deg.to_radians()),
                ..Pose::IDENTITY
            },
            score,
            ious: vec![score],
        };
        let best = select_best(vec![c(0.0, 0.9), c(10.0, 0.95), c(90.0, 0.5), c(200.0, 0.7)], 3, 30.0);
        let scores: Vec<f64> = best.iter().map(|c| c.score).collect();
        assert_eq!(scores, vec![0.95, 0.7, 0.5], "0° is within 30° of the better 10°");
    }
}
