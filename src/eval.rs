//! The paper's evaluation (SPEC §6) over a set of fitted scenes: precision, recall
//! and F1 of the estimated silhouettes at IoU > 0.25 / 0.5 / 0.75 (the paper's
//! Table 1), accuracy at ADD(-S) < 10 % of the object's diameter, error
//! distributions, grasp accuracy (Table 3) and the final loss against the number of
//! views (Fig. 6). Pure: it takes per-scene outcomes and returns figures and text.
//!
//! What counts (stated in the report too): every view of every scene holds one
//! ground-truth object (its mask). The fit makes one prediction per view — the
//! estimated pose's hard silhouette — unless that silhouette is empty (the object
//! left the view), which is a missed detection. A prediction is a true positive at
//! threshold τ when its IoU with the mask exceeds τ. Precision = TP / predictions,
//! recall = TP / ground-truth objects, F1 = 2PR / (P + R).

use crate::result::FitResult;
use serde::{Deserialize, Serialize};

/// One scene's outcome.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct SceneOutcome {
    /// The scene's name (its folder).
    pub name: String,
    /// Number of views.
    pub views: usize,
    /// Whether ADD-S (rather than ADD) is the accuracy measure (symmetric object).
    pub symmetric: bool,
    /// The fit's result (with `errors`, since eval scenes carry a ground truth).
    pub result: FitResult,
    /// Rendered silhouette area per view, pixels (0 = no prediction).
    pub predicted_area: Vec<usize>,
    /// Grasps transferred correctly / grasps in the scene (per view and grasp).
    pub grasps_correct: usize,
    /// Grasp checks made.
    pub grasps_total: usize,
    /// Final loss of re-fits using only the first k views, k = 1..=views.
    pub loss_by_views: Vec<f64>,
    /// ADD (or ADD-S) relative to the diameter of those re-fits.
    pub add_rel_by_views: Vec<f64>,
}

/// Precision, recall and F1 at one IoU threshold.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct PrfRow {
    /// IoU threshold (strictly greater than counts).
    pub threshold: f64,
    /// True positives.
    pub tp: usize,
    /// Predictions made.
    pub predictions: usize,
    /// Ground-truth objects.
    pub ground_truths: usize,
    /// TP / predictions.
    pub precision: f64,
    /// TP / ground truths.
    pub recall: f64,
    /// Harmonic mean of precision and recall.
    pub f1: f64,
}

/// Figures over a set of scenes.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Summary {
    /// Number of scenes.
    pub scenes: usize,
    /// P/R/F1 at IoU > 0.25, 0.5, 0.75.
    pub prf: Vec<PrfRow>,
    /// Fraction of scenes with ADD (ADD-S for symmetric objects) < 10 % of the diameter.
    pub add_accuracy: f64,
    /// Median rotation error, degrees.
    pub median_rotation_deg: f64,
    /// Median translation error, scene units.
    pub median_translation: f64,
    /// Median scale error (max over axes of |s/s_gt − 1|).
    pub median_scale_error: f64,
    /// Median ADD(-S) relative to the diameter.
    pub median_add_rel: f64,
    /// Mean IoU over all views.
    pub mean_iou: f64,
    /// Grasp accuracy (correct / checked), when any grasp was checked.
    pub grasp_accuracy: Option<f64>,
    /// Mean final loss by number of views used (index 0 = one view), with the count of scenes.
    pub loss_by_views: Vec<(usize, f64, usize)>,
    /// Mean ADD(-S)/diameter by number of views used.
    pub add_rel_by_views: Vec<(usize, f64, usize)>,
    /// Median fit time, seconds.
    pub median_seconds: f64,
}

/// The accuracy measure of a scene: ADD-S for symmetric objects, ADD otherwise.
pub fn accuracy_measure(o: &SceneOutcome) -> f64 {
    o.result
        .errors
        .as_ref()
        .map_or(f64::INFINITY, |e| if o.symmetric { e.add_s_rel } else { e.add_rel })
}

fn median(mut v: Vec<f64>) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// P/R/F1 at `threshold` over all views of all scenes.
pub fn prf(outcomes: &[SceneOutcome], threshold: f64) -> PrfRow {
    let (mut tp, mut pred, mut gt) = (0, 0, 0);
    for o in outcomes {
        for (i, v) in o.result.views.iter().enumerate() {
            gt += 1;
            if o.predicted_area.get(i).copied().unwrap_or(0) > 0 {
                pred += 1;
                if v.iou > threshold {
                    tp += 1;
                }
            }
        }
    }
    let ratio = |a: usize, b: usize| if b == 0 { 0.0 } else { a as f64 / b as f64 };
    let (p, r) = (ratio(tp, pred), ratio(tp, gt));
    let f1 = if p + r > 0.0 { 2.0 * p * r / (p + r) } else { 0.0 };
    PrfRow {
        threshold,
        tp,
        predictions: pred,
        ground_truths: gt,
        precision: p,
        recall: r,
        f1,
    }
}

fn by_views(outcomes: &[SceneOutcome], get: impl Fn(&SceneOutcome) -> &Vec<f64>) -> Vec<(usize, f64, usize)> {
    let max = outcomes.iter().map(|o| get(o).len()).max().unwrap_or(0);
    (0..max)
        .map(|k| {
            let vals: Vec<f64> = outcomes
                .iter()
                .filter_map(|o| get(o).get(k).copied())
                .filter(|v| v.is_finite())
                .collect();
            let n = vals.len();
            (
                k + 1,
                if n == 0 {
                    f64::NAN
                } else {
                    vals.iter().sum::<f64>() / n as f64
                },
                n,
            )
        })
        .collect()
}

/// The figures over a set of scene outcomes.
pub fn summarise(outcomes: &[SceneOutcome]) -> Summary {
    let errs: Vec<_> = outcomes.iter().filter_map(|o| o.result.errors.as_ref()).collect();
    let n = outcomes.len();
    let accurate = outcomes.iter().filter(|o| accuracy_measure(o) < 0.1).count();
    let ious: Vec<f64> = outcomes
        .iter()
        .flat_map(|o| o.result.views.iter().map(|v| v.iou))
        .collect();
    let grasps_total: usize = outcomes.iter().map(|o| o.grasps_total).sum();
    let grasps_correct: usize = outcomes.iter().map(|o| o.grasps_correct).sum();
    Summary {
        scenes: n,
        prf: [0.25, 0.5, 0.75].iter().map(|&t| prf(outcomes, t)).collect(),
        add_accuracy: if n == 0 { 0.0 } else { accurate as f64 / n as f64 },
        median_rotation_deg: median(errs.iter().map(|e| e.rotation_deg).collect()),
        median_translation: median(errs.iter().map(|e| e.translation).collect()),
        median_scale_error: median(errs.iter().map(|e| e.scale).collect()),
        median_add_rel: median(outcomes.iter().map(accuracy_measure).collect()),
        mean_iou: if ious.is_empty() {
            0.0
        } else {
            ious.iter().sum::<f64>() / ious.len() as f64
        },
        grasp_accuracy: (grasps_total > 0).then(|| grasps_correct as f64 / grasps_total as f64),
        loss_by_views: by_views(outcomes, |o| &o.loss_by_views),
        add_rel_by_views: by_views(outcomes, |o| &o.add_rel_by_views),
        median_seconds: median(outcomes.iter().map(|o| o.result.seconds).collect()),
    }
}

/// The report as Markdown: the set's tables, then one row per scene.
pub fn report_markdown(summary: &Summary, outcomes: &[SceneOutcome]) -> String {
    let mut s = String::new();
    let pct = |v: f64| format!("{:.1} %", 100.0 * v);
    s += &format!("# LocaliseBot evaluation: {} scenes\n\n", summary.scenes);
    s += "## Silhouette detection (the paper's Table 1)\n\n";
    s += "Every view of every scene holds one ground-truth object (its mask). The fit predicts one silhouette per \
          view (the estimated pose's hard render); an empty render is no prediction. A prediction is a true \
          positive at threshold τ when its IoU with the mask is greater than τ. Precision = TP / predictions, \
          recall = TP / ground-truth objects.\n\n";
    s += "| IoU > | TP | predictions | objects | precision | recall | F1 |\n|---|---|---|---|---|---|---|\n";
    for r in &summary.prf {
        s += &format!(
            "| {} | {} | {} | {} | {:.3} | {:.3} | {:.3} |\n",
            r.threshold, r.tp, r.predictions, r.ground_truths, r.precision, r.recall, r.f1
        );
    }
    s += "\n## Pose accuracy\n\nFor objects with a symmetry (a rotation of the cube group mapping the mesh onto \
          itself), errors are measured against the symmetric equivalent of the true pose closest to the estimate, \
          and accuracy by ADD-S.\n\n| figure | value |\n|---|---|\n";
    s += &format!("| ADD(-S) < 10 % of diameter | {} |\n", pct(summary.add_accuracy));
    s += &format!("| median ADD(-S) / diameter | {} |\n", pct(summary.median_add_rel));
    s += &format!("| median rotation error | {:.2}° |\n", summary.median_rotation_deg);
    s += &format!("| median translation error | {:.4} |\n", summary.median_translation);
    s += &format!("| median scale error | {} |\n", pct(summary.median_scale_error));
    s += &format!("| mean IoU | {:.4} |\n", summary.mean_iou);
    s += &format!("| median fit time | {:.2} s |\n", summary.median_seconds);
    s += "\n## Grasps (the paper's Table 3)\n\n";
    s += &match summary.grasp_accuracy {
        Some(a) => format!(
            "A grasp is correct when, transferred with the estimated pose and projected into a view, its rectangle's \
             angle is within 30° (mod 180°) of the same grasp under the true pose and the rectangles' IoU is over \
             0.25. Grasp accuracy: **{}** ({} of {} grasp-views).\n",
            pct(a),
            outcomes.iter().map(|o| o.grasps_correct).sum::<usize>(),
            outcomes.iter().map(|o| o.grasps_total).sum::<usize>()
        ),
        None => "No scene has grasps.\n".into(),
    };
    s += "\n## Loss against the number of views (the paper's Fig. 6)\n\n";
    s += "Each scene re-fitted with its first k views; mean final loss and mean ADD(-S)/diameter.\n\n";
    s += "| views | scenes | mean final loss | mean ADD(-S)/diameter |\n|---|---|---|---|\n";
    for (l, a) in summary.loss_by_views.iter().zip(&summary.add_rel_by_views) {
        s += &format!("| {} | {} | {:.4} | {} |\n", l.0, l.2, l.1, pct(a.1));
    }
    s += "\n![loss against views](loss_vs_views.svg)\n\n![errors](errors.svg)\n";
    s += "\n## Scenes\n\n| scene | views | rotation ° | translation | scale | ADD(-S)/diam | mean IoU | grasps | s |\n";
    s += "|---|---|---|---|---|---|---|---|---|\n";
    for o in outcomes {
        let e = o.result.errors.as_ref();
        s += &format!(
            "| {} | {} | {:.2} | {:.4} | {} | {} | {:.4} | {}/{} | {:.2} |\n",
            o.name,
            o.views,
            e.map_or(f64::NAN, |e| e.rotation_deg),
            e.map_or(f64::NAN, |e| e.translation),
            pct(e.map_or(f64::NAN, |e| e.scale)),
            pct(accuracy_measure(o)),
            o.result.mean_iou,
            o.grasps_correct,
            o.grasps_total,
            o.result.seconds
        );
    }
    s
}

/// The rotations of the cube group (the 24 signed permutation matrices of
/// determinant +1) that map the mesh onto itself about its bounding box's centre:
/// every rotated vertex lies within 2 % of the diameter of a vertex. Always holds the
/// identity; more than one element means the object is symmetric, and a pose is then
/// only determined up to these rotations (ADD-S is the fair measure).
pub fn symmetries(mesh: &crate::mesh::Mesh) -> Vec<glam::DMat3> {
    use glam::{DMat3, DVec3};
    use kiddo::{KdTree, SquaredEuclidean};
    let mut out = vec![DMat3::IDENTITY];
    let Some(b) = mesh.bounds() else { return out };
    let pts = mesh.used_points();
    if pts.len() < 3 {
        return out;
    }
    let c = b.centre();
    let tol = 0.02 * b.size().length();
    let mut tree: KdTree<f64, 3> = KdTree::new();
    for (i, p) in pts.iter().enumerate() {
        tree.add(&(*p - c).to_array(), i as u64);
    }
    let axes = [DVec3::X, DVec3::Y, DVec3::Z];
    for perm in [[0, 1, 2], [0, 2, 1], [1, 0, 2], [1, 2, 0], [2, 0, 1], [2, 1, 0]] {
        for signs in 0..8u32 {
            let sign = |k: u32| if signs >> k & 1 == 1 { -1.0 } else { 1.0 };
            let m = DMat3::from_cols(
                axes[perm[0]] * sign(0),
                axes[perm[1]] * sign(1),
                axes[perm[2]] * sign(2),
            );
            if (m.determinant() - 1.0).abs() > 1e-9 || m == DMat3::IDENTITY {
                continue;
            }
            let maps = pts.iter().all(|p| {
                let q = m * (*p - c);
                tree.nearest_one::<SquaredEuclidean>(&q.to_array()).distance <= tol * tol
            });
            if maps {
                out.push(m);
            }
        }
    }
    out
}

/// Whether the object has a symmetry of the cube group (see [`symmetries`]).
pub fn is_symmetric(mesh: &crate::mesh::Mesh) -> bool {
    symmetries(mesh).len() > 1
}

/// The pose `gt ∘ S` (first the model symmetry S about the mesh's box centre `c`,
/// then `gt`): the same physical object as `gt`. S is a signed permutation, so
/// `diag(s)·S = S·diag(|Sᵀs|)` and the result is again rotation, translation and
/// per-axis scale.
pub fn compose_symmetry(gt: &crate::Pose, s: glam::DMat3, c: glam::DVec3) -> crate::Pose {
    let scale = (s.transpose() * gt.scale).abs();
    let rotation = gt.rotation * s;
    // gt(S(X − c) + c) = R·(s_gt ⊙ (S X)) + R·(s_gt ⊙ (c − S c)) + t.
    let translation = gt.translation + gt.rotation * (gt.scale * (c - s * c));
    crate::Pose {
        rotation,
        translation,
        scale,
    }
}

/// Among the symmetric equivalents of `gt`, the one closest to `est` (by ADD).
pub fn closest_equivalent(
    mesh: &crate::mesh::Mesh,
    syms: &[glam::DMat3],
    est: &crate::Pose,
    gt: &crate::Pose,
) -> crate::Pose {
    let c = mesh.bounds().map_or(glam::DVec3::ZERO, |b| b.centre());
    syms.iter()
        .map(|s| compose_symmetry(gt, *s, c))
        .min_by(|a, b| crate::metrics::add(mesh, est, a).total_cmp(&crate::metrics::add(mesh, est, b)))
        .unwrap_or(*gt)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::estimator::Termination;
    use crate::metrics::PoseErrors;
    use crate::result::{PoseOut, ViewResult};

    fn outcome(ious: &[f64], areas: &[usize], add_rel: f64) -> SceneOutcome {
        let errors = PoseErrors {
            rotation_deg: 1.0,
            translation: 0.01,
            scale: 0.005,
            scale_mean: 0.004,
            add: add_rel,
            add_s: add_rel,
            diameter: 1.0,
            add_rel,
            add_s_rel: add_rel,
        };
        SceneOutcome {
            name: "s".into(),
            views: ious.len(),
            symmetric: false,
            result: FitResult {
                pose: PoseOut::from_pose(&crate::Pose::IDENTITY),
                matrix: [[0.0; 4]; 4],
                views: ious
                    .iter()
                    .map(|&iou| ViewResult {
                        name: "v".into(),
                        iou,
                        hausdorff_px: 1.0,
                    })
                    .collect(),
                mean_iou: ious.iter().sum::<f64>() / ious.len() as f64,
                loss_history: vec![],
                iterations: 1,
                termination: Some(Termination::Converged),
                seconds: 1.0,
                errors: Some(errors),
            },
            predicted_area: areas.to_vec(),
            grasps_correct: 1,
            grasps_total: 2,
            loss_by_views: vec![0.3, 0.1],
            add_rel_by_views: vec![0.2, 0.01],
        }
    }

    #[test]
    fn precision_recall_counts() {
        // Views: IoU 0.9 (TP at all), 0.6 (TP at .25/.5), 0.3 with an empty render (no prediction).
        let o = vec![
            outcome(&[0.9, 0.6, 0.3], &[100, 100, 0], 0.05),
            outcome(&[0.2], &[50], 0.5),
        ];
        let s = summarise(&o);
        let at = |t: f64| s.prf.iter().find(|r| r.threshold == t).unwrap().clone();
        let r = at(0.25);
        assert_eq!((r.tp, r.predictions, r.ground_truths), (2, 3, 4));
        assert!((r.precision - 2.0 / 3.0).abs() < 1e-12 && (r.recall - 0.5).abs() < 1e-12);
        assert!((r.f1 - 2.0 * (2.0 / 3.0) * 0.5 / (2.0 / 3.0 + 0.5)).abs() < 1e-12);
        assert_eq!(at(0.75).tp, 1);
        assert_eq!(s.add_accuracy, 0.5);
        assert_eq!(s.grasp_accuracy, Some(0.5));
        assert_eq!(s.loss_by_views[0], (1, 0.3, 2));
        let md = report_markdown(&s, &o);
        assert!(md.contains("| 0.25 | 2 | 3 | 4 | 0.667 | 0.500 |"), "{md}");
    }

    #[test]
    fn symmetry_of_box_and_blob() {
        let cube = crate::shapes::cube_mesh(1.0);
        assert!(is_symmetric(&cube));
        assert_eq!(symmetries(&cube).len(), 24, "a cube has the whole group");
        assert!(!is_symmetric(&crate::synth::blob_mesh(12, 25)));
        // An equivalent pose is the same physical object: ADD between them is ~0,
        // for an anisotropic scale too.
        let gt = crate::Pose {
            rotation: crate::so3::exp(glam::DVec3::new(0.3, -0.2, 0.5)),
            translation: glam::DVec3::new(0.1, 0.2, 0.3),
            scale: glam::DVec3::new(1.0, 1.0, 1.0),
        };
        let box_mesh = cube.clone();
        for s in symmetries(&box_mesh) {
            let e = compose_symmetry(&gt, s, box_mesh.bounds().unwrap().centre());
            assert!(crate::metrics::add_s(&box_mesh, &e, &gt) < 1e-9);
        }
        let flipped = compose_symmetry(&gt, symmetries(&box_mesh)[5], glam::DVec3::ZERO);
        assert!(crate::metrics::add(&box_mesh, &flipped, &gt) > 0.1);
        let back = closest_equivalent(&box_mesh, &symmetries(&box_mesh), &flipped, &gt);
        assert!(crate::metrics::add(&box_mesh, &flipped, &back) < 1e-9);
    }
}
