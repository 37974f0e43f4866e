//! The verdict on a fit (SPEC §3): `ok`, `poor`, `ambiguous` or `failed`, with the
//! views it doubts, from the per-view hard IoU at full resolution (over known pixels)
//! and the other poses that explain the masks nearly as well ([`ambiguous`]).
//!
//! Thresholds ([`VerdictThresholds`], documented defaults): a view *agrees* when its
//! IoU is at least `ok_iou` (0.85) and *fails* below `fail_iou` (0.5). The fit is
//! `ok` when every view agrees; `failed` when the mean IoU is below `fail_iou` or at
//! least half the views fail (the pose explains no majority of the photographs);
//! `poor` otherwise. A view that does not agree while most of the others do is
//! *doubted*: named in the result (an occluded view, a bad mask or calibration).
//! On correct synthetic fits every view's IoU is 0.98–0.999; fits into a wrong basin
//! end at 0.94–0.98 and are not caught by the IoU alone.

use serde::{Deserialize, Serialize};

/// The four verdicts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    /// Every view agrees with the pose.
    Ok,
    /// Some views disagree, or agree only loosely.
    Poor,
    /// Another pose, distinct from this one, explains the masks nearly as well: the
    /// photographs do not tell them apart (the result lists the alternatives).
    Ambiguous,
    /// The pose explains no majority of the views.
    Failed,
}

impl Verdict {
    /// `"ok"`, `"poor"`, `"ambiguous"` or `"failed"`.
    pub fn as_str(self) -> &'static str {
        match self {
            Verdict::Ok => "ok",
            Verdict::Poor => "poor",
            Verdict::Ambiguous => "ambiguous",
            Verdict::Failed => "failed",
        }
    }
}

/// Where the verdict's lines are drawn.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VerdictThresholds {
    /// A view agrees with the pose from this IoU up (default 0.85).
    pub ok_iou: f64,
    /// A view fails below this IoU (default 0.5).
    pub fail_iou: f64,
}

impl Default for VerdictThresholds {
    fn default() -> Self {
        VerdictThresholds {
            ok_iou: 0.85,
            fail_iou: 0.5,
        }
    }
}

/// A verdict with its reasons and the views it doubts.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Judgement {
    /// The verdict.
    pub verdict: Verdict,
    /// Why, one line each (empty when `ok`).
    pub reasons: Vec<String>,
    /// Views that disagree with the pose while most others agree.
    pub doubted_views: Vec<String>,
}

/// Judges a fit from its views' names and full-resolution IoUs; `inconsistent`
/// names views the robust objective down-weighted (they are doubted too).
pub fn judge(names: &[&str], ious: &[f64], inconsistent: &[String], t: &VerdictThresholds) -> Judgement {
    let n = ious.len().max(1);
    let mean = ious.iter().sum::<f64>() / n as f64;
    let agree = ious.iter().filter(|&&v| v >= t.ok_iou).count();
    let fail = ious.iter().filter(|&&v| v < t.fail_iou).count();
    let mut reasons = Vec::new();
    let mut doubted: Vec<String> = Vec::new();
    if agree * 2 > ious.len() {
        for (name, &iou) in names.iter().zip(ious) {
            if iou < t.ok_iou {
                doubted.push(name.to_string());
            }
        }
    }
    for name in inconsistent {
        if !doubted.contains(name) {
            doubted.push(name.clone());
        }
    }
    let verdict = if mean < t.fail_iou || fail * 2 >= n {
        reasons.push(format!(
            "{fail} of {} views below IoU {} (mean IoU {mean:.3}): the pose does not explain the masks",
            ious.len(),
            t.fail_iou
        ));
        Verdict::Failed
    } else if agree == ious.len() && inconsistent.is_empty() {
        Verdict::Ok
    } else {
        for (name, &iou) in names.iter().zip(ious) {
            if iou < t.ok_iou {
                reasons.push(format!("view '{name}': IoU {iou:.3} < {}", t.ok_iou));
            }
        }
        for name in inconsistent {
            reasons.push(format!(
                "view '{name}' contradicts the other views and was down-weighted"
            ));
        }
        Verdict::Poor
    };
    Judgement {
        verdict,
        reasons,
        doubted_views: doubted,
    }
}

/// A competing pose, as the verdict sees it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rival {
    /// Its mean full-resolution IoU over the views.
    pub mean_iou: f64,
    /// The rotation between it and the fit's pose, degrees (up to the object's symmetries).
    pub rotation_deg: f64,
    /// The ADD between the two poses over the object's diameter (up to its symmetries).
    pub add_rel: f64,
}

/// The judgement made `ambiguous` when `rivals` (distinct poses that explain the masks
/// nearly as well as the fit's, of mean IoU `mean_iou`) exist and the fit has not
/// `failed`: one reason per rival says how far it is and by how much it loses.
pub fn ambiguous(mut j: Judgement, mean_iou: f64, rivals: &[Rival]) -> Judgement {
    if rivals.is_empty() || j.verdict == Verdict::Failed {
        return j;
    }
    j.verdict = Verdict::Ambiguous;
    for (i, r) in rivals.iter().enumerate() {
        j.reasons.push(format!(
            "alternative {}: a pose turned {:.0}° from this one (ADD {:.0} % of the diameter apart) explains the masks \
             nearly as well (mean IoU {:.3} against {:.3}): another view would tell them apart",
            i + 1,
            r.rotation_deg,
            100.0 * r.add_rel,
            r.mean_iou,
            mean_iou
        ));
    }
    j
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thresholds_decide() {
        let t = VerdictThresholds::default();
        let names = ["a", "b", "c"];
        let j = judge(&names, &[0.97, 0.95, 0.99], &[], &t);
        assert_eq!((j.verdict, j.doubted_views.len()), (Verdict::Ok, 0));
        let j = judge(&names, &[0.97, 0.6, 0.99], &[], &t);
        assert_eq!(j.verdict, Verdict::Poor);
        assert_eq!(j.doubted_views, vec!["b".to_string()]);
        let j = judge(&names, &[0.002, 0.3, 0.9], &[], &t);
        assert_eq!(j.verdict, Verdict::Failed);
        assert!(j.doubted_views.is_empty(), "no majority agrees: nobody to doubt");
        // Agreeing IoUs, but a view the robust objective set aside: poor, and named.
        let j = judge(&names, &[0.97, 0.95, 0.99], &["c".to_string()], &t);
        assert_eq!(
            (j.verdict, j.doubted_views.clone()),
            (Verdict::Poor, vec!["c".to_string()])
        );
        assert_eq!(Verdict::Failed.as_str(), "failed");
    }

    #[test]
    fn a_rival_makes_a_fit_ambiguous_unless_it_failed() {
        let t = VerdictThresholds::default();
        let names = ["a", "b"];
        let rival = Rival {
            mean_iou: 0.96,
            rotation_deg: 179.0,
            add_rel: 0.4,
        };
        let ok = judge(&names, &[0.97, 0.98], &[], &t);
        assert_eq!(ambiguous(ok.clone(), 0.975, &[]), ok, "no rival: unchanged");
        let j = ambiguous(ok, 0.975, &[rival]);
        assert_eq!(j.verdict, Verdict::Ambiguous);
        assert_eq!(j.reasons.len(), 1);
        assert!(
            j.reasons[0].contains("179°") && j.reasons[0].contains("0.960"),
            "{}",
            j.reasons[0]
        );
        let poor = judge(&names, &[0.97, 0.8], &[], &t);
        let j = ambiguous(poor, 0.885, &[rival]);
        assert_eq!(
            (j.verdict, j.reasons.len()),
            (Verdict::Ambiguous, 2),
            "the poor view's reason is kept"
        );
        let failed = judge(&names, &[0.1, 0.2], &[], &t);
        assert_eq!(ambiguous(failed, 0.15, &[rival]).verdict, Verdict::Failed);
        assert_eq!(Verdict::Ambiguous.as_str(), "ambiguous");
    }
}
