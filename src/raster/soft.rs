//! Soft (SoftRas) silhouettes, forward pass (SPEC §4 "Soft silhouette").
//!
//! For pixel p (centre at integer coordinates, SPEC §2) and projected triangle j:
//! `d_j(p)` is the distance from p to triangle j's boundary, `δ_j = +1` if p is
//! strictly inside and −1 otherwise, `D_j = sigmoid(δ_j·d_j²/σ)` and the silhouette is
//! `A(p) = 1 − Π_j (1 − D_j(p))`; σ is in pixel². This is PyTorch3D's
//! `SoftSilhouetteShader` (`sigmoid_alpha_blend`) with σ converted from NDC² to px².
//!
//! Stages: pose → camera-frame points → pixels ([`SoftRasterizer::render`]), then the
//! 2-D stage [`SoftSilhouette::render_2d`]. The backward pass is in `soft_backward.rs`.
//!
//! Rules (all documented on the constants below): outside pairs with
//! `d² ≥ σ·ln(1/ε − 1)` (so `D_j < ε`) are skipped; triangles whose doubled projected
//! area is at most [`DEGENERATE_DOUBLE_AREA`] px² are skipped; triangles with a vertex
//! behind the near plane (`raster::project::near_plane`) are skipped (their pixels
//! would be meaningless); there is no back-face culling; a pixel stops accumulating
//! once its transmittance `T = Π(1 − D_j)` falls below [`SATURATION`].
//!
//! Speed: every triangle visits only the pixels of its bounding box expanded by the
//! σ-margin `m = √(σ·ln(1/ε − 1))`, and within each row only the span where all three
//! edge functions are ≥ −m (pixels farther than m from a half-plane are farther than
//! m from the triangle). Inside pixels cost three fused multiply-adds and one `exp`.

use crate::camera::Camera;
use crate::error::{Error, Result};
use crate::mesh::Mesh;
use crate::pose::Pose;
use crate::raster::project::near_plane;
use glam::{DMat3, DVec2, DVec3};

/// Transmittance below which a pixel is saturated: `A > 1 − 1e-9`. A saturated pixel
/// skips its remaining triangles in the forward pass and is skipped by the backward
/// pass. Effect on accuracy: `A` is off by less than 1e-9, and since every
/// `∂A/∂d_j² = δ_j·T·D_j/σ` carries the factor T, a saturated pixel's dropped gradient
/// is below `1e-9/σ` per triangle and px² — far below the ε truncation.
pub const SATURATION: f64 = 1e-9;

/// Triangles whose doubled signed projected area |(b − a) × (c − a)| is at most this
/// (px²) are degenerate and skipped (PyTorch3D skips |·| ≤ 1e-8 NDC², i.e.
/// 4·10⁻⁵ px² at 128 px: the two thresholds differ only for triangles seen exactly
/// edge-on, whose contribution is a line of zero width).
pub const DEGENERATE_DOUBLE_AREA: f64 = 1e-8;

/// Softness of the soft silhouette.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SoftSettings {
    /// σ in pixel² (default 1.0): the width of the sigmoid edge. PyTorch3D's σ in NDC²
    /// is `σ_px = σ_ndc·(min(width, height)/2)²` (see [`SoftSettings::from_ndc`]).
    pub sigma: f64,
    /// ε (default 1e-4): outside pairs with `D_j < ε`, i.e. `d² ≥ σ·ln(1/ε − 1)`, are
    /// skipped. PyTorch3D's `blur_radius = ln(1/ε − 1)·σ` with the same ε.
    pub eps: f64,
}

impl Default for SoftSettings {
    fn default() -> Self {
        SoftSettings { sigma: 1.0, eps: 1e-4 }
    }
}

impl SoftSettings {
    /// Settings equivalent to PyTorch3D's `sigma` given in NDC² for an image of this
    /// size (NDC spans 2 units over the shorter side), with ε = 1e-4.
    pub fn from_ndc(sigma_ndc: f64, width: u32, height: u32) -> SoftSettings {
        let half = width.min(height) as f64 * 0.5;
        SoftSettings {
            sigma: sigma_ndc * half * half,
            eps: 1e-4,
        }
    }

    /// The squared cut-off distance `σ·ln(1/ε − 1)` (px²) beyond which an outside
    /// triangle contributes less than ε and is skipped.
    pub fn cutoff_sq(&self) -> f64 {
        self.sigma * (1.0 / self.eps - 1.0).ln()
    }

    /// Checks `σ > 0` (finite) and `0 < ε < 0.5`.
    pub fn validate(&self) -> Result<()> {
        if !(self.sigma.is_finite() && self.sigma > 0.0) {
            return Err(Error::Settings(format!(
                "soft silhouette sigma must be a positive number of pixel², got {}",
                self.sigma
            )));
        }
        if !(self.eps > 0.0 && self.eps < 0.5) {
            return Err(Error::Settings(format!(
                "soft silhouette eps must be in (0, 0.5), got {}",
                self.eps
            )));
        }
        Ok(())
    }
}

/// One triangle ready for rasterisation: vertices, normalised edge functions
/// `e_k(p) = n_k·p + c_k` (the signed distance to the line of edge k = v_k → v_{k+1},
/// positive inside), and its σ-expanded, canvas-clipped pixel box.
#[derive(Debug, Clone, Copy)]
pub(crate) struct TriSetup {
    /// Vertex indices.
    pub idx: [u32; 3],
    /// Vertex pixel positions.
    pub v: [DVec2; 3],
    /// Edge vectors v_{k+1} − v_k.
    pub dir: [DVec2; 3],
    /// 1 / |dir_k|².
    pub inv_len2: [f64; 3],
    /// Unit inward normals of the edges.
    pub n: [DVec2; 3],
    /// Offsets of the edge functions.
    pub c: [f64; 3],
    /// Inclusive pixel box.
    pub x0: i32,
    /// Inclusive pixel box.
    pub x1: i32,
    /// Inclusive pixel box.
    pub y0: i32,
    /// Inclusive pixel box.
    pub y1: i32,
}

/// What one (pixel, triangle) pair contributes.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Pair {
    /// Strictly inside.
    pub inside: bool,
    /// Squared distance to the boundary, px².
    pub d2: f64,
}

/// The closest boundary point of a pair: edge k, parameter t along it, and p − q.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Closest {
    pub k: usize,
    pub t: f64,
    pub diff: DVec2,
}

impl TriSetup {
    /// Builds the setup, or `None` for a degenerate, non-finite or off-canvas triangle.
    #[inline]
    fn new(idx: [u32; 3], v: [DVec2; 3], margin: f64, w: i32, h: i32) -> Option<TriSetup> {
        if !(v[0].is_finite() && v[1].is_finite() && v[2].is_finite()) {
            return None;
        }
        let cr = (v[1] - v[0]).perp_dot(v[2] - v[0]);
        if cr.abs() <= DEGENERATE_DOUBLE_AREA {
            return None;
        }
        let lo = v[0].min(v[1]).min(v[2]) - DVec2::splat(margin);
        let hi = v[0].max(v[1]).max(v[2]) + DVec2::splat(margin);
        let x0 = (lo.x.ceil().max(0.0)).min(w as f64) as i32;
        let y0 = (lo.y.ceil().max(0.0)).min(h as f64) as i32;
        let x1 = (hi.x.floor().min((w - 1) as f64)).max(-1.0) as i32;
        let y1 = (hi.y.floor().min((h - 1) as f64)).max(-1.0) as i32;
        if x0 > x1 || y0 > y1 {
            return None;
        }
        let s = cr.signum();
        let mut dir = [DVec2::ZERO; 3];
        let mut inv_len2 = [0.0; 3];
        let mut n = [DVec2::ZERO; 3];
        let mut c = [0.0; 3];
        for k in 0..3 {
            let a = v[k];
            let d = v[(k + 1) % 3] - a;
            let l2 = d.length_squared();
            dir[k] = d;
            inv_len2[k] = 1.0 / l2;
            // cross(d, p − a) = d.x (p.y − a.y) − d.y (p.x − a.x), scaled to unit length.
            let nk = DVec2::new(-d.y, d.x) * (s / l2.sqrt());
            n[k] = nk;
            c[k] = -nk.dot(a);
        }
        Some(TriSetup {
            idx,
            v,
            dir,
            inv_len2,
            n,
            c,
            x0,
            x1,
            y0,
            y1,
        })
    }

    /// Inclusive x range of row `y` where every edge function is ≥ −m (empty when lo > hi).
    #[inline(always)]
    pub(crate) fn row_span(&self, y: f64, m: f64) -> (i32, i32) {
        let mut lo = self.x0 as f64;
        let mut hi = self.x1 as f64;
        for k in 0..3 {
            let a = self.n[k].x;
            let rhs = -m - self.n[k].y * y - self.c[k];
            if a > 1e-12 {
                lo = lo.max(rhs / a);
            } else if a < -1e-12 {
                hi = hi.min(rhs / a);
            } else if rhs > 1e-9 {
                return (1, 0);
            }
        }
        ((lo - 1e-7).ceil() as i32, (hi + 1e-7).floor() as i32)
    }

    /// The pair at pixel `p`, or `None` when it is outside with `d² ≥ m2`.
    #[inline(always)]
    pub(crate) fn pair(&self, p: DVec2, m: f64, m2: f64) -> Option<Pair> {
        let e0 = self.n[0].dot(p) + self.c[0];
        let e1 = self.n[1].dot(p) + self.c[1];
        let e2 = self.n[2].dot(p) + self.c[2];
        if e0 > 0.0 && e1 > 0.0 && e2 > 0.0 {
            let d = e0.min(e1).min(e2);
            return Some(Pair {
                inside: true,
                d2: d * d,
            });
        }
        if e0 <= -m || e1 <= -m || e2 <= -m {
            return None;
        }
        let e = [e0, e1, e2];
        let mut best = f64::INFINITY;
        for k in 0..3 {
            if e[k] <= 0.0 {
                let dv = p - self.v[k];
                let t = (dv.dot(self.dir[k]) * self.inv_len2[k]).clamp(0.0, 1.0);
                best = best.min((dv - self.dir[k] * t).length_squared());
            }
        }
        (best < m2).then_some(Pair {
            inside: false,
            d2: best,
        })
    }

    /// The pair at `p` and its closest boundary point (for the backward pass).
    #[inline(always)]
    pub(crate) fn pair_closest(&self, p: DVec2, m: f64, m2: f64) -> Option<(Pair, Closest)> {
        let e = [
            self.n[0].dot(p) + self.c[0],
            self.n[1].dot(p) + self.c[1],
            self.n[2].dot(p) + self.c[2],
        ];
        let inside = e[0] > 0.0 && e[1] > 0.0 && e[2] > 0.0;
        if !inside && (e[0] <= -m || e[1] <= -m || e[2] <= -m) {
            return None;
        }
        let mut best = f64::INFINITY;
        let mut cl = Closest {
            k: 0,
            t: 0.0,
            diff: DVec2::ZERO,
        };
        for k in 0..3 {
            if inside || e[k] <= 0.0 {
                let dv = p - self.v[k];
                let t = (dv.dot(self.dir[k]) * self.inv_len2[k]).clamp(0.0, 1.0);
                let diff = dv - self.dir[k] * t;
                let d2 = diff.length_squared();
                if d2 < best {
                    best = d2;
                    cl = Closest { k, t, diff };
                }
            }
        }
        if inside {
            // The perpendicular distance (the same in exact arithmetic) keeps the
            // forward and backward passes bit-identical in d².
            let d = e[0].min(e[1]).min(e[2]);
            return Some((Pair { inside, d2: d * d }, cl));
        }
        (best < m2).then_some((Pair { inside, d2: best }, cl))
    }
}

/// `1 − D` for a pair: `1 − sigmoid(δ·d²/σ)`.
#[inline(always)]
pub(crate) fn one_minus_d(pair: Pair, inv_sigma: f64) -> f64 {
    let z = pair.d2 * inv_sigma;
    if pair.inside {
        1.0 / (1.0 + z.exp())
    } else {
        1.0 / (1.0 + (-z).exp())
    }
}

/// A soft silhouette of one view, and what its backward pass needs.
#[derive(Debug, Clone, Default)]
pub struct SoftSilhouette {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// The settings it was rendered with.
    pub settings: SoftSettings,
    /// `A` per pixel in [0, 1], row-major, row 0 at the top (`width·height` values).
    pub alpha: Vec<f64>,
    /// `T = Π_j (1 − D_j) = 1 − A` per pixel, kept separately for its relative
    /// precision near A = 1; below [`SATURATION`] the pixel is saturated.
    pub transmittance: Vec<f64>,
    /// Triangles that were rasterised (not degenerate, in front, near the canvas).
    pub(crate) tris: Vec<TriSetup>,
    /// Number of 2-D vertices of the last render.
    pub(crate) vertex_count: usize,
}

impl SoftSilhouette {
    /// An empty silhouette (0×0), to be filled by [`SoftSilhouette::render_2d`].
    pub fn new() -> SoftSilhouette {
        SoftSilhouette::default()
    }

    /// Number of triangles actually rasterised in the last render.
    pub fn rasterised_triangles(&self) -> usize {
        self.tris.len()
    }

    /// The 2-D stage: renders triangles `triangles` over vertex pixel positions `uv`
    /// (a non-finite position marks a vertex behind the camera: its triangles are
    /// skipped) into a `width`×`height` silhouette, reusing this one's buffers.
    ///
    /// Errors: invalid settings, a zero or oversized canvas, or a triangle index
    /// beyond `uv`.
    pub fn render_2d(
        &mut self,
        uv: &[DVec2],
        triangles: &[[u32; 3]],
        width: u32,
        height: u32,
        settings: &SoftSettings,
    ) -> Result<()> {
        settings.validate()?;
        if width == 0 || height == 0 || width > crate::camera::MAX_SIDE || height > crate::camera::MAX_SIDE {
            return Err(Error::Settings(format!(
                "soft silhouette size must be between 1 and {} pixels a side, got {width}×{height}",
                crate::camera::MAX_SIDE
            )));
        }
        let n = uv.len();
        if let Some(t) = triangles.iter().find(|t| t.iter().any(|&i| i as usize >= n)) {
            return Err(Error::Mesh {
                file: "(mesh)".into(),
                problem: format!("triangle {t:?} refers to a vertex beyond the {n} vertices"),
            });
        }
        self.width = width;
        self.height = height;
        self.settings = *settings;
        self.vertex_count = n;
        let (w, h) = (width as i32, height as i32);
        let m2 = settings.cutoff_sq();
        let m = m2.sqrt();
        self.tris.clear();
        self.tris.extend(triangles.iter().filter_map(|&idx| {
            let v = [uv[idx[0] as usize], uv[idx[1] as usize], uv[idx[2] as usize]];
            TriSetup::new(idx, v, m, w, h)
        }));
        let npx = width as usize * height as usize;
        self.transmittance.clear();
        self.transmittance.resize(npx, 1.0);
        forward(
            &self.tris,
            width as usize,
            1.0 / settings.sigma,
            m,
            m2,
            &mut self.transmittance,
        );
        self.alpha.clear();
        self.alpha.extend(self.transmittance.iter().map(|t| 1.0 - t));
        Ok(())
    }
}

/// The forward pass: multiplies every pixel's transmittance by `1 − D_j`.
fn forward(tris: &[TriSetup], w: usize, inv_sigma: f64, m: f64, m2: f64, trans: &mut [f64]) {
    for tri in tris {
        for y in tri.y0..=tri.y1 {
            let yf = y as f64;
            let (xa, xb) = tri.row_span(yf, m);
            if xa > xb {
                continue;
            }
            let row = &mut trans[y as usize * w..(y as usize + 1) * w];
            for x in xa..=xb {
                let t = row[x as usize];
                if t < SATURATION {
                    continue;
                }
                if let Some(pair) = tri.pair(DVec2::new(x as f64, yf), m, m2) {
                    row[x as usize] = t * one_minus_d(pair, inv_sigma);
                }
            }
        }
    }
}

/// Renders the soft silhouette of `mesh` at `pose` in `camera` (allocating; use a
/// [`SoftRasterizer`] to reuse buffers across iterations).
pub fn render(mesh: &Mesh, pose: &Pose, camera: &Camera, settings: &SoftSettings) -> Result<SoftSilhouette> {
    let mut r = SoftRasterizer::new();
    r.render(mesh, pose, camera, settings)?;
    Ok(r.silhouette)
}

/// A reusable renderer for one view: holds the silhouette, the projected vertices
/// and their Jacobians from the last [`SoftRasterizer::render`], and the gradient
/// buffers of [`SoftRasterizer::backward`]. Keep one per view across iterations.
#[derive(Debug, Clone, Default)]
pub struct SoftRasterizer {
    pub(crate) silhouette: SoftSilhouette,
    /// `s ⊙ X_o` per vertex (model frame, scaled).
    pub(crate) scaled: Vec<DVec3>,
    /// Camera-frame vertices.
    pub(crate) cam: Vec<DVec3>,
    /// Pixel positions (NaN behind the near plane).
    pub(crate) uv: Vec<DVec2>,
    /// `∂(u, v)/∂(x, y, z)` per vertex (zero behind the near plane).
    pub(crate) jac: Vec<[DVec3; 2]>,
    /// The pose and camera of the last render (for the chain rule).
    pub(crate) pose: Pose,
    pub(crate) camera_rotation: DMat3,
    /// Gradient buffers.
    pub(crate) grad_uv: Vec<DVec2>,
    pub(crate) grad_cam: Vec<DVec3>,
    /// Gauss–Newton buffers: per-vertex `∂(u, v)/∂θ`, per-pixel slot, per-slot `∂A_p/∂θ`.
    pub(crate) vertex_jac: Vec<[[f64; 9]; 2]>,
    pub(crate) gn_slot: Vec<u32>,
    pub(crate) gn_rows: Vec<[f64; 9]>,
}

impl SoftRasterizer {
    /// A renderer with empty buffers.
    pub fn new() -> SoftRasterizer {
        SoftRasterizer::default()
    }

    /// The silhouette of the last render.
    pub fn silhouette(&self) -> &SoftSilhouette {
        &self.silhouette
    }

    /// Pixel positions of the vertices in the last render (NaN behind the near plane).
    pub fn uv(&self) -> &[DVec2] {
        &self.uv
    }

    /// Camera-frame vertices of the last render.
    pub fn camera_points(&self) -> &[DVec3] {
        &self.cam
    }

    /// Renders `mesh` at `pose` in `camera` (size `camera.width`×`camera.height`).
    /// Errors: invalid settings, or a triangle index beyond the vertices.
    pub fn render(
        &mut self,
        mesh: &Mesh,
        pose: &Pose,
        camera: &Camera,
        settings: &SoftSettings,
    ) -> Result<&SoftSilhouette> {
        let m = camera.rotation * pose.rotation;
        let b = camera.rotation * pose.translation + camera.translation;
        self.scaled.clear();
        self.scaled.extend(mesh.positions.iter().map(|p| pose.scale * *p));
        self.cam.clear();
        self.cam.extend(self.scaled.iter().map(|y| m * *y + b));
        let extent = mesh
            .bounds()
            .map(|bb| (bb.size() * pose.scale.abs()).length())
            .unwrap_or(1.0);
        self.pose = *pose;
        self.camera_rotation = camera.rotation;
        self.project_and_rasterise(near_plane(extent), &mesh.triangles, camera, settings)?;
        Ok(&self.silhouette)
    }

    /// The camera stage on its own: renders camera-frame vertices `cam` (vertices
    /// with `z < near` are behind the camera and their triangles skipped). The pose
    /// stored for [`SoftRasterizer::backward`] is not updated; use
    /// [`SoftRasterizer::backward_camera_frame`] after this.
    pub fn render_camera_frame(
        &mut self,
        cam: &[DVec3],
        near: f64,
        triangles: &[[u32; 3]],
        camera: &Camera,
        settings: &SoftSettings,
    ) -> Result<&SoftSilhouette> {
        self.cam.clear();
        self.cam.extend_from_slice(cam);
        self.project_and_rasterise(near, triangles, camera, settings)?;
        Ok(&self.silhouette)
    }

    /// Projects `self.cam` and rasterises.
    fn project_and_rasterise(
        &mut self,
        near: f64,
        triangles: &[[u32; 3]],
        camera: &Camera,
        settings: &SoftSettings,
    ) -> Result<()> {
        self.uv.clear();
        self.jac.clear();
        for c in &self.cam {
            if c.z >= near {
                let (uv, j) = camera.project_with_jacobian(*c);
                self.uv.push(uv);
                self.jac.push(j);
            } else {
                self.uv.push(DVec2::splat(f64::NAN));
                self.jac.push([DVec3::ZERO; 2]);
            }
        }
        self.silhouette
            .render_2d(&self.uv, triangles, camera.width, camera.height, settings)
    }
}
