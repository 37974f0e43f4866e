//! JPEGs as cameras and phones write them, for the tests of the photograph readers:
//! encoded by `image`, optionally with an EXIF block holding only an orientation tag.
//! Pure (no file system): the native tiers (`support`) and the wasm suite
//! (`tests/wasm_common`) include it by path.
#![allow(dead_code)]

use image::ImageEncoder;

/// An EXIF block (little-endian TIFF) holding only the orientation tag `value` (1–8 are
/// the valid ones; 6 is "turn a quarter clockwise to show", what a phone held upright
/// writes).
pub fn exif_orientation(value: u8) -> Vec<u8> {
    let mut t = b"II*\0".to_vec();
    t.extend_from_slice(&8u32.to_le_bytes());
    t.extend_from_slice(&1u16.to_le_bytes());
    // Tag 0x0112 (Orientation), type SHORT, one value, padded to four bytes; no next directory.
    t.extend_from_slice(&[0x12, 0x01, 3, 0, 1, 0, 0, 0, value, 0, 0, 0]);
    t.extend_from_slice(&0u32.to_le_bytes());
    t
}

/// `data` (`width`×`height`, `color`: `L8` or `Rgb8`) as a JPEG at `quality`, tagged
/// EXIF orientation `orientation` when given.
pub fn jpeg(
    data: &[u8],
    width: u32,
    height: u32,
    color: image::ExtendedColorType,
    quality: u8,
    orientation: Option<u8>,
) -> Vec<u8> {
    let mut out = Vec::new();
    let mut enc = image::codecs::jpeg::JpegEncoder::new_with_quality(&mut out, quality);
    if let Some(o) = orientation {
        enc.set_exif_metadata(exif_orientation(o)).unwrap();
    }
    enc.write_image(data, width, height, color).unwrap();
    out
}

/// The photograph `shown` as a phone held upright stores it: turned a quarter
/// anticlockwise, as a JPEG at `quality` tagged EXIF orientation 6, so that it is shown
/// as `shown` again.
pub fn sideways_jpeg(shown: &image::RgbImage, quality: u8) -> Vec<u8> {
    let stored = image::imageops::rotate270(shown);
    assert_eq!((stored.width(), stored.height()), (shown.height(), shown.width()));
    jpeg(
        stored.as_raw(),
        stored.width(),
        stored.height(),
        image::ExtendedColorType::Rgb8,
        quality,
        Some(6),
    )
}
