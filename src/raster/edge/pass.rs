//! The tile pass (module doc of `edge.rs`, steps 5–6): candidates binned into bands
//! of `TILE` rows by their m-expanded boxes; one band at a time, each candidate
//! visits, row by row, only the columns within m of its line,
//! keeping per pixel the nearest accepted candidate; then the band's soft values and
//! gradient records, in row-major order.

use super::candidates::{ceil_i64, floor_i64, Accept, EdgeSetup};
use super::{EdgeRecord, EdgeSilhouette};
use glam::DVec2;

/// Tile side in pixels (as the SoftRas kernel's).
pub(super) const TILE: usize = 16;

/// The best candidate of one pixel of a band.
#[derive(Debug, Clone, Copy)]
pub(super) struct Best {
    d2: f64,
    edge: u32,
}

const NONE: u32 = u32::MAX;

impl EdgeSilhouette {
    /// Bins the candidates into bands of `TILE` rows by their m-expanded boxes, and
    /// marks the tiles they reach.
    pub(super) fn bin(&mut self) {
        self.tiles_x = (self.width as usize).div_ceil(TILE);
        self.tiles_y = (self.height as usize).div_ceil(TILE);
        let (nb, tx) = (self.tiles_y, self.tiles_x);
        self.start.clear();
        self.start.resize(nb + 1, 0);
        self.reached.clear();
        self.reached.resize(nb * tx, false);
        for e in &self.edges {
            let (ty0, ty1) = (e.y0 as usize / TILE, e.y1 as usize / TILE);
            for ty in ty0..=ty1 {
                self.start[ty + 1] += 1;
                self.reached[ty * tx + e.x0 as usize / TILE..=ty * tx + e.x1 as usize / TILE].fill(true);
            }
        }
        for i in 0..nb {
            self.start[i + 1] += self.start[i];
        }
        self.cursor.clear();
        self.cursor.extend_from_slice(&self.start[..nb]);
        self.items.clear();
        self.items.resize(self.start[nb] as usize, 0);
        for (i, e) in self.edges.iter().enumerate() {
            for ty in e.y0 as usize / TILE..=e.y1 as usize / TILE {
                let c = &mut self.cursor[ty];
                self.items[*c as usize] = i as u32;
                *c += 1;
            }
        }
    }

    /// The tile pass, one band of `TILE` rows at a time: nearest accepted candidate per
    /// pixel of the band's tiles that candidates reach, then their soft values and
    /// records in row-major order.
    pub(super) fn tile_pass(&mut self) {
        let (w, h) = (self.width as usize, self.height as usize);
        let m2 = self.settings.cutoff_sq();
        let m = m2.sqrt();
        let inv_sigma = 1.0 / self.settings.sigma;
        let cov = &self.coverage.data;
        // Whether the pixel centre nearest to q + n_out is background or off the canvas.
        let accepted = |q: DVec2, out: DVec2| {
            let r = q + out;
            let (x, y) = (floor_i64(r.x + 0.5), floor_i64(r.y + 0.5));
            !((0..w as i64).contains(&x) && (0..h as i64).contains(&y)) || cov[y as usize * w + x as usize] == 0
        };
        let empty = Best { d2: m2, edge: NONE };
        self.band.resize(TILE * w, empty);
        for ty in 0..self.tiles_y {
            let row0 = ty * self.tiles_x;
            self.active.clear();
            self.active
                .extend((0..self.tiles_x).filter(|&tx| self.reached[row0 + tx]));
            if self.active.is_empty() {
                continue;
            }
            let y0 = ty * TILE;
            let th = TILE.min(h - y0);
            for ly in 0..th {
                for &tx in &self.active {
                    let x0 = tx * TILE;
                    self.band[ly * w + x0..ly * w + (x0 + TILE).min(w)].fill(empty);
                }
            }
            let ty1 = (y0 + th) as i32 - 1;
            for &k in &self.items[self.start[ty] as usize..self.start[ty + 1] as usize] {
                let e = &self.edges[k as usize];
                for y in e.y0.max(y0 as i32)..=e.y1.min(ty1) {
                    let yf = y as f64;
                    let Some((xa, xb)) = line_band_span(e, yf, m, e.x0, e.x1) else {
                        continue;
                    };
                    let row = &mut self.band[(y as usize - y0) * w..(y as usize - y0 + 1) * w];
                    let row = &mut row[xa as usize..=xb as usize];
                    if e.accept == Accept::Always {
                        for (x, best) in (xa..=xb).zip(row) {
                            let (_, _, d2) = e.eval(x as f64, yf);
                            // Branch-free: minsd and a conditional move.
                            let better = d2 < best.d2;
                            best.edge = if better { k } else { best.edge };
                            best.d2 = if better { d2 } else { best.d2 };
                        }
                    } else {
                        for (x, best) in (xa..=xb).zip(row) {
                            let (_, s, d2) = e.eval(x as f64, yf);
                            if d2 < best.d2 && accepted(e.point(s), e.out) {
                                *best = Best { d2, edge: k };
                            }
                        }
                    }
                }
            }
            for ly in 0..th {
                let y = y0 + ly;
                for &tx in &self.active {
                    for x in tx * TILE..(tx * TILE + TILE).min(w) {
                        let best = self.band[ly * w + x];
                        if best.edge == NONE {
                            continue;
                        }
                        let e = &self.edges[best.edge as usize];
                        let i = y * w + x;
                        let (el, s, d2) = e.eval(x as f64, y as f64);
                        let t = s.clamp(0.0, 1.0);
                        let u = (-d2 * inv_sigma).exp();
                        let inv = 1.0 / (1.0 + u);
                        let inside = cov[i] != 0;
                        self.alpha[i] = if inside { inv } else { u * inv };
                        // ∂A/∂d² = δ·A(1 − A)/σ = δ·u/((1 + u)²σ), ∂d²/∂q = −2(p − q), and
                        // p − q = (s − t)·(b − a) + e·n (p − a = s·(b − a) + e·n).
                        let da = if inside { 1.0 } else { -1.0 } * u * inv * inv * inv_sigma;
                        let g = (e.dir * (s - t) + e.n * el) * (-2.0 * da);
                        self.records.push(EdgeRecord {
                            px: i as u32,
                            a: e.ia,
                            b: e.ib,
                            ga: g * (1.0 - t),
                            gb: g * t,
                        });
                    }
                }
            }
        }
    }
}

/// Inclusive columns of row `y`, within `[lo0, hi0]`, whose centres lie within m (plus
/// a rounding slack) of the edge's line; `None` when empty. Every pixel within m of the
/// segment is inside.
#[inline(always)]
fn line_band_span(e: &EdgeSetup, y: f64, m: f64, lo0: i32, hi0: i32) -> Option<(i32, i32)> {
    const SLACK: f64 = 1e-7;
    let r = e.n.y * y + e.c;
    let (lo, hi) = if e.n.x.abs() > 1e-12 {
        let (u, v) = ((-m - r) * e.inv_nx, (m - r) * e.inv_nx);
        (u.min(v) - SLACK, u.max(v) + SLACK)
    } else if r.abs() <= m + SLACK {
        (lo0 as f64, hi0 as f64)
    } else {
        return None;
    };
    let lo = ceil_i64(lo.max(lo0 as f64));
    let hi = floor_i64(hi.min(hi0 as f64));
    (lo <= hi).then_some((lo as i32, hi as i32))
}
