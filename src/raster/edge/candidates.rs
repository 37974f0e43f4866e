//! The candidate outline edges of one render (module doc of `edge.rs`, steps 2–4):
//! present faces, the edges whose present faces all lie on one side, their outward
//! normals, and the accept test decided once per edge where it cannot depend on the
//! pixel.

use super::{EdgeSilhouette, EdgeTopology};
use crate::raster::project::Projected;
use crate::raster::soft::DEGENERATE_DOUBLE_AREA;
use glam::DVec2;

/// A candidate outline edge ready for the tile pass.
#[derive(Debug, Clone, Copy)]
pub(super) struct EdgeSetup {
    /// Original vertex indices of its ends.
    pub(super) ia: u32,
    pub(super) ib: u32,
    /// Projected first end and `b − a`.
    pub(super) a: DVec2,
    pub(super) dir: DVec2,
    /// Unit left normal and offset: `e(p) = n·p + c` is the signed distance to the line.
    pub(super) n: DVec2,
    pub(super) c: f64,
    /// `1/n.x` (0 when |n.x| ≤ 1e-12: a horizontal edge).
    pub(super) inv_nx: f64,
    /// `s(p) = sd·p + sc = (p − a)·(b − a)/|b − a|²`, the unclamped segment parameter.
    pub(super) sd: DVec2,
    pub(super) sc: f64,
    /// `|b − a|`.
    pub(super) len: f64,
    /// Unit outward normal (away from the side its faces lie on).
    pub(super) out: DVec2,
    /// Whether the accept test is the same for every pixel.
    pub(super) accept: Accept,
    /// m-expanded pixel box, clipped to the canvas (inclusive).
    pub(super) x0: i32,
    pub(super) x1: i32,
    pub(super) y0: i32,
    pub(super) y1: i32,
}

impl EdgeSetup {
    /// `(e, s, d²)` at pixel centre (x, y): the signed line distance, the unclamped
    /// parameter and the squared distance to the segment, `e² + (|b − a|·excess)²`
    /// with `excess = max(−s, s − 1, 0)` (Pythagoras: the foot on the line is `s`
    /// lengths along, the clamped end `excess` lengths from it). Branch-free.
    #[inline(always)]
    pub(super) fn eval(&self, x: f64, y: f64) -> (f64, f64, f64) {
        let e = self.n.x * x + (self.n.y * y + self.c);
        let s = self.sd.x * x + (self.sd.y * y + self.sc);
        let ex = max(max(-s, s - 1.0), 0.0) * self.len;
        (e, s, e * e + ex * ex)
    }

    /// The closest point of the segment for parameter `s`.
    #[inline(always)]
    pub(super) fn point(&self, s: f64) -> DVec2 {
        self.a + self.dir * s.clamp(0.0, 1.0)
    }
}

/// The accept test of a candidate over all pixels (see `EdgeSilhouette::classify`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Accept {
    /// Rejected for every pixel (a hidden contour): the candidate is not binned.
    Never,
    /// Accepted for every pixel.
    Always,
    /// Depends on the pixel: tested per pixel.
    PerPixel,
}

/// Largest box (pixel cells) [`EdgeSilhouette::classify`] scans.
const CLASSIFY_CELLS: i64 = 48;

/// `max(a, b)` as one instruction (no NaN handling: the inputs are finite).
#[inline(always)]
fn max(a: f64, b: f64) -> f64 {
    if a > b {
        a
    } else {
        b
    }
}

/// `⌊v⌋` without a library call (`f64::floor` is one on baseline x86-64); saturates
/// beyond the `i64` range, and NaN gives 0.
#[inline(always)]
pub(super) fn floor_i64(v: f64) -> i64 {
    let t = v as i64;
    t.saturating_sub(i64::from((t as f64) > v))
}

/// `⌈v⌉`, saturating like [`floor_i64`].
#[inline(always)]
pub(super) fn ceil_i64(v: f64) -> i64 {
    let t = v as i64;
    t.saturating_add(i64::from((t as f64) < v))
}

impl EdgeSilhouette {
    /// Present faces, then candidate outline edges and their setups.
    pub(super) fn find_candidates(&mut self, topo: &EdgeTopology, proj: &Projected, triangles: &[[u32; 3]]) {
        let uv = &proj.uv;
        self.face_sign.clear();
        self.face_sign.extend(triangles.iter().map(|t| {
            let [a, b, c] = t.map(|i| i as usize);
            let front = proj.in_front(a) & proj.in_front(b) & proj.in_front(c);
            let cr = (uv[b] - uv[a]).perp_dot(uv[c] - uv[a]);
            // A NaN area (a vertex behind the camera) fails the comparison: not present.
            let present = front & (cr.abs() > DEGENERATE_DOUBLE_AREA);
            (i8::from(cr > 0.0) - i8::from(cr < 0.0)) * i8::from(present)
        }));
        let m = self.settings.cutoff_sq().sqrt();
        let (wm, hm) = ((self.width - 1) as f64, (self.height - 1) as f64);
        self.edges.clear();
        self.outline = 0;
        for (e, &[ia, ib]) in topo.ends.iter().enumerate() {
            // The side of face (a, b, c) is the sign of (b − a) × (c − a), c its third
            // vertex: its area's sign when it runs a → b, the opposite when b → a.
            // Faces left of a → b count as positive.
            let (mut left, mut right) = (false, false);
            for inc in topo.incidences(e) {
                let s = self.face_sign[inc.face as usize];
                let s = if inc.forward { s } else { -s };
                left |= s > 0;
                right |= s < 0;
            }
            if left == right {
                continue;
            }
            self.outline += 1;
            let (a, b) = (uv[ia as usize], uv[ib as usize]);
            let lo = a.min(b) - DVec2::splat(m);
            let hi = a.max(b) + DVec2::splat(m);
            if hi.x < 0.0 || hi.y < 0.0 || lo.x > wm || lo.y > hm {
                continue;
            }
            let dir = b - a;
            let len2 = dir.length_squared();
            // Present faces have area > 0, so the edge has length > 0.
            let len = len2.sqrt();
            let n_left = DVec2::new(-dir.y, dir.x) / len;
            let out = if left { -n_left } else { n_left };
            let accept = self.classify(a + out, b + out);
            if accept == Accept::Never {
                continue;
            }
            let sd = dir / len2;
            let setup = EdgeSetup {
                ia,
                ib,
                a,
                dir,
                n: n_left,
                c: -n_left.dot(a),
                inv_nx: if n_left.x.abs() > 1e-12 { 1.0 / n_left.x } else { 0.0 },
                sd,
                sc: -sd.dot(a),
                len,
                out,
                accept,
                x0: ceil_i64(lo.x.max(0.0)) as i32,
                x1: floor_i64(hi.x.min(wm)) as i32,
                y0: ceil_i64(lo.y.max(0.0)) as i32,
                y1: floor_i64(hi.y.min(hm)) as i32,
            };
            if setup.x0 <= setup.x1 && setup.y0 <= setup.y1 {
                self.edges.push(setup);
            }
        }
    }

    /// The accept test of a whole candidate at once, when it cannot depend on the pixel:
    /// every probe `q + n_out` lies on the segment `ra`–`rb` (the edge moved by n_out),
    /// so if all pixel cells of that segment's box (plus a rounding slack) have the same
    /// verdict, that is the verdict for every pixel. Boxes of more than
    /// [`CLASSIFY_CELLS`] cells are left to the per-pixel test.
    fn classify(&self, ra: DVec2, rb: DVec2) -> Accept {
        const SLACK: f64 = 1e-7;
        let (w, h) = (self.width as i64, self.height as i64);
        let lo = ra.min(rb) - DVec2::splat(SLACK);
        let hi = ra.max(rb) + DVec2::splat(SLACK);
        // The box spans at most (extent + 2) cells a side; NaN also goes per pixel.
        let size = hi - lo + DVec2::splat(2.0);
        let cells = size.x * size.y;
        if cells.is_nan() || cells > CLASSIFY_CELLS as f64 {
            return Accept::PerPixel;
        }
        let (x0, x1) = (floor_i64(lo.x + 0.5), floor_i64(hi.x + 0.5));
        let (y0, y1) = (floor_i64(lo.y + 0.5), floor_i64(hi.y + 0.5));
        let (mut yes, mut no) = (false, false);
        for y in y0..=y1 {
            for x in x0..=x1 {
                let covered =
                    (0..w).contains(&x) && (0..h).contains(&y) && self.coverage.data[(y * w + x) as usize] != 0;
                no |= covered;
                yes |= !covered;
            }
        }
        match (yes, no) {
            (true, false) => Accept::Always,
            (false, true) => Accept::Never,
            _ => Accept::PerPixel,
        }
    }
}
