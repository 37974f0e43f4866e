//! Contour loss — a two-sided, chamfer-type mean distance between the soft
//! silhouette A and the mask M's contour (SPEC §4 "Losses": the paper's Hausdorff
//! term, made differentiable as a distance-weighted mean rather than a maximum).
//!
//! With `DT_out(p)` the distance (px, pixel centres) from p to the nearest mask pixel
//! (0 on the mask) and `DT_in(p)` the distance from p to the nearest background pixel
//! (0 off the mask), both shifted to distances from the contour, which lies half a
//! pixel from the boundary pixels' centres — `d_out = max(DT_out − ½, 0)`,
//! `d_in = max(DT_in − ½, 0)` — the loss is
//!
//! `L = [Σ_p A_p·d_out(p) + Σ_p (1 − A_p)·d_in(p)] / N`,  `N = |M|·r`,  `r = √(|M|/π)`:
//!
//! rendered mass outside the mask weighted by its distance to the mask, plus missed
//! mask pixels weighted by their depth inside it. L ≥ 0; it vanishes (up to the soft
//! fringe, O(1/r²)) when the render matches the mask; it is linear in A, so
//! `∂L/∂A_p = (d_out(p) − d_in(p))/N`, a signed distance to the contour. The
//! normaliser makes L dimensionless and independent of resolution and object size:
//! for a disc of radius r shifted by δ pixels, L ≈ ½(δ/r)². Unlike the IoU it keeps
//! growing (and keeps a gradient) when the render and the mask are disjoint — but,
//! like any mask-based term, not for a render entirely off the canvas.
//! Distances are exact (`crate::loss::edt`) and capped at the image's width + height —
//! or, for a view that asks ([`crate::View::with_contour_cap`]: a segmenter's mask, which
//! may miss a thin part of the object or fill a hole in it), at `k·r`: a render reaching
//! beyond costs in proportion to its area there, as in the IoU, not to its distance.
//!
//! Unknown pixels (outside the image, or in the view's ignore mask) count in no sum:
//! they are left out of L and of |M|, `d_out` measures the distance to the nearest
//! mask *or unknown* pixel (the object may be hidden there) and `d_in` the distance
//! to the nearest *known* background pixel.

use crate::error::{Error, Result};
use crate::loss::edt;
use crate::mask::Mask;

/// A mask's precomputed contour distances at one resolution.
#[derive(Debug, Clone, PartialEq)]
pub struct ContourTarget {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `(d_out − d_in)/N` per pixel: ∂L/∂A (row-major).
    weight: Vec<f64>,
    /// `Σ d_in / N`: the loss of an empty render.
    offset: f64,
    /// The normaliser N = |M|·√(|M|/π), px³.
    norm: f64,
}

impl ContourTarget {
    /// Precomputes the distance transforms of `mask`; `view` names it in errors.
    /// Errors: an empty mask (the loss would have no scale).
    pub fn new(mask: &Mask, view: &str) -> Result<ContourTarget> {
        ContourTarget::from_parts(mask.width, mask.height, &mask.data, None, None, view)
    }

    /// As [`ContourTarget::new`] for a `width`×`height` mask given as 0/1 bytes, with
    /// `known` (1 = known) marking the pixels that count (all when `None`) and the
    /// distances capped at `cap·r` when `cap` is given (module doc).
    pub fn from_parts(
        width: u32,
        height: u32,
        mask: &[u8],
        known: Option<&[u8]>,
        cap: Option<f64>,
        view: &str,
    ) -> Result<ContourTarget> {
        let (w, h) = (width as usize, height as usize);
        let is_known = |i: usize| known.is_none_or(|k| k[i] != 0);
        let area = (0..w * h).filter(|&i| mask[i] != 0 && is_known(i)).count();
        if area == 0 {
            return Err(Error::View {
                view: view.into(),
                problem: format!("the {w}×{h} mask is empty: the contour loss needs an object"),
            });
        }
        // Where the object may be (mask or unknown), and known background.
        let maybe_object: Vec<bool> = (0..w * h).map(|i| mask[i] != 0 || !is_known(i)).collect();
        let background: Vec<bool> = (0..w * h).map(|i| mask[i] == 0 && is_known(i)).collect();
        let dt_out = edt::distance(w, h, &maybe_object);
        let dt_in = edt::distance(w, h, &background);
        let r = (area as f64 / std::f64::consts::PI).sqrt();
        let norm = area as f64 * r;
        let cap = cap.map_or((w + h) as f64, |k| (k * r).min((w + h) as f64));
        let shift = |d: f64| (d.min(cap) - 0.5).max(0.0);
        let mut offset = 0.0;
        let weight = (0..w * h)
            .map(|i| {
                if !is_known(i) {
                    return 0.0;
                }
                let (o, n) = (shift(dt_out[i]), shift(dt_in[i]));
                offset += n;
                (o - n) / norm
            })
            .collect();
        Ok(ContourTarget {
            width,
            height,
            weight,
            offset: offset / norm,
            norm,
        })
    }

    /// The per-pixel loss `ℓ_p = [A_p·d_out + (1 − A_p)·d_in]/N` of pixel `i` (its
    /// share of [`ContourTarget::loss`]); with `w = ∂ℓ/∂A = (d_out − d_in)/N`, the
    /// distances follow from w's sign: `d_out = max(w, 0)·N`, `d_in = max(−w, 0)·N`.
    #[inline]
    pub fn pixel_loss(&self, i: usize, a: f64) -> f64 {
        let w = self.weight[i];
        if w >= 0.0 {
            a * w
        } else {
            (a - 1.0) * w
        }
    }

    /// `∂L/∂A` per pixel: the signed distance to the contour (positive outside the
    /// mask) divided by N.
    pub fn gradient(&self) -> &[f64] {
        &self.weight
    }

    /// The signed distance of pixel `i` to the mask's contour, pixels: positive
    /// outside the mask, negative inside, ±½ at the pixels either side of it (so that
    /// interpolating between pixel centres puts the contour half-way); 0 for an unknown
    /// pixel.
    pub fn signed_distance(&self, i: usize) -> f64 {
        self.weight[i] * self.norm
    }

    /// The normaliser N = |M|·√(|M|/π), in px³.
    pub fn normaliser(&self) -> f64 {
        self.norm
    }

    /// Adds `k` times a term linear in A to this one — per-pixel weights `weight` (its
    /// ∂/∂A) and value at an empty render `offset` (the region term,
    /// `crate::loss::region`) — so that [`ContourTarget::loss`] and
    /// [`ContourTarget::gradient`] are of the sum, [`ContourTarget::pixel_loss`] of the
    /// sum up to a constant (what the Gauss–Newton model needs), and
    /// [`ContourTarget::signed_distance`] no longer a distance.
    ///
    /// # Panics
    /// If `weight` has the wrong length.
    pub fn add_linear(&mut self, weight: &[f64], offset: f64, k: f64) {
        assert_eq!(weight.len(), self.weight.len(), "one weight per pixel");
        for (w, r) in self.weight.iter_mut().zip(weight) {
            *w += k * r;
        }
        self.offset += k * offset;
    }

    /// The contour loss of `alpha` (row-major, `width·height` values).
    ///
    /// # Panics
    /// If `alpha` has the wrong length.
    pub fn loss(&self, alpha: &[f64]) -> f64 {
        assert_eq!(alpha.len(), self.weight.len(), "alpha must have one value per pixel");
        self.offset + alpha.iter().zip(&self.weight).map(|(a, w)| a * w).sum::<f64>()
    }

    /// The contour loss, and `scale·∂L/∂A_p` added to `grad[p]` for every pixel.
    ///
    /// # Panics
    /// If `alpha` or `grad` has the wrong length.
    pub fn loss_grad(&self, alpha: &[f64], scale: f64, grad: &mut [f64]) -> f64 {
        assert_eq!(grad.len(), self.weight.len(), "grad must have one value per pixel");
        for (g, w) in grad.iter_mut().zip(&self.weight) {
            *g += scale * w;
        }
        self.loss(alpha)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn as_alpha(m: &Mask) -> Vec<f64> {
        m.data.iter().map(|&v| v as f64).collect()
    }

    #[test]
    fn zero_when_aligned_and_growing_with_the_shift() {
        let target = ContourTarget::new(&Mask::disc(96, 96, 40.0, 44.0, 20.0), "v").unwrap();
        assert!(target.loss(&as_alpha(&Mask::disc(96, 96, 40.0, 44.0, 20.0))) < 1e-12);
        let mut last = 0.0;
        for shift in [2.0, 5.0, 10.0, 30.0, 45.0] {
            let l = target.loss(&as_alpha(&Mask::disc(96, 96, 40.0 + shift, 44.0, 20.0)));
            assert!(l > last, "shift {shift}: {l} after {last}");
            last = l;
        }
        // ½(δ/r)² for a small shift, within the discretisation.
        let l = target.loss(&as_alpha(&Mask::disc(96, 96, 44.0, 44.0, 20.0)));
        assert!((l / (0.5 * 0.04) - 1.0).abs() < 0.25, "{l}");
    }

    #[test]
    fn a_capped_target_charges_a_far_render_by_its_area_and_a_near_one_as_before() {
        let m = Mask::disc(128, 96, 50.0, 48.0, 20.0);
        let r = (m.area() as f64 / std::f64::consts::PI).sqrt();
        let plain = ContourTarget::new(&m, "v").unwrap();
        let capped = ContourTarget::from_parts(128, 96, &m.data, None, Some(0.15), "v").unwrap();
        // Every distance at most 0.15·r (the weight is (d_out − d_in)/N).
        let cap = 0.15 * r;
        assert!(capped.gradient().iter().all(|w| (w * capped.norm).abs() <= cap + 1e-9));
        assert!(plain.gradient().iter().any(|w| (w * plain.norm).abs() > 2.0 * cap));
        // Within the cap, the same loss: a render a pixel off.
        let near = as_alpha(&Mask::disc(128, 96, 51.0, 48.0, 20.0));
        assert!((capped.loss(&near) - plain.loss(&near)).abs() < 1e-12);
        // A thin part the mask misses (a spout 30 px long, 2 px wide): uncapped it costs
        // its reach, capped at most cap·area/N.
        let mut spout = near.clone();
        for x in 71..101 {
            for y in 47..49 {
                spout[y * 128 + x] = 1.0;
            }
        }
        let (dp, dc) = (
            plain.loss(&spout) - plain.loss(&near),
            capped.loss(&spout) - capped.loss(&near),
        );
        assert!(dc > 0.0 && dc <= 60.0 * cap / capped.norm + 1e-12, "{dc}");
        assert!(dp > 3.0 * dc, "uncapped {dp}, capped {dc}");
        // Still a gradient everywhere near the mask, exact against central differences.
        let a: Vec<f64> = (0..128 * 96).map(|i| (i as f64 * 0.37).sin() * 0.5 + 0.5).collect();
        let mut g = vec![0.0; a.len()];
        capped.loss_grad(&a, 1.0, &mut g);
        for p in (0..a.len()).step_by(97) {
            let (mut ap, mut am) = (a.clone(), a.clone());
            ap[p] += 1e-4;
            am[p] -= 1e-4;
            let fd = (capped.loss(&ap) - capped.loss(&am)) / 2e-4;
            assert!((g[p] - fd).abs() < 1e-9, "pixel {p}: {} against {fd}", g[p]);
        }
    }

    #[test]
    fn resolution_independent() {
        let small = ContourTarget::new(&Mask::disc(64, 64, 30.0, 32.0, 12.0), "v").unwrap();
        let big = ContourTarget::new(&Mask::disc(256, 256, 120.0, 128.0, 48.0), "v").unwrap();
        let ls = small.loss(&as_alpha(&Mask::disc(64, 64, 33.0, 32.0, 12.0)));
        let lb = big.loss(&as_alpha(&Mask::disc(256, 256, 132.0, 128.0, 48.0)));
        assert!((ls / lb - 1.0).abs() < 0.2, "{ls} vs {lb}");
    }

    #[test]
    fn gradient_matches_central_differences_and_empty_mask_is_named() {
        let t = ContourTarget::new(&Mask::disc(20, 16, 8.0, 7.0, 4.0), "v").unwrap();
        let a: Vec<f64> = (0..320).map(|i| (i as f64 * 0.13).cos() * 0.5 + 0.5).collect();
        let mut g = vec![0.0; 320];
        let l = t.loss_grad(&a, 3.0, &mut g);
        assert!((l - t.loss(&a)).abs() < 1e-15);
        let h = 1e-4;
        for p in (0..320).step_by(7) {
            let (mut ap, mut am) = (a.clone(), a.clone());
            ap[p] += h;
            am[p] -= h;
            let fd = (t.loss(&ap) - t.loss(&am)) / (2.0 * h);
            assert!((g[p] - 3.0 * fd).abs() < 1e-9);
        }
        let e = ContourTarget::new(&Mask::empty(5, 5), "left").unwrap_err().to_string();
        assert!(e.contains("'left'") && e.contains("empty"), "{e}");
    }
}
