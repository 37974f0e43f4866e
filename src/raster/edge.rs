//! Silhouette-edge soft silhouettes (SPEC §4 "Soft silhouette", the faster variant):
//! the interior comes from the exact hard coverage, the softness and the gradient only
//! from the silhouette's outline edges, so the cost follows the outline, not the
//! triangle count.
//!
//! Inputs: an [`EdgeTopology`] (built once per mesh), the [`Projected`] mesh, its
//! triangles, the [`Camera`] (canvas `width × height`, near-plane clipping of the hard
//! coverage) and [`SoftSettings`] (σ in px², ε). Outputs, per render of an
//! [`EdgeSilhouette`]: `A(p)` for every pixel (row-major, row 0 at the top, pixel
//! centres at integer coordinates, SPEC §2), the hard coverage `C(p)`, and one
//! [`EdgeRecord`] of `∂A_p/∂uv` per pixel with a soft value.
//!
//! The definition (the tests' naive oracle implements exactly this):
//!
//! 1. `C(p) ∈ {0, 1}` is [`crate::raster::hard::render_projected_into`] of the welded
//!    triangles (each vertex at its welded representative: the plain raster whenever
//!    copies coincide exactly, as glTF seams do).
//! 2. A face is *present* when its three welded vertices are in front of the near
//!    plane and within the hard raster's guard band, and its doubled area with the
//!    vertices snapped to 1/1024 px (as the hard raster snaps them) is non-zero.
//! 3. An edge is a *candidate outline edge* when it has at least one present face and
//!    all its present faces lie on the same side of the edge line (the sign of the
//!    snapped `(b − a) × (c − a)`, c each face's third vertex): contours of closed
//!    meshes, open borders and non-manifold edges alike. Its outward normal `n_out`
//!    points away from that side.
//! 4. For pixel p and candidate e, q is the closest point of the segment to p (the
//!    segment parameter t clamped to [0, 1]) and `d = |p − q|`. The candidate is
//!    *accepted for p* only if the coverage is 0 at the pixel centre nearest to
//!    `r = q + 1.0·n_out`, i.e. `(⌊r.x + ½⌋, ⌊r.y + ½⌋)`, or that pixel is off the
//!    canvas (a contour with object on its outer side is a hidden contour inside the
//!    silhouette, not outline).
//! 5. `d*` is the distance to the nearest accepted candidate with `d² < m²`,
//!    `m² = σ·ln(1/ε − 1)`. If there is one, `A(p) = sigmoid(δ·d*²/σ)` with `δ = +1`
//!    where `C(p) = 1` and −1 elsewhere; otherwise `A(p) = C(p)`. Among candidates at
//!    the same computed d² the lowest edge index (the smallest end pair) wins; equal
//!    distances are usually a pixel nearest to the vertex two edges share, where both
//!    give the same value and the whole gradient to that vertex.
//! 6. Gradient, one [`EdgeRecord`] per soft pixel: `∂A/∂d² = δ·A(1 − A)/σ`,
//!    `∂d²/∂a = −2(1 − t)(p − q)`, `∂d²/∂b = −2t(p − q)` for the winning edge a → b;
//!    C, the candidate set and the accept test are treated as locally constant.
//!
//! As σ → 0, A → C; across an edge through a pixel centre both sides give ½.
//!
//! Speed (`candidates.rs`, `pass.rs`): the accept test is decided once per candidate
//! when every probe of the edge lands in pixels with one verdict (hidden contours are
//! then dropped before binning); the rest are binned into bands of 16 rows by their
//! m-expanded boxes; a band keeps the nearest accepted candidate per pixel of the
//! 16×16 tiles the boxes reach; each candidate visits, row by row, only the
//! columns within m of its line, where `d² = e² + (|b − a|·excess)²` (e the line
//! distance, excess the parameter's overshoot past the ends) is branch-free. The hard
//! coverage itself comes from the same pass over the edges (`coverage.rs`: the
//! triangles' boundary chain, in which every edge between two faces turned the same
//! way cancels, filled row by row), so the cost is one snap per vertex, one area sign
//! per face, a few operations per edge and the outline's m-band, with no per-triangle
//! raster. The geometry of the soft values is f64; signs and coverage are exact
//! integer arithmetic on the snapped positions.

mod candidates;
mod coverage;
mod outline;
mod pass;
mod topology;

pub use outline::OutlineSample;
pub use topology::{EdgeTopology, WELD_TOLERANCE};

use crate::camera::{Camera, MAX_SIDE};
use crate::error::{Error, Result};
use crate::mask::Mask;
use crate::raster::project::Projected;
use crate::raster::silhouette::SoftSettings;
use candidates::EdgeSetup;
use glam::DVec2;
use pass::Best;

/// One pixel's gradient: `ga = ∂A_px/∂uv_a`, `gb = ∂A_px/∂uv_b`, where a → b is the
/// outline edge nearest to the pixel (original vertex indices).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EdgeRecord {
    /// Row-major pixel index `y·width + x`.
    pub px: u32,
    /// The edge's first end (original vertex index).
    pub a: u32,
    /// The edge's second end (original vertex index).
    pub b: u32,
    /// `∂A/∂(u, v)` of vertex a.
    pub ga: DVec2,
    /// `∂A/∂(u, v)` of vertex b.
    pub gb: DVec2,
}

/// A silhouette-edge soft silhouette of one view, with the buffers it reuses across
/// renders (keep one per view).
#[derive(Debug, Clone)]
pub struct EdgeSilhouette {
    width: u32,
    height: u32,
    settings: SoftSettings,
    vertex_count: usize,
    alpha: Vec<f64>,
    coverage: Mask,
    records: Vec<EdgeRecord>,
    /// Per face: sign of its snapped welded doubled area when present, else 0.
    face_sign: Vec<i8>,
    /// The coverage's scratch (`coverage.rs`): vertices snapped to 1/1024 px, per row
    /// the column counters; the coverage's summed-area table.
    snapped: Vec<[i32; 2]>,
    diff: Vec<i32>,
    sat: Vec<u32>,
    /// Per pixel, whether it is `DEEP` pixels inside the coverage (`candidates.rs`).
    deep: Vec<u8>,
    /// The edges with a non-zero net weight or many faces (`candidates.rs`).
    busy: Vec<u32>,
    /// Edges whose present faces lie on one side, before their setup.
    candidates: Vec<candidates::Candidate>,
    /// Candidates whose m-box meets the canvas, by increasing edge index.
    edges: Vec<EdgeSetup>,
    outline: usize,
    /// Candidates per band of `TILE` rows (a counting sort), and per tile whether a
    /// candidate's box reaches it.
    tiles_x: usize,
    tiles_y: usize,
    start: Vec<u32>,
    items: Vec<u32>,
    cursor: Vec<u32>,
    reached: Vec<bool>,
    /// Nearest accepted candidate per pixel of the current band (`TILE·width`).
    band: Vec<Best>,
    /// Tile columns of the current band that hold candidates.
    active: Vec<usize>,
}

impl Default for EdgeSilhouette {
    fn default() -> Self {
        EdgeSilhouette::new()
    }
}

impl EdgeSilhouette {
    /// An empty silhouette (0×0), to be filled by [`EdgeSilhouette::render`].
    pub fn new() -> EdgeSilhouette {
        EdgeSilhouette {
            width: 0,
            height: 0,
            settings: SoftSettings::default(),
            vertex_count: 0,
            alpha: Vec::new(),
            coverage: Mask::empty(0, 0),
            records: Vec::new(),
            face_sign: Vec::new(),
            snapped: Vec::new(),
            diff: Vec::new(),
            sat: Vec::new(),
            deep: Vec::new(),
            busy: Vec::new(),
            candidates: Vec::new(),
            edges: Vec::new(),
            outline: 0,
            tiles_x: 0,
            tiles_y: 0,
            start: Vec::new(),
            items: Vec::new(),
            cursor: Vec::new(),
            reached: Vec::new(),
            band: Vec::new(),
            active: Vec::new(),
        }
    }

    /// Width of the last render, pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height of the last render, pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// `A` per pixel in [0, 1] (`width·height` values, row-major).
    pub fn alpha(&self) -> &[f64] {
        &self.alpha
    }

    /// The hard coverage C of the last render.
    pub fn coverage(&self) -> &Mask {
        &self.coverage
    }

    /// One gradient record per pixel with a soft value, by increasing pixel index.
    pub fn records(&self) -> &[EdgeRecord] {
        &self.records
    }

    /// Number of candidate outline edges in the last render (on the canvas or not).
    pub fn outline_edges(&self) -> usize {
        self.outline
    }

    /// ∂L/∂(u, v) per vertex of the last render from `grad_alpha` = ∂L/∂A per pixel,
    /// written into `grad_uv` (resized to the vertex count; zero for vertices on no
    /// outline edge).
    ///
    /// # Panics
    /// If `grad_alpha.len()` is not the pixel count (a programming error).
    pub fn backward_2d(&self, grad_alpha: &[f64], grad_uv: &mut Vec<DVec2>) {
        assert_eq!(
            grad_alpha.len(),
            self.alpha.len(),
            "grad_alpha must have one value per pixel"
        );
        grad_uv.clear();
        grad_uv.resize(self.vertex_count, DVec2::ZERO);
        for r in &self.records {
            let g = grad_alpha[r.px as usize];
            grad_uv[r.a as usize] += r.ga * g;
            grad_uv[r.b as usize] += r.gb * g;
        }
    }

    /// Renders the projected mesh (see the module doc for the definition).
    ///
    /// Errors: invalid settings, a zero or oversized canvas, a triangle index beyond
    /// the vertices, or a topology built for a different vertex or triangle count.
    pub fn render(
        &mut self,
        topo: &EdgeTopology,
        proj: &Projected,
        triangles: &[[u32; 3]],
        camera: &Camera,
        settings: &SoftSettings,
    ) -> Result<()> {
        settings.validate()?;
        let (w, h) = (camera.width, camera.height);
        if w == 0 || h == 0 || w > MAX_SIDE || h > MAX_SIDE {
            return Err(Error::Settings(format!(
                "edge silhouette size must be between 1 and {MAX_SIDE} pixels a side, got {w}×{h}"
            )));
        }
        let n = proj.uv.len();
        if proj.cam.len() != n {
            return Err(Error::Settings(format!(
                "projected mesh has {} camera-frame points but {n} pixel positions",
                proj.cam.len()
            )));
        }
        if let Some(t) = triangles.iter().find(|t| t.iter().any(|&i| i as usize >= n)) {
            return Err(Error::Mesh {
                file: "(mesh)".into(),
                problem: format!("triangle {t:?} refers to a vertex beyond the {n} vertices"),
            });
        }
        if topo.vertex_count != n || topo.face_count != triangles.len() {
            return Err(Error::Settings(format!(
                "edge topology was built for {} vertices and {} triangles, got {n} and {}",
                topo.vertex_count,
                topo.face_count,
                triangles.len()
            )));
        }
        self.width = w;
        self.height = h;
        self.settings = *settings;
        self.vertex_count = n;
        self.find_candidates(topo, proj, camera);
        self.alpha.clear();
        self.alpha.extend(self.coverage.data.iter().map(|&c| f64::from(c)));
        self.records.clear();
        self.bin();
        self.tile_pass();
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    pub(super) fn flat(uv: &[DVec2]) -> Projected {
        Projected {
            cam: vec![DVec3::Z; uv.len()],
            uv: uv.to_vec(),
            near: 1e-3,
        }
    }

    pub(super) fn camera(w: u32, h: u32) -> Camera {
        Camera::look_at(DVec3::new(0.0, 0.0, -1.0), DVec3::ZERO, DVec3::Y, w, h, 10.0)
    }

    #[test]
    fn a_single_triangle_is_all_outline_and_softens_both_sides() {
        let uv = [DVec2::new(3.2, 2.7), DVec2::new(17.6, 4.1), DVec2::new(8.3, 15.9)];
        let tris = [[0, 1, 2]];
        let topo = EdgeTopology::new(&[DVec3::ZERO, DVec3::X, DVec3::Y], &tris);
        let mut s = EdgeSilhouette::new();
        let set = SoftSettings { sigma: 1.0, eps: 1e-4 };
        s.render(&topo, &flat(&uv), &tris, &camera(21, 19), &set).unwrap();
        assert_eq!(s.outline_edges(), 3);
        assert!(s.alpha().iter().all(|a| (0.0..=1.0).contains(a)));
        let soft_in = s.alpha().iter().filter(|&&a| a > 0.5 && a < 1.0).count();
        let soft_out = s.alpha().iter().filter(|&&a| a > 0.0 && a < 0.5).count();
        assert!(soft_in > 10 && soft_out > 10, "{soft_in} {soft_out}");
        assert!(s.records().windows(2).all(|r| r[0].px < r[1].px));
        assert_eq!(
            s.records().len(),
            soft_in + soft_out + s.alpha().iter().filter(|&&a| a == 0.5).count()
        );
    }

    #[test]
    fn extreme_coordinates_do_not_panic() {
        let tris = [[0, 1, 2], [0, 2, 3], [1, 2, 3]];
        let topo = EdgeTopology::new(&[DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z], &tris);
        let mut s = EdgeSilhouette::new();
        for far in [1e300, f64::INFINITY, f64::NAN, 3e5, -1e18] {
            let uv = [
                DVec2::new(3.2, 2.7),
                DVec2::new(far, 4.1),
                DVec2::new(8.3, -far),
                DVec2::new(far, far),
            ];
            s.render(&topo, &flat(&uv), &tris, &camera(21, 19), &SoftSettings::default())
                .unwrap();
            assert!(s.alpha().iter().all(|a| (0.0..=1.0).contains(a)), "{far}");
        }
    }

    #[test]
    fn bad_input_is_an_error_not_a_panic() {
        let uv = [DVec2::new(3.2, 2.7), DVec2::new(17.6, 4.1), DVec2::new(8.3, 15.9)];
        let tris = [[0, 1, 2]];
        let topo = EdgeTopology::new(&[DVec3::ZERO, DVec3::X, DVec3::Y], &tris);
        let mut s = EdgeSilhouette::new();
        let ok = SoftSettings::default();
        let cam = camera(21, 19);
        let e = s.render(&topo, &flat(&uv), &[[0, 1, 3]], &cam, &ok).unwrap_err();
        assert!(e.to_string().contains("beyond the 3 vertices"), "{e}");
        let bad = SoftSettings { sigma: -1.0, eps: 1e-4 };
        assert!(s.render(&topo, &flat(&uv), &tris, &cam, &bad).is_err());
        assert!(s.render(&topo, &flat(&uv), &tris, &camera(0, 19), &ok).is_err());
        let other = EdgeTopology::new(&[DVec3::ZERO, DVec3::X, DVec3::Y], &[[0, 1, 2], [0, 2, 1]]);
        let e = s.render(&other, &flat(&uv), &tris, &cam, &ok).unwrap_err();
        assert!(e.to_string().contains("edge topology"), "{e}");
    }
}
