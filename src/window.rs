//! [`Window`]: a rectangle of a view's image that a stage works in (SPEC §4: "every
//! stage works in an object window per view"), in continuous pixel coordinates (pixel
//! centres at integers, so pixel i spans [i − ½, i + ½]). Rendering it at a canvas of
//! n×m pixels is rendering with the camera whose intrinsics are shifted and scaled to
//! it ([`Window::camera`]); the canvas is never finer than the image's own pixels.
//! Object windows ([`Window::around_mask`]) are squares around the mask with a
//! margin; [`Window::full`] is the whole image.

use crate::camera::Camera;
use crate::mask::Mask;
use crate::view::{PixelBox, View};
use glam::DVec2;

/// A rectangle of an image, in continuous pixel coordinates (pixel centres at
/// integers): `[x0, x0 + width] × [y0, y0 + height]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Window {
    /// Left edge.
    pub x0: f64,
    /// Top edge.
    pub y0: f64,
    /// Width, image pixels.
    pub width: f64,
    /// Height, image pixels.
    pub height: f64,
}

/// How each view's window is chosen.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum WindowMode {
    /// The whole image: resolutions count across the image's longest side.
    Full,
    /// A square around the mask's bounding box, its side the box's longest side times
    /// `1 + 2·margin`: resolutions count across the object.
    Object {
        /// Margin on each side, as a fraction of the box's longest side.
        margin: f64,
    },
}

impl Window {
    /// The whole image of `camera`.
    pub fn full(camera: &Camera) -> Window {
        Window {
            x0: -0.5,
            y0: -0.5,
            width: camera.width as f64,
            height: camera.height as f64,
        }
    }

    /// A square around the object pixels of `mask` (inclusive bounds), its side the
    /// box's longest side times `1 + 2·margin` rounded up to whole pixels (at least 8),
    /// its edges on pixel edges (so that at full resolution its pixels are the image's);
    /// `None` for an empty mask.
    pub fn around_mask(mask: &Mask, margin: f64) -> Option<Window> {
        PixelBox::of_mask(mask).map(|b| Window::around_box(&b, margin))
    }

    /// A square around the pixels `box` covers, as [`Window::around_mask`] around a mask
    /// whose bounds they are.
    pub fn around_box(b: &PixelBox, margin: f64) -> Window {
        let c = b.centre();
        let side = (b.size().max_element() * (1.0 + 2.0 * margin.max(0.0))).ceil().max(8.0);
        Window {
            x0: (c.x - side * 0.5).round() - 0.5,
            y0: (c.y - side * 0.5).round() - 0.5,
            width: side,
            height: side,
        }
    }

    /// The window of `view` under `mode`.
    pub fn for_view(view: &View, mode: WindowMode) -> Window {
        match mode {
            WindowMode::Full => Window::full(view.camera()),
            WindowMode::Object { margin } => {
                Window::around_mask(view.mask(), margin).unwrap_or_else(|| Window::full(view.camera()))
            }
        }
    }

    /// The canvas size for `resolution` pixels across the window's longest side, never
    /// finer than the image (a window of 90 image pixels is at most 90 canvas pixels;
    /// at its own resolution its canvas pixels are its image pixels).
    pub fn canvas(&self, resolution: u32) -> (u32, u32) {
        let long = self.width.max(self.height);
        if resolution as f64 >= long.round() {
            return ((self.width.round() as u32).max(1), (self.height.round() as u32).max(1));
        }
        let k = resolution.max(1) as f64 / long;
        (
            ((self.width * k).round() as u32).max(1),
            ((self.height * k).round() as u32).max(1),
        )
    }

    /// The camera that renders this window onto a `width`×`height` canvas: focal
    /// lengths scaled, principal point shifted (pixel-centre convention).
    pub fn camera(&self, camera: &Camera, width: u32, height: u32) -> Camera {
        let kx = width as f64 / self.width;
        let ky = height as f64 / self.height;
        Camera {
            width,
            height,
            fx: camera.fx * kx,
            fy: camera.fy * ky,
            cx: (camera.cx - self.x0) * kx - 0.5,
            cy: (camera.cy - self.y0) * ky - 0.5,
            ..*camera
        }
    }

    /// Image pixel coordinates of canvas point `p` on a `width`×`height` canvas.
    pub fn to_image(&self, p: DVec2, width: u32, height: u32) -> DVec2 {
        DVec2::new(
            self.x0 + (p.x + 0.5) * self.width / width as f64,
            self.y0 + (p.y + 0.5) * self.height / height as f64,
        )
    }
}
