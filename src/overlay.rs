//! Overlays: a view's image with the mask's outline and the rendered silhouette's
//! contour drawn over it (SPEC §4 step 5), and straight-line drawing for extra
//! polygons such as grasp rectangles.
//!
//! Input: a [`View`] (its image, or with none its mask shown grey on dark) and an
//! optional rendered [`Mask`]; output: an RGBA8 [`Rgba`] of the view's size, ready
//! for [`crate::io::png::encode_rgba`]. Contours are those of [`metrics::contour`]
//! (object pixels with a background 4-neighbour or on the border), thickened
//! outwards by one pixel on images whose longer side is 512 px or more.

use crate::mask::Mask;
use crate::metrics;
use crate::view::{Rgba, View};
use glam::DVec2;

/// Colours and line width of an overlay.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OverlayStyle {
    /// Colour of the mask's outline (default green).
    pub mask_colour: [u8; 4],
    /// Colour of the rendered silhouette's contour, drawn over the mask's (default magenta).
    pub render_colour: [u8; 4],
    /// Line width in pixels, 1 or 2; `None` (default) picks 1 below 512 px on the longer side, else 2.
    pub line_width: Option<u32>,
}

impl Default for OverlayStyle {
    fn default() -> Self {
        OverlayStyle {
            mask_colour: [0, 255, 0, 255],
            render_colour: [255, 0, 255, 255],
            line_width: None,
        }
    }
}

/// Grey levels of the background drawn when a view has no image.
const NO_IMAGE_OBJECT: u8 = 150;
const NO_IMAGE_BACKGROUND: u8 = 30;

/// The view's image (or its mask, grey on dark) with the mask's outline and, when
/// given, the rendered silhouette's contour, in the default [`OverlayStyle`].
pub fn overlay(view: &View, rendered: Option<&Mask>) -> Rgba {
    overlay_with(view, rendered, &OverlayStyle::default())
}

/// As [`overlay`] in the given style. A rendered mask of another size than the view
/// is stretched onto it (nearest pixel).
pub fn overlay_with(view: &View, rendered: Option<&Mask>, style: &OverlayStyle) -> Rgba {
    let (w, h) = (view.mask.width, view.mask.height);
    let mut img = match &view.image {
        Some(i) if (i.width, i.height) == (w, h) => {
            let mut i = i.clone();
            i.data.chunks_exact_mut(4).for_each(|p| p[3] = 255);
            i
        }
        _ => Rgba {
            width: w,
            height: h,
            data: view
                .mask
                .data
                .iter()
                .flat_map(|&v| {
                    let g = if v != 0 { NO_IMAGE_OBJECT } else { NO_IMAGE_BACKGROUND };
                    [g, g, g, 255]
                })
                .collect(),
        },
    };
    let width = style
        .line_width
        .unwrap_or(if w.max(h) >= 512 { 2 } else { 1 })
        .clamp(1, 2);
    draw_contour(&mut img, &view.mask, style.mask_colour, width);
    if let Some(r) = rendered {
        if (r.width, r.height) == (w, h) {
            draw_contour(&mut img, r, style.render_colour, width);
        } else {
            draw_contour(&mut img, &stretch(r, w, h), style.render_colour, width);
        }
    }
    img
}

/// Nearest-pixel resize of a mask to `w`×`h`.
fn stretch(m: &Mask, w: u32, h: u32) -> Mask {
    let mut out = Mask::empty(w, h);
    if m.width == 0 || m.height == 0 {
        return out;
    }
    for y in 0..h {
        let sy = (y as u64 * m.height as u64 / h as u64) as u32;
        for x in 0..w {
            let sx = (x as u64 * m.width as u64 / w as u64) as u32;
            out.data[(y * w + x) as usize] = m.get(sx, sy) as u8;
        }
    }
    out
}

#[inline]
fn put(img: &mut Rgba, x: i64, y: i64, c: [u8; 4]) {
    if x >= 0 && y >= 0 && x < img.width as i64 && y < img.height as i64 {
        let i = (y as usize * img.width as usize + x as usize) * 4;
        img.data[i..i + 4].copy_from_slice(&c);
    }
}

/// Paints the contour of `mask` (and, for width 2, its outer 4-neighbours) in `c`.
fn draw_contour(img: &mut Rgba, mask: &Mask, c: [u8; 4], width: u32) {
    let con = metrics::contour(mask);
    let w = mask.width as i64;
    for (i, &v) in con.data.iter().enumerate() {
        if v == 0 {
            continue;
        }
        let (x, y) = (i as i64 % w, i as i64 / w);
        put(img, x, y, c);
        if width >= 2 {
            for (dx, dy) in [(-1, 0), (1, 0), (0, -1), (0, 1)] {
                let (nx, ny) = (x + dx, y + dy);
                let inside = nx >= 0 && ny >= 0 && nx < w && ny < mask.height as i64;
                if inside && !mask.get(nx as u32, ny as u32) {
                    put(img, nx, ny, c);
                }
            }
        }
    }
}

/// Draws the closed polygon through `pts` (pixel coordinates, centres at integers)
/// in `colour`, 1 px wide (Bresenham), clipped to the image; segments with a
/// non-finite end are skipped.
pub fn draw_polygon(img: &mut Rgba, pts: &[DVec2], colour: [u8; 4]) {
    let n = pts.len();
    for k in 0..n {
        draw_line(img, pts[k], pts[(k + 1) % n], colour);
    }
}

/// Draws the segment from `a` to `b` (pixel coordinates), 1 px wide, clipped to the image.
pub fn draw_line(img: &mut Rgba, a: DVec2, b: DVec2, colour: [u8; 4]) {
    if !a.is_finite() || !b.is_finite() {
        return;
    }
    // Clip to a margin around the image so that far-away ends cost nothing.
    let lim = DVec2::new(img.width as f64 + 1.0, img.height as f64 + 1.0);
    let Some((a, b)) = clip_segment(a, b, DVec2::splat(-1.0), lim) else {
        return;
    };
    let (mut x, mut y) = (a.x.round() as i64, a.y.round() as i64);
    let (x1, y1) = (b.x.round() as i64, b.y.round() as i64);
    let (dx, dy) = ((x1 - x).abs(), -(y1 - y).abs());
    let (sx, sy) = (if x < x1 { 1 } else { -1 }, if y < y1 { 1 } else { -1 });
    let mut err = dx + dy;
    loop {
        put(img, x, y, colour);
        if x == x1 && y == y1 {
            break;
        }
        let e2 = 2 * err;
        if e2 >= dy {
            err += dy;
            x += sx;
        }
        if e2 <= dx {
            err += dx;
            y += sy;
        }
    }
}

/// Liang–Barsky clipping of the segment a–b to the box [lo, hi].
fn clip_segment(a: DVec2, b: DVec2, lo: DVec2, hi: DVec2) -> Option<(DVec2, DVec2)> {
    let d = b - a;
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for (p, q) in [
        (-d.x, a.x - lo.x),
        (d.x, hi.x - a.x),
        (-d.y, a.y - lo.y),
        (d.y, hi.y - a.y),
    ] {
        if p == 0.0 {
            if q < 0.0 {
                return None;
            }
        } else {
            let r = q / p;
            if p < 0.0 {
                t0 = t0.max(r);
            } else {
                t1 = t1.min(r);
            }
        }
    }
    (t0 <= t1).then(|| (a + d * t0, a + d * t1))
}
