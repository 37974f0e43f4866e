//! Levenberg–Marquardt on the objective's Gauss–Newton model (SPEC §4 "Parameters
//! and optimiser"; [`crate::loss::objective`]): the objective accumulates the 9×9
//! curvature `JᵀJ` and the exact gradient `Jᵀr` while it walks the pixels; a step solves
//! `(JᵀJ + λ·diag(JᵀJ)) δ = −Jᵀr` in the scaled parameters (see
//! [`crate::optim::params`]), restricted to the free parameters of the scale mode.
//! One rasterisation per iteration: a rejected step re-solves from the stored
//! equations of the last accepted pose with a larger λ.

use crate::loss::objective::NormalEquations;
use crate::pose::Pose;

/// The LM state between iterations.
#[derive(Debug, Clone)]
pub struct Lm {
    /// Damping λ (relative to the diagonal).
    pub lambda: f64,
    /// The last accepted pose and its normal equations (scaled parameters).
    accepted: Option<(Pose, NormalEquations)>,
}

impl Default for Lm {
    fn default() -> Self {
        Lm {
            lambda: 1e-2,
            accepted: None,
        }
    }
}

/// Which parameters move: all 9, rotation + translation + one shared log-scale, or no scale.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Free {
    /// All nine.
    All,
    /// Log-scale shared by the three axes.
    IsotropicScale,
    /// Scale fixed.
    NoScale,
}

impl Lm {
    /// A fresh state.
    pub fn new() -> Lm {
        Lm::default()
    }

    /// Given the normal equations `ne` (scaled parameters) evaluated at `pose`, returns
    /// the pose to evaluate next. A pose whose cost is higher than the last accepted
    /// one is rejected: λ grows and the step is re-solved from the accepted pose.
    pub fn next_pose(
        &mut self,
        pose: Pose,
        ne: NormalEquations,
        free: Free,
        apply: impl Fn(&Pose, &[f64; 9]) -> Pose,
    ) -> Pose {
        match &self.accepted {
            Some((_, prev)) if ne.cost.partial_cmp(&prev.cost) != Some(std::cmp::Ordering::Less) => {
                self.lambda = (self.lambda * 4.0).min(1e8)
            }
            _ => {
                self.lambda = (self.lambda / 3.0).max(1e-7);
                self.accepted = Some((pose, ne));
            }
        }
        let (base, eqs) = self.accepted.as_ref().expect("set above");
        let delta = solve_damped(&eqs.jtj, &eqs.jtr, self.lambda, free);
        apply(base, &delta)
    }

    /// The last accepted pose.
    pub fn best(&self) -> Option<Pose> {
        self.accepted.as_ref().map(|a| a.0)
    }
}

/// Solves `(H + λ·diag(H) + tiny·I) δ = −g` over the free parameters.
pub fn solve_damped(h: &[[f64; 9]; 9], g: &[f64; 9], lambda: f64, free: Free) -> [f64; 9] {
    // Columns of the map from free parameters to the nine.
    let p: Vec<[f64; 9]> = match free {
        Free::All => (0..9).map(unit).collect(),
        Free::NoScale => (0..6).map(unit).collect(),
        Free::IsotropicScale => {
            let mut v: Vec<[f64; 9]> = (0..6).map(unit).collect();
            v.push([0., 0., 0., 0., 0., 0., 1., 1., 1.]);
            v
        }
    };
    let k = p.len();
    let mut a = vec![vec![0.0; k + 1]; k];
    let trace: f64 = (0..9).map(|i| h[i][i]).sum::<f64>().max(1e-300);
    for i in 0..k {
        for j in 0..k {
            let mut s = 0.0;
            for r in 0..9 {
                for c in 0..9 {
                    s += p[i][r] * h[r][c] * p[j][c];
                }
            }
            a[i][j] = s;
        }
        let diag = a[i][i];
        a[i][i] += lambda * diag + 1e-12 * trace;
        a[i][k] = -(0..9).map(|r| p[i][r] * g[r]).sum::<f64>();
    }
    let x = gauss(a);
    let mut out = [0.0; 9];
    for (i, col) in p.iter().enumerate() {
        for r in 0..9 {
            out[r] += col[r] * x[i];
        }
    }
    if out.iter().all(|v| v.is_finite()) {
        out
    } else {
        [0.0; 9]
    }
}

fn unit(i: usize) -> [f64; 9] {
    let mut e = [0.0; 9];
    e[i] = 1.0;
    e
}

/// Gaussian elimination with partial pivoting on an augmented k×(k+1) matrix.
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

/// Scales normal equations from pose units `[ω, t, ls]` to the optimiser's scaled
/// parameters `[ω, τ, ℓ]` (translation columns × `length`).
pub fn scale_equations(ne: &NormalEquations, length: f64) -> NormalEquations {
    let d = |i: usize| if (3..6).contains(&i) { length } else { 1.0 };
    let mut out = *ne;
    for i in 0..9 {
        for j in 0..9 {
            out.jtj[i][j] *= d(i) * d(j);
        }
        out.jtr[i] *= d(i);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solves_a_known_system() {
        // H = diag(1..9) + coupling, g chosen so that δ = −(1, −1, 2, …).
        let mut h = [[0.0; 9]; 9];
        for i in 0..9 {
            h[i][i] = 1.0 + i as f64;
            if i > 0 {
                h[i][i - 1] = 0.3;
                h[i - 1][i] = 0.3;
            }
        }
        let want = [1.0, -1.0, 2.0, 0.5, -0.5, 0.25, 0.1, -0.2, 0.3];
        let mut g = [0.0; 9];
        for i in 0..9 {
            g[i] = -(0..9).map(|j| h[i][j] * want[j]).sum::<f64>();
        }
        let d = solve_damped(&h, &g, 0.0, Free::All);
        for i in 0..9 {
            assert!((d[i] - want[i]).abs() < 1e-9, "{d:?}");
        }
        // Damping shortens the step; fixing the scale zeroes its part.
        let damped = solve_damped(&h, &g, 10.0, Free::All);
        assert!(damped.iter().map(|x| x * x).sum::<f64>() < want.iter().map(|x| x * x).sum::<f64>());
        let fixed = solve_damped(&h, &g, 0.0, Free::NoScale);
        assert_eq!(&fixed[6..], &[0.0; 3]);
        let iso = solve_damped(&h, &g, 0.0, Free::IsotropicScale);
        assert!(iso[6] == iso[7] && iso[7] == iso[8]);
    }

    #[test]
    fn rejected_steps_raise_damping_and_restart_from_the_best_pose() {
        let mut lm = Lm::new();
        let mut ne = NormalEquations::default();
        for i in 0..9 {
            ne.jtj[i][i] = 1.0;
        }
        ne.jtr[3] = 1.0;
        ne.cost = 1.0;
        let apply = |p: &Pose, d: &[f64; 9]| Pose {
            translation: p.translation + glam::DVec3::new(d[3], d[4], d[5]),
            ..*p
        };
        let p1 = lm.next_pose(Pose::IDENTITY, ne, Free::All, apply);
        assert!(p1.translation.x < 0.0);
        let l1 = lm.lambda;
        let mut worse = ne;
        worse.cost = 2.0;
        let p2 = lm.next_pose(p1, worse, Free::All, apply);
        assert!(lm.lambda > l1);
        assert_eq!(lm.best(), Some(Pose::IDENTITY));
        assert!(
            p2.translation.x > p1.translation.x,
            "a shorter step from the accepted pose"
        );
    }
}
