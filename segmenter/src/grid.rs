//! Where a crop sits in the encoder's 1024² input and how pixels and logits move
//! between the crop and that input: a crop resized and normalised into its region (the
//! whole input, or a 512² tile of a mosaic), the decoder's 256² logits brought back to
//! the crop (SAM's bilinear upscaling), and a previous mask's logits put back on the
//! input's grid as mask input.

use crate::{Result, SegmentError, INPUT, LOW_RES, MEAN, STD, TILE};

/// Where a crop sits in the encoder's 1024² input: the whole of it, or one of the
/// 512² tiles of a mosaic ([`crate::Sam::embed_tiles`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Region {
    pub(crate) x0: usize,
    pub(crate) y0: usize,
    pub(crate) size: usize,
}

impl Region {
    pub(crate) const FULL: Region = Region {
        x0: 0,
        y0: 0,
        size: INPUT,
    };

    /// Tile `k` (0–3) of the 2×2 mosaic, row by row.
    pub(crate) fn tile(k: usize) -> Region {
        Region {
            x0: TILE * (k % 2),
            y0: TILE * (k / 2),
            size: TILE,
        }
    }
}

/// Bilinear resampling with PyTorch's `align_corners=False` rule, `src` `sw × sh` to
/// `dw × dh`.
pub(crate) fn bilinear(src: &[f32], sw: usize, sh: usize, dw: usize, dh: usize) -> Vec<f32> {
    let index = |d: usize, out: usize, inp: usize| -> (usize, usize, f32) {
        let f = ((d as f32 + 0.5) * inp as f32 / out as f32 - 0.5).max(0.0);
        let i0 = (f.floor() as usize).min(inp - 1);
        (i0, (i0 + 1).min(inp - 1), f - i0 as f32)
    };
    let xs: Vec<_> = (0..dw).map(|x| index(x, dw, sw)).collect();
    let mut dst = vec![0f32; dw * dh];
    for y in 0..dh {
        let (y0, y1, fy) = index(y, dh, sh);
        for (x, &(x0, x1, fx)) in xs.iter().enumerate() {
            let a = src[y0 * sw + x0] * (1.0 - fx) + src[y0 * sw + x1] * fx;
            let b = src[y1 * sw + x0] * (1.0 - fx) + src[y1 * sw + x1] * fx;
            dst[y * dw + x] = a * (1.0 - fy) + b * fy;
        }
    }
    dst
}

/// SAM's postprocessing for a square input: the 256² logits to 1024², then the crop's
/// region of them to the crop's side.
pub(crate) fn upscale(low: &[f32], side: usize, r: Region) -> Vec<f32> {
    let big = bilinear(low, LOW_RES, LOW_RES, INPUT, INPUT);
    if r == Region::FULL {
        return bilinear(&big, INPUT, INPUT, side, side);
    }
    bilinear(&sub(&big, INPUT, r.x0, r.y0, r.size), r.size, r.size, side, side)
}

/// The `size²` block of a row-major square of side `n` at `(x0, y0)`.
pub(crate) fn sub(src: &[f32], n: usize, x0: usize, y0: usize, size: usize) -> Vec<f32> {
    (y0..y0 + size)
        .flat_map(|y| src[y * n + x0..y * n + x0 + size].iter().copied())
        .collect()
}

/// The grid scale between the input's pixels and the low-resolution logits.
pub(crate) const GRID: usize = INPUT / LOW_RES;

/// A crop's 256² logits placed on the decoder's input grid at the crop's region (the
/// rest of the mosaic: background).
pub(crate) fn to_input_grid(crop: &[f32], r: Region) -> Vec<f32> {
    if r == Region::FULL {
        return crop.to_vec();
    }
    let n = r.size / GRID;
    let small = bilinear(crop, LOW_RES, LOW_RES, n, n);
    let mut grid = vec![BACKGROUND_LOGIT; LOW_RES * LOW_RES];
    let (gx, gy) = (r.x0 / GRID, r.y0 / GRID);
    for y in 0..n {
        grid[(gy + y) * LOW_RES + gx..(gy + y) * LOW_RES + gx + n].copy_from_slice(&small[y * n..(y + 1) * n]);
    }
    grid
}

/// The decoder's 256² logits of a crop's region, as the crop's own 256² logits.
pub(crate) fn from_input_grid(low: &[f32], r: Region) -> Vec<f32> {
    if r == Region::FULL {
        return low.to_vec();
    }
    let n = r.size / GRID;
    let block = sub(low, LOW_RES, r.x0 / GRID, r.y0 / GRID, n);
    bilinear(&block, n, n, LOW_RES, LOW_RES)
}

/// The logit of a mask input outside the crop's tile: surely not the object.
pub(crate) const BACKGROUND_LOGIT: f32 = -20.0;

/// Resizes a square crop (RGB8 `side²`) into `region` of a normalised 1×3×1024² input.
pub(crate) fn place(data: &mut [f32], rgb: &[u8], side: u32, r: Region) -> Result<()> {
    if side == 0 || rgb.len() as u64 != side as u64 * side as u64 * 3 {
        return Err(SegmentError::Input(format!(
            "{} bytes for a {side}×{side} RGB crop",
            rgb.len()
        )));
    }
    let img = image::RgbImage::from_raw(side, side, rgb.to_vec())
        .ok_or_else(|| SegmentError::Input("bad crop buffer".into()))?;
    let resized = image::imageops::resize(
        &img,
        r.size as u32,
        r.size as u32,
        image::imageops::FilterType::Triangle,
    );
    let plane = INPUT * INPUT;
    for (x, y, p) in resized.enumerate_pixels() {
        let o = (r.y0 + y as usize) * INPUT + r.x0 + x as usize;
        for c in 0..3 {
            data[c * plane + o] = (p[c] as f32 - MEAN[c]) / STD[c];
        }
    }
    Ok(())
}
