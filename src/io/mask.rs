//! PNG masks and images: any bit depth and channel count, decoded with `image`.
//! Mask rule (SPEC §2): if the PNG has an alpha channel that is not fully opaque
//! everywhere, a pixel is object where alpha ≥ 128 (of 255); otherwise where luma ≥ 128.

use crate::error::{Error, Result};
use crate::mask::Mask;
use crate::view::Rgba;

fn decode(bytes: &[u8]) -> std::result::Result<image::DynamicImage, String> {
    image::load_from_memory(bytes).map_err(|e| format!("cannot decode image: {e}"))
}

/// Decodes a mask PNG and binarises it by the SPEC rule.
/// `view` and `file` name it in errors. Emptiness is checked by the scene loader.
pub fn decode_mask(bytes: &[u8], view: &str, file: &str) -> Result<Mask> {
    let err = |p: String| Error::Mask {
        view: view.into(),
        file: file.into(),
        problem: p,
    };
    let img = decode(bytes).map_err(err)?;
    let (w, h) = (img.width(), img.height());
    let data = if img.color().has_alpha() {
        let a = img.to_rgba16();
        let alpha: Vec<u16> = a.pixels().map(|p| p.0[3]).collect();
        if alpha.iter().any(|&v| v != u16::MAX) {
            alpha.iter().map(|&v| (v >= 128 * 257) as u8).collect()
        } else {
            luma(&img)
        }
    } else {
        luma(&img)
    };
    Ok(Mask {
        width: w,
        height: h,
        data,
    })
}

fn luma(img: &image::DynamicImage) -> Vec<u8> {
    // 16-bit luma keeps 16-bit masks exact; 128/255 of full scale is the threshold.
    img.to_luma16().pixels().map(|p| (p.0[0] >= 128 * 257) as u8).collect()
}

/// Decodes a photograph into RGBA8.
pub fn decode_image(bytes: &[u8], view: &str, file: &str) -> Result<Rgba> {
    let img = decode(bytes).map_err(|p| Error::Image {
        view: view.into(),
        file: file.into(),
        problem: p,
    })?;
    let rgba = img.to_rgba8();
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
