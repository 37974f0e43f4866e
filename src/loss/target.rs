//! What a loss compares a render with: one view's mask seen through its
//! [`Window`](crate::Window) at a working resolution.
//!
//! A [`ViewTarget`] is the view at one stage: the window camera, the mask resampled
//! into the canvas (object where at least half of a canvas pixel's known image
//! pixels are), which canvas pixels are *known* (a pixel whose image pixels are
//! mostly outside the image or in the ignore mask is unknown and counts in no loss
//! term and no IoU), the mask's area and centroid, bit masks for the search, and the
//! contour loss's distance fields when asked for (with, for a view with a photograph,
//! the region term folded in when asked for).

use crate::camera::Camera;
use crate::error::Result;
use crate::loss::contour::ContourTarget;
use crate::loss::region;
use crate::mask::Mask;
use crate::raster::hard::BitMask;
use crate::view::View;
use crate::window::Window;
use glam::DVec2;

/// For each canvas column (or row) of a window side starting at `origin` (image
/// coordinates) with `k` canvas pixels per image pixel, the image pixels it overlaps
/// and the overlap lengths (in image pixels; out-of-image indices included as
/// negative or ≥ `n_image`, to be treated as unknown).
fn overlaps(origin: f64, k: f64, n_canvas: usize) -> Vec<Vec<(i64, f64)>> {
    (0..n_canvas)
        .map(|c| {
            let (a, b) = (origin + c as f64 / k, origin + (c + 1) as f64 / k);
            // Image pixel i spans [i − ½, i + ½].
            let (first, last) = ((a + 0.5).floor() as i64, (b + 0.5).ceil() as i64 - 1);
            (first..=last)
                .filter_map(|i| {
                    let o = (b.min(i as f64 + 0.5) - a.max(i as f64 - 0.5)).max(0.0);
                    (o > 1e-12).then_some((i, o))
                })
                .collect()
        })
        .collect()
}

/// The mask and known pixels of `view` resampled into `window` on a `w`×`h` canvas
/// by exact area weights: a canvas pixel is known when at least half of its area
/// lies on known image pixels (inside the image, not ignored), and object when at
/// least half of that known area is object. When the canvas has the window's own
/// resolution (an object window is aligned to the pixel grid) this is a plain copy.
fn resample(view: &View, window: &Window, w: u32, h: u32) -> (Vec<u8>, Vec<u8>) {
    let mask = view.mask();
    let (iw, ih) = (mask.width as i64, mask.height as i64);
    let (w, h) = (w as usize, h as usize);
    let kx = w as f64 / window.width;
    let ky = h as f64 / window.height;
    let cols = overlaps(window.x0, kx, w);
    let rows = overlaps(window.y0, ky, h);
    let area = 1.0 / (kx * ky);
    let mut mask_out = vec![0u8; w * h];
    let mut known_out = vec![0u8; w * h];
    for (r, row) in rows.iter().enumerate() {
        for (c, col) in cols.iter().enumerate() {
            let (mut known, mut object) = (0.0, 0.0);
            for &(y, wy) in row {
                if y < 0 || y >= ih {
                    continue;
                }
                for &(x, wx) in col {
                    if x < 0 || x >= iw {
                        continue;
                    }
                    let i = (y * iw + x) as usize;
                    if view.is_known(i) {
                        known += wx * wy;
                        if mask.data[i] != 0 {
                            object += wx * wy;
                        }
                    }
                }
            }
            let o = r * w + c;
            if known >= 0.5 * area - 1e-9 {
                known_out[o] = 1;
                mask_out[o] = u8::from(object > 0.0 && object >= 0.5 * known - 1e-9);
            }
        }
    }
    (mask_out, known_out)
}

/// One view prepared for a loss at one resolution (module doc).
#[derive(Debug, Clone)]
pub struct ViewTarget {
    /// The view's name.
    pub name: String,
    /// The window, in the view's image.
    pub window: Window,
    /// The camera rendering the window onto the canvas (its width × height is the canvas).
    pub camera: Camera,
    /// 1 where the canvas pixel is object (and known), row-major.
    pub mask: Vec<u8>,
    /// 1 where the canvas pixel is known; `None` when every pixel is.
    pub known: Option<Vec<u8>>,
    /// Known object pixels (may be 0 when the object vanishes at a coarse resolution).
    pub area: f64,
    /// Their centroid, canvas pixels.
    pub centroid: DVec2,
    /// The mask as bits.
    pub bits: BitMask,
    /// The known pixels as bits (`None`: all known).
    pub known_bits: Option<BitMask>,
    /// The contour loss's distance fields, when asked for and the mask is not empty.
    pub contour: Option<ContourTarget>,
    /// The view's cap on the contour loss's distances ([`crate::View::contour_cap`]).
    pub contour_cap: Option<f64>,
}

impl ViewTarget {
    /// Prepares `view` in `window` at `resolution` pixels across it; with `contour`,
    /// also the contour loss's distance fields.
    pub fn new(view: &View, window: Window, resolution: u32, contour: bool) -> Result<ViewTarget> {
        ViewTarget::with_region(view, window, resolution, contour, 0.0)
    }

    /// As [`ViewTarget::new`], with the region term (`crate::loss::region`) of the
    /// view's photograph folded into the contour term's weights with weight `region`
    /// relative to it, when `region` > 0, the contour term is asked for and the view
    /// asks for it ([`View::colour_refined`]).
    pub fn with_region(view: &View, window: Window, resolution: u32, contour: bool, region: f64) -> Result<ViewTarget> {
        let (w, h) = window.canvas(resolution);
        let camera = window.camera(view.camera(), w, h);
        let (mask, known) = resample(view, &window, w, h);
        let all_known = known.iter().all(|&k| k != 0);
        let to_mask = |data: &[u8]| Mask {
            width: w,
            height: h,
            data: data.to_vec(),
        };
        let bits = BitMask::from_mask(&to_mask(&mask));
        let known_bits = (!all_known).then(|| BitMask::from_mask(&to_mask(&known)));
        let (area, centroid) = bits.area_and_centroid();
        let known = (!all_known).then_some(known);
        let contour = if contour && area > 0.0 {
            let mut c = ContourTarget::from_parts(w, h, &mask, known.as_deref(), view.contour_cap(), view.name())?;
            if let Some(image) = view.image().filter(|_| region > 0.0 && view.colour_refined()) {
                let colours = region::canvas_colours(
                    image,
                    &overlaps(window.x0, w as f64 / window.width, w as usize),
                    &overlaps(window.y0, h as f64 / window.height, h as usize),
                );
                let term = region::weights(w as usize, h as usize, &colours, &mask, known.as_deref(), region::BAND);
                if let Some((weights, offset)) = term {
                    c.add_linear(&weights, offset, region);
                }
            }
            Some(c)
        } else {
            None
        };
        Ok(ViewTarget {
            name: view.name().to_string(),
            window,
            camera,
            mask,
            known,
            area,
            centroid,
            contour_cap: view.contour_cap(),
            bits,
            known_bits,
            contour,
        })
    }

    /// Canvas width and height.
    pub fn size(&self) -> (u32, u32) {
        (self.camera.width, self.camera.height)
    }

    /// Whether canvas pixel `i` is known.
    #[inline]
    pub fn is_known(&self, i: usize) -> bool {
        self.known.as_ref().is_none_or(|k| k[i] != 0)
    }

    /// Hard IoU of a rendered bit mask with the mask over the known pixels; 0 when
    /// both are empty there.
    pub fn hard_iou(&self, rendered: &BitMask) -> f64 {
        let (mut inter, mut union) = (0u64, 0u64);
        match &self.known_bits {
            None => {
                for (a, b) in rendered.words.iter().zip(&self.bits.words) {
                    inter += u64::from((a & b).count_ones());
                    union += u64::from((a | b).count_ones());
                }
            }
            Some(k) => {
                for ((a, b), k) in rendered.words.iter().zip(&self.bits.words).zip(&k.words) {
                    inter += u64::from((a & b).count_ones());
                    union += u64::from(((a | b) & k).count_ones());
                }
            }
        }
        if union == 0 {
            0.0
        } else {
            inter as f64 / union as f64
        }
    }

    /// Keeps only the known pixels of a rendered bit mask (in place).
    pub fn keep_known(&self, rendered: &mut BitMask) {
        if let Some(k) = &self.known_bits {
            for (a, k) in rendered.words.iter_mut().zip(&k.words) {
                *a &= k;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::view::ViewSources;
    use crate::window::WindowMode;
    use glam::DVec3;

    fn view_with(mask: Mask, ignore: Option<Mask>) -> View {
        let cam = Camera::look_at(
            DVec3::new(0.0, 0.0, -3.0),
            DVec3::ZERO,
            DVec3::Y,
            mask.width,
            mask.height,
            200.0,
        );
        View::new("v", cam, mask, ignore, None, &ViewSources::default()).unwrap()
    }

    fn rect(w: u32, h: u32, x0: u32, y0: u32, x1: u32, y1: u32) -> Mask {
        let mut m = Mask::empty(w, h);
        for y in y0..=y1 {
            for x in x0..=x1 {
                m.data[(y * w + x) as usize] = 1;
            }
        }
        m
    }

    #[test]
    fn full_window_camera_is_the_scaled_camera() {
        let v = view_with(rect(640, 480, 100, 100, 140, 150), None);
        let win = Window::full(v.camera());
        assert_eq!(win.canvas(128), (128, 96));
        assert_eq!(win.canvas(4000), (640, 480), "never finer than the image");
        let a = win.camera(v.camera(), 128, 96);
        let b = v.camera().scaled(128, 96);
        assert!((a.cx - b.cx).abs() < 1e-12 && (a.fy - b.fy).abs() < 1e-12);
    }

    #[test]
    fn object_window_maps_pixels_onto_the_canvas() {
        let v = view_with(rect(640, 480, 300, 200, 339, 229), None);
        let win = Window::for_view(&v, WindowMode::Object { margin: 0.25 });
        // A 40-px box: a 60-px square centred on it.
        assert!((win.width - 60.0).abs() < 1e-12 && (win.height - 60.0).abs() < 1e-12);
        assert_eq!(win.canvas(256), (60, 60), "never upsampled");
        assert_eq!(win.canvas(30), (30, 30));
        // A world point projects to the same image point through the window camera.
        let cam = win.camera(v.camera(), 30, 30);
        let p = DVec3::new(0.05, -0.03, 0.1);
        let full = v.camera().project(v.camera().to_camera(p));
        let canvas = cam.project(cam.to_camera(p));
        assert!((win.to_image(canvas, 30, 30) - full).length() < 1e-9);
        let t = ViewTarget::new(&v, win, 30, true).unwrap();
        // 40×30 image pixels at half resolution: 20×15 canvas pixels (a row more
        // where the box's edges fall mid-pixel: half-covered pixels count as object).
        assert!((t.area - 300.0).abs() <= 20.0, "{}", t.area);
        assert!(t.known.is_none() && t.contour.is_some());
        assert!((win.to_image(t.centroid, 30, 30) - DVec2::new(319.5, 214.5)).length() < 0.6);
    }

    #[test]
    fn pixels_outside_the_image_and_ignored_pixels_are_unknown() {
        // An object cut by the left border, and an ignore mask over part of it.
        let mask = rect(200, 100, 0, 40, 29, 69);
        let ignore = rect(200, 100, 20, 40, 29, 49);
        let v = view_with(mask, Some(ignore));
        let win = Window::for_view(&v, WindowMode::Object { margin: 0.5 });
        let t = ViewTarget::new(&v, win, 256, true).unwrap();
        let (w, h) = t.size();
        assert_eq!((w, h), (60, 60));
        let known = t.known.as_ref().unwrap();
        // The window starts 15 px left of the image: those columns are unknown.
        assert!((0..h as usize).all(|y| known[y * w as usize + 10] == 0));
        assert_eq!(known[30 * w as usize + 40], 1);
        // The ignored 10×10 block is unknown and not object.
        assert_eq!(t.area, 30.0 * 30.0 - 100.0);
        let mut full = BitMask::empty(w, h);
        for y in 0..h {
            full.fill_span(y as usize, 0, w as usize - 1);
        }
        // A render covering the whole canvas: IoU = object / known pixels.
        let n_known = known.iter().filter(|&&k| k != 0).count() as f64;
        assert!((t.hard_iou(&full) - t.area / n_known).abs() < 1e-12);
    }
}
