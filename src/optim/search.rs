//! Coarse orientation search (paper §3.1.3; SPEC §4 step 3): candidate rotations —
//! a uniform SO(3) sampling (default) or the paper's k³ Euler grid — each scored
//! cheaply by hard-silhouette IoU at low resolution after re-fitting the translation
//! and an isotropic scale to the masks' centroids and areas; the n best distinct
//! candidates are kept for refinement.

use crate::camera::Camera;
use crate::mesh::Mesh;
use crate::pose::Pose;
use crate::raster::hard::{render_bits, BitMask};
use crate::raster::project::project_mesh;
use crate::so3;
use crate::view::View;
use glam::{DMat3, DVec2, DVec3};

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
    /// How many of the best distinct candidates to keep (default 8).
    pub keep: usize,
    /// Longest image side at which candidates are scored (default 64 px).
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
            keep: 8,
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

/// A view prepared for cheap scoring: its camera and mask at low resolution.
#[derive(Debug, Clone)]
pub struct LowResView {
    /// The camera scaled to the low resolution.
    pub camera: Camera,
    /// The mask, resampled, as bits.
    pub bits: BitMask,
    /// Object pixels of the resampled mask.
    pub area: f64,
    /// Their centroid.
    pub centroid: DVec2,
}

/// Prepares the views for scoring at `resolution` (longest side).
pub fn low_res_views(views: &[View], resolution: u32) -> Vec<LowResView> {
    views
        .iter()
        .map(|v| {
            let (w, h) = fit_size(v.camera.width, v.camera.height, resolution);
            let camera = v.camera.scaled(w, h);
            let mask = v.mask.resample(w, h);
            let bits = BitMask::from_mask(&mask);
            let (area, centroid) = stats(&bits);
            LowResView {
                camera,
                bits,
                area,
                centroid,
            }
        })
        .collect()
}

/// The size with longest side `max_side` (never larger than the original).
pub fn fit_size(w: u32, h: u32, max_side: u32) -> (u32, u32) {
    let m = w.max(h);
    if m <= max_side {
        return (w, h);
    }
    let f = max_side as f64 / m as f64;
    (
        ((w as f64 * f).round() as u32).max(1),
        ((h as f64 * f).round() as u32).max(1),
    )
}

/// Area (pixels) and centroid of a bit mask, by popcount per word and trailing-zero
/// walks over the set bits.
pub fn stats(b: &BitMask) -> (f64, DVec2) {
    let stride = b.stride();
    let (mut n, mut sx, mut sy) = (0u64, 0u64, 0u64);
    for (i, &w) in b.words.iter().enumerate() {
        if w == 0 {
            continue;
        }
        let (y, x0) = ((i / stride) as u64, 64 * (i % stride) as u64);
        let c = w.count_ones() as u64;
        n += c;
        sy += y * c;
        let mut bits = w;
        while bits != 0 {
            sx += x0 + bits.trailing_zeros() as u64;
            bits &= bits - 1;
        }
    }
    if n == 0 {
        return (0.0, DVec2::ZERO);
    }
    (n as f64, DVec2::new(sx as f64 / n as f64, sy as f64 / n as f64))
}

/// A scored candidate.
#[derive(Debug, Clone, Copy)]
pub struct Candidate {
    /// Its pose after the translation/scale re-fit.
    pub pose: Pose,
    /// Mean hard IoU over the views at low resolution.
    pub score: f64,
}

/// Re-fits translation and isotropic scale of `pose` to the views' centroids and
/// areas, `rounds` times, then scores it. `centre` is the mesh's model-frame centre.
pub fn score_candidate(mesh: &Mesh, views: &[LowResView], mut pose: Pose, centre: DVec3, rounds: usize) -> Candidate {
    for _ in 0..rounds {
        let mut area_r = 0.0;
        let mut area_m = 0.0;
        let mut a = DMat3::ZERO;
        let mut b = DVec3::ZERO;
        for v in views {
            let proj = project_mesh(mesh, &pose, &v.camera);
            let bits = render_bits(&proj, &mesh.triangles, &v.camera);
            let (ar, cr) = stats(&bits);
            area_r += ar;
            area_m += v.area;
            if ar == 0.0 {
                continue;
            }
            // Shift the object so its rendered centroid moves onto the mask's:
            // a camera-frame move (Δx, Δy) at the object's depth z.
            let z = v.camera.to_camera(pose.apply(centre)).z.max(1e-9);
            let d = v.centroid - cr;
            let target = DVec3::new(d.x * z / v.camera.fx, d.y * z / v.camera.fy, 0.0);
            let r = v.camera.rotation;
            // Least squares over views of |P·R·Δt − target|², P dropping the z row.
            let rx = r.row(0);
            let ry = r.row(1);
            a += DMat3::from_cols(rx * rx.x, rx * rx.y, rx * rx.z) + DMat3::from_cols(ry * ry.x, ry * ry.y, ry * ry.z);
            b += rx * target.x + ry * target.y;
        }
        if area_r == 0.0 {
            break;
        }
        // A little damping keeps one-view (depth-blind) fits well posed.
        let damp = 1e-6 * (a.x_axis.x + a.y_axis.y + a.z_axis.z);
        let dt = (a + DMat3::IDENTITY * damp).inverse() * b;
        let ds = (area_m / area_r).sqrt().clamp(0.5, 2.0);
        // Scale about the object's centre, so the centre stays where it was moved to.
        let c_world = pose.apply(centre) + if dt.is_finite() { dt } else { DVec3::ZERO };
        pose.scale *= ds;
        pose.translation = c_world - pose.rotation * (pose.scale * centre);
    }
    let score = views
        .iter()
        .map(|v| {
            let proj = project_mesh(mesh, &pose, &v.camera);
            render_bits(&proj, &mesh.triangles, &v.camera).iou(&v.bits)
        })
        .sum::<f64>()
        / views.len().max(1) as f64;
    Candidate { pose, score }
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
    use crate::mask::Mask;

    #[test]
    fn stats_match_the_mask() {
        let mut m = Mask::empty(130, 7);
        for (x, y) in [(0, 0), (63, 1), (64, 1), (129, 6), (70, 3)] {
            m.data[y * 130 + x] = 1;
        }
        let (n, c) = stats(&BitMask::from_mask(&m));
        assert_eq!(n, m.area() as f64);
        assert!((c - m.centroid().unwrap()).length() < 1e-12);
        assert_eq!(stats(&BitMask::from_mask(&Mask::empty(5, 5))).0, 0.0);
    }

    #[test]
    fn keeps_distinct_candidates() {
        let c = |deg: f64, score: f64| Candidate {
            pose: Pose {
                rotation: DMat3::from_rotation_z(deg.to_radians()),
                ..Pose::IDENTITY
            },
            score,
        };
        let best = select_best(vec![c(0.0, 0.9), c(10.0, 0.95), c(90.0, 0.5), c(200.0, 0.7)], 3, 30.0);
        let scores: Vec<f64> = best.iter().map(|c| c.score).collect();
        assert_eq!(scores, vec![0.95, 0.7, 0.5], "0° is within 30° of the better 10°");
    }
}
