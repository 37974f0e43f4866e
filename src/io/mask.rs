//! PNG masks and PNG or JPEG images: any bit depth and channel count, decoded with
//! `image`, turned by their EXIF orientation (as a browser or a phone shows them).
//! Mask rule (SPEC §2): if the PNG has an alpha channel that is not fully opaque
//! everywhere, a pixel is object where alpha ≥ 128 (of 255); otherwise where luma ≥ 128.

use crate::error::{Error, Result};
use crate::mask::Mask;
use crate::view::Rgba;
use image::{metadata::Orientation, DynamicImage, ImageDecoder, ImageReader, Limits};
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

/// Whether an orientation turns the picture a quarter (its width and height swap).
fn swaps(o: Orientation) -> bool {
    matches!(
        o,
        Orientation::Rotate90 | Orientation::Rotate270 | Orientation::Rotate90FlipH | Orientation::Rotate270FlipH
    )
}

/// A file's header: its size as stored and its EXIF orientation (none when it has no
/// such tag or an unreadable one), read without decoding the pixels.
fn header(bytes: &[u8]) -> std::result::Result<((u32, u32), Orientation), String> {
    let mut d = reader(bytes)?
        .into_decoder()
        .map_err(|e| format!("cannot decode image: {e}"))?;
    let o = d.orientation().unwrap_or(Orientation::NoTransforms);
    Ok((d.dimensions(), o))
}

/// The width and height of a PNG or JPEG as it is shown — its EXIF orientation applied,
/// as a browser, a phone's gallery and OpenCV's `imread` show it — read from its header
/// without decoding the pixels.
pub fn dimensions(bytes: &[u8]) -> std::result::Result<(u32, u32), String> {
    let ((w, h), o) = header(bytes)?;
    Ok(if swaps(o) { (h, w) } else { (w, h) })
}

/// Decodes with limits, turning the picture by its EXIF orientation: `expected` (when
/// given) must be the size as shown, checked from the header before any pixel is
/// decoded, so a small file declaring a huge canvas is refused cheaply.
fn decode(bytes: &[u8], expected: Option<(u32, u32)>) -> std::result::Result<DynamicImage, Refusal> {
    let (stored, orientation) = header(bytes).map_err(Refusal::Decode)?;
    let got = if swaps(orientation) {
        (stored.1, stored.0)
    } else {
        stored
    };
    match expected {
        Some(want) if got != want && stored == want => return Err(Refusal::Turned { shown: got }),
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
    // The decoder sees the stored size, the caller's is the shown one.
    let side = expected.map_or(crate::camera::MAX_SIDE, |(w, h)| w.max(h));
    limits.max_image_width = Some(side);
    limits.max_image_height = Some(side);
    r.limits(limits);
    let failed = |e: image::ImageError| Refusal::Decode(format!("cannot decode image: {e}"));
    let decoder = r.into_decoder().map_err(failed)?;
    if decoder.total_bytes() > MAX_ALLOC {
        return Err(Refusal::Decode(format!(
            "its pixels would take {} bytes, more than the {MAX_ALLOC} allowed",
            decoder.total_bytes()
        )));
    }
    let mut img = DynamicImage::from_decoder(decoder).map_err(failed)?;
    img.apply_orientation(orientation);
    Ok(img)
}

enum Refusal {
    Decode(String),
    Size((u32, u32)),
    /// The stored size is the camera's, but the EXIF orientation turns the picture.
    Turned {
        shown: (u32, u32),
    },
}

/// What to say of a picture that its EXIF orientation turns off its camera's size.
fn turned(shown: (u32, u32), expected: Option<(u32, u32)>) -> String {
    let (w, h) = expected.unwrap_or_default();
    format!(
        "is {}×{} as its EXIF orientation turns it (as browsers and OpenCV show it), {w}×{h} as stored, \
         but the camera is {w}×{h}: give the camera of the picture as shown (its width and height swapped, \
         its intrinsics turned with it), or save the picture without its orientation tag",
        shown.0, shown.1
    )
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
        Refusal::Turned { shown } => Error::Mask {
            view: view.into(),
            file: file.into(),
            problem: turned(shown, expected),
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
        Refusal::Turned { shown } => Error::Image {
            view: view.into(),
            file: file.into(),
            problem: turned(shown, expected),
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

/// The JPEG writers the integration tests use, for this module's tests.
#[cfg(test)]
#[path = "../../tests/support/jpeg.rs"]
mod jpeg_support;

#[cfg(test)]
mod tests {
    use super::jpeg_support;
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

    /// A 32×16 picture, its left half red and its right half blue, as a JPEG (quality
    /// 95) with the EXIF orientation `value`, or none.
    fn jpeg(value: Option<u8>) -> Vec<u8> {
        let px: Vec<u8> = (0..16)
            .flat_map(|_| (0..32).flat_map(|x| if x < 16 { [230, 20, 20] } else { [20, 20, 230] }))
            .collect();
        jpeg_support::jpeg(&px, 32, 16, image::ExtendedColorType::Rgb8, 95, value)
    }

    /// Whether the pixel (x, y) is mostly red (or else mostly blue).
    fn red_at(img: &Rgba, x: u32, y: u32) -> bool {
        let i = 4 * (y * img.width + x) as usize;
        let p = &img.data[i..i + 3];
        assert!((p[0] > 180 && p[2] < 70) || (p[2] > 180 && p[0] < 70), "{p:?}");
        p[0] > p[2]
    }

    #[test]
    fn jpeg_photographs_decode_turned_by_their_exif_orientation() {
        // No orientation tag, or "1": as stored.
        for bytes in [jpeg(None), jpeg(Some(1))] {
            assert_eq!(dimensions(&bytes).unwrap(), (32, 16));
            let img = decode_image_sized(&bytes, "v", "a.jpg", 32, 16).unwrap();
            assert!(red_at(&img, 4, 8) && !red_at(&img, 28, 8));
        }
        // 6: turned a quarter clockwise, as a phone held upright writes it: the left
        // (red) half is now on top.
        let turned = jpeg(Some(6));
        assert_eq!(dimensions(&turned).unwrap(), (16, 32));
        let img = decode_image_sized(&turned, "v", "a.jpg", 16, 32).unwrap();
        assert_eq!((img.width, img.height), (16, 32));
        assert!(red_at(&img, 8, 4) && !red_at(&img, 8, 28));
        // 8: a quarter anticlockwise: the left half at the bottom.
        let img = decode_image(&jpeg(Some(8)), "v", "a.jpg").unwrap();
        assert!(!red_at(&img, 8, 4) && red_at(&img, 8, 28));
        // 3: half a turn: the left half on the right.
        let img = decode_image(&jpeg(Some(3)), "v", "a.jpg").unwrap();
        assert!(!red_at(&img, 4, 8) && red_at(&img, 28, 8));
        // A camera of the stored size: the orientation is named, not just the sizes.
        let e = decode_image_sized(&turned, "left", "a.jpg", 32, 16)
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("view 'left': image 'a.jpg': is 16×32 as its EXIF orientation turns it")
                && e.contains("32×16 as stored"),
            "{e}"
        );
        let e = decode_mask_sized(&turned, "left", "m.jpg", 32, 16)
            .unwrap_err()
            .to_string();
        assert!(e.contains("mask 'm.jpg'") && e.contains("EXIF orientation"), "{e}");
        // Any other size is the plain mismatch.
        let e = decode_image_sized(&turned, "left", "a.jpg", 30, 20).unwrap_err();
        assert!(matches!(e, Error::ImageSize { size: (16, 32), .. }), "{e}");
        // A PNG's eXIf orientation is honoured the same way.
        use image::ImageEncoder;
        let px: Vec<u8> = [[255u8; 3], [255; 3], [0; 3], [0; 3]].concat();
        let mut png = Vec::new();
        let mut enc = image::codecs::png::PngEncoder::new(&mut png);
        enc.set_exif_metadata(jpeg_support::exif_orientation(6)).unwrap();
        enc.write_image(&px, 2, 2, image::ExtendedColorType::Rgb8).unwrap();
        // Stored: top row white, bottom black; turned clockwise: the right column white.
        let img = decode_image(&png, "v", "m.png").unwrap();
        assert_eq!(img.data[0..8], [0, 0, 0, 255, 255, 255, 255, 255]);
        assert_eq!(decode_mask(&png, "v", "m.png").unwrap().data, vec![0, 1, 0, 1]);
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
