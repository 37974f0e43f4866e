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
    let mask = view.mask();
    let (w, h) = (mask.width, mask.height);
    let mut img = match view.image() {
        Some(i) if (i.width, i.height) == (w, h) => {
            let mut i = i.clone();
            i.data.chunks_exact_mut(4).for_each(|p| p[3] = 255);
            i
        }
        _ => Rgba {
            width: w,
            height: h,
            data: mask
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
    draw_contour(&mut img, mask, style.mask_colour, width);
    if let Some(r) = rendered {
        if (r.width, r.height) == (w, h) {
            draw_contour(&mut img, r, style.render_colour, width);
        } else {
            draw_contour(&mut img, &stretch(r, w, h), style.render_colour, width);
        }
    }
    img
}

/// A view's object window as an overlay of `size`×`size` pixels (SPEC §4: in a real
/// photograph the object covers 50–150 px, so the page shows its window): the
/// window's part of the image (or mask), enlarged with nearest-pixel sampling (pixels
/// outside the image dark, ignored pixels dimmed), the mask's outline and — given
/// the mesh and pose — the contour of the mesh rendered *through the window camera at
/// `size`* (sharp, not an enlarged contour). `extra` draws more on the overlay with
/// the window camera (e.g. grasp rectangles).
pub fn overlay_window(
    view: &View,
    window: &crate::window::Window,
    size: u32,
    posed: Option<(&crate::mesh::Mesh, &crate::pose::Pose)>,
    style: &OverlayStyle,
) -> (Rgba, crate::camera::Camera) {
    let size = size.clamp(8, 2048);
    let mask = view.mask();
    let (iw, ih) = (mask.width as i64, mask.height as i64);
    let cam = window.camera(view.camera(), size, size);
    let k = size as f64 / window.width;
    let mut img = Rgba {
        width: size,
        height: size,
        data: vec![0; (size * size * 4) as usize],
    };
    let mut mask_win = Mask::empty(size, size);
    for y in 0..size {
        let sy = (window.y0 + (y as f64 + 0.5) / k + 0.5).floor() as i64;
        for x in 0..size {
            let sx = (window.x0 + (x as f64 + 0.5) / k + 0.5).floor() as i64;
            let o = ((y * size + x) * 4) as usize;
            if sx < 0 || sy < 0 || sx >= iw || sy >= ih {
                img.data[o..o + 4].copy_from_slice(&[12, 12, 16, 255]);
                continue;
            }
            let i = (sy * iw + sx) as usize;
            let mut px = match view.image() {
                Some(im) => [im.data[4 * i], im.data[4 * i + 1], im.data[4 * i + 2], 255],
                None => {
                    let g = if mask.data[i] != 0 {
                        NO_IMAGE_OBJECT
                    } else {
                        NO_IMAGE_BACKGROUND
                    };
                    [g, g, g, 255]
                }
            };
            if !view.is_known(i) {
                px = [px[0] / 3, px[1] / 3, px[2] / 3 + 40, 255];
            }
            img.data[o..o + 4].copy_from_slice(&px);
            mask_win.data[(y * size + x) as usize] = mask.data[i];
        }
    }
    let width = style.line_width.unwrap_or(if size >= 512 { 2 } else { 1 }).clamp(1, 2);
    draw_contour(&mut img, &mask_win, style.mask_colour, width);
    if let Some((mesh, pose)) = posed {
        let rendered = crate::raster::hard::render(mesh, pose, &cam);
        draw_contour(&mut img, &rendered, style.render_colour, width);
    }
    (img, cam)
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::Camera;

    fn rect(w: u32, h: u32, x0: u32, y0: u32, x1: u32, y1: u32) -> Mask {
        let mut m = Mask::empty(w, h);
        for y in y0..=y1 {
            for x in x0..=x1 {
                m.data[(y * w + x) as usize] = 1;
            }
        }
        m
    }

    fn view(mask: Mask, image: Option<Rgba>) -> View {
        let camera = Camera::look_at(
            glam::DVec3::Z,
            glam::DVec3::ZERO,
            glam::DVec3::Y,
            mask.width,
            mask.height,
            10.0,
        );
        View::new("v", camera, mask, None, image, &Default::default()).unwrap()
    }

    fn px(img: &Rgba, x: u32, y: u32) -> [u8; 4] {
        let i = ((y * img.width + x) * 4) as usize;
        img.data[i..i + 4].try_into().unwrap()
    }

    #[test]
    fn window_overlay_shows_the_object_large() {
        use crate::window::{Window, WindowMode};
        let mesh = crate::app::synth::blob_mesh(8, 12);
        let s = crate::app::synth::synthesize(
            &mesh,
            &crate::app::synth::SynthSettings {
                views: 1,
                width: 320,
                height: 240,
                fill: 0.2,
                ..Default::default()
            },
            None,
        )
        .unwrap();
        let v = &s.views()[0];
        let win = Window::for_view(v, WindowMode::Object { margin: 0.3 });
        let (img, cam) = overlay_window(v, &win, 200, Some((&mesh, &s.pose)), &OverlayStyle::default());
        assert_eq!((img.width, img.height, cam.width), (200, 200, 200));
        let is = |x: i64, y: i64, c: [u8; 4]| {
            x >= 0 && y >= 0 && x < 200 && y < 200 && img.data[((y * 200 + x) * 4) as usize..][..4] == c
        };
        // Magenta (the render's contour) pixels with green (the mask's outline) within 3 px.
        let near = |img_is: &dyn Fn(i64, i64, [u8; 4]) -> bool| {
            let (mut n, mut close) = (0, 0);
            for y in 0..200i64 {
                for x in 0..200i64 {
                    if img_is(x, y, [255, 0, 255, 255]) {
                        n += 1;
                        let g = (-3..=3).any(|dy| (-3..=3).any(|dx| img_is(x + dx, y + dy, [0, 255, 0, 255])));
                        close += usize::from(g);
                    }
                }
            }
            (n, close as f64 / n.max(1) as f64)
        };
        let (n, at_truth) = near(&is);
        assert!(
            n > 150 && at_truth > 0.8,
            "{n} contour pixels, {at_truth} near the outline"
        );
        // Off the truth by a tenth of the window: the contours part.
        let off = crate::pose::Pose {
            translation: s.pose.translation
                + cam.rotation.transpose()
                    * glam::DVec3::new(
                        0.1 * win.width * cam.to_camera(s.pose.translation).z / v.camera().fx,
                        0.0,
                        0.0,
                    ),
            ..s.pose
        };
        let (img2, _) = overlay_window(v, &win, 200, Some((&mesh, &off)), &OverlayStyle::default());
        let is2 = |x: i64, y: i64, c: [u8; 4]| {
            x >= 0 && y >= 0 && x < 200 && y < 200 && img2.data[((y * 200 + x) * 4) as usize..][..4] == c
        };
        let (_, off_truth) = near(&is2);
        assert!(off_truth < 0.5, "{off_truth}");
        // The object fills a good part of the window: grey object pixels.
        let grey = img
            .data
            .chunks_exact(4)
            .filter(|p| p[0] == NO_IMAGE_OBJECT && p[1] == NO_IMAGE_OBJECT)
            .count();
        assert!(grey > 200 * 200 / 5, "{grey}");
    }

    #[test]
    fn outline_pixels_are_exactly_the_mask_border() {
        let style = OverlayStyle::default();
        let v = view(rect(8, 7, 2, 1, 5, 4), None);
        let img = overlay(&v, None);
        for y in 0..7 {
            for x in 0..8 {
                let inside = (2..=5).contains(&x) && (1..=4).contains(&y);
                let border = inside && (x == 2 || x == 5 || y == 1 || y == 4);
                let want = if border {
                    style.mask_colour
                } else if inside {
                    [NO_IMAGE_OBJECT, NO_IMAGE_OBJECT, NO_IMAGE_OBJECT, 255]
                } else {
                    [NO_IMAGE_BACKGROUND, NO_IMAGE_BACKGROUND, NO_IMAGE_BACKGROUND, 255]
                };
                assert_eq!(px(&img, x, y), want, "pixel ({x}, {y})");
            }
        }
    }

    #[test]
    fn rendered_contour_surrounds_the_rendered_object_over_the_image() {
        let image = Rgba {
            width: 20,
            height: 16,
            data: [10, 20, 30, 0].repeat(20 * 16),
        };
        let v = view(rect(20, 16, 2, 2, 8, 8), Some(image));
        let rendered = rect(20, 16, 10, 6, 15, 12);
        let style = OverlayStyle::default();
        let img = overlay(&v, Some(&rendered));
        let has = |x, y, c| px(&img, x, y) == c;
        // The rendered box's corners and edges carry the render colour, its inside the image.
        for (x, y) in [(10, 6), (15, 12), (12, 6), (10, 9), (15, 8)] {
            assert!(has(x, y, style.render_colour), "({x}, {y})");
        }
        assert!(has(12, 9, [10, 20, 30, 255]), "the image shows through, opaque");
        assert!(has(2, 2, style.mask_colour) && has(8, 5, style.mask_colour));
        let n = img.data.chunks_exact(4).filter(|p| *p == style.render_colour).count();
        assert_eq!(n, 2 * 6 + 2 * 5, "the 6 × 7 box's ring has 22 pixels");
        // A low-resolution render is stretched onto the view.
        let small = rect(10, 8, 5, 3, 7, 6);
        let img2 = overlay(&v, Some(&small));
        assert!(px(&img2, 10, 6) == style.render_colour && px(&img2, 15, 13) == style.render_colour);
        // Wide images get 2-pixel lines: the ring outside the mask is painted too.
        let big = view(rect(600, 20, 100, 5, 200, 15), None);
        let img3 = overlay(&big, None);
        assert!(px(&img3, 100, 10) == style.mask_colour && px(&img3, 99, 10) == style.mask_colour);
        assert!(px(&img3, 98, 10) != style.mask_colour && px(&img3, 101, 10) != style.mask_colour);
    }

    #[test]
    fn polygons_are_closed_clipped_and_encode_to_png() {
        let mut img = Rgba {
            width: 12,
            height: 10,
            data: vec![0; 12 * 10 * 4],
        };
        let red = [255, 0, 0, 255];
        let square = [(2.0, 2.0), (8.0, 2.0), (8.0, 6.0), (2.0, 6.0)].map(|(x, y)| DVec2::new(x, y));
        draw_polygon(&mut img, &square, red);
        let lit: Vec<(u32, u32)> = (0..120)
            .filter(|&i| img.data[i * 4..i * 4 + 4] == red)
            .map(|i| (i as u32 % 12, i as u32 / 12))
            .collect();
        let want: Vec<(u32, u32)> = (2..=6)
            .flat_map(|y| (2..=8).map(move |x| (x, y)))
            .filter(|&(x, y)| x == 2 || x == 8 || y == 2 || y == 6)
            .collect();
        assert_eq!(lit, want);
        // A segment running far off the image, and a non-finite one, do not panic.
        draw_polygon(
            &mut img,
            &[DVec2::new(-1e9, 5.0), DVec2::new(1e9, 5.0), DVec2::NAN],
            red,
        );
        assert!((0..12).all(|x| img.data[((5 * 12 + x) * 4) as usize] == 255));
        let png = crate::io::png::encode_rgba(&img);
        let back = image::load_from_memory(&png).unwrap().to_rgba8();
        assert_eq!((back.width(), back.height()), (12, 10));
        assert_eq!(back.into_raw(), img.data);
    }
}
