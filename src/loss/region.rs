//! Region term — pixel-wise colour posteriors along the outline (PWP3D, SRT3D), a
//! boundary refinement for views with a photograph.
//!
//! The view's photograph is averaged into the canvas; colour histograms (16 bins a
//! channel) are counted over the mask's known pixels (foreground) and over the known
//! background within a ring around it (local background, the part of the scene the
//! outline can move into). Each canvas pixel near the outline — within `band·r` of it,
//! `r = √(|M|/π)`, at least two pixels — gets the log-likelihood ratio
//! `ρ(p) = ln(P(c_p | background) / P(c_p | object))`, clamped to ±[`CLAMP`] (Laplace-
//! smoothed histograms); other pixels get 0. The term is the segmentation's negative
//! log-likelihood, linear in the soft silhouette A as the contour term is:
//!
//! `R = [Σ_p A_p·ρ⁺(p) + Σ_p (1 − A_p)·ρ⁻(p)] / |M|`,  `ρ± = max(±ρ, 0)`,
//!
//! so `∂R/∂A_p = ρ(p)/|M|`: rendered mass on background-coloured pixels costs, object-
//! coloured pixels left out cost. Unknown pixels count in no sum. Being linear in A it
//! is folded into the contour term's per-pixel weights
//! ([`crate::loss::contour::ContourTarget::add_linear`]) with the weight λ_region/λ2,
//! and so enters every evaluation — value, exact gradient, Gauss–Newton model — as the
//! contour term does.
//!
//! The histograms are learnt from the mask the term refines (the segmenter's): where the
//! mask follows the photograph they change nothing; where its outline strays over a
//! colour edge by a few pixels, the pixels between the two are coloured like the side
//! they belong to and pull the outline there.

use crate::view::Rgba;

/// Histogram bins per colour channel.
const BINS: usize = 16;
/// The log-likelihood ratio's bound (nats).
pub const CLAMP: f64 = 3.0;
/// The outline band's half-width, in units of the equivalent radius r (at least two
/// pixels): the region term refines the outline, it does not segment.
pub const BAND: f64 = 0.25;
/// The local background ring's width, in units of the equivalent radius r.
const RING: f64 = 0.5;

/// Per-pixel weights `ρ(p)/|M|` of the region term on a `w`×`h` canvas (module doc),
/// and the term's value at an empty render, `Σ ρ⁻/|M|`; `None` when the mask or the
/// local background has no known pixel.
///
/// `colours` holds each canvas pixel's mean RGB (0–255); `mask` and `known` are 0/1
/// per pixel (`known` `None`: all known); `band` is the outline band's half-width in
/// units of r.
pub fn weights(
    w: usize,
    h: usize,
    colours: &[[f32; 3]],
    mask: &[u8],
    known: Option<&[u8]>,
    band: f64,
) -> Option<(Vec<f64>, f64)> {
    let n = w * h;
    let is_known = |i: usize| known.is_none_or(|k| k[i] != 0);
    let area = (0..n).filter(|&i| mask[i] != 0 && is_known(i)).count();
    if area == 0 || colours.len() != n || mask.len() != n {
        return None;
    }
    let object: Vec<bool> = (0..n).map(|i| mask[i] != 0).collect();
    let background: Vec<bool> = (0..n).map(|i| mask[i] == 0).collect();
    // Distances (px) from the object (0 on it) and from the background (0 off it).
    let d_out = crate::loss::edt::distance(w, h, &object);
    let d_in = crate::loss::edt::distance(w, h, &background);
    let r = (area as f64 / std::f64::consts::PI).sqrt();
    let ring = (RING * r).max(3.0);
    let reach = (band * r).max(2.0);
    let bin = |c: &[f32; 3]| {
        let q = |v: f32| ((v.clamp(0.0, 255.0) as usize) * BINS / 256).min(BINS - 1);
        (q(c[0]) * BINS + q(c[1])) * BINS + q(c[2])
    };
    let mut fg = vec![0.0f64; BINS * BINS * BINS];
    let mut bg = fg.clone();
    let (mut nf, mut nb) = (0.0, 0.0);
    for i in (0..n).filter(|&i| is_known(i)) {
        if object[i] {
            fg[bin(&colours[i])] += 1.0;
            nf += 1.0;
        } else if d_out[i] <= ring {
            bg[bin(&colours[i])] += 1.0;
            nb += 1.0;
        }
    }
    if nb == 0.0 {
        return None;
    }
    // Laplace smoothing: half a count in every bin.
    let bins = fg.len() as f64;
    let (sf, sb) = (nf + 0.5 * bins, nb + 0.5 * bins);
    let norm = area as f64;
    let mut empty = 0.0;
    let out = (0..n)
        .map(|i| {
            let near = if object[i] { d_in[i] } else { d_out[i] };
            if !is_known(i) || near > reach {
                return 0.0;
            }
            let b = bin(&colours[i]);
            let rho = (((bg[b] + 0.5) / sb) / ((fg[b] + 0.5) / sf)).ln().clamp(-CLAMP, CLAMP);
            empty += (-rho).max(0.0);
            rho / norm
        })
        .collect();
    Some((out, empty / norm))
}

/// The photograph `image` averaged into canvas pixels: for each canvas pixel, the
/// overlap-weighted mean RGB of the image pixels it covers (`cols[c]`, `rows[r]`: the
/// image pixels and overlaps of each canvas column and row, out-of-image indices
/// skipped). A pixel covering no image pixel is black.
pub fn canvas_colours(image: &Rgba, cols: &[Vec<(i64, f64)>], rows: &[Vec<(i64, f64)>]) -> Vec<[f32; 3]> {
    let (iw, ih) = (i64::from(image.width), i64::from(image.height));
    let mut out = Vec::with_capacity(cols.len() * rows.len());
    for row in rows {
        for col in cols {
            let (mut sum, mut wsum) = ([0.0f64; 3], 0.0);
            for &(y, wy) in row.iter().filter(|(y, _)| (0..ih).contains(y)) {
                for &(x, wx) in col.iter().filter(|(x, _)| (0..iw).contains(x)) {
                    let k = 4 * (y * iw + x) as usize;
                    let a = wx * wy;
                    for (s, v) in sum.iter_mut().zip(&image.data[k..k + 3]) {
                        *s += a * f64::from(*v);
                    }
                    wsum += a;
                }
            }
            let m = |s: f64| if wsum > 0.0 { (s / wsum) as f32 } else { 0.0 };
            out.push([m(sum[0]), m(sum[1]), m(sum[2])]);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A red disc on a mottled blue-green background, and a mask of the disc moved
    /// right by `shift` pixels.
    fn scene(shift: i64) -> (usize, usize, Vec<[f32; 3]>, Vec<u8>) {
        let (w, h) = (80usize, 60usize);
        let inside = |x: i64, y: i64, dx: i64| ((x - 40 - dx).pow(2) + (y - 30).pow(2)) <= 15 * 15;
        let colours = (0..w * h)
            .map(|i| {
                let (x, y) = ((i % w) as i64, (i / w) as i64);
                if inside(x, y, 0) {
                    [200.0, 40.0, 30.0]
                } else {
                    [20.0, 60.0 + ((x * 7 + y * 13) % 90) as f32, 150.0]
                }
            })
            .collect();
        let mask = (0..w * h)
            .map(|i| u8::from(inside((i % w) as i64, (i / w) as i64, shift)))
            .collect();
        (w, h, colours, mask)
    }

    #[test]
    fn the_weights_pull_a_strayed_outline_onto_the_colour_edge() {
        let (w, h, colours, mask) = scene(3);
        let (rho, empty) = weights(w, h, &colours, &mask, None, 0.3).unwrap();
        // The pixels the mask missed (left of the disc's mask, red) weigh negative: the
        // render should take them; the pixels it took wrongly (right edge, background
        // colours) weigh positive.
        let at = |x: usize, y: usize| rho[y * w + x];
        assert!(at(26, 30) < 0.0, "missed object pixel {}", at(26, 30));
        assert!(at(57, 30) > 0.0, "background inside the mask {}", at(57, 30));
        // Far from the outline nothing.
        assert_eq!(at(2, 2), 0.0);
        assert_eq!(at(42, 30), 0.0);
        assert!(empty > 0.0);
        // The loss is lower at the true disc than at the mask that made the model.
        let loss = |shift: i64| {
            let (_, _, _, m) = scene(shift);
            empty + m.iter().zip(&rho).map(|(&a, r)| f64::from(a) * r).sum::<f64>()
        };
        assert!(loss(0) < loss(3), "{} vs {}", loss(0), loss(3));
        assert!(loss(3) < loss(6), "{} vs {}", loss(3), loss(6));
    }

    #[test]
    fn no_background_or_no_object_gives_no_term() {
        let (w, h, colours, _) = scene(0);
        assert!(weights(w, h, &colours, &vec![1; w * h], None, 0.3).is_none());
        assert!(weights(w, h, &colours, &vec![0; w * h], None, 0.3).is_none());
        // Unknown pixels weigh nothing.
        let (_, _, _, mask) = scene(3);
        let mut known = vec![1u8; w * h];
        known[30 * w + 26] = 0;
        let (rho, _) = weights(w, h, &colours, &mask, Some(&known), 0.3).unwrap();
        assert_eq!(rho[30 * w + 26], 0.0);
    }

    #[test]
    fn colours_are_area_means() {
        let image = Rgba {
            width: 2,
            height: 1,
            data: vec![0, 0, 0, 255, 200, 100, 50, 255],
        };
        // One canvas pixel over both image pixels, a quarter of the first and all of
        // the second; one out of the image.
        let cols = vec![vec![(0, 0.25), (1, 1.0)], vec![(5, 1.0)]];
        let rows = vec![vec![(0, 1.0)]];
        let c = canvas_colours(&image, &cols, &rows);
        assert_eq!(c.len(), 2);
        assert!((c[0][0] - 160.0).abs() < 1e-4 && (c[0][2] - 40.0).abs() < 1e-4);
        assert_eq!(c[1], [0.0; 3]);
    }
}
