//! The soft rasteriser's kernel: triangle setup, binning into `TILE`² pixel tiles, and
//! the tile pass shared by the forward pass, the backward pass and the
//! Gauss–Newton accumulation.
//!
//! Each triangle is binned into the tiles its σ-expanded bounding box touches. A tile
//! is processed on its own, triangle by triangle: for every row of the triangle's box
//! inside the tile, only the span where all three edge functions are ≥ −m (m the
//! cut-off distance) is visited, `LANES` pixels at a time. Every contributing (pixel, triangle) pair multiplies
//! the pixel's transmittance `T` by `1 − D` and, when asked, leaves a [`Record`] of its
//! `∂A/∂(2-D vertex)` divided by T. Once the tile is done its T are final, and the
//! caller's tile callback turns the records into gradients while they are in cache —
//! so the forward and backward passes need one sweep and no per-pixel lists.

use glam::DVec2;
use wide::{CmpGe, CmpGt, CmpLe, CmpLt};

/// The lane types of the kernel: two f64 lanes (SSE2, wasm simd128, or scalar),
/// four where the build enables AVX (e.g. `-C target-cpu=native`).
#[cfg(not(target_feature = "avx"))]
type F = wide::f64x2;
#[cfg(not(target_feature = "avx"))]
type U = wide::u64x2;
#[cfg(target_feature = "avx")]
type F = wide::f64x4;
#[cfg(target_feature = "avx")]
type U = wide::u64x4;

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

/// Tile side in pixels (16 measured ~6 % faster than 8 on the reference blob: fewer
/// triangles are split between tiles).
pub(crate) const TILE: usize = 16;

/// One triangle ready for rasterisation: vertices, normalised edge functions
/// `e_k(p) = n_k·p + c_k` (the signed distance to the line of edge k = v_k → v_{k+1},
/// positive inside), and its σ-expanded, canvas-clipped pixel box (inclusive).
#[derive(Debug, Clone, Copy)]
pub(crate) struct TriSetup {
    pub idx: [u32; 3],
    /// `idx` rotated: the end vertex of each edge.
    pub next: [u32; 3],
    /// Unit inward edge normals and offsets: `e_k(p) = n_k·p + c_k`.
    pub n: [DVec2; 3],
    pub c: [f64; 3],
    /// The parameter of p's projection on edge k, `s_k(p) = (p − v_k)·(v_{k+1} − v_k) /
    /// |v_{k+1} − v_k|² = sd_k·p + sc_k` (0 at v_k, 1 at v_{k+1}).
    pub sd: [DVec2; 3],
    pub sc: [f64; 3],
    /// Edge vectors `v_{k+1} − v_k` and their lengths.
    pub dir: [DVec2; 3],
    pub len: [f64; 3],
    /// 1 / n_k.x (0 for a horizontal edge).
    pub inv_nx: [f64; 3],
    pub x0: i32,
    pub x1: i32,
    pub y0: i32,
    pub y1: i32,
}

impl TriSetup {
    /// Builds the setup, or `None` for a degenerate (|doubled area| ≤ `min_area`),
    /// non-finite or off-canvas triangle. `margin` is the cut-off distance m.
    #[inline]
    pub fn new(idx: [u32; 3], v: [DVec2; 3], margin: f64, min_area: f64, w: i32, h: i32) -> Option<TriSetup> {
        if !(v[0].is_finite() && v[1].is_finite() && v[2].is_finite()) {
            return None;
        }
        let cr = (v[1] - v[0]).perp_dot(v[2] - v[0]);
        if cr.abs() <= min_area {
            return None;
        }
        let lo = v[0].min(v[1]).min(v[2]) - DVec2::splat(margin);
        let hi = v[0].max(v[1]).max(v[2]) + DVec2::splat(margin);
        if hi.x < 0.0 || hi.y < 0.0 || lo.x > (w - 1) as f64 || lo.y > (h - 1) as f64 {
            return None;
        }
        let x0 = lo.x.max(0.0).ceil() as i32;
        let y0 = lo.y.max(0.0).ceil() as i32;
        let x1 = hi.x.min((w - 1) as f64).floor() as i32;
        let y1 = hi.y.min((h - 1) as f64).floor() as i32;
        if x0 > x1 || y0 > y1 {
            return None;
        }
        let s = cr.signum();
        let mut t = TriSetup {
            idx,
            next: [idx[1], idx[2], idx[0]],
            n: [DVec2::ZERO; 3],
            c: [0.0; 3],
            sd: [DVec2::ZERO; 3],
            sc: [0.0; 3],
            dir: [DVec2::ZERO; 3],
            len: [0.0; 3],
            inv_nx: [0.0; 3],
            x0,
            x1,
            y0,
            y1,
        };
        for k in 0..3 {
            let a = v[k];
            let d = v[(k + 1) % 3] - a;
            let l2 = d.length_squared();
            t.sd[k] = d / l2;
            t.sc[k] = -a.dot(d) / l2;
            t.dir[k] = d;
            t.len[k] = l2.sqrt();
            // cross(d, p − a) = d.x (p.y − a.y) − d.y (p.x − a.x), scaled to unit length.
            let nk = DVec2::new(-d.y, d.x) * (s / l2.sqrt());
            t.n[k] = nk;
            t.c[k] = -nk.dot(a);
            t.inv_nx[k] = if nk.x.abs() > 1e-12 { 1.0 / nk.x } else { 0.0 };
        }
        Some(t)
    }

    /// Inclusive x range of row `y`, within `[lo0, hi0]` (non-negative integers), where
    /// every edge function is ≥ −m; `None` when empty.
    #[inline(always)]
    fn span(&self, y: f64, m: f64, lo0: i32, hi0: i32) -> Option<(i32, i32)> {
        let mut lo = f64::NEG_INFINITY;
        let mut hi = f64::INFINITY;
        for k in 0..3 {
            let a = self.n[k].x;
            let rhs = -m - self.n[k].y * y - self.c[k];
            if a > 1e-12 {
                lo = lo.max(rhs * self.inv_nx[k]);
            } else if a < -1e-12 {
                hi = hi.min(rhs * self.inv_nx[k]);
            } else if rhs > 1e-9 {
                return None;
            }
        }
        let lo = (lo - 1e-7).max(lo0 as f64);
        let hi = (hi + 1e-7).min(hi0 as f64);
        // Both are finite here (`max`/`min` with the finite bounds drop a NaN).
        if lo > hi {
            return None;
        }
        // Both are ≥ 0 here, so truncation is floor.
        let t = lo as i32;
        let xa = if (t as f64) < lo { t + 1 } else { t };
        let xb = hi as i32;
        (xa <= xb).then_some((xa, xb))
    }
}

/// Triangles grouped by the tiles their boxes touch (a counting sort).
#[derive(Debug, Clone, Default)]
pub(crate) struct Bins {
    pub tiles_x: usize,
    pub tiles_y: usize,
    /// `items[start[t]..start[t + 1]]` are tile t's triangles (indices into the setups).
    pub start: Vec<u32>,
    pub items: Vec<u32>,
    cursor: Vec<u32>,
}

impl Bins {
    /// Bins `tris` for a `w`×`h` canvas.
    pub fn build(&mut self, tris: &[TriSetup], w: usize, h: usize) {
        self.tiles_x = w.div_ceil(TILE);
        self.tiles_y = h.div_ceil(TILE);
        let nt = self.tiles_x * self.tiles_y;
        self.start.clear();
        self.start.resize(nt + 1, 0);
        for t in tris {
            for ty in t.y0 as usize / TILE..=t.y1 as usize / TILE {
                for tx in t.x0 as usize / TILE..=t.x1 as usize / TILE {
                    self.start[ty * self.tiles_x + tx + 1] += 1;
                }
            }
        }
        for i in 0..nt {
            self.start[i + 1] += self.start[i];
        }
        self.cursor.clear();
        self.cursor.extend_from_slice(&self.start[..nt]);
        self.items.clear();
        self.items.resize(self.start[nt] as usize, 0);
        for (i, t) in tris.iter().enumerate() {
            for ty in t.y0 as usize / TILE..=t.y1 as usize / TILE {
                for tx in t.x0 as usize / TILE..=t.x1 as usize / TILE {
                    let c = &mut self.cursor[ty * self.tiles_x + tx];
                    self.items[*c as usize] = i as u32;
                    *c += 1;
                }
            }
        }
    }
}

/// A contributing pair's gradient, divided by its pixel's final T: the pixel's
/// `∂A_p/∂v_a = T_p·ga` and `∂A_p/∂v_b = T_p·gb`, (a, b) the closest edge's vertices.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Record {
    /// Pixel index within the tile (`ly·TILE + lx`).
    pub px: u32,
    pub a: u32,
    pub b: u32,
    pub ga: DVec2,
    pub gb: DVec2,
}

/// A finished tile handed to the tile callback.
pub(crate) struct Tile<'a> {
    /// Pixel origin of the tile.
    pub x0: usize,
    pub y0: usize,
    /// Its size (smaller than `TILE` on the right and bottom edges).
    pub w: usize,
    pub h: usize,
    /// Final transmittance per tile pixel (`ly·TILE + lx`).
    pub t: &'a [f64; TILE * TILE],
    /// The contributing pairs (empty unless records were asked for).
    pub records: &'a [Record],
}

/// Inputs of a tile pass.
pub(crate) struct Pass<'a> {
    pub tris: &'a [TriSetup],
    pub bins: &'a Bins,
    pub width: usize,
    pub height: usize,
    pub sigma: f64,
    pub cutoff_sq: f64,
}

/// Lanes processed together (a row chunk of the tile; `TILE` is a multiple).
const LANES: usize = std::mem::size_of::<F>() / 8;

/// A vector with every lane `v`. (`wide`'s own `splat` and `From` go through
/// `bytemuck::cast`, whose debug-build precondition checks made the kernel five times
/// slower with debug assertions on; `new` is a plain transmute.)
#[inline(always)]
const fn sp(v: f64) -> F {
    F::new([v; LANES])
}

/// `e^{−z}` per lane for z ≥ 0, to within a few ulps: range reduction by ln 2 and a
/// degree-11 Taylor polynomial on |r| ≤ ln2/2 (truncation error < 1e-14), branch-free.
/// z is clamped to 708 (e^{−708} ≈ 3e-308).
#[inline(always)]
fn exp_neg_lanes(z: F) -> F {
    const LOG2E: F = sp(std::f64::consts::LOG2_E);
    // fdlibm's split of ln 2: LN2_HI has trailing zero bits, so k·LN2_HI is exact.
    const LN2_HI: F = sp(f64::from_bits(0x3FE6_2E42_FEE0_0000));
    const LN2_LO: F = sp(f64::from_bits(0x3DEA_39EF_3579_3C76));
    // Round to nearest by the 1.5·2^52 trick: the low bits of `kk` then hold k.
    const MAGIC: F = sp(6_755_399_441_055_744.0);
    const ZMAX: F = sp(708.0);
    const C: [F; 12] = [
        sp(1.0 / 39_916_800.0),
        sp(1.0 / 3_628_800.0),
        sp(1.0 / 362_880.0),
        sp(1.0 / 40_320.0),
        sp(1.0 / 5_040.0),
        sp(1.0 / 720.0),
        sp(1.0 / 120.0),
        sp(1.0 / 24.0),
        sp(1.0 / 6.0),
        sp(0.5),
        sp(1.0),
        sp(1.0),
    ];
    const EXP_ONE: U = U::new([1023u64 << 52; LANES]);
    let z = z.fast_min(ZMAX);
    let kk = z * LOG2E + MAGIC;
    let kf = kk - MAGIC;
    let r = (kf * LN2_HI - z) + kf * LN2_LO;
    let mut p = C[0];
    for c in &C[1..] {
        p = p * r + *c;
    }
    // 2^−k: exponent field 1023 − k (k = low bits of kk, 0 ≤ k ≤ 1022).
    let bits: U = bytemuck::cast(kk);
    p * bytemuck::cast::<U, F>(EXP_ONE - (bits << 52u32))
}

/// Per-row constants of one triangle: at pixel x of the row,
/// `e_k = n_k.x·x + re_k` and `s_k = sd_k.x·x + rs_k`.
struct RowConsts {
    y: f64,
    re: [f64; 3],
    rs: [f64; 3],
}

/// Per-triangle lane constants: lane offsets l, `n_k.x·l`, `sd_k.x·l` and the edge
/// lengths.
struct LaneConsts {
    offs: F,
    ne: [F; 3],
    ns: [F; 3],
    len: [F; 3],
}

/// One chunk of `LANES` pixels of a tile row: multiplies the row's transmittance
/// lanes `row[base / LANES]` by `1 − D` for the lanes with `lo ≤ base + l ≤ hi`
/// (pixel x = `xbase + l`) and, with `REC`, pushes their records.
///
/// The squared distance to the boundary is the smallest squared distance to the
/// three edge segments, `e_k² + (|v_{k+1} − v_k|·excess_k)²` with
/// `excess_k = max(−s_k, s_k − 1, 0)` — for inside and outside pixels alike (inside,
/// the closest edge's foot lies on the segment, so this is `min_k e_k²`).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn chunk<const REC: bool>(
    tri: &TriSetup,
    rc: &RowConsts,
    lc: &LaneConsts,
    row: &mut [F],
    li0: usize,
    xbase: f64,
    lo: usize,
    hi: usize,
    base: usize,
    inv_sigma: f64,
    m2: f64,
    records: &mut Vec<Record>,
) {
    const ZERO: F = sp(0.0);
    const ONE: F = sp(1.0);
    const INF: F = sp(f64::INFINITY);
    const SAT: F = sp(SATURATION);
    let lane = lc.offs + sp(base as f64);
    let tcur = row[base / LANES];
    let live = lane.cmp_ge(sp(lo as f64)) & lane.cmp_le(sp(hi as f64)) & tcur.cmp_ge(SAT);
    let mut d2 = INF;
    let mut emin = INF;
    let mut best_k = ZERO;
    for k in 0..3 {
        let e = lc.ne[k] + sp(tri.n[k].x * xbase + rc.re[k]);
        let s = lc.ns[k] + sp(tri.sd[k].x * xbase + rc.rs[k]);
        let excess = (ZERO - s).fast_max(s - ONE).fast_max(ZERO) * lc.len[k];
        let sd = e * e + excess * excess;
        if REC {
            best_k = sd.cmp_lt(d2).blend(sp(k as f64), best_k);
        }
        d2 = d2.fast_min(sd);
        emin = emin.fast_min(e);
    }
    let inside = emin.cmp_gt(ZERO);
    let keep = live & (inside | d2.cmp_lt(sp(m2)));
    let mask = keep.move_mask();
    if mask == 0 {
        return;
    }
    let u = exp_neg_lanes(d2 * sp(inv_sigma));
    let inv = ONE / (ONE + u);
    let uinv = u * inv;
    // Inside: D = 1/(1 + u), 1 − D = u/(1 + u); outside the reverse.
    row[base / LANES] = tcur * keep.blend(inside.blend(uinv, inv), ONE);
    if !REC {
        return;
    }
    // ∂A/∂d² = δ·T·D/σ, and ∂d²/∂a = −2(1 − s)(p − q), ∂d²/∂b = −2s(p − q): the
    // record keeps c = −2δ·D/σ, to be multiplied by T once it is final.
    let coef = inside
        .blend(inv * sp(-2.0 * inv_sigma), uinv * sp(2.0 * inv_sigma))
        .to_array();
    let best_k = best_k.to_array();
    for l in 0..LANES {
        if mask & (1 << l) == 0 {
            continue;
        }
        let k = (best_k[l] as usize).min(2);
        let (n, dir) = (tri.n[k], tri.dir[k]);
        let (px, py) = (xbase + l as f64, rc.y);
        let e = n.x * px + n.y * py + tri.c[k];
        let s = tri.sd[k].x * px + tri.sd[k].y * py + tri.sc[k];
        let sc = s.clamp(0.0, 1.0);
        // p − q with q = v_k + sc·dir_k, from p − v_k = s·dir_k + e·n_k.
        let c = coef[l];
        let g = DVec2::new((dir.x * (s - sc) + n.x * e) * c, (dir.y * (s - sc) + n.y * e) * c);
        records.push(Record {
            px: (li0 + base + l) as u32,
            a: tri.idx[k],
            b: tri.next[k],
            ga: g * (1.0 - sc),
            gb: g * sc,
        });
    }
}

/// Runs the tile pass: writes every pixel's final transmittance into `trans`
/// (`width·height`, row-major) and calls `on_tile` for every tile that has
/// triangles; with `REC`, each tile's contributing pairs come with it.
#[inline(always)]
pub(crate) fn run<const REC: bool>(
    pass: &Pass,
    trans: &mut [f64],
    records: &mut Vec<Record>,
    mut on_tile: impl FnMut(&Tile),
) {
    let inv_sigma = 1.0 / pass.sigma;
    let m2 = pass.cutoff_sq;
    let m = m2.sqrt();
    let bins = pass.bins;
    trans.fill(1.0);
    let mut t = [1.0f64; TILE * TILE];
    // The tile's transmittance in lanes while it is rendered (`t` is its f64 copy).
    let mut tl = [sp(1.0); TILE * TILE / LANES];
    let offs = F::new(std::array::from_fn(|l| l as f64));
    for ty in 0..bins.tiles_y {
        for tx in 0..bins.tiles_x {
            let ti = ty * bins.tiles_x + tx;
            let list = &bins.items[bins.start[ti] as usize..bins.start[ti + 1] as usize];
            if list.is_empty() {
                continue;
            }
            let (x0, y0) = (tx * TILE, ty * TILE);
            let tw = TILE.min(pass.width - x0);
            let th = TILE.min(pass.height - y0);
            let (tx1, ty1) = ((x0 + tw - 1) as i32, (y0 + th - 1) as i32);
            tl.fill(sp(1.0));
            records.clear();
            for &k in list {
                let tri = &pass.tris[k as usize];
                let lc = LaneConsts {
                    offs,
                    ne: std::array::from_fn(|k| offs * sp(tri.n[k].x)),
                    ns: std::array::from_fn(|k| offs * sp(tri.sd[k].x)),
                    len: std::array::from_fn(|k| sp(tri.len[k])),
                };
                let xl = tri.x0.max(x0 as i32);
                let xh = tri.x1.min(tx1);
                for y in tri.y0.max(y0 as i32)..=tri.y1.min(ty1) {
                    let yf = y as f64;
                    let Some((xa, xb)) = tri.span(yf, m, xl, xh) else {
                        continue;
                    };
                    let rc = RowConsts {
                        y: yf,
                        re: std::array::from_fn(|k| tri.n[k].y * yf + tri.c[k]),
                        rs: std::array::from_fn(|k| tri.sd[k].y * yf + tri.sc[k]),
                    };
                    let li0 = (y as usize - y0) * TILE;
                    let row = &mut tl[li0 / LANES..(li0 + TILE) / LANES];
                    let (lo, hi) = (xa as usize - x0, xb as usize - x0);
                    let mut base = lo / LANES * LANES;
                    while base <= hi {
                        let xbase = (x0 + base) as f64;
                        chunk::<REC>(tri, &rc, &lc, row, li0, xbase, lo, hi, base, inv_sigma, m2, records);
                        base += LANES;
                    }
                }
            }
            for (i, v) in tl.iter().enumerate() {
                t[i * LANES..(i + 1) * LANES].copy_from_slice(&v.to_array());
            }
            for ly in 0..th {
                let o = (y0 + ly) * pass.width + x0;
                trans[o..o + tw].copy_from_slice(&t[ly * TILE..ly * TILE + tw]);
            }
            on_tile(&Tile {
                x0,
                y0,
                w: tw,
                h: th,
                t: &t,
                records,
            });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exp_neg_matches_std() {
        let mut worst = 0.0f64;
        for i in 0..(76000 / LANES) {
            let z: [f64; LANES] = std::array::from_fn(|o| (LANES * i + o) as f64 * 0.0093);
            let got = exp_neg_lanes(F::new(z)).to_array();
            for l in 0..LANES {
                if z[l] <= 708.0 {
                    worst = worst.max((got[l] / (-z[l]).exp() - 1.0).abs());
                }
            }
        }
        assert!(worst < 1e-14, "{worst}");
        assert_eq!(exp_neg_lanes(sp(0.0)).to_array(), [1.0; LANES]);
        for z in [800.0, f64::INFINITY, 708.0, 1e300] {
            assert!(exp_neg_lanes(sp(z)).to_array().iter().all(|&v| v < 1e-300));
        }
    }

    #[test]
    fn bins_hold_every_overlap_once() {
        let m = 1.5;
        let tris: Vec<TriSetup> = [
            [DVec2::new(1.0, 1.0), DVec2::new(30.0, 4.0), DVec2::new(9.0, 20.0)],
            [DVec2::new(-5.0, -5.0), DVec2::new(2.0, -4.0), DVec2::new(0.0, 3.0)],
        ]
        .iter()
        .filter_map(|v| TriSetup::new([0, 1, 2], *v, m, 1e-8, 21, 19))
        .collect();
        let mut b = Bins::default();
        b.build(&tris, 21, 19);
        assert_eq!((b.tiles_x, b.tiles_y), (21usize.div_ceil(TILE), 19usize.div_ceil(TILE)));
        // Triangle 0 spans x 0..=20 (clipped), y 0..=18: every tile; triangle 1: tile 0.
        assert_eq!(b.items.len(), b.tiles_x * b.tiles_y + 1);
        assert_eq!(&b.items[b.start[0] as usize..b.start[1] as usize], &[0, 1]);
    }
}
