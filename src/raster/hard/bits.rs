//! Binary masks as bitsets: 64 pixels per `u64` word, rows padded to whole words.
//!
//! The coarse orientation search scores hundreds of candidate poses by hard
//! silhouette IoU at low resolution (SPEC §4 "where the time goes"); with masks as
//! bitsets, intersection and union are word-wise AND/OR and a popcount.

use crate::mask::Mask;
use glam::DVec2;

/// A binary mask, row-major, row 0 at the top; pixel (x, y) is bit `x % 64` (least
/// significant first) of word `y · stride + x / 64`. Padding bits past `width` are 0.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct BitMask {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `height · stride()` words.
    pub words: Vec<u64>,
}

impl BitMask {
    /// An all-background mask.
    pub fn empty(width: u32, height: u32) -> BitMask {
        BitMask {
            width,
            height,
            words: vec![0; Self::stride_for(width) * height as usize],
        }
    }

    fn stride_for(width: u32) -> usize {
        (width as usize).div_ceil(64)
    }

    /// Words per row.
    #[inline]
    pub fn stride(&self) -> usize {
        Self::stride_for(self.width)
    }

    /// Resizes to `width`×`height` and clears every bit, reusing the allocation.
    pub fn reset(&mut self, width: u32, height: u32) {
        self.width = width;
        self.height = height;
        self.words.clear();
        self.words.resize(Self::stride_for(width) * height as usize, 0);
    }

    /// Value at (x, y).
    ///
    /// # Panics
    /// If (x, y) is outside the mask.
    #[inline]
    pub fn get(&self, x: u32, y: u32) -> bool {
        assert!(x < self.width && y < self.height, "pixel ({x}, {y}) outside the mask");
        self.words[y as usize * self.stride() + (x / 64) as usize] >> (x % 64) & 1 == 1
    }

    /// Sets the pixels `x0..=x1` of row `y` (caller keeps them inside the mask).
    #[inline]
    pub(crate) fn fill_span(&mut self, y: usize, x0: usize, x1: usize) {
        let base = y * self.stride();
        let row = &mut self.words[base..];
        let (w0, w1) = (x0 >> 6, x1 >> 6);
        let first = !0u64 << (x0 & 63);
        let last = !0u64 >> (63 - (x1 & 63));
        if w0 == w1 {
            row[w0] |= first & last;
        } else {
            row[w0] |= first;
            row[w0 + 1..w1].fill(!0);
            row[w1] |= last;
        }
    }

    /// Number of object pixels.
    pub fn count(&self) -> u64 {
        self.words.iter().map(|w| u64::from(w.count_ones())).sum()
    }

    /// The bitset form of a byte mask.
    pub fn from_mask(mask: &Mask) -> BitMask {
        let mut out = BitMask::empty(mask.width, mask.height);
        let (w, stride) = (mask.width as usize, out.stride());
        if w == 0 {
            return out;
        }
        for (y, row) in mask.data.chunks_exact(w).enumerate() {
            for (x, &v) in row.iter().enumerate() {
                if v != 0 {
                    out.words[y * stride + x / 64] |= 1 << (x % 64);
                }
            }
        }
        out
    }

    /// The byte-mask form.
    pub fn to_mask(&self) -> Mask {
        let mut m = Mask::empty(self.width, self.height);
        let (w, stride) = (self.width as usize, self.stride());
        for y in 0..self.height as usize {
            for x in 0..w {
                m.data[y * w + x] = (self.words[y * stride + x / 64] >> (x % 64) & 1) as u8;
            }
        }
        m
    }

    /// Number of set pixels and their centroid (0 and the origin when empty), by
    /// popcount per word and trailing-zero walks over the set bits.
    pub fn area_and_centroid(&self) -> (f64, DVec2) {
        let stride = self.stride();
        let (mut n, mut sx, mut sy) = (0u64, 0u64, 0u64);
        for (i, &w) in self.words.iter().enumerate() {
            if w == 0 {
                continue;
            }
            let (y, x0) = ((i / stride) as u64, 64 * (i % stride) as u64);
            let c = w.count_ones() as u64;
            n += c;
            sy += y * c;
            let mut bits = w;
            while bits != 0 {
                sx += x0 + bits.trailing_zeros() as u64;
                bits &= bits - 1;
            }
        }
        if n == 0 {
            return (0.0, DVec2::ZERO);
        }
        (n as f64, DVec2::new(sx as f64 / n as f64, sy as f64 / n as f64))
    }

    /// Number of pixels set in both masks.
    ///
    /// # Panics
    /// If the sizes differ.
    pub fn intersection_count(&self, other: &BitMask) -> u64 {
        self.assert_same_size(other);
        self.words
            .iter()
            .zip(&other.words)
            .map(|(a, b)| u64::from((a & b).count_ones()))
            .sum()
    }

    /// Intersection over union, |A ∩ B| / |A ∪ B|; 0 when both are empty.
    ///
    /// # Panics
    /// If the sizes differ.
    pub fn iou(&self, other: &BitMask) -> f64 {
        self.assert_same_size(other);
        let (mut inter, mut union) = (0u64, 0u64);
        for (a, b) in self.words.iter().zip(&other.words) {
            inter += u64::from((a & b).count_ones());
            union += u64::from((a | b).count_ones());
        }
        if union == 0 {
            0.0
        } else {
            inter as f64 / union as f64
        }
    }

    fn assert_same_size(&self, other: &BitMask) {
        assert!(
            self.width == other.width && self.height == other.height,
            "bit masks differ in size: {}×{} and {}×{}",
            self.width,
            self.height,
            other.width,
            other.height
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spans_round_trip_and_iou() {
        let mut a = BitMask::empty(130, 3);
        a.fill_span(1, 60, 129);
        a.fill_span(2, 3, 3);
        assert_eq!(a.count(), 71);
        assert!(a.get(63, 1) && a.get(64, 1) && a.get(129, 1) && !a.get(59, 1) && a.get(3, 2));
        let m = a.to_mask();
        assert_eq!(m.area(), 71);
        assert_eq!(BitMask::from_mask(&m), a);
        let mut b = BitMask::empty(130, 3);
        b.fill_span(1, 0, 69);
        // |A ∩ B| = 10 (60..=69), |A ∪ B| = 70 + 71 − 10.
        assert_eq!(a.intersection_count(&b), 10);
        assert!((a.iou(&b) - 10.0 / 131.0).abs() < 1e-15);
        assert_eq!(BitMask::empty(5, 5).iou(&BitMask::empty(5, 5)), 0.0);
        b.reset(7, 2);
        assert_eq!((b.words.len(), b.count()), (2, 0));
    }
}
