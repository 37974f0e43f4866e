//! A view: one calibrated photograph of the object — its camera, its binary mask, an
//! optional `ignore` mask (pixels that are unknown: occluders, the gripper, other
//! objects; SPEC §2) and, optionally, the image itself (for display only). A
//! [`PhotoView`] is a view whose mask is still to be made from its photograph, with a
//! [`PixelBox`] around the object when the user drew one.
//!
//! [`View::new`] is the one door: it checks that the mask, the ignore mask and the
//! image have the camera's size and that some object pixel is known, so every stage
//! after it trusts a view as it is. Fields are private.

use crate::camera::Camera;
use crate::error::{Error, Result};
use crate::mask::Mask;
use std::sync::Arc;

/// An RGBA8 image, row-major, row 0 at the top.
#[derive(Debug, Clone, PartialEq)]
pub struct Rgba {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// 4 bytes per pixel.
    pub data: Vec<u8>,
}

/// Where each of a view's inputs came from, for error messages (file names as the
/// scene wrote them, or a description such as `"RGBA pixels"`).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ViewSources {
    /// The mask's file.
    pub mask: String,
    /// The ignore mask's file, when there is one.
    pub ignore: String,
    /// The image's file, when there is one.
    pub image: String,
}

impl ViewSources {
    /// Sources with these file names (empty strings for absent files).
    pub fn files(mask: &str, ignore: &str, image: &str) -> ViewSources {
        ViewSources {
            mask: mask.into(),
            ignore: ignore.into(),
            image: image.into(),
        }
    }
}

/// One validated view of the object.
#[derive(Debug, Clone, PartialEq)]
pub struct View {
    name: String,
    camera: Camera,
    mask: Mask,
    ignore: Option<Mask>,
    /// Shared: a photograph's views of successive fits hold one copy.
    image: Option<Arc<Rgba>>,
    /// Object pixels of the mask that are not ignored.
    known_area: usize,
    /// The contour loss's distances capped at this multiple of the mask's equivalent
    /// radius (`None`: uncapped).
    contour_cap: Option<f64>,
    /// The mask's outline is refined by the photograph's colours (the region term).
    colour_refined: bool,
}

impl View {
    /// A view from its parts. `sources` names the files in errors.
    ///
    /// Errors: a mask, ignore mask or image whose size is not the camera's
    /// ([`Error::MaskSize`], [`Error::ImageSize`]); a mask with no object pixel outside
    /// the ignore mask ([`Error::EmptyMask`]).
    pub fn new(
        name: &str,
        camera: Camera,
        mask: Mask,
        ignore: Option<Mask>,
        image: Option<Rgba>,
        sources: &ViewSources,
    ) -> Result<View> {
        View::sharing(name, camera, mask, ignore, image.map(Arc::new), sources)
    }

    /// As [`View::new`], with a photograph shared with other views (a made mask's view
    /// in each round's fit: no copy of a phone's 48 MB per view and round).
    ///
    /// Errors: those of [`View::new`].
    pub fn sharing(
        name: &str,
        camera: Camera,
        mask: Mask,
        ignore: Option<Mask>,
        image: Option<Arc<Rgba>>,
        sources: &ViewSources,
    ) -> Result<View> {
        let expected = (camera.width, camera.height);
        let size_err = |file: &str, m: &Mask| Error::MaskSize {
            view: name.into(),
            file: file.into(),
            size: (m.width, m.height),
            expected,
        };
        if (mask.width, mask.height) != expected || mask.data.len() != mask.width as usize * mask.height as usize {
            return Err(size_err(&sources.mask, &mask));
        }
        if let Some(ig) = &ignore {
            if (ig.width, ig.height) != expected || ig.data.len() != mask.data.len() {
                return Err(size_err(&sources.ignore, ig));
            }
        }
        if let Some(img) = &image {
            if (img.width, img.height) != expected || img.data.len() != 4 * mask.data.len() {
                return Err(Error::ImageSize {
                    view: name.into(),
                    file: sources.image.clone(),
                    size: (img.width, img.height),
                    expected,
                });
            }
        }
        let known_area = match &ignore {
            None => mask.area(),
            Some(ig) => mask
                .data
                .iter()
                .zip(&ig.data)
                .filter(|(&m, &i)| m != 0 && i == 0)
                .count(),
        };
        if known_area == 0 {
            return Err(Error::EmptyMask {
                view: name.into(),
                file: sources.mask.clone(),
                ignored: ignore.is_some() && mask.area() > 0,
            });
        }
        Ok(View {
            name: name.into(),
            camera,
            mask,
            ignore,
            image,
            known_area,
            contour_cap: None,
            colour_refined: false,
        })
    }

    /// The view's name (unique within a scene).
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The camera (OpenCV axes).
    pub fn camera(&self) -> &Camera {
        &self.camera
    }

    /// The same view seen through other extrinsics (a corrected camera): the
    /// intrinsics, the size, the masks and the image stay.
    pub fn with_extrinsics(&self, rotation: glam::DMat3, translation: glam::DVec3) -> View {
        View {
            camera: Camera {
                rotation,
                translation,
                ..self.camera
            },
            ..self.clone()
        }
    }

    /// The object's mask, the camera's size.
    pub fn mask(&self) -> &Mask {
        &self.mask
    }

    /// The ignore mask (1 = unknown pixel), when given.
    pub fn ignore(&self) -> Option<&Mask> {
        self.ignore.as_ref()
    }

    /// The photograph, when given.
    pub fn image(&self) -> Option<&Rgba> {
        self.image.as_deref()
    }

    /// Object pixels of the mask that are not ignored (> 0).
    pub fn known_area(&self) -> usize {
        self.known_area
    }

    /// Whether pixel `i` (row-major) is known (not in the ignore mask).
    #[inline]
    pub fn is_known(&self, i: usize) -> bool {
        self.ignore.as_ref().is_none_or(|m| m.data[i] == 0)
    }

    /// The same view seen through another camera of the same size (a corrected
    /// calibration). Errors: a different image size.
    pub fn with_camera(&self, camera: Camera) -> Result<View> {
        if (camera.width, camera.height) != (self.camera.width, self.camera.height) {
            return Err(Error::Settings(format!(
                "view '{}': a replacement camera must keep the size {}×{}",
                self.name, self.camera.width, self.camera.height
            )));
        }
        Ok(View { camera, ..self.clone() })
    }

    /// The same view with the contour loss's distances capped at `k` times the mask's
    /// equivalent radius `√(|M|/π)` (`loss::contour`): for a mask that may miss a thin
    /// part of the object or fill a hole in it (a segmenter's), a render reaching far
    /// outside it costs in proportion to its area beyond `k·r`, not to its distance.
    /// `k` must be positive (a non-positive or non-finite `k` leaves it uncapped).
    pub fn with_contour_cap(mut self, k: f64) -> View {
        self.contour_cap = (k.is_finite() && k > 0.0).then_some(k);
        self
    }

    /// The contour loss's cap, a multiple of the mask's equivalent radius, when set
    /// ([`View::with_contour_cap`]).
    pub fn contour_cap(&self) -> Option<f64> {
        self.contour_cap
    }

    /// The same view with its mask's outline refined by its photograph's colours (the
    /// region term, `loss::region`, weighted by `FitSettings::lambda_region`): for a
    /// mask a segmenter made, which may stray from the object's edge by a few pixels.
    /// A view without a photograph is unchanged by it.
    pub fn with_colour_refinement(mut self) -> View {
        self.colour_refined = true;
        self
    }

    /// Whether the fit refines the mask's outline by the photograph's colours
    /// ([`View::with_colour_refinement`]; only with a photograph).
    pub fn colour_refined(&self) -> bool {
        self.colour_refined && self.image.is_some()
    }

    /// The same view without its image (to save memory where it is not shown).
    pub fn without_image(mut self) -> View {
        self.image = None;
        self
    }
}

/// A rough box around the object in an image, pixels: it covers the pixels with
/// `x0 ≤ x < x1`, `y0 ≤ y < y1` (SPEC §3), so in the continuous coordinates of pixel
/// centres at integers it spans `[x0 − ½, x1 − ½] × [y0 − ½, y1 − ½]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PixelBox {
    /// Left edge (first column covered).
    pub x0: f64,
    /// Top edge (first row covered).
    pub y0: f64,
    /// Right edge (one past the last column covered).
    pub x1: f64,
    /// Bottom edge (one past the last row covered).
    pub y1: f64,
}

impl PixelBox {
    /// A box from `[x_min, y_min, x_max, y_max]` in an image of `width × height`,
    /// validated: finite, not inverted, at least one pixel wide and high, and overlapping
    /// the image; a box that reaches past the image's edges is clipped to it (a box a
    /// person drags need not stop at the border). `view` names the view in errors.
    pub fn new(view: &str, b: [f64; 4], width: u32, height: u32) -> Result<PixelBox> {
        let bad = |problem: String| {
            Err(Error::View {
                view: view.into(),
                problem: format!("box {b:?}: {problem}"),
            })
        };
        if !b.iter().all(|v| v.is_finite()) {
            return bad("holds a number that is not finite".into());
        }
        if let Some(v) = b.iter().find(|v| v.abs() > crate::limits::MAX_BOX_PX) {
            return bad(format!(
                "{v:e} lies beyond any image (box coordinates are pixels, at most ±{:e})",
                crate::limits::MAX_BOX_PX
            ));
        }
        let [x0, y0, x1, y1] = b;
        if x1 <= x0 || y1 <= y0 {
            return bad(
                "is empty or inverted: expected [x_min, y_min, x_max, y_max] with x_min < x_max and y_min < y_max"
                    .into(),
            );
        }
        let (w, h) = (width as f64, height as f64);
        let c = PixelBox {
            x0: x0.max(0.0),
            y0: y0.max(0.0),
            x1: x1.min(w),
            y1: y1.min(h),
        };
        if c.x1 - c.x0 < 1.0 || c.y1 - c.y0 < 1.0 {
            return bad(format!(
                "covers less than one pixel of the {width}×{height} image (it must overlap the image)"
            ));
        }
        Ok(c)
    }

    /// The box's centre, in pixel-centre coordinates.
    pub fn centre(&self) -> glam::DVec2 {
        glam::DVec2::new(0.5 * (self.x0 + self.x1) - 0.5, 0.5 * (self.y0 + self.y1) - 0.5)
    }

    /// Width and height, pixels.
    pub fn size(&self) -> glam::DVec2 {
        glam::DVec2::new(self.x1 - self.x0, self.y1 - self.y0)
    }

    /// The box's wire form, `[x_min, y_min, x_max, y_max]`.
    pub fn to_array(&self) -> [f64; 4] {
        [self.x0, self.y0, self.x1, self.y1]
    }

    /// The tight box of a mask's object pixels, `None` for an empty mask.
    pub fn of_mask(mask: &Mask) -> Option<PixelBox> {
        mask.bbox().map(|(x0, y0, x1, y1)| PixelBox {
            x0: x0 as f64,
            y0: y0 as f64,
            x1: (x1 + 1) as f64,
            y1: (y1 + 1) as f64,
        })
    }
}

/// A view whose mask is to be made from its photograph: the camera, the image, an
/// optional ignore mask and the box around the object (`None`: the box comes from the
/// geometry of the other views).
#[derive(Debug, Clone, PartialEq)]
pub struct PhotoView {
    /// The view's name (unique within a scene).
    pub name: String,
    /// The camera (OpenCV axes).
    pub camera: Camera,
    /// The photograph, the camera's size (shared with the views of the rounds' fits).
    pub image: Arc<Rgba>,
    /// Unknown pixels, when given.
    pub ignore: Option<Mask>,
    /// The box around the object, when given.
    pub hint: Option<PixelBox>,
    /// Its position among the scene's views.
    pub index: usize,
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{DMat3, DVec3};

    #[test]
    fn boxes_are_validated_and_clipped() {
        let b = PixelBox::new("v", [-5.0, 10.0, 30.5, 900.0], 64, 48).unwrap();
        assert_eq!(b.to_array(), [0.0, 10.0, 30.5, 48.0]);
        assert_eq!(b.size(), glam::DVec2::new(30.5, 38.0));
        for (bad, says) in [
            ([10.0, 0.0, 5.0, 9.0], "inverted"),
            ([1.0, 1.0, 1.0, 9.0], "empty"),
            ([f64::NAN, 0.0, 5.0, 9.0], "not finite"),
            ([70.0, 0.0, 90.0, 9.0], "overlap the image"),
            ([0.0, -20.0, 9.0, -1.0], "overlap the image"),
        ] {
            let e = PixelBox::new("left", bad, 64, 48).unwrap_err().to_string();
            assert!(e.contains("view 'left'") && e.contains(says), "{e}");
        }
        let mut m = Mask::empty(10, 8);
        assert_eq!(PixelBox::of_mask(&m), None);
        m.data[3 * 10 + 2] = 1;
        m.data[5 * 10 + 6] = 1;
        let t = PixelBox::of_mask(&m).unwrap();
        assert_eq!(t.to_array(), [2.0, 3.0, 7.0, 6.0]);
        assert_eq!(t.centre(), glam::DVec2::new(4.0, 4.0));
    }

    fn camera(w: u32, h: u32) -> Camera {
        Camera::look_at(DVec3::new(0.0, 0.0, -2.0), DVec3::ZERO, DVec3::Y, w, h, 50.0)
    }

    fn square(w: u32, h: u32) -> Mask {
        let mut m = Mask::empty(w, h);
        m.data[(h / 2 * w + w / 2) as usize] = 1;
        m
    }

    #[test]
    fn sizes_and_emptiness_are_checked_with_their_files() {
        let src = ViewSources::files("m.png", "i.png", "rgb.png");
        let ok = View::new("v", camera(8, 6), square(8, 6), None, None, &src).unwrap();
        assert_eq!(ok.known_area(), 1);
        assert!(ok.is_known(0));
        let e = View::new("v", camera(8, 6), square(6, 8), None, None, &src).unwrap_err();
        assert!(
            matches!(&e, Error::MaskSize { file, size: (6, 8), expected: (8, 6), .. } if file == "m.png"),
            "{e}"
        );
        let e = View::new("v", camera(8, 6), square(8, 6), Some(Mask::empty(8, 5)), None, &src).unwrap_err();
        assert!(matches!(&e, Error::MaskSize { file, .. } if file == "i.png"), "{e}");
        let img = Rgba {
            width: 8,
            height: 5,
            data: vec![0; 160],
        };
        let e = View::new("v", camera(8, 6), square(8, 6), None, Some(img), &src).unwrap_err();
        assert!(matches!(&e, Error::ImageSize { file, .. } if file == "rgb.png"), "{e}");
        let e = View::new("v", camera(8, 6), Mask::empty(8, 6), None, None, &src).unwrap_err();
        assert!(matches!(e, Error::EmptyMask { ignored: false, .. }), "{e}");
        // Every object pixel ignored: nothing known to fit.
        let e = View::new("v", camera(8, 6), square(8, 6), Some(square(8, 6)), None, &src).unwrap_err();
        assert!(matches!(e, Error::EmptyMask { ignored: true, .. }), "{e}");
    }

    #[test]
    fn a_new_camera_keeps_the_size() {
        let v = View::new("v", camera(8, 6), square(8, 6), None, None, &ViewSources::default()).unwrap();
        let mut c = camera(8, 6);
        c.rotation = DMat3::from_rotation_y(0.1) * c.rotation;
        assert_eq!(v.with_camera(c).unwrap().camera().rotation, c.rotation);
        assert!(v.with_camera(camera(9, 6)).is_err());
    }
}
