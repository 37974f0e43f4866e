//! The paper's evaluation (SPEC §6) over a set of fitted scenes: precision, recall
//! and F1 of the estimated silhouettes at IoU > 0.25 / 0.5 / 0.75 (the paper's
//! Table 1), accuracy at ADD(-S) < 10 % of the object's diameter, error
//! distributions, grasp accuracy (Table 3) and the final loss against the number of
//! views (Fig. 6). Pure: it takes per-scene outcomes and returns figures and text.
//!
//! What counts (stated in the report too): every view of every scene holds one
//! ground-truth object (its mask). The fit makes one prediction per view — the
//! estimated pose's hard silhouette — unless the fit's verdict is `failed` (the
//! estimator itself rejects the pose) or that silhouette is empty (the object left
//! the view): those are missed detections, so precision and recall differ. A prediction is a true positive at
//! threshold τ when its IoU with the mask exceeds τ. Precision = TP / predictions,
//! recall = TP / ground-truth objects, F1 = 2PR / (P + R).

use crate::estimator::FitResult;
use crate::metrics::median;
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

/// P/R/F1 at `threshold` over all views of all scenes.
pub fn prf(outcomes: &[SceneOutcome], threshold: f64) -> PrfRow {
    let (mut tp, mut pred, mut gt) = (0, 0, 0);
    for o in outcomes {
        for (i, v) in o.result.views.iter().enumerate() {
            gt += 1;
            let failed = o.result.verdict == Some(crate::verdict::Verdict::Failed);
            if !failed && o.predicted_area.get(i).copied().unwrap_or(0) > 0 {
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
        median_rotation_deg: median(&errs.iter().map(|e| e.rotation_deg).collect::<Vec<_>>()),
        median_translation: median(&errs.iter().map(|e| e.translation).collect::<Vec<_>>()),
        median_scale_error: median(&errs.iter().map(|e| e.scale).collect::<Vec<_>>()),
        median_add_rel: median(&outcomes.iter().map(accuracy_measure).collect::<Vec<_>>()),
        mean_iou: if ious.is_empty() {
            0.0
        } else {
            ious.iter().sum::<f64>() / ious.len() as f64
        },
        grasp_accuracy: (grasps_total > 0).then(|| grasps_correct as f64 / grasps_total as f64),
        loss_by_views: by_views(outcomes, |o| &o.loss_by_views),
        add_rel_by_views: by_views(outcomes, |o| &o.add_rel_by_views),
        median_seconds: median(&outcomes.iter().map(|o| o.result.seconds).collect::<Vec<_>>()),
    }
}

/// The report as Markdown: the set's tables, then one row per scene.
pub fn report_markdown(summary: &Summary, outcomes: &[SceneOutcome]) -> String {
    let mut s = String::new();
    let pct = |v: f64| format!("{:.1} %", 100.0 * v);
    s += &format!("# LocaliseBot evaluation: {} scenes\n\n", summary.scenes);
    s += "## Silhouette detection (the paper's Table 1)\n\n";
    s += "Every view of every scene holds one ground-truth object (its mask). The fit predicts one silhouette per \
          view (the estimated pose's hard render); an empty render, or any view of a fit whose verdict is \
          `failed`, is no prediction. A prediction is a true \
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::estimator::Termination;
    use crate::estimator::{PoseOut, ViewResult};
    use crate::metrics::PoseErrors;
    use crate::verdict::Verdict;

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
                        weight: 1.0,
                    })
                    .collect(),
                mean_iou: ious.iter().sum::<f64>() / ious.len() as f64,
                loss_history: vec![],
                iterations: 1,
                termination: Some(Termination::Converged),
                scale_mode: crate::ScaleMode::Anisotropic,
                verdict: Some(Verdict::Ok),
                verdict_reasons: vec![],
                doubted_views: vec![],
                covariance: None,
                std_dev: None,
                uncertainty_error: None,
                camera_corrections: None,
                camera_correction_error: None,
                camera_test: None,
                seconds: 1.0,
                alternatives: Vec::new(),
                masks: Vec::new(),
                errors: Some(errors),
                symmetric: Some(false),
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
        // A failed fit predicts nothing: its views leave precision alone and lower recall.
        let mut failed = outcome(&[0.1, 0.05], &[80, 90], 0.9);
        failed.result.verdict = Some(Verdict::Failed);
        let o2 = vec![o[0].clone(), o[1].clone(), failed];
        let r2 = summarise(&o2).prf[0].clone();
        assert_eq!((r2.tp, r2.predictions, r2.ground_truths), (2, 3, 6));
        assert!(r2.precision > r2.recall);
    }
}
