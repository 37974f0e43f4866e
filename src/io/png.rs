//! PNG encoding of RGBA and grey images (overlays, synthetic masks).

use crate::view::Rgba;
use image::ImageEncoder;

/// Encodes an RGBA8 image as PNG bytes.
pub fn encode_rgba(img: &Rgba) -> Vec<u8> {
    let mut out = Vec::new();
    image::codecs::png::PngEncoder::new(&mut out)
        .write_image(&img.data, img.width, img.height, image::ExtendedColorType::Rgba8)
        .expect("encoding a well-formed RGBA buffer into memory cannot fail");
    out
}

/// Encodes an 8-bit grey image as PNG bytes.
pub fn encode_gray(width: u32, height: u32, data: &[u8]) -> Vec<u8> {
    let mut out = Vec::new();
    image::codecs::png::PngEncoder::new(&mut out)
        .write_image(data, width, height, image::ExtendedColorType::L8)
        .expect("encoding a well-formed grey buffer into memory cannot fail");
    out
}
