//! The candidate outline edges of one render (module doc of `edge.rs`, steps 2–4):
//! present faces, the edges whose present faces all lie on one side, their outward
//! normals, and the accept test decided once per edge where it cannot depend on the
//! pixel (a summed-area table of the coverage counts a box's covered pixels). The one
//! pass over the edges also gives the coverage its boundary chain (`coverage.rs`).

use super::coverage::chain_edge;
use super::topology::{MANY_FACES, NO_FACE};
use super::{EdgeSilhouette, EdgeTopology};
use crate::camera::Camera;
use crate::raster::hard::{self, SUBPIXEL_BITS};
use crate::raster::project::Projected;
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

/// How deep (in pixels, Chebyshev) a pixel must be inside the coverage for
/// `deep_inside`: the ends' pixels ± 2 of an edge at most one pixel long lie within 3.
const DEEP: i64 = 3;

/// Largest box (pixel cells) [`EdgeSilhouette::classify`] decides at once (beyond any
/// canvas; keeps its integer arithmetic far from overflow).
const MAX_CLASSIFY_CELLS: f64 = 1e12;

/// The pixel cell `⌊x + ½⌋` of a snapped coordinate, exactly.
#[inline(always)]
fn cell(v: i32) -> i64 {
    (i64::from(v) + (1 << (SUBPIXEL_BITS - 1))) >> SUBPIXEL_BITS
}

/// A snapped position back in pixels.
#[inline(always)]
fn unsnap(p: [i32; 2]) -> DVec2 {
    DVec2::new(f64::from(p[0]), f64::from(p[1])) / f64::from(1u32 << SUBPIXEL_BITS)
}

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

/// An edge whose present faces all lie on one side (before its setup).
#[derive(Debug, Clone, Copy)]
pub(super) struct Candidate {
    pub(super) edge: u32,
    /// Whether its faces lie left of a → b.
    pub(super) left: bool,
    /// Its ends snapped (both are: its faces are present).
    pub(super) a: [i32; 2],
    pub(super) b: [i32; 2],
}

impl EdgeSilhouette {
    /// The hard coverage (`coverage.rs`), present faces, then candidate outline edges
    /// and their setups.
    pub(super) fn find_candidates(&mut self, topo: &EdgeTopology, proj: &Projected, camera: &Camera) {
        let chain = self.snap_vertices(proj);
        self.face_signs(topo);
        if chain {
            self.edge_pass::<true>(topo);
            self.chain_fill();
        } else {
            self.edge_pass::<false>(topo);
            // The back faces of closed, consistently oriented components cover nothing
            // their front faces do not (topology module doc): skipped.
            hard::render_projected_culled_into(proj, &topo.welded_faces, camera, &topo.front, &mut self.coverage);
        }
        self.build_sat();
        self.setup_candidates(topo, proj);
    }

    /// One pass over the edges: the candidates (present faces on one side) and, with
    /// `CHAIN`, each edge's net weight in the coverage's counters. (Kept out of line,
    /// so that profiles show it apart from the tile pass.)
    #[inline(never)]
    fn edge_pass<const CHAIN: bool>(&mut self, topo: &EdgeTopology) {
        self.candidates.clear();
        // The side of face (a, b, c) is the sign of (b − a) × (c − a), c its third
        // vertex: its area's sign when it runs a → b, the opposite when b → a. Faces
        // left of a → b count as positive.
        let sign = &self.face_sign;
        let side = |packed: u32| {
            let s = i32::from(sign[(packed >> 1) as usize]);
            if packed & 1 == 1 {
                s
            } else {
                -s
            }
        };
        // Branch-free first (which edges go on is unpredictable): the edges with a
        // non-zero net weight, or many faces, compacted into `busy`.
        self.busy.clear();
        self.busy.resize(topo.pairs.len(), 0);
        let mut n = 0;
        for (e, &[p0, p1]) in topo.pairs.iter().enumerate() {
            let many = p0 == MANY_FACES;
            let q0 = if many { 0 } else { p0 };
            let two = p1 != NO_FACE && !many;
            let q1 = if two { p1 } else { q0 };
            let net = side(q0) + side(q1) * i32::from(two);
            self.busy[n] = e as u32;
            n += usize::from(net != 0 || many);
        }
        for &e in &self.busy[..n] {
            let e = e as usize;
            let [p0, p1] = topo.pairs[e];
            let (left, right, net) = if p0 == MANY_FACES {
                let (mut left, mut right, mut net) = (false, false, 0i32);
                for inc in topo.incidences(e) {
                    let s = side(inc.face << 1 | u32::from(inc.forward));
                    left |= s > 0;
                    right |= s < 0;
                    net += s;
                }
                (left, right, net)
            } else {
                let s0 = side(p0);
                let s1 = if p1 == NO_FACE { 0 } else { side(p1) };
                ((s0 > 0) | (s1 > 0), (s0 < 0) | (s1 < 0), s0 + s1)
            };
            // Faces on one side only imply a non-zero net.
            if net == 0 {
                continue;
            }
            let [ia, ib] = topo.ends[e];
            let (a, b) = (self.snapped[ia as usize], self.snapped[ib as usize]);
            if CHAIN {
                chain_edge(&mut self.diff, self.width, self.height, a, b, net);
            }
            if left != right {
                self.candidates.push(Candidate {
                    edge: e as u32,
                    left,
                    a,
                    b,
                });
            }
        }
    }

    /// The setups of the candidates whose m-box meets the canvas and that the accept
    /// test does not reject everywhere.
    fn setup_candidates(&mut self, topo: &EdgeTopology, proj: &Projected) {
        let uv = &proj.uv;
        let m = self.settings.cutoff_sq().sqrt();
        let (wm, hm) = ((self.width - 1) as f64, (self.height - 1) as f64);
        self.edges.clear();
        self.outline = self.candidates.len();
        for k in 0..self.candidates.len() {
            let Candidate { edge, left, a, b } = self.candidates[k];
            // Every probe lies within one pixel of the segment (and the snapped ends
            // within 1/2048 px of the ends): a covered box around it rejects a hidden
            // contour before its setup.
            let (sa, sb) = (unsnap(a), unsnap(b));
            let (slo, shi) = (sa.min(sb), sa.max(sb));
            if shi.x < -m - 1.0 || shi.y < -m - 1.0 || slo.x > wm + m + 1.0 || slo.y > hm + m + 1.0 {
                continue;
            }
            if self.deep_inside(a, b) {
                continue;
            }
            if self.classify_snapped(a, b) == Accept::Never {
                continue;
            }
            let [ia, ib] = topo.ends[edge as usize];
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

    /// Whether a short edge with snapped ends `a`, `b` lies deep inside the coverage:
    /// their pixels are at most one apart and the one of `a` is [`DEEP`] deep. Then
    /// every cell of the box [`Self::classify_snapped`] counts for it (the ends' pixels
    /// ± 2) is covered, so its verdict is `Never`: this decides it with one lookup.
    #[inline(always)]
    fn deep_inside(&self, a: [i32; 2], b: [i32; 2]) -> bool {
        let ([px, py], [qx, qy]) = (a.map(cell), b.map(cell));
        let (w, h) = (i64::from(self.width), i64::from(self.height));
        (px - qx).abs() <= 1
            && (py - qy).abs() <= 1
            && (0..w).contains(&px)
            && (0..h).contains(&py)
            && self.deep[(py * w + px) as usize] != 0
    }

    /// [`Self::classify`] of the box of snapped ends `a`, `b` grown by 1.001 px: every
    /// probe of the edge lies within one pixel of it. In integers: the cell of
    /// `a/2^10 − 1.001 − 1e-7` is `⌊(a − 514)/2^10⌋` and that of `b/2^10 + 1.001 +
    /// 1e-7` is `⌊(b + 1537)/2^10⌋` exactly (no multiple of 2^10 lies between the
    /// integer and the real numerator), so the verdict equals the float box's.
    #[inline(always)]
    fn classify_snapped(&self, a: [i32; 2], b: [i32; 2]) -> Accept {
        let lo = |u: i32, v: i32| (i64::from(u.min(v)) - 514) >> SUBPIXEL_BITS;
        let hi = |u: i32, v: i32| (i64::from(u.max(v)) + 1537) >> SUBPIXEL_BITS;
        self.classify_cells(lo(a[0], b[0]), hi(a[0], b[0]), lo(a[1], b[1]), hi(a[1], b[1]))
    }

    /// The summed-area table of the coverage: `sat[(y + 1)(w + 1) + x + 1]` counts the
    /// covered pixels in columns `0..=x` of rows `0..=y`; and the pixels [`DEEP`] deep
    /// (every pixel within `DEEP` columns and rows covered, all on the canvas).
    fn build_sat(&mut self) {
        let (w, h) = (self.width as usize, self.height as usize);
        let stride = w + 1;
        self.sat.clear();
        self.sat.resize(stride * (h + 1), 0);
        for y in 0..h {
            let mut run = 0u32;
            for x in 0..w {
                run += u32::from(self.coverage.data[y * w + x] != 0);
                self.sat[(y + 1) * stride + x + 1] = self.sat[y * stride + x + 1] + run;
            }
        }
        let d = DEEP as usize;
        let full = ((2 * d + 1) * (2 * d + 1)) as u32;
        self.deep.clear();
        self.deep.resize(w * h, 0);
        for y in d..h.saturating_sub(d) {
            let (top, bottom) = ((y - d) * stride, (y + d + 1) * stride);
            for x in d..w.saturating_sub(d) {
                let (l, r) = (x - d, x + d + 1);
                let n = self.sat[bottom + r] + self.sat[top + l] - self.sat[bottom + l] - self.sat[top + r];
                self.deep[y * w + x] = u8::from(n == full);
            }
        }
    }

    /// The accept test of a whole candidate at once, when it cannot depend on the pixel:
    /// every probe `q + n_out` lies on the segment `ra`–`rb` (the edge moved by n_out),
    /// so if all pixel cells of that segment's box (plus a rounding slack) have the same
    /// verdict (cells off the canvas are background), that is the verdict for every
    /// pixel. Counted with the summed-area table.
    fn classify(&self, ra: DVec2, rb: DVec2) -> Accept {
        const SLACK: f64 = 1e-7;
        let lo = ra.min(rb) - DVec2::splat(SLACK);
        let hi = ra.max(rb) + DVec2::splat(SLACK);
        // Boxes beyond any canvas (or NaN) are left to the per-pixel test.
        let size = hi - lo + DVec2::splat(2.0);
        let cells = size.x * size.y;
        if cells.is_nan() || cells > MAX_CLASSIFY_CELLS {
            return Accept::PerPixel;
        }
        let (x0, x1) = (floor_i64(lo.x + 0.5), floor_i64(hi.x + 0.5));
        let (y0, y1) = (floor_i64(lo.y + 0.5), floor_i64(hi.y + 0.5));
        self.classify_cells(x0, x1, y0, y1)
    }

    /// The verdict of the pixel cells `x0..=x1` × `y0..=y1` (cells off the canvas are
    /// background): `Always` when none is covered, `Never` when all are.
    #[inline(always)]
    fn classify_cells(&self, x0: i64, x1: i64, y0: i64, y1: i64) -> Accept {
        let (w, h) = (self.width as i64, self.height as i64);
        let total = (x1 - x0 + 1) * (y1 - y0 + 1);
        let (cx0, cx1) = (x0.max(0), x1.min(w - 1));
        let (cy0, cy1) = (y0.max(0), y1.min(h - 1));
        let covered = if cx0 <= cx1 && cy0 <= cy1 {
            let s = (w + 1) as usize;
            let at = |x: i64, y: i64| i64::from(self.sat[y as usize * s + x as usize]);
            at(cx1 + 1, cy1 + 1) - at(cx0, cy1 + 1) - at(cx1 + 1, cy0) + at(cx0, cy0)
        } else {
            0
        };
        if covered == 0 {
            Accept::Always
        } else if covered == total {
            Accept::Never
        } else {
            Accept::PerPixel
        }
    }
}
