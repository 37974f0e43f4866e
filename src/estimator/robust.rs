//! Occlusion without an ignore mask (SPEC §4): the views' robust weights and the
//! leave-one-out consensus test, and the short Levenberg–Marquardt fits they use.

use super::settings::ScaleMode;
use super::Track;
use crate::error::Result;
use crate::loss::objective::Objective;
use crate::optim::lm::{self, Free, Lm};
use crate::optim::params;
use crate::pose::Pose;
use crate::raster::silhouette::RenderMesh;

/// The LM parameters a scale mode frees.
pub(super) fn free_parameters(mode: ScaleMode) -> Free {
    match mode {
        ScaleMode::Fixed => Free::NoScale,
        ScaleMode::Isotropic => Free::IsotropicScale,
        ScaleMode::Anisotropic => Free::All,
    }
}

/// Levenberg–Marquardt iterations of `objective` from `start`; the best pose and loss.
pub(super) fn polish(
    objective: &mut Objective,
    mesh: &RenderMesh,
    start: Pose,
    iterations: usize,
    free: Free,
    radius: f64,
) -> Result<(Pose, f64)> {
    let mut lm = Lm::new();
    let (mut pose, mut best) = (start, (start, f64::INFINITY));
    for _ in 0..iterations {
        let (ev, ne) = objective.normal_equations(mesh, &pose)?;
        if ev.total < best.1 {
            best = (pose, ev.total);
        }
        let length = radius * pose.scale.max_element();
        pose = lm.next_pose(pose, lm::scale_equations(&ne, length), free, |p, d| {
            params::apply(p, d, length)
        });
    }
    Ok(best)
}

/// Iterations of each leave-one-out fit.
const LOO_ITERATIONS: usize = 15;

/// The leave-one-out consensus test (SPEC §4, occlusion without an ignore mask): when
/// one view's loss stands out at the candidate's pose, each view in turn is left out
/// for a short fit; a view is inconsistent when, without it, the others agree better
/// (their mean IoU loss falls) while it disagrees with them (its loss above twice the
/// worst of theirs, plus 0.05). Returns the view
/// whose omission helps the others most, with the pose fitted without it.
pub(super) fn leave_one_out(
    objective: &mut Objective,
    mesh: &RenderMesh,
    track: &Track,
    free: Free,
    radius: f64,
) -> Result<Option<(usize, Pose)>> {
    let n = track.weights.len();
    if n < 3 || track.excluded.iter().any(|&x| x) {
        return Ok(None);
    }
    objective.set_weights(&track.weights)?;
    let losses: Vec<f64> = objective
        .value(mesh, &track.pose)?
        .views
        .iter()
        .map(|v| v.iou)
        .collect();
    let mut sorted = losses.clone();
    sorted.sort_by(f64::total_cmp);
    let (median, worst) = (sorted[n / 2], sorted[n - 1]);
    if worst <= 1.3 * median || worst < median + 0.05 {
        return Ok(None);
    }
    let mut found: Option<(f64, usize, Pose)> = None;
    for v in 0..n {
        let mut w = track.weights.clone();
        w[v] = 0.0;
        if w.iter().sum::<f64>() <= 0.0 {
            continue;
        }
        objective.set_weights(&w)?;
        let (pose, _) = polish(objective, mesh, track.pose, LOO_ITERATIONS, free, radius)?;
        let l: Vec<f64> = objective.value(mesh, &pose)?.views.iter().map(|v| v.iou).collect();
        let others = |x: &[f64]| {
            x.iter()
                .enumerate()
                .filter(|(u, _)| *u != v)
                .map(|(_, l)| *l)
                .collect::<Vec<_>>()
        };
        let (before, after) = (others(&losses), others(&l));
        let mean = |x: &[f64]| x.iter().sum::<f64>() / x.len() as f64;
        let worst_other = after.iter().fold(0.0f64, |m, x| m.max(*x));
        if mean(&after) < mean(&before)
            && l[v] > 2.0 * worst_other + 0.05
            && found.as_ref().is_none_or(|f| mean(&after) < f.0)
        {
            found = Some((mean(&after), v, pose));
        }
    }
    objective.set_weights(&track.weights)?;
    Ok(found.map(|(_, v, p)| (v, p)))
}

/// The views' weights from their soft IoU losses `r_v` at a candidate's pose (SPEC
/// §4, occlusion without an ignore mask): a view whose loss is far above the others'
/// contradicts them — an occluder, the gripper, a bad mask — and is down-weighted.
/// With the robust scale `τ = max(2·median(r), 0.05)`, `w_v = 1` for `r_v ≤ τ` and
/// `(τ/r_v)²` above (a Cauchy-like tail); with fewer than 3 views there is no majority
/// to trust and every weight is 1.
pub fn robust_weights(losses: &[f64]) -> Vec<f64> {
    if losses.len() < 3 || losses.iter().any(|r| !r.is_finite()) {
        return vec![1.0; losses.len()];
    }
    let mut sorted = losses.to_vec();
    sorted.sort_by(f64::total_cmp);
    let n = sorted.len();
    let median = if n % 2 == 1 {
        sorted[n / 2]
    } else {
        0.5 * (sorted[n / 2 - 1] + sorted[n / 2])
    };
    let tau = (2.0 * median).max(0.05);
    losses
        .iter()
        .map(|&r| if r <= tau { 1.0 } else { (tau / r).powi(2) })
        .collect()
}
