//! A view: one calibrated photograph of the object — its camera, its binary mask
//! and, optionally, the image itself (for display only).

use crate::camera::Camera;
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

/// One view of the object.
#[derive(Debug, Clone, PartialEq)]
pub struct View {
    /// The view's name (unique within a scene).
    pub name: String,
    /// The validated camera (OpenCV axes).
    pub camera: Camera,
    /// The object's mask, the camera's size.
    pub mask: Mask,
    /// The photograph, the camera's size, when given.
    pub image: Option<Rgba>,
}
