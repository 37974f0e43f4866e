//! PNG masks and images: any bit depth and channel count, decoded with `image`.
//! Mask rule (SPEC §2): if the PNG has an alpha channel that is not fully opaque
//! everywhere, a pixel is object where alpha ≥ 128 (of 255); otherwise where luma ≥ 128.

use crate::error::{Error, Result};
use crate::mask::Mask;
use crate::view::Rgba;
use image::{DynamicImage, ImageReader, Limits};
use std::io::Cursor;

/// Largest decoded buffer accepted for one mask or image (bytes): 16384² pixels of
/// RGBA16 would need 2 GiB; 1 GiB is more than any camera this crate accepts needs
/// for 8-bit data.
const MAX_ALLOC: u64 = 1 << 30;

fn reader(bytes: &[u8]) -> std::result::Result<ImageReader<Cursor<&[u8]>>, String> {
    ImageReader::new(Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| format!("cannot read image: {e}"))
}

/// The width and height a PNG (or other supported image) declares in its header,
/// read without decoding the pixels.
pub fn dimensions(bytes: &[u8]) -> std::result::Result<(u32, u32), String> {
    reader(bytes)?
        .into_dimensions()
        .map_err(|e| format!("cannot decode image: {e}"))
}

/// Decodes with limits: `expected` (when given) must be the declared size, checked
/// from the header before any pixel is decoded, so a small file declaring a huge
/// canvas is refused cheaply.
fn decode(bytes: &[u8], expected: Option<(u32, u32)>) -> std::result::Result<DynamicImage, Refusal> {
    let got = dimensions(bytes).map_err(Refusal::Decode)?;
    match expected {
        Some(want) if got != want => return Err(Refusal::Size(got)),
        // Without a camera's size (the importers), a canvas is held to the default
        // `view_pixels` limit, from the header (a 72-byte PNG may declare a gigabyte).
        None if got.0 as u64 * got.1 as u64 > crate::limits::Limits::DEFAULT.view_pixels => {
            return Err(Refusal::Decode(format!(
                "its header declares {}×{} pixels, more than the limit view_pixels of {}",
                got.0,
                got.1,
                crate::limits::Limits::DEFAULT.view_pixels
            )))
        }
        _ => {}
    }
    let mut r = reader(bytes).map_err(Refusal::Decode)?;
    let mut limits = Limits::default();
    limits.max_alloc = Some(MAX_ALLOC);
    if let Some((w, h)) = expected {
        limits.max_image_width = Some(w);
        limits.max_image_height = Some(h);
    } else {
        limits.max_image_width = Some(crate::camera::MAX_SIDE);
        limits.max_image_height = Some(crate::camera::MAX_SIDE);
    }
    r.limits(limits);
    r.decode()
        .map_err(|e| Refusal::Decode(format!("cannot decode image: {e}")))
}

enum Refusal {
    Decode(String),
    Size((u32, u32)),
}

/// Decodes a mask PNG and binarises it by the SPEC rule. `view` and `file` name it
/// in errors. Emptiness is checked by [`crate::View::new`].
pub fn decode_mask(bytes: &[u8], view: &str, file: &str) -> Result<Mask> {
    decode_mask_as(bytes, view, file, None)
}

/// As [`decode_mask`], for a camera of `width`×`height`: a PNG of another size is an
/// [`Error::MaskSize`], found from its header before it is decoded.
pub fn decode_mask_sized(bytes: &[u8], view: &str, file: &str, width: u32, height: u32) -> Result<Mask> {
    decode_mask_as(bytes, view, file, Some((width, height)))
}

fn decode_mask_as(bytes: &[u8], view: &str, file: &str, expected: Option<(u32, u32)>) -> Result<Mask> {
    let img = decode(bytes, expected).map_err(|r| match r {
        Refusal::Decode(problem) => Error::Mask {
            view: view.into(),
            file: file.into(),
            problem,
        },
        Refusal::Size(size) => Error::MaskSize {
            view: view.into(),
            file: file.into(),
            size,
            expected: expected.unwrap_or_default(),
        },
    })?;
    let (w, h) = (img.width(), img.height());
    let data = match &img {
        // 8-bit data is binarised as it is; wider data through 16 bits.
        DynamicImage::ImageLuma8(g) => g.as_raw().iter().map(|&v| (v >= 128) as u8).collect(),
        DynamicImage::ImageLumaA8(g) => {
            let raw = g.as_raw();
            if raw.chunks_exact(2).any(|p| p[1] != u8::MAX) {
                raw.chunks_exact(2).map(|p| (p[1] >= 128) as u8).collect()
            } else {
                raw.chunks_exact(2).map(|p| (p[0] >= 128) as u8).collect()
            }
        }
        DynamicImage::ImageRgba8(c) => {
            let raw = c.as_raw();
            if raw.chunks_exact(4).any(|p| p[3] != u8::MAX) {
                raw.chunks_exact(4).map(|p| (p[3] >= 128) as u8).collect()
            } else {
                luma(&img)
            }
        }
        _ if img.color().has_alpha() => {
            let a = img.to_rgba16();
            let alpha: Vec<u16> = a.pixels().map(|p| p.0[3]).collect();
            if alpha.iter().any(|&v| v != u16::MAX) {
                alpha.iter().map(|&v| (v >= 128 * 257) as u8).collect()
            } else {
                luma(&img)
            }
        }
        _ => luma(&img),
    };
    Ok(Mask {
        width: w,
        height: h,
        data,
    })
}

fn luma(img: &DynamicImage) -> Vec<u8> {
    // 16-bit luma keeps 16-bit masks exact; 128/255 of full scale is the threshold.
    img.to_luma16().pixels().map(|p| (p.0[0] >= 128 * 257) as u8).collect()
}

/// Decodes a photograph into RGBA8.
pub fn decode_image(bytes: &[u8], view: &str, file: &str) -> Result<Rgba> {
    decode_image_as(bytes, view, file, None)
}

/// As [`decode_image`], for a camera of `width`×`height` (an [`Error::ImageSize`]
/// otherwise, found from the header before decoding).
pub fn decode_image_sized(bytes: &[u8], view: &str, file: &str, width: u32, height: u32) -> Result<Rgba> {
    decode_image_as(bytes, view, file, Some((width, height)))
}

fn decode_image_as(bytes: &[u8], view: &str, file: &str, expected: Option<(u32, u32)>) -> Result<Rgba> {
    let img = decode(bytes, expected).map_err(|r| match r {
        Refusal::Decode(problem) => Error::Image {
            view: view.into(),
            file: file.into(),
            problem,
        },
        Refusal::Size(size) => Error::ImageSize {
            view: view.into(),
            file: file.into(),
            size,
            expected: expected.unwrap_or_default(),
        },
    })?;
    let rgba = img.into_rgba8();
    Ok(Rgba {
        width: rgba.width(),
        height: rgba.height(),
        data: rgba.into_raw(),
    })
}

/// The mask of an RGBA pixel buffer (e.g. from a browser canvas) by the same rule.
pub fn mask_from_rgba(img: &Rgba) -> Mask {
    let has_alpha = img.data.chunks_exact(4).any(|p| p[3] != 255);
    let data = img
        .data
        .chunks_exact(4)
        .map(|p| {
            if has_alpha {
                (p[3] >= 128) as u8
            } else {
                let l = 0.2126 * p[0] as f32 + 0.7152 * p[1] as f32 + 0.0722 * p[2] as f32;
                (l >= 127.5) as u8
            }
        })
        .collect();
    Mask {
        width: img.width,
        height: img.height,
        data,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::png::{encode_gray, encode_rgba};

    #[test]
    fn grey_and_alpha_rules() {
        let g = encode_gray(3, 1, &[0, 127, 128]);
        assert_eq!(decode_mask(&g, "v", "m.png").unwrap().data, vec![0, 0, 1]);
        // Alpha not fully opaque: alpha decides, colour is ignored.
        let rgba = Rgba {
            width: 2,
            height: 1,
            data: vec![0, 0, 0, 200, 255, 255, 255, 10],
        };
        assert_eq!(decode_mask(&encode_rgba(&rgba), "v", "m.png").unwrap().data, vec![1, 0]);
        // Fully opaque alpha: luma decides.
        let rgba = Rgba {
            width: 2,
            height: 1,
            data: vec![0, 0, 0, 255, 255, 255, 255, 255],
        };
        assert_eq!(decode_mask(&encode_rgba(&rgba), "v", "m.png").unwrap().data, vec![0, 1]);
        assert_eq!(mask_from_rgba(&rgba).data, vec![0, 1]);
    }

    #[test]
    fn sixteen_bit_masks() {
        let mut out = Vec::new();
        use image::ImageEncoder;
        let px: Vec<u8> = [0u16, 32767, 40000].iter().flat_map(|v| v.to_ne_bytes()).collect();
        image::codecs::png::PngEncoder::new(&mut out)
            .write_image(&px, 3, 1, image::ExtendedColorType::L16)
            .unwrap();
        assert_eq!(decode_mask(&out, "v", "m.png").unwrap().data, vec![0, 0, 1]);
    }

    /// A PNG that declares `w`×`h` 8-bit grey pixels but holds no pixel data (a
    /// "decompression bomb" in miniature).
    fn png_header_only(w: u32, h: u32) -> Vec<u8> {
        fn crc32(data: &[u8]) -> u32 {
            let mut c = !0u32;
            for &b in data {
                c ^= b as u32;
                for _ in 0..8 {
                    c = if c & 1 != 0 { 0xEDB8_8320 ^ (c >> 1) } else { c >> 1 };
                }
            }
            !c
        }
        let mut out = vec![0x89, b'P', b'N', b'G', 0x0D, 0x0A, 0x1A, 0x0A];
        let mut chunk = |kind: &[u8; 4], body: &[u8]| {
            out.extend_from_slice(&(body.len() as u32).to_be_bytes());
            let mut data = kind.to_vec();
            data.extend_from_slice(body);
            out.extend_from_slice(&data);
            out.extend_from_slice(&crc32(&data).to_be_bytes());
        };
        let mut ihdr = Vec::new();
        ihdr.extend_from_slice(&w.to_be_bytes());
        ihdr.extend_from_slice(&h.to_be_bytes());
        ihdr.extend_from_slice(&[8, 0, 0, 0, 0]);
        chunk(b"IHDR", &ihdr);
        // An empty zlib stream: the header is readable, the pixels are not there.
        chunk(b"IDAT", &[0x78, 0x9c, 0x03, 0x00, 0x00, 0x00, 0x00, 0x01]);
        chunk(b"IEND", &[]);
        out
    }

    #[test]
    fn a_tiny_file_declaring_a_huge_canvas_is_refused_before_decoding() {
        let bomb = png_header_only(60_000, 60_000);
        assert!(bomb.len() < 100);
        assert_eq!(dimensions(&bomb).unwrap(), (60_000, 60_000));
        let e = decode_mask_sized(&bomb, "v", "m.png", 640, 480).unwrap_err();
        assert!(
            matches!(
                e,
                Error::MaskSize {
                    size: (60_000, 60_000),
                    expected: (640, 480),
                    ..
                }
            ),
            "{e}"
        );
        let e = decode_image_sized(&bomb, "v", "i.png", 640, 480).unwrap_err();
        assert!(matches!(e, Error::ImageSize { .. }), "{e}");
        // Without a camera to compare with, the side limit refuses it.
        let e = decode_mask(&bomb, "v", "m.png").unwrap_err().to_string();
        assert!(e.contains("'m.png'"), "{e}");
        // Within the side limit but over view_pixels (16384² RGBA would be 1 GiB; a
        // fuzz target found it decoded): refused from the header, naming the limit.
        let wide = png_header_only(16_384, 16_384);
        for e in [
            decode_image(&wide, "v", "i.png").unwrap_err().to_string(),
            decode_mask(&wide, "v", "m.png").unwrap_err().to_string(),
        ] {
            assert!(e.contains("16384×16384") && e.contains("view_pixels"), "{e}");
        }
        // The right size decodes.
        let ok = encode_gray(3, 2, &[0, 255, 0, 255, 0, 0]);
        assert_eq!(decode_mask_sized(&ok, "v", "m.png", 3, 2).unwrap().area(), 2);
    }

    #[test]
    fn garbage_names_view_and_file() {
        let e = decode_mask(b"not a png", "left", "masks/left.png")
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("view 'left': mask 'masks/left.png': cannot decode"),
            "{e}"
        );
    }
}
