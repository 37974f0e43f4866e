//! Adam (Kingma & Ba, 2015) on the 9 pose parameters, with one step size per
//! group (rotation, translation, log-scale). The parameters are increments in the
//! tangent space of the current pose (see [`crate::optim::params`]).

/// Adam's settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AdamSettings {
    /// Step size of the rotation increment ω (radians).
    pub lr_rotation: f64,
    /// Step size of the translation increment, in object radii.
    pub lr_translation: f64,
    /// Step size of the log-scale increment.
    pub lr_log_scale: f64,
    /// First-moment decay (default 0.9).
    pub beta1: f64,
    /// Second-moment decay (default 0.999).
    pub beta2: f64,
    /// Denominator guard (default 1e-8).
    pub eps: f64,
}

impl Default for AdamSettings {
    fn default() -> Self {
        AdamSettings {
            lr_rotation: 0.03,
            lr_translation: 0.03,
            lr_log_scale: 0.02,
            beta1: 0.9,
            beta2: 0.999,
            eps: 1e-8,
        }
    }
}

/// Adam's moment estimates.
#[derive(Debug, Clone, Default)]
pub struct Adam {
    m: [f64; 9],
    v: [f64; 9],
    t: u32,
}

impl Adam {
    /// A fresh optimiser (zero moments).
    pub fn new() -> Self {
        Self::default()
    }

    /// The update Δθ for gradient `g` (9, in the scaled parameters), with the step sizes
    /// multiplied by `lr_factor` (a schedule's decay). Descends: Δθ has the sign of −g.
    pub fn update(&mut self, g: &[f64; 9], s: &AdamSettings, lr_factor: f64) -> [f64; 9] {
        self.t += 1;
        let b1t = 1.0 - s.beta1.powi(self.t as i32);
        let b2t = 1.0 - s.beta2.powi(self.t as i32);
        let mut d = [0.0; 9];
        for i in 0..9 {
            self.m[i] = s.beta1 * self.m[i] + (1.0 - s.beta1) * g[i];
            self.v[i] = s.beta2 * self.v[i] + (1.0 - s.beta2) * g[i] * g[i];
            let mh = self.m[i] / b1t;
            let vh = self.v[i] / b2t;
            let lr = match i {
                0..=2 => s.lr_rotation,
                3..=5 => s.lr_translation,
                _ => s.lr_log_scale,
            };
            d[i] = -lr * lr_factor * mh / (vh.sqrt() + s.eps);
        }
        d
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn first_step_is_the_step_size_against_the_gradient() {
        let mut a = Adam::new();
        let s = AdamSettings::default();
        let g = [1.0, -2.0, 0.0, 3.0, 0.0, 0.0, -1.0, 0.0, 0.0];
        let d = a.update(&g, &s, 1.0);
        assert!((d[0] + s.lr_rotation).abs() < 1e-6);
        assert!((d[1] - s.lr_rotation).abs() < 1e-6);
        assert_eq!(d[2], 0.0);
        assert!((d[3] + s.lr_translation).abs() < 1e-6);
        assert!((d[6] - s.lr_log_scale).abs() < 1e-6);
    }

    #[test]
    fn minimises_a_quadratic() {
        // f(x) = Σ (x_i − c_i)², starting at 0.
        let c = [0.3, -0.2, 0.1, 0.5, -0.4, 0.2, 0.1, 0.05, -0.1];
        let mut x = [0.0; 9];
        let mut a = Adam::new();
        let s = AdamSettings {
            lr_rotation: 0.02,
            lr_translation: 0.02,
            lr_log_scale: 0.02,
            ..Default::default()
        };
        for it in 0..2000 {
            let g: Vec<f64> = x.iter().zip(c).map(|(x, c)| 2.0 * (x - c)).collect();
            let d = a.update(&g.try_into().unwrap(), &s, 0.999f64.powi(it));
            for i in 0..9 {
                x[i] += d[i];
            }
        }
        for i in 0..9 {
            assert!((x[i] - c[i]).abs() < 1e-3, "{i}: {} vs {}", x[i], c[i]);
        }
    }
}
