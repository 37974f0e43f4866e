//! The masks the rounds return: the fitted pose's silhouette where the segmenter saw
//! the object. The pose is fitted to every view at once, so its outline follows the
//! photographs more closely than one view's segmentation does; the segmenter's mask says
//! which parts of it the photograph shows (an occluder, the image's edge). A visible
//! mask is the silhouette's pixels within [`REACH`] of the segmenter's mask — the way a
//! dataset's visible masks are made from its poses, with the segmenter standing in for
//! the depth that tells what is in front.

use crate::loss::edt;
use crate::mask::Mask;

/// How far (a fraction of the silhouette's equivalent radius, √(area/π)) a silhouette
/// pixel may be from the segmenter's mask and be kept. Measured on the LM-O photographs
/// (tier2 `photos`, boxes in 3 views, 24 views; median IoU against the annotated
/// visible masks): the segmenter's masks 0.814, the whole silhouettes 0.847, kept within
/// 0.1 / 0.2 / 0.3 / 0.5 of the radius 0.849 / 0.856 / 0.847 / 0.847.
pub const REACH: f64 = 0.2;

/// The pixels of `silhouette` within [`REACH`] of `made` (both the image's size).
/// Exact: the distances are measured in the silhouette's box widened by the reach, which
/// holds every made pixel near enough to count.
pub fn visible(silhouette: &Mask, made: &Mask) -> Mask {
    let (w, h) = (silhouette.width, silhouette.height);
    debug_assert_eq!((made.width, made.height), (w, h));
    let mut out = Mask::empty(w, h);
    let Some((x0, y0, x1, y1)) = silhouette.bbox() else {
        return out;
    };
    let reach = REACH * (silhouette.area() as f64 / std::f64::consts::PI).sqrt();
    let pad = reach.ceil() as u32 + 1;
    let (wx0, wy0) = (x0.saturating_sub(pad), y0.saturating_sub(pad));
    let (wx1, wy1) = ((x1 + pad).min(w - 1), (y1 + pad).min(h - 1));
    let (ww, wh) = ((wx1 - wx0 + 1) as usize, (wy1 - wy0 + 1) as usize);
    let at = |x: usize, y: usize| (wy0 as usize + y) * w as usize + wx0 as usize + x;
    let seed: Vec<bool> = (0..wh)
        .flat_map(|y| (0..ww).map(move |x| (x, y)))
        .map(|(x, y)| made.data[at(x, y)] != 0)
        .collect();
    let d2 = edt::squared_distance(ww, wh, &seed);
    for y in 0..wh {
        for x in 0..ww {
            let i = at(x, y);
            if silhouette.data[i] != 0 && d2[y * ww + x] <= reach * reach {
                out.data[i] = 1;
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A disc about (`cx`, `cy`) in image coordinates (pixel centres at +0.5).
    fn disc(w: u32, h: u32, cx: f64, cy: f64, r: f64) -> Mask {
        Mask::disc(w, h, cx - 0.5, cy - 0.5, r)
    }

    /// The same by brute force over the whole image.
    fn oracle(silhouette: &Mask, made: &Mask) -> Mask {
        let (w, h) = (silhouette.width as i64, silhouette.height as i64);
        let reach = REACH * (silhouette.area() as f64 / std::f64::consts::PI).sqrt();
        let mut out = Mask::empty(silhouette.width, silhouette.height);
        let made_px: Vec<(i64, i64)> = (0..h)
            .flat_map(|y| (0..w).map(move |x| (x, y)))
            .filter(|&(x, y)| made.data[(y * w + x) as usize] != 0)
            .collect();
        for y in 0..h {
            for x in 0..w {
                let i = (y * w + x) as usize;
                let near = made_px
                    .iter()
                    .any(|&(mx, my)| (((mx - x).pow(2) + (my - y).pow(2)) as f64) <= reach * reach);
                out.data[i] = u8::from(silhouette.data[i] != 0 && near);
            }
        }
        out
    }

    #[test]
    fn a_segmentation_a_little_off_returns_the_whole_silhouette() {
        let sil = disc(64, 48, 30.0, 24.0, 15.0);
        let made = disc(64, 48, 31.0, 23.0, 14.5);
        assert_eq!(visible(&sil, &made), sil);
    }

    #[test]
    fn an_occluded_part_is_left_out_but_for_the_reach() {
        let sil = disc(64, 48, 30.0, 24.0, 15.0);
        // The segmenter saw the object's left half: an occluder covers x ≥ 30.
        let mut made = sil.clone();
        for y in 0..48 {
            for x in 30..64 {
                made.data[y * 64 + x] = 0;
            }
        }
        let v = visible(&sil, &made);
        let reach = REACH * (sil.area() as f64 / std::f64::consts::PI).sqrt();
        assert!(reach > 2.0 && reach < 4.0, "{reach}");
        for y in 0..48u32 {
            for x in 0..64u32 {
                // The nearest pixel the segmenter saw is (29, y), in every row.
                let expected = sil.get(x, y) && (x < 30 || f64::from(x - 29) <= reach);
                assert_eq!(v.get(x, y), expected, "({x}, {y})");
            }
        }
        assert_eq!(v, oracle(&sil, &made));
    }

    #[test]
    fn the_windowed_distances_are_the_whole_image_s() {
        // Made pixels beyond the silhouette's box, touching the image's edges, and none.
        let cases = [
            (disc(40, 30, 20.0, 15.0, 8.0), disc(40, 30, 30.0, 15.0, 8.0)),
            (disc(40, 30, 3.0, 3.0, 9.0), disc(40, 30, 8.0, 2.0, 6.0)),
            (disc(40, 30, 37.0, 27.0, 9.0), disc(40, 30, 39.0, 20.0, 3.0)),
            (disc(40, 30, 20.0, 15.0, 30.0), disc(40, 30, 10.0, 10.0, 4.0)),
            (disc(40, 30, 20.0, 15.0, 8.0), Mask::empty(40, 30)),
            (Mask::empty(40, 30), disc(40, 30, 20.0, 15.0, 8.0)),
        ];
        for (k, (sil, made)) in cases.iter().enumerate() {
            let v = visible(sil, made);
            assert_eq!(v, oracle(sil, made), "case {k}");
            assert!(
                v.data.iter().zip(&sil.data).all(|(a, b)| a <= b),
                "case {k}: within the silhouette"
            );
        }
        // The first case keeps part of the silhouette and drops part: not trivially all or none.
        let v = visible(&cases[0].0, &cases[0].1);
        assert!(v.area() > 0 && v.area() < cases[0].0.area());
    }
}
