//! The hard coverage C of an edge render (module doc of `edge.rs`, step 1) from the
//! mesh's boundary chain instead of its triangles: the cost follows the outline, not
//! the triangle count.
//!
//! The hard rasteriser's rule (`raster::hard`: vertices snapped to 1/1024 px, exact
//! integer edge functions, the top-left rule) covers, in row y, the columns
//! `x ≥ c_L(y)` and `x < c_R(y)` of each triangle turned to positive area, where
//! `c(y)` is the smallest column at or right of an edge's crossing of the row and the
//! edge is active in the rows with `y_min ≤ y·2^10 < y_max` (its ends' snapped y). So
//! the number of triangles covering a pixel centre is a sum over directed edges of
//! `±[x ≥ c(y)]`, and the two faces of an interior edge (both turned the same way on
//! screen) cancel exactly: only the net weight of each welded edge — its faces'
//! projected-area signs, taken along the edge — is left, which is non-zero on
//! contours (a front and a back face: weight ±2), open borders and non-manifold
//! edges only. A pixel is covered when the count is positive. The result is the hard
//! raster of the triangles with every vertex at its welded representative, pixel for
//! pixel (a test checks it), at the price of one area sign per face, one sum per edge
//! and a few integer divisions per row crossed by an outline edge.
//!
//! Triangles crossing the near plane or reaching past the guard band take the hard
//! rasteriser's clipping path: when any vertex is there, the whole coverage comes from
//! `hard::render_projected_culled_into` instead (`candidates.rs`).

use super::{EdgeSilhouette, EdgeTopology};
use crate::raster::hard::{snap, GUARD_BAND_PX, SUBPIXEL_BITS};
use crate::raster::project::Projected;

const ONE: i64 = 1 << SUBPIXEL_BITS;

/// A vertex behind the near plane or beyond the guard band (snapped coordinates are
/// within ±2^28, so this pair never occurs).
pub(super) const NOT_SNAPPED: [i32; 2] = [i32::MIN, i32::MIN];

/// Smallest integer ≥ n / d, for d > 0.
#[inline(always)]
fn ceil_div(n: i64, d: i64) -> i64 {
    -(-n).div_euclid(d)
}

impl EdgeSilhouette {
    /// Snaps every vertex (`NOT_SNAPPED` for those behind the near plane or beyond the
    /// guard band); whether all of them are snapped (else the coverage comes from the
    /// hard rasteriser, module doc).
    pub(super) fn snap_vertices(&mut self, proj: &Projected) -> bool {
        self.snapped.clear();
        let mut all = true;
        self.snapped.extend(proj.uv.iter().zip(&proj.cam).map(|(p, c)| {
            let ok = c.z >= proj.near && p.x.abs() <= GUARD_BAND_PX && p.y.abs() <= GUARD_BAND_PX;
            all &= ok;
            if ok {
                [snap(p.x) as i32, snap(p.y) as i32]
            } else {
                NOT_SNAPPED
            }
        }));
        let (w, h) = (self.width as usize, self.height as usize);
        self.diff.clear();
        if all {
            self.diff.resize((w + 1) * h, 0);
        }
        all
    }

    /// Per face, the sign of its snapped welded doubled area, 0 when that is zero or a
    /// vertex is not snapped (the face is not present).
    pub(super) fn face_signs(&mut self, topo: &EdgeTopology) {
        let v = &self.snapped;
        self.face_sign.clear();
        self.face_sign.extend(topo.welded_faces.iter().map(|t| {
            let [a, b, c] = t.map(|i| v[i as usize]);
            if a == NOT_SNAPPED || b == NOT_SNAPPED || c == NOT_SNAPPED {
                return 0;
            }
            let [a, b, c] = [a, b, c].map(|p| p.map(i64::from));
            let area = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
            area.signum() as i8
        }));
    }

    /// The coverage from the row counters: covered where the running count is positive.
    pub(super) fn chain_fill(&mut self) {
        let w = self.width as usize;
        let cov = &mut self.coverage;
        cov.width = self.width;
        cov.height = self.height;
        cov.data.clear();
        cov.data.reserve(w * self.height as usize);
        for row in self.diff.chunks_exact(w + 1) {
            let mut n = 0i32;
            cov.data.extend(row[..w].iter().map(|&d| {
                n += d;
                u8::from(n > 0)
            }));
        }
    }
}

/// Adds edge a → b (snapped ends) with net weight `net` (the sum over its faces of
/// their area signs, taken along a → b) to the row counters.
#[inline]
pub(super) fn chain_edge(diff: &mut [i32], width: u32, height: u32, a: [i32; 2], b: [i32; 2], net: i32) {
    let (a, b) = (a.map(i64::from), b.map(i64::from));
    let dy = b[1] - a[1];
    if dy == 0 {
        return;
    }
    let (w, h) = (i64::from(width), i64::from(height));
    let stride = w as usize + 1;
    // A face turned to positive area runs a → b when its sign along the edge is +1;
    // then it adds −sign(dy)·[x ≥ c(y)] (a left edge starts its run at c, a right
    // edge ends it there).
    let (k, s, d) = (-(dy.signum() as i32) * net, dy.signum(), dy.abs());
    let (ylo, yhi) = (a[1].min(b[1]), a[1].max(b[1]));
    let y0 = (-((-ylo) >> SUBPIXEL_BITS)).max(0);
    let y1 = ((yhi - 1) >> SUBPIXEL_BITS).min(h - 1);
    let dx = b[0] - a[0];
    let den = ONE * d;
    for y in y0..=y1 {
        // Column x is at or right of the crossing when x·ONE·d ≥ a.x·d + s·dx·(y·ONE − a.y).
        let num = a[0] * d + s * dx * (y * ONE - a[1]);
        let c = ceil_div(num, den).clamp(0, w) as usize;
        diff[y as usize * stride + c] += k;
    }
}

#[cfg(test)]
mod tests {
    use super::super::tests::{camera, flat};
    use super::*;
    use crate::raster::hard;
    use crate::raster::silhouette::SoftSettings;
    use glam::{DVec2, DVec3};

    /// The edge render's coverage against the hard raster of all triangles.
    fn check(uv: &[DVec2], tris: &[[u32; 3]], w: u32, h: u32) -> usize {
        let pos: Vec<DVec3> = (0..uv.len()).map(|i| DVec3::new(i as f64, 0.0, 0.0)).collect();
        let topo = EdgeTopology::new(&pos, tris);
        let mut s = EdgeSilhouette::new();
        let cam = camera(w, h);
        s.render(&topo, &flat(uv), tris, &cam, &SoftSettings::default())
            .unwrap();
        let want = hard::render_projected(&flat(uv), tris, &cam);
        assert_eq!(s.coverage().data, want.data, "{uv:?} {tris:?}");
        want.data.iter().filter(|&&c| c != 0).count()
    }

    #[test]
    fn chain_coverage_equals_the_triangle_raster_on_lattice_soups() {
        // Random soups on a quarter-pixel lattice (ties on pixel centres and rows, shared
        // and repeated edges, both windings, degenerate and overlapping triangles,
        // vertices off the canvas).
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = |n: u64| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state % n
        };
        let mut covered = 0;
        for trial in 0..400 {
            let nv = 3 + next(12) as usize;
            let uv: Vec<DVec2> = (0..nv)
                .map(|_| DVec2::new(next(120) as f64 / 4.0 - 4.0, next(100) as f64 / 4.0 - 3.0))
                .collect();
            let nt = 1 + next(10) as usize;
            let tris: Vec<[u32; 3]> = (0..nt)
                .map(|_| [0, 0, 0].map(|_: u32| next(nv as u64) as u32))
                .collect();
            covered += check(&uv, &tris, 23 + (trial % 3), 19);
        }
        assert!(covered > 5_000, "only {covered} covered pixels");
    }

    #[test]
    fn a_closed_fan_and_its_open_half_match_the_raster() {
        // An octahedron-like closed fan seen from the front: contours carry weight 2.
        let uv = [
            DVec2::new(10.3, 9.1),
            DVec2::new(2.5, 3.0),
            DVec2::new(18.0, 2.5),
            DVec2::new(17.25, 16.0),
            DVec2::new(3.0, 15.5),
        ];
        let front = [[0u32, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 1]];
        let back = [[1u32, 3, 2], [1, 4, 3]];
        let all: Vec<[u32; 3]> = front.iter().chain(&back).copied().collect();
        assert!(check(&uv, &all, 21, 19) > 100);
        assert!(check(&uv, &front, 21, 19) > 100);
    }
}
