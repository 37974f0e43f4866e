//! Backward pass of the soft silhouette (`soft.rs`): from `∂L/∂A` per pixel to the
//! 2-D vertices, the camera-frame vertices and the 9 pose parameters; a fused
//! render-and-backward for losses whose `∂L/∂A` is a combination of fixed per-pixel
//! fields; and forward-mode `∂A_p/∂θ` per pixel for Gauss–Newton models.
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

use super::tiles::TILE;
use super::{SoftRasterizer, SoftSilhouette, SATURATION};
use crate::camera::Camera;
use crate::error::Result;
use crate::mesh::Mesh;
use crate::pose::Pose;
pub use crate::raster::project::POSE_DIM;
use crate::raster::silhouette::SoftSettings;
use glam::{DVec2, DVec3};
use wide::f64x2;

impl SoftSilhouette {
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
        self.projection.pose_gradient(|i| self.grad_uv[i])
    }

    /// Backward to the camera-frame vertices (after [`SoftRasterizer::render`] or
    /// [`SoftRasterizer::render_camera_frame`]): ∂L/∂X_c per vertex.
    ///
    /// # Panics
    /// If `grad_alpha.len()` is not the silhouette's pixel count.
    pub fn backward_camera_frame(&mut self, grad_alpha: &[f64]) -> &[DVec3] {
        self.silhouette.backward_2d(grad_alpha, &mut self.grad_uv);
        self.grad_cam.clear();
        let p = &self.projection;
        self.grad_cam
            .extend(self.grad_uv.iter().enumerate().map(|(i, g)| p.camera_gradient(i, *g)));
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
            *o = self
                .projection
                .pose_gradient(|i| DVec2::from_array(buf[i * K + f].to_array()));
        }
        self.grad_fields = buf;
        Ok(out)
    }

    /// Renders `mesh` at `pose` and, in the same sweep, calls `visit(p, A_p, J_p)` for
    /// every pixel p (row-major index) whose silhouette value has a non-zero
    /// derivative, with `J_p = ∂A_p/∂θ` (θ order `[ω, t, ls]`): forward mode, for
    /// Gauss–Newton models. Pixels not visited have `J_p = 0`; the silhouette is in
    /// [`SoftRasterizer::silhouette`] afterwards.
    pub fn render_with_jacobians(
        &mut self,
        mesh: &Mesh,
        pose: &Pose,
        camera: &Camera,
        settings: &SoftSettings,
        mut visit: impl FnMut(usize, f64, &[f64; POSE_DIM]),
    ) -> Result<&SoftSilhouette> {
        self.prepare(mesh, pose, camera, settings)?;
        self.projection.vertex_pose_jacobians(&mut self.vertex_jac);
        let vj = &self.vertex_jac;
        let w = self.silhouette.width as usize;
        let mut rows = [[f64x2::ZERO; 5]; TILE * TILE];
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
                    let jr: [f64; POSE_DIM] = std::array::from_fn(|c| rows[li][c / 2].to_array()[c % 2]);
                    visit((tile.y0 + ly) * w + tile.x0 + lx, 1.0 - t, &jr);
                }
            }
        });
        Ok(&self.silhouette)
    }
}
