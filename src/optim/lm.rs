//! Levenberg–Marquardt: the one damped Gauss–Newton loop of the crate, used by every
//! refinement stage, the robust polish of the leave-one-out test and the joint camera
//! correction. The caller evaluates its cost and Gauss–Newton model `(H, g)` at a
//! point (for the fit, [`crate::loss::objective`] accumulates `JᵀJ` and the exact
//! gradient while it walks the pixels); [`Lm::next`] accepts the point if its cost is
//! lower than the last accepted one, and returns the next point to evaluate: a step
//! `δ` solving `(H + λ·diag(H) + ε·tr(H)/k·I) δ = −g` from the last *accepted* point,
//! so a rejected step costs no extra evaluation — it is re-solved from the stored model
//! with a larger λ.
//!
//! The schedule: λ starts at 10⁻², is divided by 3 on an accepted step (down to 10⁻⁷)
//! and multiplied by 4 on a rejected one (up to 10⁸). The stopping rule
//! ([`Lm::stalled`]): λ at its ceiling, or three accepted steps in a row that each
//! lowered the cost by less than 10⁻⁵ of it.

use crate::loss::objective::NormalEquations;
use crate::optim::params::{unit, ScaleMode};
use crate::pose::{Pose, Vec9, POSE_DIM};
use nalgebra::{DMatrix, DVector};

/// λ's start.
pub const LAMBDA_START: f64 = 1e-2;
/// λ's floor.
const LAMBDA_MIN: f64 = 1e-7;
/// λ's ceiling: reaching it is a stall.
const LAMBDA_MAX: f64 = 1e8;
/// An accepted step that lowers the cost by less than this fraction is flat…
const FLAT_GAIN: f64 = 1e-5;
/// …and this many flat steps in a row are a stall.
const FLAT_STEPS: usize = 3;

/// The LM state between evaluations, over points of type `P`.
#[derive(Debug, Clone)]
pub struct Lm<P> {
    lambda: f64,
    accepted: Option<Accepted<P>>,
    flat: usize,
}

/// The last accepted point, its cost and its model.
#[derive(Debug, Clone)]
struct Accepted<P> {
    point: P,
    cost: f64,
    h: DMatrix<f64>,
    g: DVector<f64>,
}

impl<P: Clone> Default for Lm<P> {
    fn default() -> Self {
        Lm {
            lambda: LAMBDA_START,
            accepted: None,
            flat: 0,
        }
    }
}

impl<P: Clone> Lm<P> {
    /// A fresh state.
    pub fn new() -> Lm<P> {
        Lm::default()
    }

    /// Takes the `cost` and the Gauss–Newton model `(h, g)` evaluated at `point` and
    /// returns the point to evaluate next, `step(base, δ)`: `base` the last accepted
    /// point (this one, if its cost is lower than that one's), `δ` the damped step
    /// from it. A step that `step` refuses (`None`: it leaves the domain, e.g. a scale
    /// that overflows) is a rejected one, re-solved with a larger λ at no evaluation's
    /// cost; a model that gives no step even at the ceiling of λ returns `base`.
    pub fn next(
        &mut self,
        point: P,
        cost: f64,
        h: DMatrix<f64>,
        g: DVector<f64>,
        step: impl Fn(&P, &DVector<f64>) -> Option<P>,
    ) -> P {
        let better = self.accepted.as_ref().map(|a| cost < a.cost);
        match better {
            Some(false) => self.lambda = (self.lambda * 4.0).min(LAMBDA_MAX),
            _ => {
                if let Some(a) = &self.accepted {
                    let gain = (a.cost - cost) / a.cost.abs().max(1e-300);
                    self.flat = if gain < FLAT_GAIN { self.flat + 1 } else { 0 };
                }
                self.lambda = (self.lambda / 3.0).max(LAMBDA_MIN);
                self.accepted = Some(Accepted { point, cost, h, g });
            }
        }
        let a = self.accepted.as_ref().expect("set above");
        loop {
            if let Some(p) = solve_damped(&a.h, &a.g, self.lambda).and_then(|d| step(&a.point, &d)) {
                return p;
            }
            if self.lambda >= LAMBDA_MAX {
                return a.point.clone();
            }
            self.lambda = (self.lambda * 4.0).min(LAMBDA_MAX);
        }
    }

    /// Whether LM has stopped making progress (module doc).
    pub fn stalled(&self) -> bool {
        self.lambda >= LAMBDA_MAX || self.flat >= FLAT_STEPS
    }

    /// The last accepted point and its cost.
    pub fn best(&self) -> Option<(&P, f64)> {
        self.accepted.as_ref().map(|a| (&a.point, a.cost))
    }

    /// The damping λ.
    pub fn lambda(&self) -> f64 {
        self.lambda
    }
}

impl Lm<Pose> {
    /// One step of the pose fit: the objective's normal equations `ne` at `pose` (pose
    /// units), in the scaled parameters of [`crate::optim::params`] (translation in
    /// object radii `length`), over the directions `mode` frees.
    pub fn next_pose(&mut self, pose: Pose, ne: &NormalEquations, mode: ScaleMode, length: f64) -> Pose {
        // B = D·P: the free directions in pose units, D the scaled parameters' units.
        let mut b = mode.basis();
        for i in 0..POSE_DIM {
            b.row_mut(i).scale_mut(unit(i, length));
        }
        let h = b.transpose() * DMatrix::from_fn(POSE_DIM, POSE_DIM, |i, j| ne.jtj[(i, j)]) * &b;
        let g = b.transpose() * DVector::from_column_slice(ne.jtr.as_slice());
        self.next(pose, ne.cost, h, g, |p, d| {
            let full = &b * d;
            let next = p.perturbed(&Vec9::from_column_slice(full.as_slice()));
            next.validate().is_ok().then_some(next)
        })
    }
}

/// Solves `(H + λ·diag(H) + 10⁻¹²·tr(H)/k·I) δ = −g`; `None` when the solution is not
/// finite.
pub fn solve_damped(h: &DMatrix<f64>, g: &DVector<f64>, lambda: f64) -> Option<DVector<f64>> {
    let k = g.len();
    let trace = h.trace().max(1e-300);
    let mut a = vec![vec![0.0; k + 1]; k];
    for i in 0..k {
        for j in 0..k {
            a[i][j] = h[(i, j)];
        }
        a[i][i] += lambda * h[(i, i)] + 1e-12 * trace;
        a[i][k] = -g[i];
    }
    let x = DVector::from_vec(gauss(a));
    x.iter().all(|v| v.is_finite()).then_some(x)
}

/// Gaussian elimination with partial pivoting on an augmented k×(k+1) matrix; a
/// vanishing pivot leaves its unknown at 0.
fn gauss(mut a: Vec<Vec<f64>>) -> Vec<f64> {
    let k = a.len();
    for col in 0..k {
        let piv = (col..k)
            .max_by(|&x, &y| a[x][col].abs().total_cmp(&a[y][col].abs()))
            .unwrap_or(col);
        a.swap(col, piv);
        let d = a[col][col];
        if d.abs() < 1e-300 {
            continue;
        }
        for row in 0..k {
            if row != col {
                let f = a[row][col] / d;
                if f != 0.0 {
                    let pivot_row = a[col].clone();
                    for (x, p) in a[row][col..].iter_mut().zip(&pivot_row[col..]) {
                        *x -= f * p;
                    }
                }
            }
        }
    }
    (0..k)
        .map(|i| if a[i][i].abs() < 1e-300 { 0.0 } else { a[i][k] / a[i][i] })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pose::Mat9;

    #[test]
    fn solves_a_known_system() {
        // H = diag(1..9) + coupling, g chosen so that δ = −(1, −1, 2, …).
        let h = DMatrix::from_fn(9, 9, |i, j| match i.abs_diff(j) {
            0 => 1.0 + i as f64,
            1 => 0.3,
            _ => 0.0,
        });
        let want = DVector::from_column_slice(&[1.0, -1.0, 2.0, 0.5, -0.5, 0.25, 0.1, -0.2, 0.3]);
        let g = -(&h * &want);
        let d = solve_damped(&h, &g, 0.0).unwrap();
        assert!((&d - &want).amax() < 1e-9, "{d:?}");
        // Damping shortens the step.
        let damped = solve_damped(&h, &g, 10.0).unwrap();
        assert!(damped.norm() < want.norm());
        // A non-finite model has no solution.
        assert!(solve_damped(&h, &DVector::from_element(9, f64::NAN), 0.0).is_none());
    }

    #[test]
    fn pose_steps_move_only_the_free_parameters() {
        let mut ne = NormalEquations {
            jtj: Mat9::identity(),
            jtr: Vec9::from_column_slice(&[0.1, 0.0, 0.0, 1.0, 0.0, 0.0, 0.3, -0.1, 0.2]),
            cost: 1.0,
        };
        let step = |mode| Lm::new().next_pose(Pose::IDENTITY, &ne, mode, 2.0);
        let fixed = step(ScaleMode::Fixed);
        assert_eq!(fixed.scale, glam::DVec3::ONE);
        assert!(fixed.translation.x < 0.0);
        let iso = step(ScaleMode::Isotropic);
        assert!((iso.scale.x - iso.scale.y).abs() < 1e-15 && (iso.scale.y - iso.scale.z).abs() < 1e-15);
        assert!(iso.scale.x < 1.0, "descends the summed log-scale gradient");
        let all = step(ScaleMode::Anisotropic);
        assert!(all.scale.x < 1.0 && all.scale.y > 1.0 && all.scale.z < 1.0);
        // The scaled parameters change the conditioning, not the Gauss–Newton step: in
        // pose units it is the same for any length unit (λ damps relative to the diagonal).
        let other = Lm::new().next_pose(Pose::IDENTITY, &ne, ScaleMode::Anisotropic, 7.0);
        assert!((all.translation - other.translation).length() < 1e-9 * all.translation.length());
        // A step whose scale would overflow is refused and re-solved, damped, in range.
        ne.jtr[6] = 1e6;
        let huge = Lm::new().next_pose(Pose::IDENTITY, &ne, ScaleMode::Anisotropic, 1.0);
        assert!(huge.validate().is_ok(), "{huge:?}");
        assert!(huge.scale.x < 1.0);
    }

    #[test]
    fn rejected_steps_raise_damping_and_restart_from_the_accepted_point() {
        // Points are numbers; the model of ½x² around x is H = 1, g = x.
        let model = |x: f64| (DMatrix::from_element(1, 1, 1.0), DVector::from_element(1, x));
        let step = |p: &f64, d: &DVector<f64>| Some(p + d[0]);
        let mut lm = Lm::new();
        let (h, g) = model(2.0);
        let x1 = lm.next(2.0, 2.0, h, g, step);
        assert!(x1.abs() < 2.0);
        let l1 = lm.lambda();
        let (h, g) = model(x1);
        let x2 = lm.next(x1, 5.0, h, g, step); // a higher cost: rejected
        assert!(lm.lambda() > l1);
        assert_eq!(lm.best(), Some((&2.0, 2.0)));
        assert!(x2 > x1, "a shorter step from the accepted point: {x2} vs {x1}");
    }

    #[test]
    fn stalls_on_flat_steps_or_at_the_ceiling_of_lambda() {
        let step = |p: &f64, d: &DVector<f64>| Some(p + d[0]);
        let (h, g) = (DMatrix::from_element(1, 1, 1.0), DVector::from_element(1, 0.0));
        let mut lm = Lm::new();
        let mut cost = 1.0;
        for _ in 0..=FLAT_STEPS {
            assert!(!lm.stalled());
            lm.next(0.0, cost, h.clone(), g.clone(), step);
            cost *= 1.0 - 1e-7;
        }
        assert!(lm.stalled(), "three flat accepted steps");
        let mut lm = Lm::new();
        lm.next(0.0, 1.0, h.clone(), g.clone(), step);
        let mut rejected = 0;
        while !lm.stalled() {
            lm.next(0.0, 2.0, h.clone(), g.clone(), step);
            rejected += 1;
            assert!(rejected < 100);
        }
        assert_eq!(lm.lambda(), LAMBDA_MAX);
    }
}
