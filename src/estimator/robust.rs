//! Occlusion without an ignore mask (SPEC §4): the views' robust weights and the
//! leave-one-out consensus test, and the short Levenberg–Marquardt fits they use.

use super::refine::Track;
use crate::error::Result;
use crate::loss::objective::Objective;
use crate::metrics::median;
use crate::optim::lm::Lm;
use crate::optim::params::ScaleMode;
use crate::pose::Pose;
use crate::raster::silhouette::RenderMesh;

/// Levenberg–Marquardt iterations of `objective` from `start`; the best pose and loss.
pub(super) fn polish(
    objective: &mut Objective,
    mesh: &RenderMesh,
    start: Pose,
    iterations: usize,
    mode: ScaleMode,
    radius: f64,
) -> Result<(Pose, f64)> {
    let mut lm = Lm::new();
    let mut pose = start;
    for _ in 0..iterations {
        let (_, ne) = objective.normal_equations(mesh, &pose)?;
        pose = lm.next_pose(pose, &ne, mode, radius * pose.scale.max_element());
        if lm.stalled() {
            break;
        }
    }
    Ok(lm.best().map_or((start, f64::INFINITY), |(p, c)| (*p, c)))
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
    mode: ScaleMode,
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
    let (median, worst) = (median(&losses), losses.iter().fold(f64::NEG_INFINITY, |m, &l| m.max(l)));
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
        let (pose, _) = polish(objective, mesh, track.pose, LOO_ITERATIONS, mode, radius)?;
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
pub(super) fn robust_weights(losses: &[f64]) -> Vec<f64> {
    if losses.len() < 3 || losses.iter().any(|r| !r.is_finite()) {
        return vec![1.0; losses.len()];
    }
    let tau = (2.0 * median(losses)).max(0.05);
    losses
        .iter()
        .map(|&r| if r <= tau { 1.0 } else { (tau / r).powi(2) })
        .collect()
}
