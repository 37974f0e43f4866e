//! Backward pass of the soft silhouette (`soft.rs`): from `∂L/∂A` per pixel to the
//! 2-D vertices, the camera-frame vertices and the 9 pose parameters; and the
//! Gauss–Newton normal equations (forward-mode `∂A_p/∂θ` per pixel).
//!
//! Per (pixel p, triangle j) pair, with `T_p = Π_k (1 − D_k)`:
//! `∂A_p/∂d_j² = δ_j·T_p·D_j/σ` (no division: `∂A/∂D_j = T/(1 − D_j)` and
//! `∂D_j/∂d² = δ_j·D_j(1 − D_j)/σ`). With q = a + t·(b − a) the closest point of
//! p on the closest edge a → b, `∂d²/∂a = −2(1 − t)(p − q)` and `∂d²/∂b = −2t(p − q)`
//! (envelope theorem: t is optimal). Then `∂L/∂X_c = Jᵀ·∂L/∂(u, v)` (projection
//! Jacobian) and, with `y = s ⊙ X_o` and `h = (R_wc·R)ᵀ·∂L/∂X_c`:
//! `∂L/∂ω = Σ y × h`, `∂L/∂t = R·Σ h`, `∂L/∂ls = Σ y ⊙ h`.
//!
//! Pose-gradient order everywhere: `[ω0, ω1, ω2, t0, t1, t2, ls0, ls1, ls2]`, ω the
//! rotation perturbation on the right (`R·exp([ω]×)`, ω = 0 at the current pose), t the
//! translation, ls the log scale (`s = exp(ls)`).

use crate::raster::soft::{SoftRasterizer, SoftSilhouette, TriSetup, SATURATION};
use glam::{DVec2, DVec3};

/// Number of pose parameters.
pub const POSE_DIM: usize = 9;

/// Gauss–Newton normal equations over pixel residuals r_p with Jacobian rows
/// `J_p = ∂r_p/∂θ` (θ in the order `[ω, t, ls]`, see the module doc).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct NormalEquations {
    /// `Σ w·J_pᵀ J_p` (9×9, symmetric), row-major `jtj[i][j]`.
    pub jtj: [[f64; POSE_DIM]; POSE_DIM],
    /// `Σ w·J_pᵀ r_p`.
    pub jtr: [f64; POSE_DIM],
    /// `½ Σ w·r_p²`.
    pub cost: f64,
}

impl NormalEquations {
    /// Adds `other` scaled by `weight` (e.g. to average views).
    pub fn add_scaled(&mut self, other: &NormalEquations, weight: f64) {
        for i in 0..POSE_DIM {
            for j in 0..POSE_DIM {
                self.jtj[i][j] += weight * other.jtj[i][j];
            }
            self.jtr[i] += weight * other.jtr[i];
        }
        self.cost += weight * other.cost;
    }
}

/// Visits every (pixel, triangle) pair that the backward pass needs — pixels with
/// `∂L/∂A ≠ 0` (when `grad` is given) that are not saturated — calling
/// `f(pixel index, ∂A_p/∂d², ∂d²/∂v_k, ∂d²/∂v_{k+1}, k)` with k the closest edge.
#[inline(always)]
fn for_each_pair(
    sil: &SoftSilhouette,
    tri: &TriSetup,
    grad: Option<&[f64]>,
    mut f: impl FnMut(usize, f64, DVec2, DVec2, usize),
) {
    let w = sil.width as usize;
    let inv_sigma = 1.0 / sil.settings.sigma;
    let m2 = sil.settings.cutoff_sq();
    let m = m2.sqrt();
    for y in tri.y0..=tri.y1 {
        let yf = y as f64;
        let (xa, xb) = tri.row_span(yf, m);
        if xa > xb {
            continue;
        }
        let base = y as usize * w;
        for x in xa..=xb {
            let i = base + x as usize;
            let t = sil.transmittance[i];
            if t < SATURATION || grad.is_some_and(|g| g[i] == 0.0) {
                continue;
            }
            if let Some((pair, cl)) = tri.pair_closest(DVec2::new(x as f64, yf), m, m2) {
                let z = pair.d2 * inv_sigma;
                let da_dd2 = if pair.inside {
                    t * inv_sigma / (1.0 + (-z).exp())
                } else {
                    -t * inv_sigma / (1.0 + z.exp())
                };
                let f2 = -2.0 * cl.diff;
                f(i, da_dd2, f2 * (1.0 - cl.t), f2 * cl.t, cl.k);
            }
        }
    }
}

impl SoftSilhouette {
    /// The 2-D backward stage: from `grad_alpha` = ∂L/∂A per pixel (`width·height`
    /// values, row-major) to ∂L/∂(u, v) per vertex of the last render, written into
    /// `grad_uv` (resized to the vertex count; zero for unused or skipped vertices).
    ///
    /// # Panics
    /// If `grad_alpha.len() != width·height` (a programming error, not user input).
    pub fn backward_2d(&self, grad_alpha: &[f64], grad_uv: &mut Vec<DVec2>) {
        assert_eq!(
            grad_alpha.len(),
            self.alpha.len(),
            "grad_alpha must have one value per pixel"
        );
        grad_uv.clear();
        grad_uv.resize(self.vertex_count, DVec2::ZERO);
        for tri in &self.tris {
            let mut g = [DVec2::ZERO; 3];
            for_each_pair(self, tri, Some(grad_alpha), |i, da_dd2, ga, gb, k| {
                let c = grad_alpha[i] * da_dd2;
                g[k] += ga * c;
                g[(k + 1) % 3] += gb * c;
            });
            for (v, gv) in tri.idx.iter().zip(g) {
                grad_uv[*v as usize] += gv;
            }
        }
    }
}

impl SoftRasterizer {
    /// Backward of the last [`SoftRasterizer::render`]: from ∂L/∂A per pixel to
    /// ∂L/∂θ, θ = `[ω0, ω1, ω2, t0, t1, t2, ls0, ls1, ls2]` (ω: right rotation
    /// perturbation `R·exp([ω]×)`; t: translation; ls: log scale). The intermediate
    /// gradients stay readable through [`SoftRasterizer::grad_uv`] and
    /// [`SoftRasterizer::grad_camera_points`].
    ///
    /// # Panics
    /// If `grad_alpha.len()` is not the silhouette's pixel count.
    pub fn backward(&mut self, grad_alpha: &[f64]) -> [f64; POSE_DIM] {
        self.backward_camera_frame(grad_alpha);
        let q = (self.camera_rotation * self.pose.rotation).transpose();
        let (mut gw, mut gt, mut gs) = (DVec3::ZERO, DVec3::ZERO, DVec3::ZERO);
        for (y, gc) in self.scaled.iter().zip(&self.grad_cam) {
            if *gc == DVec3::ZERO {
                continue;
            }
            let h = q * *gc;
            gw += y.cross(h);
            gt += h;
            gs += *y * h;
        }
        let gt = self.pose.rotation * gt;
        [gw.x, gw.y, gw.z, gt.x, gt.y, gt.z, gs.x, gs.y, gs.z]
    }

    /// Backward to the camera-frame vertices (after [`SoftRasterizer::render`] or
    /// [`SoftRasterizer::render_camera_frame`]): ∂L/∂X_c per vertex.
    ///
    /// # Panics
    /// If `grad_alpha.len()` is not the silhouette's pixel count.
    pub fn backward_camera_frame(&mut self, grad_alpha: &[f64]) -> &[DVec3] {
        self.silhouette.backward_2d(grad_alpha, &mut self.grad_uv);
        self.grad_cam.clear();
        self.grad_cam
            .extend(self.grad_uv.iter().zip(&self.jac).map(|(g, j)| j[0] * g.x + j[1] * g.y));
        &self.grad_cam
    }

    /// ∂L/∂(u, v) per vertex from the last backward call.
    pub fn grad_uv(&self) -> &[DVec2] {
        &self.grad_uv
    }

    /// ∂L/∂X_c per vertex from the last backward call.
    pub fn grad_camera_points(&self) -> &[DVec3] {
        &self.grad_cam
    }

    /// `∂(u, v)/∂θ` of every vertex at the last render's pose (rows u, v; 9 columns
    /// in the order `[ω, t, ls]`).
    fn vertex_pose_jacobians(&mut self) {
        let r = self.pose.rotation;
        let rc = self.camera_rotation;
        let m = rc * r;
        self.vertex_jac.clear();
        for (y, j) in self.scaled.iter().zip(&self.jac) {
            let mut rows = [[0.0; POSE_DIM]; 2];
            for k in 0..3 {
                let mut e = DVec3::ZERO;
                e[k] = 1.0;
                let cols = [m * e.cross(*y), rc * e, m * (e * *y)];
                for (g, col) in cols.iter().enumerate() {
                    rows[0][3 * g + k] = j[0].dot(*col);
                    rows[1][3 * g + k] = j[1].dot(*col);
                }
            }
            self.vertex_jac.push(rows);
        }
    }

    /// Adds this view's Gauss–Newton terms for per-pixel residuals `residual` (one
    /// per pixel, e.g. `A_p − M_p`) whose Jacobian is `∂A_p/∂θ`, each weighted by
    /// `weight`, to `out`: `JᵀJ += w·Σ J_pJ_pᵀ`, `Jᵀr += w·Σ J_p r_p`,
    /// `cost += ½ w·Σ r_p²` (θ order `[ω, t, ls]`). Uses the last render.
    ///
    /// # Panics
    /// If `residual.len()` is not the silhouette's pixel count.
    pub fn accumulate_normal_equations(&mut self, residual: &[f64], weight: f64, out: &mut NormalEquations) {
        let npx = self.silhouette.alpha.len();
        assert_eq!(residual.len(), npx, "residual must have one value per pixel");
        self.vertex_pose_jacobians();
        // One 9-vector slot per unsaturated pixel that some triangle reaches.
        self.gn_slot.clear();
        self.gn_slot.resize(npx, u32::MAX);
        self.gn_rows.clear();
        for (i, &t) in self.silhouette.transmittance.iter().enumerate() {
            if t < 1.0 && t >= SATURATION {
                self.gn_slot[i] = self.gn_rows.len() as u32;
                self.gn_rows.push([0.0; POSE_DIM]);
            }
        }
        let sil = &self.silhouette;
        let vj = &self.vertex_jac;
        let (slot, rows) = (&self.gn_slot, &mut self.gn_rows);
        for tri in &sil.tris {
            let mj = [
                &vj[tri.idx[0] as usize],
                &vj[tri.idx[1] as usize],
                &vj[tri.idx[2] as usize],
            ];
            for_each_pair(sil, tri, None, |i, da_dd2, ga, gb, k| {
                let s = slot[i];
                if s == u32::MAX {
                    return;
                }
                let (ma, mb) = (mj[k], mj[(k + 1) % 3]);
                let (ax, ay, bx, by) = (ga.x * da_dd2, ga.y * da_dd2, gb.x * da_dd2, gb.y * da_dd2);
                let row = &mut rows[s as usize];
                for c in 0..POSE_DIM {
                    row[c] += ax * ma[0][c] + ay * ma[1][c] + bx * mb[0][c] + by * mb[1][c];
                }
            });
        }
        let mut cost = 0.0;
        for (i, &r) in residual.iter().enumerate() {
            cost += r * r;
            let s = self.gn_slot[i];
            if s == u32::MAX {
                continue;
            }
            let jr = &self.gn_rows[s as usize];
            for a in 0..POSE_DIM {
                out.jtr[a] += weight * jr[a] * r;
                let wa = weight * jr[a];
                for b in a..POSE_DIM {
                    out.jtj[a][b] += wa * jr[b];
                }
            }
        }
        for a in 0..POSE_DIM {
            for b in 0..a {
                // Fill the lower triangle from the upper one accumulated above.
                out.jtj[a][b] = out.jtj[b][a];
            }
        }
        out.cost += 0.5 * weight * cost;
    }
}
