//! Exact coverage of one triangle, row by row, in fixed point.
//!
//! Input: three vertices in pixel coordinates already snapped to 1/2^[`SUBPIXEL_BITS`]
//! px (`i64`, within the guard band of [`GUARD_BAND_PX`]); output: for every canvas
//! row the triangle touches, the inclusive run of pixel columns whose centres it
//! covers. The edge functions are integers, so the inside test is exact; a centre
//! exactly on an edge belongs to the triangle only if that edge is a top or left
//! edge (the Direct3D / OpenGL top-left rule). Each row's run is solved from the
//! three edge functions by exact integer division instead of testing every pixel
//! (narrow boxes, the common case at search resolutions, are tested pixel by pixel).

/// Fractional bits of the fixed-point vertex coordinates (vertices snap to 1/1024 px).
pub const SUBPIXEL_BITS: u32 = 10;

/// Vertices farther than this from the image origin (pixels, either axis) are
/// clipped away in the image plane before snapping, which keeps every edge
/// function within `i64` (|coordinate| ≤ 2^28 units, products ≤ 2^59).
pub const GUARD_BAND_PX: f64 = (1u64 << 18) as f64;

const ONE: i64 = 1 << SUBPIXEL_BITS;

/// Bounding boxes narrower than this many columns are tested pixel by pixel.
const NARROW: i64 = 8;

/// Snaps a pixel coordinate (|v| ≤ [`GUARD_BAND_PX`]) to fixed point:
/// `(v · 2^SUBPIXEL_BITS).round_ties_even()`.
#[inline]
pub fn snap(v: f64) -> i64 {
    // Adding and removing 1.5·2^52 rounds to the nearest integer, ties to even, for
    // |x| < 2^51 in two additions (`round_ties_even` is a library call on baseline x86-64).
    const MAGIC: f64 = 6755399441055744.0;
    ((v * ONE as f64 + MAGIC) - MAGIC) as i64
}

/// Smallest integer ≥ a / b, for a > 0 and b > 0.
#[inline]
fn ceil_div_pos(a: i64, b: i64) -> i64 {
    (a + b - 1) / b
}

/// Calls `span(y, x0, x1)` (inclusive columns) for every row of the `width`×`height`
/// canvas in which the triangle `v` (snapped, any winding) covers a pixel centre.
/// Degenerate (zero-area) triangles cover nothing.
#[inline]
pub fn triangle_spans(mut v: [[i64; 2]; 3], width: u32, height: u32, span: &mut impl FnMut(usize, usize, usize)) {
    let area = (v[1][0] - v[0][0]) * (v[2][1] - v[0][1]) - (v[1][1] - v[0][1]) * (v[2][0] - v[0][0]);
    if area == 0 {
        return;
    }
    if area < 0 {
        v.swap(1, 2);
    }
    // Pixel bounds: centres k·ONE inside [min, max], clamped to the canvas.
    let (mut min_x, mut max_x, mut min_y, mut max_y) = (v[0][0], v[0][0], v[0][1], v[0][1]);
    for p in &v[1..] {
        min_x = min_x.min(p[0]);
        max_x = max_x.max(p[0]);
        min_y = min_y.min(p[1]);
        max_y = max_y.max(p[1]);
    }
    let x_lo = (-((-min_x) >> SUBPIXEL_BITS)).max(0);
    let x_hi = (max_x >> SUBPIXEL_BITS).min(width as i64 - 1);
    let y_lo = (-((-min_y) >> SUBPIXEL_BITS)).max(0);
    let y_hi = (max_y >> SUBPIXEL_BITS).min(height as i64 - 1);
    if x_lo > x_hi || y_lo > y_hi {
        return;
    }
    // Edge i runs from v[i] to v[i+1]; with positive area the interior is where
    // E(p) = dx·(py − ay) − dy·(px − ax) > 0. The bias −1 on non-top-left edges
    // turns "E > 0, or E = 0 on a top-left edge" into "w ≥ 0".
    let (px, py) = (x_lo * ONE, y_lo * ONE);
    let mut w = [0i64; 3];
    let mut step_x = [0i64; 3];
    let mut step_y = [0i64; 3];
    for i in 0..3 {
        let a = v[i];
        let b = v[(i + 1) % 3];
        let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
        let top_left = dy < 0 || (dy == 0 && dx > 0);
        w[i] = dx * (py - a[1]) - dy * (px - a[0]) - i64::from(!top_left);
        step_x[i] = -dy * ONE;
        step_y[i] = dx * ONE;
    }
    let last = x_hi - x_lo;
    if last < NARROW {
        // Few columns (most triangles at search resolutions): test each pixel, the
        // sign bit of w0 | w1 | w2 telling whether any edge function is negative.
        for y in y_lo..=y_hi {
            let (mut lo, mut hi) = (i64::MAX, -1);
            let mut e = w;
            for k in 0..=last {
                if (e[0] | e[1] | e[2]) >= 0 {
                    lo = lo.min(k);
                    hi = k;
                }
                for i in 0..3 {
                    e[i] += step_x[i];
                }
            }
            if lo <= hi {
                span(y as usize, (x_lo + lo) as usize, (x_lo + hi) as usize);
            }
            for i in 0..3 {
                w[i] += step_y[i];
            }
        }
        return;
    }
    for y in y_lo..=y_hi {
        // Columns k = x − x_lo with w_i + step_x_i · k ≥ 0 for all three edges.
        let (mut lo, mut hi) = (0i64, last);
        for i in 0..3 {
            let (wi, s) = (w[i], step_x[i]);
            if s > 0 {
                if wi < 0 {
                    lo = lo.max(ceil_div_pos(-wi, s));
                }
            } else if s < 0 {
                if wi < 0 {
                    hi = -1;
                } else if wi + s * hi < 0 {
                    hi = hi.min(wi / -s);
                }
            } else if wi < 0 {
                hi = -1;
            }
        }
        if lo <= hi {
            span(y as usize, (x_lo + lo) as usize, (x_lo + hi) as usize);
        }
        for i in 0..3 {
            w[i] += step_y[i];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn covered(v: [[f64; 2]; 3], w: u32, h: u32) -> Vec<(usize, usize)> {
        let mut out = Vec::new();
        let v = v.map(|p| [snap(p[0]), snap(p[1])]);
        triangle_spans(v, w, h, &mut |y, x0, x1| out.extend((x0..=x1).map(|x| (x, y))));
        out
    }

    #[test]
    fn right_triangle_on_pixel_centres_follows_top_left_rule() {
        // Legs on x = 0 (left edge: included) and y = 0 (top edge: included); the
        // hypotenuse x + y = 4 is a bottom-right edge: centres on it are excluded.
        let got = covered([[0.0, 0.0], [4.0, 0.0], [0.0, 4.0]], 10, 10);
        let want: Vec<(usize, usize)> = (0..4).flat_map(|y| (0..4 - y).map(move |x| (x, y))).collect();
        assert_eq!(got, want);
        // The other winding covers the same centres.
        assert_eq!(covered([[0.0, 0.0], [0.0, 4.0], [4.0, 0.0]], 10, 10), want);
    }

    /// Per-pixel exact test in i128 (no spans, no increments, no bounding box).
    fn naive(v: [[i64; 2]; 3], w: u32, h: u32) -> Vec<(usize, usize)> {
        let v = v.map(|p| p.map(i128::from));
        let cross =
            |a: [i128; 2], b: [i128; 2], c: [i128; 2]| (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
        let area = cross(v[0], v[1], v[2]);
        let v = if area < 0 { [v[0], v[2], v[1]] } else { v };
        let mut out = Vec::new();
        for y in 0..h as i128 {
            for x in 0..w as i128 {
                let p = [x * ONE as i128, y * ONE as i128];
                let inside = area != 0
                    && (0..3).all(|i| {
                        let (a, b) = (v[i], v[(i + 1) % 3]);
                        let e = cross(a, b, p);
                        let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
                        e > 0 || (e == 0 && (dy < 0 || (dy == 0 && dx > 0)))
                    });
                if inside {
                    out.push((x as usize, y as usize));
                }
            }
        }
        out
    }

    #[test]
    fn spans_match_per_pixel_tests_up_to_the_guard_band() {
        // Small, medium and huge triangles (vertices up to the guard band), on a
        // lattice fine enough to hit ties and coarse enough to be random.
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = |range: f64| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            ((state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0) * range
        };
        let (w, h) = (37, 29);
        let mut total = 0;
        for trial in 0..3000 {
            let spread = [3.0, 20.0, GUARD_BAND_PX][trial % 3];
            let c = [18.0 + next(25.0), 14.0 + next(20.0)];
            let mut p = [[0.0; 2]; 3];
            for (k, q) in p.iter_mut().enumerate() {
                let s = if k == 0 { 3.0 } else { spread };
                *q = [c[0] + next(s), c[1] + next(s)].map(|x: f64| (x * 4.0).round() / 4.0);
            }
            let v = p.map(|q| {
                [
                    snap(q[0].clamp(-GUARD_BAND_PX, GUARD_BAND_PX)),
                    snap(q[1].clamp(-GUARD_BAND_PX, GUARD_BAND_PX)),
                ]
            });
            let mut got = Vec::new();
            triangle_spans(v, w, h, &mut |y, x0, x1| got.extend((x0..=x1).map(|x| (x, y))));
            let want = naive(v, w, h);
            assert_eq!(got, want, "triangle {v:?}");
            total += want.len();
        }
        assert!(
            total > 100_000,
            "only {total} covered pixels: the triangles missed the canvas"
        );
    }

    #[test]
    fn clamps_to_canvas_and_skips_degenerate() {
        let got = covered([[-5.5, -5.5], [100.0, -5.5], [-5.5, 100.0]], 3, 2);
        assert_eq!(got, vec![(0, 0), (1, 0), (2, 0), (0, 1), (1, 1), (2, 1)]);
        assert!(covered([[0.0, 0.0], [2.0, 2.0], [4.0, 4.0]], 10, 10).is_empty());
    }
}
