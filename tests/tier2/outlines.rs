//! A figure to look at beside the photograph path's numbers: for each LM-O fit of the
//! first set of boxes, each view's photograph around the object, as it is and with three
//! outlines drawn over it — the annotated visible mask's (green), the segmenter's last
//! mask's (red) and the fitted pose's silhouette's (blue) — three times enlarged, the
//! views one under the other. Written to `target/tmp/lmo-outlines/object<N>.png` (made
//! from the `../shared` photographs, so kept out of the repository). The ADD(-S) and IoU
//! figures are measured against the annotation; these show where it, the segmenter and
//! the fit lie on the photographs themselves.

use localisebot::{metrics, Mask, Rgba};
use std::path::PathBuf;

/// Pixels around the outlines' union.
const MARGIN: u32 = 12;
/// The enlargement.
const ZOOM: u32 = 3;

const ANNOTATED: [u8; 3] = [0, 255, 0];
const SEGMENTER: [u8; 3] = [255, 0, 0];
const FITTED: [u8; 3] = [0, 128, 255];

/// The box (x0, y0, x1, y1), exclusive ends, of the masks' pixels with a margin.
fn frame(masks: &[&Mask], w: u32, h: u32) -> Option<(u32, u32, u32, u32)> {
    let (x0, y0, x1, y1) = masks
        .iter()
        .filter_map(|m| m.bbox())
        .reduce(|a, b| (a.0.min(b.0), a.1.min(b.1), a.2.max(b.2), a.3.max(b.3)))?;
    Some((
        x0.saturating_sub(MARGIN),
        y0.saturating_sub(MARGIN),
        (x1 + 1 + MARGIN).min(w),
        (y1 + 1 + MARGIN).min(h),
    ))
}

/// One view's strip: the photograph's crop as it is, and with the outlines.
fn strip(photo: &Rgba, annotated: &Mask, segmenter: &Mask, fitted: &Mask) -> Option<image::RgbImage> {
    let (x0, y0, x1, y1) = frame(&[annotated, segmenter, fitted], photo.width, photo.height)?;
    let (w, h) = (x1 - x0, y1 - y0);
    let outlines = [
        (metrics::contour(annotated), ANNOTATED),
        (metrics::contour(segmenter), SEGMENTER),
        (metrics::contour(fitted), FITTED),
    ];
    let mut out = image::RgbImage::new(2 * w * ZOOM, h * ZOOM);
    for y in 0..h {
        for x in 0..w {
            let (sx, sy) = (x0 + x, y0 + y);
            let i = 4 * (sy * photo.width + sx) as usize;
            let plain = [photo.data[i], photo.data[i + 1], photo.data[i + 2]];
            let mut drawn = plain;
            for (outline, colour) in &outlines {
                if outline.get(sx, sy) {
                    drawn = *colour;
                }
            }
            for dy in 0..ZOOM {
                for dx in 0..ZOOM {
                    out.put_pixel(x * ZOOM + dx, y * ZOOM + dy, image::Rgb(plain));
                    out.put_pixel((w + x) * ZOOM + dx, y * ZOOM + dy, image::Rgb(drawn));
                }
            }
        }
    }
    Some(out)
}

/// Writes object `object`'s figure (one strip per view, in order) and returns its path;
/// views without a segmenter's mask are left out.
pub fn write(
    object: u32,
    photos: &[std::sync::Arc<Rgba>],
    annotated: &[Mask],
    segmenter: &[Option<&Mask>],
    fitted: &[Mask],
) -> PathBuf {
    let strips: Vec<image::RgbImage> = (0..photos.len())
        .filter_map(|i| strip(&photos[i], &annotated[i], segmenter[i]?, &fitted[i]))
        .collect();
    assert!(!strips.is_empty(), "object {object}: no view to draw");
    let width = strips.iter().map(|s| s.width()).max().unwrap();
    let height = strips.iter().map(|s| s.height()).sum();
    let mut sheet = image::RgbImage::new(width, height);
    let mut y = 0;
    for s in &strips {
        image::imageops::replace(&mut sheet, s, 0, y as i64);
        y += s.height();
    }
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("lmo-outlines");
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(format!("object{object}.png"));
    sheet.save(&path).unwrap();
    path
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The frame is the mask's box with the margin, clipped; the strip puts the
    /// photograph on the left untouched and the outlines' colours on the right (a 3×3
    /// square's outline leaves its centre), the fitted one drawn last.
    #[test]
    fn outlines_are_drawn_beside_the_plain_photograph() {
        let mut m = Mask::empty(20, 20);
        for y in 8..11 {
            for x in 8..11 {
                m.data[(y * 20 + x) as usize] = 1;
            }
        }
        assert_eq!(frame(&[&m], 20, 20), Some((0, 0, 20, 20)));
        assert_eq!(frame(&[&m], 40, 40), Some((0, 0, 11 + MARGIN, 11 + MARGIN)));
        assert_eq!(frame(&[&Mask::empty(20, 20)], 20, 20), None);
        let photo = Rgba {
            width: 20,
            height: 20,
            data: vec![7; 20 * 20 * 4],
        };
        let empty = Mask::empty(20, 20);
        let s = strip(&photo, &m, &empty, &empty).unwrap();
        assert_eq!(s.dimensions(), (2 * 20 * ZOOM, 20 * ZOOM));
        assert_eq!(s.get_pixel(8 * ZOOM, 8 * ZOOM).0, [7, 7, 7]);
        assert_eq!(s.get_pixel((20 + 8) * ZOOM, 8 * ZOOM).0, ANNOTATED);
        assert_eq!(s.get_pixel((20 + 9) * ZOOM, 9 * ZOOM).0, [7, 7, 7]);
        // The fitted outline is drawn last, over the others.
        let s = strip(&photo, &m, &m, &m).unwrap();
        assert_eq!(s.get_pixel((20 + 8) * ZOOM + 1, 8 * ZOOM + 1).0, FITTED);
    }
}
