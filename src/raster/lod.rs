//! Levels of detail: simplified copies of a mesh, and the choice, per render, of the
//! coarsest one whose geometric error stays below a tolerance in pixels, so that a
//! render's cost follows the pixels it covers, not the triangles of the scan
//! (as Nanite and every real-time renderer choose a mesh's level from its
//! projected error).
//!
//! Building ([`DetailLevels::build`] once per mesh, each level when first chosen):
//!
//! 1. The mesh is welded (the edge topology's weld: glTF seams repeat positions), and
//!    triangles with a repeated welded vertex or the same welded vertex set as an
//!    earlier triangle are dropped (double-sided sheets: the coverage is a union, so
//!    neither changes the silhouette).
//! 2. Level k has the error bound `d·2^(−k/2)`, from d/2048 to d/32 (d the mesh's
//!    diameter; 13 levels a factor √2 apart). The first render that chooses it runs
//!    meshoptimizer's quadric edge-collapse simplifier (the pure-Rust
//!    `meshoptimizer-rs` port) on the welded mesh with that absolute error bound; the
//!    level is used only if it keeps at most [`KEEP_RATIO`] of the triangles (else the
//!    mesh itself is rendered). Its vertices are compacted.
//!
//! Choosing ([`DetailLevels::choose`], every render): a displacement δ of `e` model
//! units (at pose scale s, `s·e` in the world) of a point at camera depth
//! `z ≥ z_near` moves its projection by `(f/z)·(δ_xy − δ_z·(uv − c)/f)`, at most
//! `s·e·√(f² + r²)/(z_near − s·e)` pixels (the moved point may be `s·e` nearer), f
//! the larger focal length and r a bound on how far from the principal point c a
//! pixel that matters lies: the farther of the canvas corners, or of the projected
//! corners of the mesh's bounding box (whose hull holds the object's image) if
//! nearer, plus the tolerance. `z_near` is the deeper of two lower bounds on the
//! vertices' depth: a sphere about the bounds' centre holding every vertex, and the
//! box's 8 corners. The tolerance is the levels' tolerance t at σ ≥ 1 px² and `t·σ`
//! below (σ in px²): the blurred coarse stages of a fit may use coarse levels, the sharp
//! last ones — whose fits are precise to a tenth of a pixel — render the mesh itself
//! or nearly. (`t·√σ`, the blur's length, was measured too: as accurate on fits from
//! no pose, but refits from a good pose lost precision, and the next-best-view check
//! fell from 76 % to 67 %; docs/benchmark-history.md.) The coarsest level whose error moves the
//! silhouette by at most the tolerance is used; none (the mesh itself) when the
//! sphere and the box both reach behind the camera or the tolerance is 0. The choice
//! is piecewise constant in the pose: within one level the render and its gradient
//! are exact for that level's mesh.

use crate::camera::Camera;
use crate::mesh::Mesh;
use crate::pose::Pose;
use crate::raster::edge::EdgeTopology;
use glam::{DVec2, DVec3};
use meshoptimizer_rs::{simplify, Positions, SimplifyOptions, SimplifySettings, Workspace};
use std::collections::{HashMap, HashSet};
use std::sync::OnceLock;

/// Default tolerance: the most a level may move the silhouette, pixels.
pub const DEFAULT_DETAIL_PX: f64 = 0.5;

/// A level is used only when it has at most this share of the mesh's triangles.
pub const KEEP_RATIO: f64 = 0.7;

/// Meshes with fewer triangles get no levels (their cost is the pixels').
const MIN_TRIANGLES: usize = 256;

/// The levels' error bounds are `d·2^(−k/2)` for k from `FINEST` down to `COARSEST`
/// (d/2048 … d/32, d the diameter), a factor √2 apart.
const FINEST: i32 = 22;
const COARSEST: i32 = 10;

/// One simplified copy of a mesh.
#[derive(Debug, Clone)]
pub struct Level {
    /// The simplified mesh (its own, compacted vertices; model frame).
    pub mesh: Mesh,
    /// Its edge topology.
    pub topology: EdgeTopology,
    /// The simplifier's measured error, model units (at most the level's bound).
    pub error: f64,
}

/// The welded mesh the levels are simplified from.
#[derive(Debug, Clone, Default)]
struct Source {
    positions: Vec<DVec3>,
    /// `positions` − the bounds' centre, as the simplifier reads them.
    packed: Vec<[f32; 3]>,
    indices: Vec<u32>,
    triangles: usize,
}

/// A mesh's levels (each simplified the first time a render chooses it), and what
/// choosing one needs.
#[derive(Debug, Clone, Default)]
pub struct DetailLevels {
    source: Source,
    /// Per level, finest first: its error bound (model units) and, once built, the
    /// level (`None` when it would not have saved enough triangles).
    bounds: Vec<f64>,
    built: Vec<OnceLock<Option<Level>>>,
    /// Centre (the bounds' centre) and radius of a sphere holding the mesh's used
    /// vertices (model frame).
    centre: DVec3,
    radius: f64,
    /// The corners of the mesh's bounding box (model frame).
    corners: [DVec3; 8],
    /// The tolerance, pixels (0: never simplified).
    tolerance_px: f64,
}

impl DetailLevels {
    /// No levels: every render uses the mesh itself.
    pub fn none() -> DetailLevels {
        DetailLevels::default()
    }

    /// The levels of `mesh` (whose edge topology is `topology`) for renders that may
    /// move its silhouette by at most `tolerance_px` pixels at σ ≥ 1 px² (0, negative
    /// or not finite: no levels). Each level is simplified when first chosen.
    pub fn build(mesh: &Mesh, topology: &EdgeTopology, tolerance_px: f64) -> DetailLevels {
        let Some(b) = mesh.bounds() else {
            return DetailLevels::none();
        };
        let own = topology.vertex_count == mesh.positions.len() && topology.face_count == mesh.triangles.len();
        if !(tolerance_px > 0.0 && tolerance_px.is_finite()) || mesh.triangles.len() < MIN_TRIANGLES || !own {
            return DetailLevels::none();
        }
        // The smallest sphere about the box's centre holding every vertex a triangle uses.
        let centre = b.centre();
        let radius = mesh
            .triangles
            .iter()
            .flatten()
            .filter_map(|&i| mesh.positions.get(i as usize))
            .map(|p| (*p - centre).length())
            .fold(0.0, f64::max);
        let diameter = mesh.diameter();
        if !(diameter > 0.0 && diameter.is_finite() && radius.is_finite()) {
            return DetailLevels::none();
        }
        let (positions, indices) = welded(mesh, topology);
        let packed = positions.iter().map(|p| (*p - centre).as_vec3().to_array()).collect();
        let bounds: Vec<f64> = (COARSEST..=FINEST)
            .rev()
            .map(|k| diameter * 0.5f64.sqrt().powi(k))
            .collect();
        DetailLevels {
            source: Source {
                positions,
                packed,
                indices,
                triangles: mesh.triangles.len(),
            },
            built: bounds.iter().map(|_| OnceLock::new()).collect(),
            bounds,
            centre,
            radius,
            corners: std::array::from_fn(|i| {
                let pick = |bit: usize, lo: f64, hi: f64| if i >> bit & 1 == 1 { hi } else { lo };
                DVec3::new(
                    pick(0, b.min.x, b.max.x),
                    pick(1, b.min.y, b.max.y),
                    pick(2, b.min.z, b.max.z),
                )
            }),
            tolerance_px,
        }
    }

    /// Number of levels (built or not).
    pub fn len(&self) -> usize {
        self.bounds.len()
    }

    /// Whether there are no levels.
    pub fn is_empty(&self) -> bool {
        self.bounds.is_empty()
    }

    /// Level `k`'s error bound, model units (levels finest first).
    pub fn bound(&self, k: usize) -> f64 {
        self.bounds[k]
    }

    /// Level `k` (simplified now if it was not yet), or `None` when it would keep more
    /// than [`KEEP_RATIO`] of the mesh's triangles (or the simplifier refused).
    ///
    /// # Panics
    /// If `k >= len()`.
    pub fn level(&self, k: usize) -> Option<&Level> {
        self.built[k]
            .get_or_init(|| simplified(&self.source, self.bounds[k]))
            .as_ref()
    }

    /// The tolerance the levels are chosen with, pixels.
    pub fn tolerance_px(&self) -> f64 {
        self.tolerance_px
    }

    /// The tolerance at softness σ (px²): `t·min(1, σ)`, t the levels' tolerance.
    pub fn tolerance_at(&self, sigma: f64) -> f64 {
        self.tolerance_px * sigma.min(1.0)
    }

    /// The coarsest level whose error moves the silhouette of the mesh at `pose` in
    /// `camera` by at most the tolerance at softness `sigma` (module doc), or `None`
    /// for the mesh itself.
    pub fn choose(&self, pose: &Pose, camera: &Camera, sigma: f64) -> Option<&Level> {
        let tolerance = self.tolerance_at(sigma);
        if self.bounds.is_empty() || tolerance.is_nan() || tolerance <= 0.0 {
            return None;
        }
        let s = pose.scale.abs().max_element();
        // Nearest depth: the sphere's and the box's (its 8 corners), whichever is deeper
        // (both hold every vertex).
        let to_cam = |p: DVec3| camera.to_camera(pose.apply(p));
        let corners = self.corners.map(to_cam);
        let z_box = corners.iter().map(|c| c.z).fold(f64::INFINITY, f64::min);
        let z_near = (to_cam(self.centre).z - s * self.radius).max(z_box);
        if z_near.is_nan() || z_near <= 0.0 {
            return None;
        }
        // How far from the principal point a pixel that matters lies: within the canvas
        // and, when every box corner is in front, the hull of their projections.
        let c = DVec2::new(camera.cx, camera.cy);
        let (w, h) = (f64::from(camera.width), f64::from(camera.height));
        let canvas = [(0.0, 0.0), (w, 0.0), (0.0, h), (w, h)]
            .map(|(x, y)| (DVec2::new(x - 0.5, y - 0.5) - c).length())
            .into_iter()
            .fold(0.0, f64::max);
        let hull = if z_box > 0.0 {
            corners
                .iter()
                .map(|p| (camera.project(*p) - c).length())
                .fold(0.0, f64::max)
        } else {
            f64::INFINITY
        };
        let r = canvas.min(hull) + tolerance;
        let f = camera.fx.abs().max(camera.fy.abs());
        let reach = f.hypot(r);
        // A point at depth ≥ z_near moved by at most s·e lies at depth ≥ z_near − s·e.
        let moved = |e: f64| s * e * reach / (z_near - s * e);
        let k = self
            .bounds
            .iter()
            .rposition(|&e| s * e < z_near && moved(e) <= tolerance)?;
        self.level(k)
    }
}

/// The source simplified to error bound `bound` (module doc), if that saves enough.
fn simplified(source: &Source, bound: f64) -> Option<Level> {
    let settings = SimplifySettings {
        target_index_count: 0,
        target_error: bound as f32,
        options: SimplifyOptions::ERROR_ABSOLUTE,
    };
    // The simplifier refuses only malformed input, which welding rules out; a refusal
    // leaves the mesh itself in use.
    let out = simplify(
        &source.indices,
        Positions::from_packed(&source.packed),
        settings,
        &mut Workspace::default(),
    )
    .ok()?;
    let count = out.indices.len() / 3;
    if count == 0 || count as f64 > KEEP_RATIO * source.triangles as f64 {
        return None;
    }
    let mesh = compact(&source.positions, &out.indices);
    let topology = EdgeTopology::from_mesh(&mesh);
    Some(Level {
        mesh,
        topology,
        error: f64::from(out.error).max(0.0),
    })
}

/// The welded triangles (the topology's representatives) without degenerate or
/// repeated ones, over their own compacted vertices.
fn welded(mesh: &Mesh, topology: &EdgeTopology) -> (Vec<DVec3>, Vec<u32>) {
    let mut slot = vec![u32::MAX; mesh.positions.len()];
    let mut positions = Vec::new();
    let mut seen = HashSet::new();
    let mut indices = Vec::with_capacity(topology.welded_faces.len() * 3);
    for w in &topology.welded_faces {
        let mut key = *w;
        key.sort_unstable();
        if key[0] == key[1] || key[1] == key[2] || !seen.insert(key) {
            continue;
        }
        for &v in w {
            if slot[v as usize] == u32::MAX {
                slot[v as usize] = positions.len() as u32;
                positions.push(mesh.positions[v as usize]);
            }
            indices.push(slot[v as usize]);
        }
    }
    (positions, indices)
}

/// The triangles `indices` over `positions` with only their own vertices.
fn compact(positions: &[DVec3], indices: &[u32]) -> Mesh {
    let mut slot: HashMap<u32, u32> = HashMap::new();
    let mut mesh = Mesh::default();
    for t in indices.chunks_exact(3) {
        let tri = [t[0], t[1], t[2]].map(|i| {
            *slot.entry(i).or_insert_with(|| {
                mesh.positions.push(positions[i as usize]);
                mesh.positions.len() as u32 - 1
            })
        });
        mesh.triangles.push(tri);
    }
    mesh
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::app::shapes::blob_mesh;
    use crate::mask::Mask;
    use crate::raster::hard;
    use crate::raster::silhouette::SoftSettings;
    use crate::raster::silhouette::{RasterKind, RenderMesh, SilhouetteRenderer};

    /// A camera on the +z side looking at the origin from `distance`.
    fn camera(distance: f64, side: u32) -> Camera {
        Camera::look_at(
            DVec3::new(0.3, 0.2, 1.0).normalize() * distance,
            DVec3::ZERO,
            DVec3::Y,
            side,
            side,
            150.0,
        )
    }

    /// Pixels on the mask's boundary (covered, with an uncovered 4-neighbour or the edge).
    fn boundary(m: &Mask) -> usize {
        let (w, h) = (m.width as i64, m.height as i64);
        let at = |x: i64, y: i64| x >= 0 && y >= 0 && x < w && y < h && m.data[(y * w + x) as usize] != 0;
        (0..h)
            .flat_map(|y| (0..w).map(move |x| (x, y)))
            .filter(|&(x, y)| at(x, y) && !(at(x - 1, y) && at(x + 1, y) && at(x, y - 1) && at(x, y + 1)))
            .count()
    }

    #[test]
    fn welding_drops_seams_degenerate_and_repeated_triangles() {
        let cube = Mesh::cuboid(DVec3::ONE);
        // Every triangle gets its own three copies of its corners (a glTF seam everywhere),
        // then a repeated triangle, its reverse and a degenerate one.
        let mut soup = Mesh::default();
        for t in &cube.triangles {
            let base = soup.positions.len() as u32;
            soup.positions.extend(t.map(|i| cube.positions[i as usize]));
            soup.triangles.push([base, base + 1, base + 2]);
        }
        soup.triangles.push(soup.triangles[0]);
        let [a, b, c] = soup.triangles[1];
        soup.triangles.push([c, b, a]);
        soup.triangles.push([a, a, b]);
        let (positions, indices) = welded(&soup, &EdgeTopology::from_mesh(&soup));
        assert_eq!(positions.len(), 8);
        assert_eq!(indices.len(), 3 * 12);
        let m = compact(&positions, &indices);
        assert_eq!((m.positions.len(), m.triangles.len()), (8, 12));
        assert_eq!(EdgeTopology::from_mesh(&m).edge_count(), 18);
    }

    #[test]
    fn levels_get_coarser_and_far_views_choose_coarser_ones() {
        let mesh = blob_mesh(52, 100);
        let d = DetailLevels::build(&mesh, &EdgeTopology::from_mesh(&mesh), 0.25);
        assert_eq!(d.len(), 13);
        let used: Vec<&Level> = (0..d.len()).filter_map(|k| d.level(k)).collect();
        assert!(used.len() >= 8, "{} levels save triangles", used.len());
        for (k, level) in (0..d.len()).filter_map(|k| d.level(k).map(|l| (k, l))) {
            assert!(level.mesh.triangles.len() as f64 <= KEEP_RATIO * mesh.triangles.len() as f64);
            assert!(level.mesh.positions.len() < mesh.positions.len());
            assert!(
                level.error <= d.bound(k) * (1.0 + 1e-6),
                "level {k}: {} > {}",
                level.error,
                d.bound(k)
            );
            assert!(k == 0 || d.bound(k) > d.bound(k - 1));
        }
        assert!(used
            .windows(2)
            .all(|w| w[0].mesh.triangles.len() >= w[1].mesh.triangles.len()));
        assert!(used[0].mesh.triangles.len() > 2 * used[used.len() - 1].mesh.triangles.len());
        let index = |c: &Camera| d.choose(&Pose::IDENTITY, c, 1.0).map(|x| x.error);
        // Closer views may only choose finer levels.
        let errors: Vec<f64> = [2.5, 5.0, 10.0, 20.0, 40.0]
            .iter()
            .map(|&z| index(&camera(z, 128)).unwrap_or(0.0))
            .collect();
        assert!(errors.windows(2).all(|w| w[0] <= w[1]), "{errors:?}");
        assert!(errors[4] > errors[0], "{errors:?}");
        // No levels at tolerance 0, for tiny meshes, or when the sphere reaches behind.
        assert!(DetailLevels::build(&mesh, &EdgeTopology::from_mesh(&mesh), 0.0).is_empty());
        assert!(DetailLevels::build(&mesh, &EdgeTopology::from_mesh(&mesh), f64::NAN).is_empty());
        let other = blob_mesh(20, 30);
        assert!(DetailLevels::build(&mesh, &EdgeTopology::from_mesh(&other), 0.25).is_empty());
        for bad in [-1.0, f64::NAN, f64::INFINITY] {
            let s = crate::FitSettings {
                detail_px: bad,
                ..Default::default()
            };
            let e = s.validate().unwrap_err().to_string();
            assert!(e.contains("--detail-px"), "{e}");
        }
        assert!({
            let cube = Mesh::cuboid(DVec3::ONE);
            DetailLevels::build(&cube, &EdgeTopology::from_mesh(&cube), 1.0)
        }
        .is_empty());
        assert!(d.choose(&Pose::IDENTITY, &camera(0.5, 128), 1.0).is_none());
        // Sharper silhouettes get a tighter tolerance: finer levels, the mesh itself at σ → 0.
        let far = camera(40.0, 128);
        let at = |sigma: f64| d.choose(&Pose::IDENTITY, &far, sigma).map_or(0.0, |x| x.error);
        assert_eq!(d.tolerance_at(4.0), 0.25);
        assert!((d.tolerance_at(0.01) - 0.0025).abs() < 1e-15);
        assert!(
            at(0.01) < at(1.0) && at(1.0) == at(9.0),
            "{} {} {}",
            at(0.01),
            at(1.0),
            at(9.0)
        );
        assert!(d.choose(&Pose::IDENTITY, &far, 1e-12).is_none());
        let big = Pose {
            scale: DVec3::splat(100.0),
            ..Pose::IDENTITY
        };
        assert!(d.choose(&big, &camera(20.0, 128), 1.0).is_none());
    }

    #[test]
    fn a_chosen_level_moves_the_silhouette_by_less_than_the_tolerance() {
        let mesh = blob_mesh(52, 100);
        for tolerance in [0.25, 1.0] {
            let d = DetailLevels::build(&mesh, &EdgeTopology::from_mesh(&mesh), tolerance);
            let mut used = 0;
            for z in [3.0, 6.0, 12.0] {
                for side in [96, 256] {
                    let cam = camera(z, side);
                    let Some(level) = d.choose(&Pose::IDENTITY, &cam, 1.0) else {
                        continue;
                    };
                    used += 1;
                    let full = hard::render(&mesh, &Pose::IDENTITY, &cam);
                    let coarse = hard::render(&level.mesh, &Pose::IDENTITY, &cam);
                    let changed = full.data.iter().zip(&coarse.data).filter(|(a, b)| a != b).count();
                    // Moving the outline by ≤ t px flips at most about t pixel centres
                    // per boundary pixel.
                    let bound = (tolerance * boundary(&full) as f64).ceil() as usize + 2;
                    assert!(
                        changed <= bound,
                        "tolerance {tolerance}, z {z}, {side}²: {changed} pixels changed, bound {bound}"
                    );
                }
            }
            assert!(used >= 3, "tolerance {tolerance}: levels chosen in only {used} renders");
        }
    }

    #[test]
    fn a_long_object_seen_side_on_gets_coarser_levels_that_stay_within_the_tolerance() {
        // Stretched 4× along x and seen nearly along z, its sphere reaches far nearer the
        // camera than any vertex, and its image fills a small part of the canvas: the
        // box's depth and the image's extent choose coarser levels than the sphere and
        // the canvas alone would, and they still move the silhouette by ≤ the tolerance.
        let mesh = blob_mesh(52, 100);
        let tolerance = 0.5;
        let d = DetailLevels::build(&mesh, &EdgeTopology::from_mesh(&mesh), tolerance);
        let pose = Pose {
            scale: DVec3::new(4.0, 1.0, 1.0),
            ..Pose::IDENTITY
        };
        let mut coarser = 0;
        for z in [9.0, 14.0, 24.0] {
            let cam = Camera::look_at(DVec3::new(0.0, 0.15, z), DVec3::ZERO, DVec3::Y, 256, 256, 150.0);
            // The sphere-and-canvas rule (the previous one), as a reference.
            let zc = cam.to_camera(pose.apply(d.centre)).z;
            let reach = 150.0f64.hypot(0.5 * 256f64.hypot(256.0));
            let old = (0..d.len()).rposition(|k| 4.0 * d.bound(k) * reach / (zc - 4.0 * d.radius) <= tolerance);
            let Some(level) = d.choose(&pose, &cam, 1.0) else {
                continue;
            };
            let k = (0..d.len())
                .find(|&k| d.level(k).is_some_and(|l| std::ptr::eq(l, level)))
                .unwrap();
            assert!(old.is_none_or(|o| k >= o), "z {z}: level {k} finer than {old:?}");
            coarser += usize::from(old.is_none_or(|o| k > o));
            let full = hard::render(&mesh, &pose, &cam);
            let coarse = hard::render(&level.mesh, &pose, &cam);
            let changed = full.data.iter().zip(&coarse.data).filter(|(a, b)| a != b).count();
            let bound = (tolerance * boundary(&full) as f64).ceil() as usize + 2;
            assert!(changed <= bound, "z {z}: {changed} pixels changed, bound {bound}");
        }
        assert!(coarser >= 2, "coarser in only {coarser} of 3 views");
    }

    #[test]
    fn the_renderer_renders_the_chosen_level_exactly() {
        let mesh = blob_mesh(52, 100);
        let m = RenderMesh::new(mesh);
        let cam = camera(12.0, 128);
        let level = m
            .detail()
            .choose(&Pose::IDENTITY, &cam, 1.0)
            .expect("a level at this distance");
        let alone = RenderMesh::exact(level.mesh.clone());
        let s = SoftSettings { sigma: 1.0, eps: 1e-4 };
        let w: Vec<f64> = (0..128 * 128).map(|i| ((i * 7919) % 13) as f64 - 6.0).collect();
        let (mut a, mut b) = (
            SilhouetteRenderer::new(RasterKind::Edge),
            SilhouetteRenderer::new(RasterKind::Edge),
        );
        let ga = a
            .render_with_gradients(&m, &Pose::IDENTITY, &cam, &s, |p| [w[p]])
            .unwrap();
        let gb = b
            .render_with_gradients(&alone, &Pose::IDENTITY, &cam, &s, |p| [w[p]])
            .unwrap();
        assert_eq!(a.alpha(), b.alpha());
        assert_eq!(ga, gb);
        assert!(ga[0].iter().any(|g| *g != 0.0));
        // SoftRas, the paper's renderer, always renders the mesh itself.
        let mut soft = SilhouetteRenderer::new(RasterKind::SoftRas);
        let full = soft.render(&m, &Pose::IDENTITY, &cam, &s).unwrap().to_vec();
        let mut soft_full = SilhouetteRenderer::new(RasterKind::SoftRas);
        let exact = RenderMesh::exact(m.mesh.clone());
        assert_eq!(full, soft_full.render(&exact, &Pose::IDENTITY, &cam, &s).unwrap());
    }
}
