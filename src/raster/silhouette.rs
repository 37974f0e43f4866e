//! The soft silhouette a loss sees, from either rasteriser behind one interface:
//! [`RasterKind::Edge`] (the default: the hard coverage inside, softness and gradient
//! from the outline edges only, `raster::edge`) or [`RasterKind::SoftRas`] (the
//! paper's renderer, every triangle's σ-band, `raster::softras`, the cargo feature
//! `softras`; the one PyTorch3D checks). A [`RenderMesh`] is a mesh with the edge topology it needs, built once.
//!
//! Three entry points, as the objective needs them: the silhouette alone; the
//! silhouette and, in the same sweep, the 9-gradients of `Σ_p W_f(p)·A_p` for K
//! per-pixel weight fields; and the silhouette with `∂A_p/∂θ` per pixel (forward mode,
//! for Gauss–Newton). θ order `[ω0, ω1, ω2, t0, t1, t2, ls0, ls1, ls2]` (see
//! `raster::project`).

use crate::camera::Camera;
use crate::error::{Error, Result};
use crate::mesh::Mesh;
use crate::pose::Pose;
use crate::raster::edge::{EdgeSilhouette, EdgeTopology};
use crate::raster::lod::{DetailLevels, DEFAULT_DETAIL_PX};
use crate::raster::project::{PoseProjection, POSE_DIM};
#[cfg(feature = "softras")]
use crate::raster::softras::SoftRasterizer;
use glam::DVec2;
use serde::{Deserialize, Serialize};
use wide::f64x2;

/// Softness of the soft silhouette (both rasterisers).
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

/// Which soft rasteriser renders the silhouettes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RasterKind {
    /// Silhouette-edge: interior from the exact hard coverage, softness and gradient
    /// from the outline edges (cost follows the outline, not the triangle count).
    #[default]
    Edge,
    /// SoftRas (Liu et al. 2019; the paper's renderer): every triangle's σ-band. Needs
    /// the cargo feature `softras` (on by default natively, off in the shipped wasm).
    SoftRas,
}

impl RasterKind {
    /// An error when this build cannot render with it (SoftRas without the cargo
    /// feature `softras`).
    pub fn check_available(self) -> Result<()> {
        if self == RasterKind::SoftRas && !cfg!(feature = "softras") {
            return Err(Error::Settings(
                "SoftRas is not in this build (it is the cargo feature `softras`, off in the wasm package); \
                 use the default rasteriser, edge"
                    .into(),
            ));
        }
        Ok(())
    }
}

/// A mesh with the edge topology the silhouette-edge rasteriser needs (welded
/// adjacency, built once per mesh) and its levels of detail (`raster::lod`).
#[derive(Debug, Clone)]
pub struct RenderMesh {
    /// The mesh, model frame.
    pub mesh: Mesh,
    topology: EdgeTopology,
    detail: DetailLevels,
}

impl RenderMesh {
    /// Builds the topology of `mesh` and its levels of detail for the default
    /// tolerance, [`DEFAULT_DETAIL_PX`].
    pub fn new(mesh: Mesh) -> RenderMesh {
        RenderMesh::with_detail(mesh, DEFAULT_DETAIL_PX)
    }

    /// As [`RenderMesh::new`], with levels whose silhouettes move by at most
    /// `tolerance_px` pixels (0: the mesh itself in every render).
    pub fn with_detail(mesh: Mesh, tolerance_px: f64) -> RenderMesh {
        let topology = EdgeTopology::from_mesh(&mesh);
        let detail = DetailLevels::build(&mesh, &topology, tolerance_px);
        RenderMesh { mesh, topology, detail }
    }

    /// The mesh alone, never simplified.
    pub fn exact(mesh: Mesh) -> RenderMesh {
        RenderMesh::with_detail(mesh, 0.0)
    }

    /// Its levels of detail.
    pub fn detail(&self) -> &DetailLevels {
        &self.detail
    }

    /// The mesh and topology the edge rasteriser renders at `pose` in `camera` at
    /// softness `sigma`: the coarsest level within the tolerance, or the mesh itself.
    pub fn for_render(&self, pose: &Pose, camera: &Camera, sigma: f64) -> (&Mesh, &EdgeTopology) {
        match self.detail.choose(pose, camera, sigma) {
            Some(l) => (&l.mesh, &l.topology),
            None => (&self.mesh, &self.topology),
        }
    }

    /// The edge topology.
    pub fn topology(&self) -> &EdgeTopology {
        &self.topology
    }
}

/// One view's reusable soft-silhouette renderer (keep one per view).
#[derive(Debug, Clone)]
pub struct SilhouetteRenderer {
    kind: RasterKind,
    #[cfg(feature = "softras")]
    soft: SoftRasterizer,
    edge: EdgeSilhouette,
    /// The edge path's projection (SoftRas keeps its own).
    projection: PoseProjection,
    /// Per vertex, its slot among the vertices the last records touch (`u32::MAX`: none);
    /// reset after use, so only touched vertices cost anything.
    slot: Vec<u32>,
    /// The touched vertices, in slot order.
    touched: Vec<u32>,
    /// Per touched vertex: `∂(u, v)/∂θ`, or the fields' ∂/∂(u, v).
    vertex_jac: Vec<[[f64x2; 5]; 2]>,
    grad_buf: Vec<DVec2>,
}

impl SilhouetteRenderer {
    /// A renderer of `kind` with empty buffers.
    pub fn new(kind: RasterKind) -> SilhouetteRenderer {
        SilhouetteRenderer {
            kind,
            #[cfg(feature = "softras")]
            soft: SoftRasterizer::new(),
            edge: EdgeSilhouette::new(),
            projection: PoseProjection::default(),
            slot: Vec::new(),
            touched: Vec::new(),
            vertex_jac: Vec::new(),
            grad_buf: Vec::new(),
        }
    }

    /// The rasteriser in use.
    pub fn kind(&self) -> RasterKind {
        self.kind
    }

    /// The last render's silhouette A (row-major, the camera's width × height).
    pub fn alpha(&self) -> &[f64] {
        match self.kind {
            #[cfg(feature = "softras")]
            RasterKind::SoftRas => &self.soft.silhouette().alpha,
            #[cfg(not(feature = "softras"))]
            RasterKind::SoftRas => &[],
            RasterKind::Edge => self.edge.alpha(),
        }
    }

    /// Renders the level `m` chooses; the number of its vertices.
    fn render_edge(&mut self, m: &RenderMesh, pose: &Pose, camera: &Camera, s: &SoftSettings) -> Result<usize> {
        let (mesh, topology) = m.for_render(pose, camera, s.sigma);
        self.projection.project(mesh, pose, camera);
        self.edge
            .render(topology, &self.projection.proj, &mesh.triangles, camera, s)?;
        Ok(mesh.positions.len())
    }

    /// Renders the silhouette of `m` at `pose` in `camera`.
    pub fn render(&mut self, m: &RenderMesh, pose: &Pose, camera: &Camera, s: &SoftSettings) -> Result<&[f64]> {
        self.kind.check_available()?;
        match self.kind {
            #[cfg(feature = "softras")]
            RasterKind::SoftRas => {
                self.soft.render(&m.mesh, pose, camera, s)?;
            }
            #[cfg(not(feature = "softras"))]
            RasterKind::SoftRas => {}
            RasterKind::Edge => {
                self.render_edge(m, pose, camera, s)?;
            }
        }
        Ok(self.alpha())
    }

    /// Renders and returns, for K per-pixel weight fields (`field(p)` gives pixel p's
    /// K weights), the 9-gradient of `Σ_p W_f(p)·A_p` for each field.
    pub fn render_with_gradients<const K: usize>(
        &mut self,
        m: &RenderMesh,
        pose: &Pose,
        camera: &Camera,
        s: &SoftSettings,
        field: impl Fn(usize) -> [f64; K],
    ) -> Result<[[f64; POSE_DIM]; K]> {
        self.kind.check_available()?;
        #[cfg(feature = "softras")]
        if self.kind == RasterKind::SoftRas {
            return self.soft.render_with_gradients(&m.mesh, pose, camera, s, field);
        }
        let n = self.render_edge(m, pose, camera, s)?;
        self.index_touched(n);
        // Each field's ∂/∂uv per touched vertex, in one pass over the records.
        self.grad_buf.clear();
        self.grad_buf.resize(self.touched.len() * K, DVec2::ZERO);
        for r in self.edge.records() {
            let w = field(r.px as usize);
            let (sa, sb) = (
                self.slot[r.a as usize] as usize * K,
                self.slot[r.b as usize] as usize * K,
            );
            for (f, wf) in w.iter().enumerate() {
                self.grad_buf[sa + f] += r.ga * *wf;
                self.grad_buf[sb + f] += r.gb * *wf;
            }
        }
        let mut out = [[0.0; POSE_DIM]; K];
        for (f, o) in out.iter_mut().enumerate() {
            let (g, t) = (&self.grad_buf, &self.touched);
            *o = self
                .projection
                .pose_gradient_sparse(t.iter().enumerate().map(|(k, &v)| (v as usize, g[k * K + f])));
        }
        self.reset_touched();
        Ok(out)
    }

    /// Gives every vertex the last records touch a slot (`self.touched` in slot order).
    fn index_touched(&mut self, n: usize) {
        if self.slot.len() != n {
            self.slot.clear();
            self.slot.resize(n, u32::MAX);
        }
        self.touched.clear();
        for r in self.edge.records() {
            for v in [r.a, r.b] {
                if self.slot[v as usize] == u32::MAX {
                    self.slot[v as usize] = self.touched.len() as u32;
                    self.touched.push(v);
                }
            }
        }
    }

    /// Clears the slots of the touched vertices.
    fn reset_touched(&mut self) {
        for &v in &self.touched {
            self.slot[v as usize] = u32::MAX;
        }
    }

    /// Renders and calls `visit(p, A_p, J_p)` for every pixel p whose value has a
    /// non-zero derivative, `J_p = ∂A_p/∂θ`.
    pub fn render_with_jacobians(
        &mut self,
        m: &RenderMesh,
        pose: &Pose,
        camera: &Camera,
        s: &SoftSettings,
        mut visit: impl FnMut(usize, f64, &[f64; POSE_DIM]),
    ) -> Result<()> {
        self.kind.check_available()?;
        #[cfg(feature = "softras")]
        if self.kind == RasterKind::SoftRas {
            self.soft.render_with_jacobians(&m.mesh, pose, camera, s, visit)?;
            return Ok(());
        }
        let n = self.render_edge(m, pose, camera, s)?;
        self.index_touched(n);
        self.vertex_jac.clear();
        let p = &self.projection;
        self.vertex_jac
            .extend(self.touched.iter().map(|&v| p.vertex_pose_jacobian(v as usize)));
        let (vj, alpha, slot) = (&self.vertex_jac, self.edge.alpha(), &self.slot);
        for r in self.edge.records() {
            let (ma, mb) = (&vj[slot[r.a as usize] as usize], &vj[slot[r.b as usize] as usize]);
            let [ax, ay, bx, by] = [r.ga.x, r.ga.y, r.gb.x, r.gb.y].map(|v| f64x2::new([v; 2]));
            let mut j = [0.0; POSE_DIM];
            for c in 0..5 {
                let v = (ma[0][c] * ax + ma[1][c] * ay + mb[0][c] * bx + mb[1][c] * by).to_array();
                j[2 * c] = v[0];
                if 2 * c + 1 < POSE_DIM {
                    j[2 * c + 1] = v[1];
                }
            }
            visit(r.px as usize, alpha[r.px as usize], &j);
        }
        self.reset_touched();
        Ok(())
    }
}
