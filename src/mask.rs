//! Binary masks: which pixels of a view are the object (SPEC §2 mask rule), with
//! the figures the initialisation needs (area, centroid, extent).

use glam::DVec2;

/// A binary mask, row-major, row 0 at the top; `data[y * width + x]` is 0 or 1.
#[derive(Debug, Clone, PartialEq)]
pub struct Mask {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// One byte per pixel, 0 (background) or 1 (object).
    pub data: Vec<u8>,
}

impl Mask {
    /// An all-background mask.
    pub fn empty(width: u32, height: u32) -> Mask {
        Mask {
            width,
            height,
            data: vec![0; width as usize * height as usize],
        }
    }

    /// Value at (x, y).
    #[inline]
    pub fn get(&self, x: u32, y: u32) -> bool {
        self.data[y as usize * self.width as usize + x as usize] != 0
    }

    /// Number of object pixels.
    pub fn area(&self) -> usize {
        self.data.iter().filter(|&&v| v != 0).count()
    }

    /// Mean pixel coordinate of the object pixels (`None` when empty).
    pub fn centroid(&self) -> Option<DVec2> {
        let (mut sx, mut sy, mut n) = (0.0, 0.0, 0usize);
        for y in 0..self.height {
            for x in 0..self.width {
                if self.get(x, y) {
                    sx += x as f64;
                    sy += y as f64;
                    n += 1;
                }
            }
        }
        (n > 0).then(|| DVec2::new(sx / n as f64, sy / n as f64))
    }

    /// Inclusive pixel bounds (min x, min y, max x, max y) of the object (`None` when empty).
    pub fn bbox(&self) -> Option<(u32, u32, u32, u32)> {
        let mut b: Option<(u32, u32, u32, u32)> = None;
        for y in 0..self.height {
            for x in 0..self.width {
                if self.get(x, y) {
                    b = Some(match b {
                        None => (x, y, x, y),
                        Some((a, c, d, e)) => (a.min(x), c.min(y), d.max(x), e.max(y)),
                    });
                }
            }
        }
        b
    }

    /// Whether any object pixel lies on the image border.
    pub fn touches_border(&self) -> bool {
        match self.bbox() {
            None => false,
            Some((x0, y0, x1, y1)) => x0 == 0 || y0 == 0 || x1 + 1 == self.width || y1 + 1 == self.height,
        }
    }

    /// Downsamples by box filtering to `w`×`h` as coverage fractions in [0, 1].
    pub fn resample_coverage(&self, w: u32, h: u32) -> Vec<f32> {
        let mut out = vec![0f32; (w * h) as usize];
        let mut cnt = vec![0u32; (w * h) as usize];
        for y in 0..self.height {
            let ty = (y as u64 * h as u64 / self.height as u64) as u32;
            for x in 0..self.width {
                let tx = (x as u64 * w as u64 / self.width as u64) as u32;
                let i = (ty * w + tx) as usize;
                cnt[i] += 1;
                if self.get(x, y) {
                    out[i] += 1.0;
                }
            }
        }
        for (o, c) in out.iter_mut().zip(cnt) {
            if c > 0 {
                *o /= c as f32;
            } else {
                *o = 0.0;
            }
        }
        out
    }

    /// Downsamples to `w`×`h`, a pixel being object where at least half of it was.
    pub fn resample(&self, w: u32, h: u32) -> Mask {
        if w == self.width && h == self.height {
            return self.clone();
        }
        let cov = self.resample_coverage(w, h);
        Mask {
            width: w,
            height: h,
            data: cov.iter().map(|&c| (c >= 0.5) as u8).collect(),
        }
    }
}

#[cfg(test)]
impl Mask {
    /// The pixels (x, y) within `r` of (`cx`, `cy`), in a `w × h` mask (for tests).
    pub(crate) fn disc(w: u32, h: u32, cx: f64, cy: f64, r: f64) -> Mask {
        let mut m = Mask::empty(w, h);
        for y in 0..h {
            for x in 0..w {
                m.data[(y * w + x) as usize] = u8::from((x as f64 - cx).powi(2) + (y as f64 - cy).powi(2) <= r * r);
            }
        }
        m
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn figures_of_a_rectangle() {
        let mut m = Mask::empty(10, 8);
        for y in 2..4 {
            for x in 3..7 {
                m.data[y * 10 + x] = 1;
            }
        }
        assert_eq!(m.area(), 8);
        assert_eq!(m.centroid().unwrap(), DVec2::new(4.5, 2.5));
        assert_eq!(m.bbox(), Some((3, 2, 6, 3)));
        assert!(!m.touches_border());
        let r = m.resample(5, 4);
        // Rows 2-3 -> row 1; columns 3..7 -> 1 (half), 2 (full), 3 (half): half counts as object.
        assert_eq!(r.area(), 3, "{:?}", r.data);
    }
}
