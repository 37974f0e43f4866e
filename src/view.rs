//! A view: one calibrated photograph of the object — its camera, its binary mask, an
//! optional `ignore` mask (pixels that are unknown: occluders, the gripper, other
//! objects; SPEC §2) and, optionally, the image itself (for display only).
//!
//! [`View::new`] is the one door: it checks that the mask, the ignore mask and the
//! image have the camera's size and that some object pixel is known, so every stage
//! after it trusts a view as it is. Fields are private.

use crate::camera::Camera;
use crate::error::{Error, Result};
use crate::mask::Mask;

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
    image: Option<Rgba>,
    /// Object pixels of the mask that are not ignored.
    known_area: usize,
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
        self.image.as_ref()
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

    /// The same view without its image (to save memory where it is not shown).
    pub fn without_image(mut self) -> View {
        self.image = None;
        self
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{DMat3, DVec3};

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
