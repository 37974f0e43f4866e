//! Soft (SoftRas) silhouettes, forward pass (SPEC §4 "Soft silhouette").
//!
//! For pixel p (centre at integer coordinates, SPEC §2) and projected triangle j:
//! `d_j(p)` is the distance from p to triangle j's boundary, `δ_j = +1` if p is
//! strictly inside and −1 otherwise, `D_j = sigmoid(δ_j·d_j²/σ)` and the silhouette is
//! `A(p) = 1 − Π_j (1 − D_j(p))`; σ is in pixel². This is PyTorch3D's
//! `SoftSilhouetteShader` (`sigmoid_alpha_blend`) with σ converted from NDC² to px².
//!
//! Stages: pose → camera-frame points → pixels (`raster::project`, through
//! [`SoftRasterizer::render`]), then the 2-D stage [`SoftSilhouette::render_2d`]. The backward pass is in `backward.rs`.
//!
//! Behind the cargo feature `softras` (on by default natively, off in the shipped
//! wasm): the reference renderer, checked against PyTorch3D, and `fit --raster softras`.
//!
//! Rules (all documented on the constants below): outside pairs with
//! `d² ≥ σ·ln(1/ε − 1)` (so `D_j < ε`) are skipped; triangles whose doubled projected
//! area is at most [`DEGENERATE_DOUBLE_AREA`] px² are skipped; triangles with a vertex
//! behind the near plane (`raster::project::near_plane`) are skipped (their pixels
//! would be meaningless); there is no back-face culling; a pixel stops accumulating
//! once its transmittance `T = Π(1 − D_j)` falls below [`SATURATION`].
//!
//! Speed (`tiles.rs`): triangles are binned into 16×16-pixel tiles by their boxes
//! expanded by the cut-off distance `m = √(σ·ln(1/ε − 1))`; within a tile each
//! triangle visits, row by row, only the span where all three edge functions are
//! ≥ −m, a few pixels at a time in SIMD lanes (f64, `wide`). Everything is f64: the
//! results match a naive f64 oracle to 1e-9 and the gradients match central
//! differences to ~1e-9 relative. Note that with a fine mesh and a small σ interior
//! pixels rarely saturate (SoftRas's internal edges keep `T` around 1e-3..1e-1), so
//! nearly every pair in the σ-band of every triangle is evaluated.

use crate::camera::Camera;
use crate::error::{Error, Result};
use crate::mesh::Mesh;
use crate::pose::Pose;
use crate::raster::project::PoseProjection;
use crate::raster::silhouette::SoftSettings;
use tiles::{Bins, Pass, Record, Tile, TriSetup};
pub use tiles::{DEGENERATE_DOUBLE_AREA, SATURATION};

mod backward;
mod tiles;
use glam::{DVec2, DVec3};

/// A soft silhouette of one view, and the rasterised geometry its backward pass
/// re-walks.
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
    /// Triangles that are rasterised (not degenerate, in front, near the canvas).
    pub(crate) tris: Vec<TriSetup>,
    /// The triangles binned into tiles.
    pub(crate) bins: Bins,
    /// Scratch for the pairs of one tile.
    pub(crate) records: Vec<Record>,
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
        self.prepare(uv, triangles, width, height, settings)?;
        self.run_pass::<false>(|_| {});
        Ok(())
    }

    /// Validates, sets up and bins the triangles (everything but the tile pass).
    pub(crate) fn prepare(
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
        let m = settings.cutoff_sq().sqrt();
        self.tris.clear();
        self.tris.extend(triangles.iter().filter_map(|&idx| {
            let v = [uv[idx[0] as usize], uv[idx[1] as usize], uv[idx[2] as usize]];
            TriSetup::new(idx, v, m, DEGENERATE_DOUBLE_AREA, w, h)
        }));
        self.bins.build(&self.tris, width as usize, height as usize);
        let npx = width as usize * height as usize;
        self.transmittance.resize(npx, 1.0);
        self.alpha.resize(npx, 0.0);
        Ok(())
    }

    /// Runs the tile pass over the prepared geometry (see `tiles::run`), then sets
    /// `alpha = 1 − transmittance`.
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

    /// `alpha = 1 − transmittance`.
    fn finish(&mut self) {
        for (a, t) in self.alpha.iter_mut().zip(&self.transmittance) {
            *a = 1.0 - t;
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

/// A reusable renderer for one view: holds the silhouette, the projection of the
/// last render (with its Jacobians) and the gradient buffers. Keep one per view
/// across iterations.
#[derive(Debug, Clone, Default)]
pub struct SoftRasterizer {
    pub(crate) silhouette: SoftSilhouette,
    /// The projection of the last render.
    pub(crate) projection: PoseProjection,
    /// Gradient buffers: ∂L/∂(u, v) and ∂L/∂X_c of the last backward call, and the
    /// per-field vertex gradients of the fused pass.
    pub(crate) grad_uv: Vec<DVec2>,
    pub(crate) grad_cam: Vec<DVec3>,
    pub(crate) grad_fields: Vec<wide::f64x2>,
    /// Gauss–Newton buffer: per-vertex `∂(u, v)/∂θ`, the 9 columns in lane pairs
    /// (the 10th zero).
    pub(crate) vertex_jac: Vec<[[wide::f64x2; 5]; 2]>,
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
        self.projection.uv()
    }

    /// Camera-frame vertices of the last render.
    pub fn camera_points(&self) -> &[DVec3] {
        &self.projection.proj.cam
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
        self.prepare(mesh, pose, camera, settings)?;
        self.forward();
        Ok(&self.silhouette)
    }

    /// The camera stage on its own: renders camera-frame vertices `cam` (vertices
    /// with `z < near` are behind the camera and their triangles skipped). The pose
    /// chain is then unavailable; use [`SoftRasterizer::backward_camera_frame`] after this.
    pub fn render_camera_frame(
        &mut self,
        cam: &[DVec3],
        near: f64,
        triangles: &[[u32; 3]],
        camera: &Camera,
        settings: &SoftSettings,
    ) -> Result<&SoftSilhouette> {
        self.projection.from_camera_points(cam, near, camera);
        self.silhouette
            .prepare(self.projection.uv(), triangles, camera.width, camera.height, settings)?;
        self.forward();
        Ok(&self.silhouette)
    }

    /// Projects the posed mesh and prepares the 2-D stage (no tile pass).
    pub(crate) fn prepare(&mut self, mesh: &Mesh, pose: &Pose, camera: &Camera, settings: &SoftSettings) -> Result<()> {
        self.projection.project(mesh, pose, camera);
        self.silhouette.prepare(
            self.projection.uv(),
            &mesh.triangles,
            camera.width,
            camera.height,
            settings,
        )
    }

    /// The forward tile pass over the prepared geometry.
    pub(crate) fn forward(&mut self) {
        self.silhouette.run_pass::<false>(|_| {});
    }
}
