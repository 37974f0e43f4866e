//! Backward pass of the soft silhouette (`soft.rs`): from `∂L/∂A` per pixel to the
//! 2-D vertices, the camera-frame vertices and the 9 pose parameters; a fused
//! render-and-backward for losses whose `∂L/∂A` is a combination of fixed per-pixel
//! fields; and the Gauss–Newton normal equations (forward-mode `∂A_p/∂θ` per pixel).
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
//!
//! Saturated pixels (`T < SATURATION`) and pixels no triangle reaches contribute no
//! gradient. Every entry point re-walks the prepared geometry with the tile pass
//! (`tiles.rs`), recomputing T bit-identically, so no per-pixel lists are stored.

use crate::camera::Camera;
use crate::error::Result;
use crate::mesh::Mesh;
use crate::pose::Pose;
use crate::raster::soft::{SoftRasterizer, SoftSettings, SoftSilhouette, SATURATION};
use crate::raster::tiles::{self, Pass, Tile, TILE};
use glam::{DVec2, DVec3};
use wide::f64x2;

/// Number of pose parameters.
pub const POSE_DIM: usize = 9;

/// Gauss–Newton normal equations over pixel residuals r_p with Jacobian rows
/// `J_p = ∂r_p/∂θ = ∂A_p/∂θ` (θ in the order `[ω, t, ls]`, see the module doc).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct NormalEquations {
    /// `Σ w·J_pᵀ J_p` (9×9, symmetric), `jtj[i][j]`.
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

impl SoftSilhouette {
    /// Runs the tile pass over the prepared geometry (see `tiles::run`).
    pub(crate) fn run_pass<const REC: bool>(&mut self, on_tile: impl FnMut(&Tile)) {
        let pass = Pass {
            tris: &self.tris,
            bins: &self.bins,
            width: self.width as usize,
            height: self.height as usize,
            sigma: self.settings.sigma,
            cutoff_sq: self.settings.cutoff_sq(),
        };
        tiles::run::<REC>(&pass, &mut self.transmittance, &mut self.records, on_tile);
        self.finish();
    }

    /// For K per-pixel weight fields W_f (`field(p)` gives the K weights of pixel p),
    /// writes `∂(Σ_p W_f(p)·A_p)/∂v` into `out[v·K + f]` for every vertex v, in the same
    /// sweep that (re)computes the silhouette.
    pub(crate) fn field_gradients<const K: usize>(&mut self, field: impl Fn(usize) -> [f64; K], out: &mut Vec<f64x2>) {
        out.clear();
        out.resize(self.vertex_count * K, f64x2::ZERO);
        let w = self.width as usize;
        let mut ct = [[0.0f64; K]; TILE * TILE];
        self.run_pass::<true>(|tile| {
            for ly in 0..tile.h {
                for lx in 0..tile.w {
                    let li = ly * TILE + lx;
                    let t = tile.t[li];
                    ct[li] = if (SATURATION..1.0).contains(&t) {
                        field((tile.y0 + ly) * w + tile.x0 + lx).map(|f| f * t)
                    } else {
                        [0.0; K]
                    };
                }
            }
            for r in tile.records {
                let c = &ct[r.px as usize];
                let (a, b) = (r.a as usize * K, r.b as usize * K);
                let (ga, gb) = (f64x2::new(r.ga.to_array()), f64x2::new(r.gb.to_array()));
                for f in 0..K {
                    let cf = f64x2::new([c[f]; 2]);
                    out[a + f] += ga * cf;
                    out[b + f] += gb * cf;
                }
            }
        });
    }

    /// The 2-D backward stage: from `grad_alpha` = ∂L/∂A per pixel (`width·height`
    /// values, row-major) to ∂L/∂(u, v) per vertex of the last render, written into
    /// `grad_uv` (resized to the vertex count; zero for unused or skipped vertices).
    ///
    /// # Panics
    /// If `grad_alpha.len() != width·height` (a programming error, not user input).
    pub fn backward_2d(&mut self, grad_alpha: &[f64], grad_uv: &mut Vec<DVec2>) {
        assert_eq!(
            grad_alpha.len(),
            self.alpha.len(),
            "grad_alpha must have one value per pixel"
        );
        let mut buf = Vec::new();
        self.field_gradients(|p| [grad_alpha[p]], &mut buf);
        grad_uv.clear();
        grad_uv.extend(buf.iter().map(|g| DVec2::from_array(g.to_array())));
    }
}

impl SoftRasterizer {
    /// Chains per-vertex ∂L/∂(u, v) (given by `grad_uv(i)`) through the projection and
    /// the pose to `[ω, t, ls]`.
    fn pose_gradient(&self, grad_uv: impl Fn(usize) -> DVec2) -> [f64; POSE_DIM] {
        let q = (self.camera_rotation * self.pose.rotation).transpose();
        let (mut gw, mut gt, mut gs) = (DVec3::ZERO, DVec3::ZERO, DVec3::ZERO);
        for (i, (y, j)) in self.scaled.iter().zip(&self.jac).enumerate() {
            let g = grad_uv(i);
            if g == DVec2::ZERO {
                continue;
            }
            let h = q * (j[0] * g.x + j[1] * g.y);
            gw += y.cross(h);
            gt += h;
            gs += *y * h;
        }
        let gt = self.pose.rotation * gt;
        [gw.x, gw.y, gw.z, gt.x, gt.y, gt.z, gs.x, gs.y, gs.z]
    }

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
        self.pose_gradient(|i| self.grad_uv[i])
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

    /// Renders `mesh` at `pose` and, in the same sweep, returns for each of K
    /// per-pixel weight fields W_f (`field(p)` gives pixel p's K weights, p row-major)
    /// the 9-gradient of `Σ_p W_f(p)·A_p`, order `[ω0, ω1, ω2, t0, t1, t2, ls0, ls1, ls2]`.
    /// A loss whose `∂L/∂A` is a combination of such fields with coefficients that
    /// depend on A only through sums (IoU, contour) gets its gradient from this one
    /// pass; the silhouette is then in [`SoftRasterizer::silhouette`].
    pub fn render_with_gradients<const K: usize>(
        &mut self,
        mesh: &Mesh,
        pose: &Pose,
        camera: &Camera,
        settings: &SoftSettings,
        field: impl Fn(usize) -> [f64; K],
    ) -> Result<[[f64; POSE_DIM]; K]> {
        self.prepare(mesh, pose, camera, settings)?;
        let mut buf = std::mem::take(&mut self.grad_fields);
        self.silhouette.field_gradients(field, &mut buf);
        let mut out = [[0.0; POSE_DIM]; K];
        for (f, o) in out.iter_mut().enumerate() {
            *o = self.pose_gradient(|i| DVec2::from_array(buf[i * K + f].to_array()));
        }
        self.grad_fields = buf;
        Ok(out)
    }

    /// `∂(u, v)/∂θ` of every vertex at the last render's pose (rows u, v; 9 columns
    /// in the order `[ω, t, ls]`).
    fn vertex_pose_jacobians(&mut self) {
        let r = self.pose.rotation;
        let rc = self.camera_rotation;
        let m = rc * r;
        self.vertex_jac.clear();
        for (y, j) in self.scaled.iter().zip(&self.jac) {
            let mut rows = [[0.0; 10]; 2];
            for k in 0..3 {
                let mut e = DVec3::ZERO;
                e[k] = 1.0;
                let cols = [m * e.cross(*y), rc * e, m * (e * *y)];
                for (g, col) in cols.iter().enumerate() {
                    rows[0][3 * g + k] = j[0].dot(*col);
                    rows[1][3 * g + k] = j[1].dot(*col);
                }
            }
            self.vertex_jac
                .push(rows.map(|r| std::array::from_fn(|c| f64x2::new([r[2 * c], r[2 * c + 1]]))));
        }
    }

    /// Renders `mesh` at `pose` and, in the same sweep, adds the Gauss–Newton terms of
    /// the per-pixel residuals `r_p = residual(p, A_p)` whose Jacobian is `∂A_p/∂θ`
    /// (e.g. `A_p − M_p`), each weighted by `weight`, to `out`:
    /// `JᵀJ += w·Σ J_pJ_pᵀ`, `Jᵀr += w·Σ J_p r_p`, `cost += ½ w·Σ r_p²` over all pixels
    /// (θ order `[ω, t, ls]`).
    #[allow(clippy::too_many_arguments)]
    pub fn render_with_normal_equations(
        &mut self,
        mesh: &Mesh,
        pose: &Pose,
        camera: &Camera,
        settings: &SoftSettings,
        residual: impl Fn(usize, f64) -> f64,
        weight: f64,
        out: &mut NormalEquations,
    ) -> Result<&SoftSilhouette> {
        self.prepare(mesh, pose, camera, settings)?;
        self.normal_equations_pass(residual, weight, out);
        Ok(&self.silhouette)
    }

    /// [`SoftRasterizer::render_with_normal_equations`] for the geometry of the last
    /// render and residuals given per pixel (`residual.len()` = pixel count).
    ///
    /// # Panics
    /// If `residual.len()` is not the silhouette's pixel count.
    pub fn accumulate_normal_equations(&mut self, residual: &[f64], weight: f64, out: &mut NormalEquations) {
        assert_eq!(
            residual.len(),
            self.silhouette.alpha.len(),
            "residual must have one value per pixel"
        );
        self.normal_equations_pass(|p, _| residual[p], weight, out);
    }

    fn normal_equations_pass(&mut self, residual: impl Fn(usize, f64) -> f64, weight: f64, out: &mut NormalEquations) {
        self.vertex_pose_jacobians();
        let vj = &self.vertex_jac;
        let w = self.silhouette.width as usize;
        let mut rows = [[f64x2::ZERO; 5]; TILE * TILE];
        let mut jtj = [[0.0f64; POSE_DIM]; POSE_DIM];
        let mut jtr = [0.0f64; POSE_DIM];
        self.silhouette.run_pass::<true>(|tile| {
            for r in rows.iter_mut() {
                *r = [f64x2::ZERO; 5];
            }
            for rec in tile.records {
                let t = tile.t[rec.px as usize];
                if t < SATURATION {
                    continue;
                }
                let (ma, mb) = (&vj[rec.a as usize], &vj[rec.b as usize]);
                let [ax, ay, bx, by] =
                    [rec.ga.x * t, rec.ga.y * t, rec.gb.x * t, rec.gb.y * t].map(|v| f64x2::new([v; 2]));
                let row = &mut rows[rec.px as usize];
                for c in 0..5 {
                    row[c] += ma[0][c] * ax + ma[1][c] * ay + mb[0][c] * bx + mb[1][c] * by;
                }
            }
            for ly in 0..tile.h {
                for lx in 0..tile.w {
                    let li = ly * TILE + lx;
                    let t = tile.t[li];
                    if !(SATURATION..1.0).contains(&t) {
                        continue;
                    }
                    let jr: [f64; 10] = std::array::from_fn(|c| rows[li][c / 2].to_array()[c % 2]);
                    let rp = residual((tile.y0 + ly) * w + tile.x0 + lx, 1.0 - t);
                    for a in 0..POSE_DIM {
                        jtr[a] += jr[a] * rp;
                        for b in a..POSE_DIM {
                            jtj[a][b] += jr[a] * jr[b];
                        }
                    }
                }
            }
        });
        let cost: f64 = self
            .silhouette
            .alpha
            .iter()
            .enumerate()
            .map(|(p, &a)| {
                let r = residual(p, a);
                r * r
            })
            .sum();
        for (a, row) in out.jtj.iter_mut().enumerate() {
            out.jtr[a] += weight * jtr[a];
            for (b, v) in row.iter_mut().enumerate() {
                // Only the upper triangle was accumulated.
                *v += weight * if b >= a { jtj[a][b] } else { jtj[b][a] };
            }
        }
        out.cost += 0.5 * weight * cost;
    }
}
