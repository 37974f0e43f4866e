//! What the segmenter is asked: a [`SegmentJob`] per view — the square of the
//! photograph it sees ([`Crop`]) and the prompt in that square's pixels — and what it
//! answers ([`SegmentOutput`]). Prompts come from the user's box, from the geometry of
//! the other views, or, after a fit, from the fitted pose ([`from_pose`]): the rendered
//! silhouette's tight box, a positive point deep inside it where the previous mask
//! agrees, a negative point where the previous mask reaches farthest beyond it, and
//! the previous mask as the mask input.

use crate::loss::edt;
use crate::mask::Mask;
use crate::view::{PixelBox, Rgba};
use glam::DVec2;
use serde::{Deserialize, Serialize};

/// A square of image pixels, `[x0, x0 + side) × [y0, y0 + side)`; it may reach past the
/// image, whose missing pixels the segmenter sees as mean grey.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct Crop {
    /// First column.
    pub x0: i64,
    /// First row.
    pub y0: i64,
    /// Side, pixels (at least [`MIN_CROP`] when made by [`Crop::around`]).
    pub side: u32,
}

/// The smallest crop side: below it a box is enlarged to this much context.
pub const MIN_CROP: u32 = 96;

/// A view's earlier crop is kept for a redrawn box ([`Crop::kept_or_around`]) while the
/// box is at least this fraction of the crop's side from each of its edges …
pub const KEPT_SLACK: f64 = 0.03;

/// … and the crop's side is within these multiples of the side a new crop would have.
pub const KEPT_SIDE_RATIO: (f64, f64) = (0.8, 1.25);

impl Crop {
    /// The square around `b` whose side is `1 + 2·margin` times the box's longest side
    /// (at least [`MIN_CROP`]), centred on it.
    pub fn around(b: &PixelBox, margin: f64) -> Crop {
        let side = (b.size().max_element() * (1.0 + 2.0 * margin))
            .ceil()
            .max(MIN_CROP as f64);
        let c = b.centre();
        Crop {
            x0: (c.x + 0.5 - side / 2.0).round() as i64,
            y0: (c.y + 0.5 - side / 2.0).round() as i64,
            side: side as u32,
        }
    }

    /// The crop for box `b`: `kept` — the crop a segmenter was given for this view's
    /// earlier box, whose encoding it keeps — while it still frames `b` (the box inside
    /// it, [`KEPT_SLACK`] of its side from its edges, and its side within
    /// [`KEPT_SIDE_RATIO`] of the side [`Crop::around`] would give), else a new one
    /// around `b`. A box redrawn a little then costs a prompt, not another run of the
    /// encoder. `kept` of side 0: none.
    pub fn kept_or_around(kept: Crop, b: &PixelBox, margin: f64) -> Crop {
        let fresh = Crop::around(b, margin);
        let ratio = kept.side as f64 / fresh.side as f64;
        let (lo, hi) = KEPT_SIDE_RATIO;
        if kept.side > 0 && (lo..=hi).contains(&ratio) && kept.holds(b, KEPT_SLACK, 0.0) {
            kept
        } else {
            fresh
        }
    }

    /// Whether `b` lies inside the crop, `slack` of the side away from its edges, and is
    /// at least `min_fraction` of its side (else the segmenter should see a new crop).
    pub fn holds(&self, b: &PixelBox, slack: f64, min_fraction: f64) -> bool {
        let (s, pad) = (self.side as f64, self.side as f64 * slack);
        b.x0 >= self.x0 as f64 + pad
            && b.y0 >= self.y0 as f64 + pad
            && b.x1 <= self.x0 as f64 + s - pad
            && b.y1 <= self.y0 as f64 + s - pad
            && b.size().max_element() >= min_fraction * s
    }

    /// An image point (pixel-centre coordinates) in the crop's pixels.
    pub fn to_crop(&self, p: DVec2) -> DVec2 {
        p - DVec2::new(self.x0 as f64, self.y0 as f64)
    }

    /// The crop's pixels of `image` as RGB8, row-major; pixels outside the image are the
    /// segmenter's mean colour (zero after its normalisation).
    pub fn rgb(&self, image: &Rgba) -> Vec<u8> {
        const MEAN: [u8; 3] = [124, 116, 104];
        let n = self.side as usize;
        let mut out = Vec::with_capacity(n * n * 3);
        for y in 0..n as i64 {
            let iy = self.y0 + y;
            for x in 0..n as i64 {
                let ix = self.x0 + x;
                if ix >= 0 && iy >= 0 && (ix as u32) < image.width && (iy as u32) < image.height {
                    let i = 4 * (iy as usize * image.width as usize + ix as usize);
                    out.extend_from_slice(&image.data[i..i + 3]);
                } else {
                    out.extend_from_slice(&MEAN);
                }
            }
        }
        out
    }

    /// The IoU of a crop-sized mask, placed back into `reference`'s image (what falls
    /// outside it dropped), with `reference`: [`hard_iou`](crate::metrics::hard_iou) of
    /// [`Crop::to_image`]'s mask, counted over the crop alone (a 12-MP photograph's
    /// masks are not made to compare them); `reference_area`: its [`Mask::area`].
    pub fn iou_in_image(&self, crop_mask: &Mask, reference: &Mask, reference_area: usize) -> f64 {
        let (w, h) = (reference.width as i64, reference.height as i64);
        let (mut inter, mut area) = (0usize, 0usize);
        for y in 0..crop_mask.height as i64 {
            let iy = self.y0 + y;
            if iy < 0 || iy >= h {
                continue;
            }
            for x in 0..crop_mask.width as i64 {
                let ix = self.x0 + x;
                if ix >= 0 && ix < w && crop_mask.get(x as u32, y as u32) {
                    area += 1;
                    inter += usize::from(reference.data[(iy * w + ix) as usize] != 0);
                }
            }
        }
        let union = area + reference_area - inter;
        if union == 0 {
            0.0
        } else {
            inter as f64 / union as f64
        }
    }

    /// Whether image pixel `(x, y)` is set in a crop-sized mask placed back into the
    /// image (false outside the crop; the caller checks the image's bounds).
    pub fn holds_pixel(&self, crop_mask: &Mask, x: i64, y: i64) -> bool {
        let (cx, cy) = (x - self.x0, y - self.y0);
        (0..crop_mask.width as i64).contains(&cx)
            && (0..crop_mask.height as i64).contains(&cy)
            && crop_mask.get(cx as u32, cy as u32)
    }

    /// A crop-sized mask placed back into an image of `width × height` (what falls
    /// outside the image is dropped).
    pub fn to_image(&self, crop_mask: &Mask, width: u32, height: u32) -> Mask {
        let mut m = Mask::empty(width, height);
        for y in 0..crop_mask.height as i64 {
            let iy = self.y0 + y;
            if iy < 0 || iy >= height as i64 {
                continue;
            }
            for x in 0..crop_mask.width as i64 {
                let ix = self.x0 + x;
                if ix >= 0 && ix < width as i64 && crop_mask.get(x as u32, y as u32) {
                    m.data[iy as usize * width as usize + ix as usize] = 1;
                }
            }
        }
        m
    }
}

/// A prompt point: where (crop pixels, pixel centres at integers) and whether it is on
/// the object (SAM's labels 1 and 0).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PromptPoint {
    /// Crop pixel coordinates.
    pub at: [f64; 2],
    /// On the object (`true`) or not.
    pub object: bool,
}

/// One segmentation the fit asks for.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SegmentJob {
    /// The view, by its position in the scene.
    pub view: usize,
    /// The square of the photograph the segmenter sees.
    pub crop: Crop,
    /// The box around the object, `[x_min, y_min, x_max, y_max]` in crop pixel-edge
    /// coordinates (a pixel i spans [i, i + 1]).
    pub prompt_box: [f64; 4],
    /// Points on and off the object.
    pub points: Vec<PromptPoint>,
    /// The previous mask's logits for the same crop (the segmenter's low-resolution
    /// grid), as its mask input.
    pub previous: Option<Vec<f32>>,
}

/// One mask the segmenter offers for a [`SegmentJob`].
#[derive(Debug, Clone, PartialEq)]
pub struct MaskCandidate {
    /// The crop's mask, `side × side`.
    pub mask: Mask,
    /// Its logits on the segmenter's low-resolution grid (to pass back as `previous`).
    pub logits: Vec<f32>,
    /// The segmenter's own estimate of the mask's IoU.
    pub score: f32,
}

/// The segmenter's answer to a [`SegmentJob`]: its masks (a prompted segmenter offers
/// several readings — the whole object, a part) and the one it prefers. The fit
/// chooses among them once it has a silhouette to compare with.
#[derive(Debug, Clone, PartialEq)]
pub struct SegmentOutput {
    /// At least one.
    pub candidates: Vec<MaskCandidate>,
    /// The segmenter's own choice (an index into `candidates`).
    pub preferred: usize,
}

impl SegmentOutput {
    /// An answer of one mask.
    pub fn single(mask: Mask, logits: Vec<f32>, score: f32) -> SegmentOutput {
        SegmentOutput {
            candidates: vec![MaskCandidate { mask, logits, score }],
            preferred: 0,
        }
    }
}

impl SegmentJob {
    /// The points in the segmenter's coordinates (pixel edges: the core's pixel centre
    /// i is the segmenter's i + ½), `[x, y, 1 on the object | 0 off it]`.
    pub fn segmenter_points(&self) -> Vec<[f32; 3]> {
        self.points
            .iter()
            .map(|p| {
                [
                    (p.at[0] + 0.5) as f32,
                    (p.at[1] + 0.5) as f32,
                    f32::from(u8::from(p.object)),
                ]
            })
            .collect()
    }

    /// A job from a box in image pixels (the user's, or the geometry's) in `crop`.
    pub fn from_box(view: usize, crop: Crop, b: &PixelBox) -> SegmentJob {
        let (x, y) = (crop.x0 as f64, crop.y0 as f64);
        SegmentJob {
            view,
            crop,
            prompt_box: [b.x0 - x, b.y0 - y, b.x1 - x, b.y1 - y],
            points: Vec::new(),
            previous: None,
        }
    }
}

/// The deepest pixel of `region` (row-major `w × h`): the one farthest from any pixel
/// outside it, with its distance; `None` when the region is empty.
fn deepest(region: &[bool], w: usize, h: usize) -> Option<(DVec2, f64)> {
    let outside: Vec<bool> = region.iter().map(|&r| !r).collect();
    if outside.iter().all(|&o| o) {
        return None;
    }
    // A region that fills the image has no outside: measure from the border instead.
    let d = if outside.iter().any(|&o| o) {
        edt::distance(w, h, &outside)
    } else {
        vec![1.0; w * h]
    };
    let (i, &best) = d
        .iter()
        .enumerate()
        .filter(|(i, _)| region[*i])
        .max_by(|a, b| a.1.total_cmp(b.1))?;
    Some((DVec2::new((i % w) as f64, (i / w) as f64), best))
}

/// The re-prompt of a view from a fitted pose (module doc): `silhouette` the pose's
/// render in the full image, `previous` the last mask made for it (full image) and its
/// logits, `crop` the square the segmenter saw. `None` when the silhouette is empty.
///
/// The distances are measured within the box of the silhouette's and the previous
/// mask's pixels, one pixel wider on each side the image allows: every pixel beyond it
/// is farther from a pixel inside it than the nearest pixel of that border, so the
/// points are the ones the whole image would give, at a cost that follows the object,
/// not the photograph (a 12-MP one).
pub fn from_pose(view: usize, crop: Crop, silhouette: &Mask, previous: Option<(&Mask, &[f32])>) -> Option<SegmentJob> {
    let tight = PixelBox::of_mask(silhouette)?;
    let (w, h) = (silhouette.width as usize, silhouette.height as usize);
    // A pixel or two of slack: SAM's boxes are loose by nature.
    let pad = (0.02 * tight.size().max_element()).max(1.0);
    let b = PixelBox {
        x0: (tight.x0 - pad).max(0.0),
        y0: (tight.y0 - pad).max(0.0),
        x1: (tight.x1 + pad).min(w as f64),
        y1: (tight.y1 + pad).min(h as f64),
    };
    let mut job = SegmentJob::from_box(view, crop, &b);
    // The window: the silhouette's and the previous mask's pixels, and a border.
    let mut reach = (
        tight.x0 as usize,
        tight.y0 as usize,
        tight.x1 as usize,
        tight.y1 as usize,
    );
    if let Some((x0, y0, x1, y1)) = previous.and_then(|(m, _)| m.bbox()) {
        let (x0, y0, x1, y1) = (x0 as usize, y0 as usize, x1 as usize + 1, y1 as usize + 1);
        reach = (reach.0.min(x0), reach.1.min(y0), reach.2.max(x1), reach.3.max(y1));
    }
    let (wx0, wy0) = (reach.0.saturating_sub(1), reach.1.saturating_sub(1));
    let (ww, wh) = ((reach.2 + 1).min(w) - wx0, (reach.3 + 1).min(h) - wy0);
    let window = |m: &Mask| -> Vec<bool> {
        (0..wh)
            .flat_map(|y| (0..ww).map(move |x| (x, y)))
            .map(|(x, y)| m.data[(wy0 + y) * w + wx0 + x] != 0)
            .collect()
    };
    let inside = window(silhouette);
    let point = |p: DVec2, object| PromptPoint {
        at: crop.to_crop(p + DVec2::new(wx0 as f64, wy0 as f64)).to_array(),
        object,
    };
    let prev = previous.map(|(m, logits)| (window(m), logits));
    // On the object: deep inside the silhouette where the previous mask agrees.
    let agree: Vec<bool> = match &prev {
        Some((m, _)) => inside.iter().zip(m).map(|(&s, &m)| s && m).collect(),
        None => inside.clone(),
    };
    if let Some((p, _)) = deepest(&agree, ww, wh).or_else(|| deepest(&inside, ww, wh)) {
        job.points.push(point(p, true));
    }
    if let Some((m, logits)) = prev {
        // Off the object: where the previous mask reaches farthest beyond the silhouette
        // (more than a few pixels: the outline's own uncertainty).
        let margin = (0.04 * tight.size().max_element()).max(3.0);
        let to_sil = edt::distance(ww, wh, &inside);
        let beyond: Vec<bool> = m.iter().zip(&to_sil).map(|(&m, &d)| m && d > margin).collect();
        if let Some((p, _)) = deepest(&beyond, ww, wh) {
            job.points.push(point(p, false));
        }
        job.previous = Some(logits.to_vec());
    }
    Some(job)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn disc(w: u32, h: u32, c: DVec2, r: f64) -> Mask {
        let mut m = Mask::empty(w, h);
        for y in 0..h {
            for x in 0..w {
                if (DVec2::new(x as f64, y as f64) - c).length() <= r {
                    m.data[(y * w + x) as usize] = 1;
                }
            }
        }
        m
    }

    #[test]
    fn crops_hold_the_box_and_map_pixels_both_ways() {
        let b = PixelBox::new("v", [100.0, 50.0, 160.0, 90.0], 640, 480).unwrap();
        let c = Crop::around(&b, 0.5);
        assert_eq!(c.side, 120);
        assert!(c.holds(&b, 0.1, 0.2) && !c.holds(&b, 0.3, 0.2));
        // The box's centre is the crop's.
        let centre = c.to_crop(b.centre());
        assert!((centre - DVec2::splat(59.5)).length() <= 0.5, "{centre}");
        // A crop reaching past the image pads with the mean colour and drops it back.
        let img = Rgba {
            width: 4,
            height: 3,
            data: (0..48).map(|i| i as u8).collect(),
        };
        let c = Crop { x0: -1, y0: 1, side: 3 };
        let rgb = c.rgb(&img);
        assert_eq!(&rgb[0..3], &[124, 116, 104]);
        assert_eq!(&rgb[3..6], &img.data[16..19]); // pixel (0, 1)
        let mut cm = Mask::empty(3, 3);
        cm.data.fill(1);
        let m = c.to_image(&cm, 4, 3);
        assert_eq!(m.area(), 4); // columns 0–1 of rows 1–2
        assert!(m.get(0, 1) && m.get(1, 2) && !m.get(2, 1) && !m.get(0, 0));
    }

    #[test]
    fn a_box_redrawn_a_little_keeps_its_crop_and_one_moved_or_resized_gets_a_new_one() {
        let bx = |a: [f64; 4]| PixelBox::new("v", a, 640, 480).unwrap();
        let first = bx([100.0, 50.0, 200.0, 130.0]);
        let kept = Crop::around(&first, 0.15);
        assert_eq!((kept.x0, kept.y0, kept.side), (85, 25, 130));
        // No earlier crop: a new one.
        assert_eq!(Crop::kept_or_around(Crop { x0: 0, y0: 0, side: 0 }, &first, 0.15), kept);
        // Drawn 3 % tighter, shifted 4 px, or 20 % wider within it: the same pixels, so
        // the same encoding.
        for redrawn in [
            [103.0, 53.0, 197.0, 127.0],
            [104.0, 52.0, 204.0, 132.0],
            [90.0, 50.0, 210.0, 130.0],
        ] {
            assert_eq!(Crop::kept_or_around(kept, &bx(redrawn), 0.15), kept, "{redrawn:?}");
        }
        // Moved out of it, reaching within 3 % of its edge (3.9 px), or shrunk by more
        // than 1.25: a crop around the new box.
        for moved in [
            [150.0, 50.0, 250.0, 130.0],
            [100.0, 50.0, 213.0, 130.0],
            [100.0, 28.0, 200.0, 130.0],
            [110.0, 55.0, 188.0, 125.0],
        ] {
            let b = bx(moved);
            let c = Crop::kept_or_around(kept, &b, 0.15);
            assert_ne!(c, kept, "{moved:?}");
            assert_eq!(c, Crop::around(&b, 0.15), "{moved:?}");
        }
    }

    #[test]
    fn a_fitted_pose_prompts_inside_its_silhouette_and_against_the_masks_excess() {
        let sil = disc(80, 60, DVec2::new(40.0, 30.0), 10.0);
        // The previous mask: the disc plus a blob 15 px to its right (an occluder).
        let mut prev = sil.clone();
        for (i, p) in disc(80, 60, DVec2::new(62.0, 30.0), 5.0).data.iter().enumerate() {
            prev.data[i] |= p;
        }
        let crop = Crop {
            x0: 10,
            y0: 0,
            side: 60,
        };
        let logits = vec![0.5f32; 16];
        let job = from_pose(3, crop, &sil, Some((&prev, &logits))).unwrap();
        assert_eq!(job.view, 3);
        // The box: the silhouette's tight box, a pixel loose, in crop coordinates.
        let [x0, y0, x1, y1] = job.prompt_box;
        assert!(
            (x0 - 19.0).abs() <= 1.5 && (x1 - 41.0).abs() <= 1.5,
            "{:?}",
            job.prompt_box
        );
        assert!(
            (y0 - 19.0).abs() <= 1.5 && (y1 - 41.0).abs() <= 1.5,
            "{:?}",
            job.prompt_box
        );
        let on: Vec<_> = job.points.iter().filter(|p| p.object).collect();
        let off: Vec<_> = job.points.iter().filter(|p| !p.object).collect();
        assert_eq!((on.len(), off.len()), (1, 1));
        // On the object near the disc's centre (crop x = 40 − 10); off it in the blob.
        assert!((DVec2::from_array(on[0].at) - DVec2::new(30.0, 30.0)).length() <= 1.5);
        assert!(
            (DVec2::from_array(off[0].at) - DVec2::new(52.0, 30.0)).length() <= 2.0,
            "{:?}",
            off[0]
        );
        assert_eq!(job.previous.as_deref(), Some(&logits[..]));
        // Without a previous mask: the box and the positive point only.
        let first = from_pose(0, crop, &sil, None).unwrap();
        assert!(first.points.len() == 1 && first.points[0].object && first.previous.is_none());
        assert!(from_pose(0, crop, &Mask::empty(80, 60), None).is_none());
    }

    /// The prompt's points as the whole image gives them (the measure before windows):
    /// image coordinates, on the object or not.
    fn points_over_the_whole_image(sil: &Mask, prev: Option<&Mask>) -> Vec<([f64; 2], bool)> {
        let (w, h) = (sil.width as usize, sil.height as usize);
        let inside: Vec<bool> = sil.data.iter().map(|&s| s != 0).collect();
        let tight = PixelBox::of_mask(sil).unwrap();
        let mut out = Vec::new();
        let agree: Vec<bool> = match prev {
            Some(m) => inside.iter().zip(&m.data).map(|(&s, &m)| s && m != 0).collect(),
            None => inside.clone(),
        };
        if let Some((p, _)) = deepest(&agree, w, h).or_else(|| deepest(&inside, w, h)) {
            out.push((p.to_array(), true));
        }
        if let Some(m) = prev {
            let margin = (0.04 * tight.size().max_element()).max(3.0);
            let to_sil = edt::distance(w, h, &inside);
            let beyond: Vec<bool> = m
                .data
                .iter()
                .zip(&to_sil)
                .map(|(&m, &d)| m != 0 && d > margin)
                .collect();
            if let Some((p, _)) = deepest(&beyond, w, h) {
                out.push((p.to_array(), false));
            }
        }
        out
    }

    #[test]
    fn a_fitted_pose_s_points_are_the_whole_image_s() {
        let (w, h) = (160u32, 120u32);
        let union = |a: &Mask, b: &Mask| Mask {
            width: a.width,
            height: a.height,
            data: a.data.iter().zip(&b.data).map(|(&a, &b)| a | b).collect(),
        };
        let bar = |x0: u32, y0: u32, x1: u32, y1: u32| {
            let mut m = Mask::empty(w, h);
            for y in y0..y1 {
                for x in x0..x1 {
                    m.data[(y * w + x) as usize] = 1;
                }
            }
            m
        };
        let crop = Crop {
            x0: -20,
            y0: -30,
            side: 200,
        };
        let cases: Vec<(&str, Mask, Option<Mask>)> = vec![
            ("a disc alone", disc(w, h, DVec2::new(70.0, 50.0), 18.0), None),
            (
                "a disc and a mask beyond it",
                disc(w, h, DVec2::new(70.0, 50.0), 18.0),
                Some(union(&disc(w, h, DVec2::new(72.0, 52.0), 17.0), &bar(85, 40, 130, 62))),
            ),
            (
                "at the image's corner",
                union(&disc(w, h, DVec2::new(5.0, 4.0), 20.0), &bar(0, 0, 12, 40)),
                Some(union(&disc(w, h, DVec2::new(8.0, 6.0), 21.0), &bar(0, 30, 50, 38))),
            ),
            (
                "the previous mask far off and touching the far border",
                bar(30, 20, 70, 80),
                Some(union(&bar(32, 22, 70, 78), &bar(120, 60, 160, 120))),
            ),
            ("filling the image", bar(0, 0, w, h), Some(bar(0, 0, w, 100))),
        ];
        for (name, sil, prev) in &cases {
            let logits = [0.0f32; 4];
            let job = from_pose(0, crop, sil, prev.as_ref().map(|m| (m, &logits[..]))).unwrap();
            let got: Vec<([f64; 2], bool)> = job
                .points
                .iter()
                .map(|p| {
                    (
                        (DVec2::from_array(p.at) + DVec2::new(crop.x0 as f64, crop.y0 as f64)).to_array(),
                        p.object,
                    )
                })
                .collect();
            let want = points_over_the_whole_image(sil, prev.as_ref());
            assert_eq!(got.len(), want.len(), "{name}: {got:?} against {want:?}");
            for (g, e) in got.iter().zip(&want) {
                assert_eq!(g.1, e.1, "{name}");
                assert!(
                    (g.0[0] - e.0[0]).abs() < 1e-9 && (g.0[1] - e.0[1]).abs() < 1e-9,
                    "{name}: {got:?} against {want:?}"
                );
            }
            assert!(!got.is_empty() && got[0].1, "{name}: a point on the object");
        }
    }

    #[test]
    fn a_crop_s_mask_compares_with_the_image_s_as_placed_back() {
        let (w, h) = (90u32, 70u32);
        let reference = disc(w, h, DVec2::new(20.0, 30.0), 14.0);
        let area = reference.area();
        // Crops inside the image, past its top-left corner, past its bottom-right one.
        for crop in [
            Crop {
                x0: 5,
                y0: 10,
                side: 40,
            },
            Crop {
                x0: -12,
                y0: -8,
                side: 50,
            },
            Crop {
                x0: 60,
                y0: 45,
                side: 40,
            },
        ] {
            for (c, r) in [
                (DVec2::new(22.0, 20.0), 12.0),
                (DVec2::new(5.0, 5.0), 30.0),
                (DVec2::new(0.0, 0.0), 0.0),
            ] {
                let m = disc(crop.side, crop.side, c, r);
                let placed = crop.to_image(&m, w, h);
                let want = crate::metrics::hard_iou(&placed, &reference);
                let got = crop.iou_in_image(&m, &reference, area);
                assert!(
                    (got - want).abs() < 1e-12,
                    "{crop:?}, disc at {c} r {r}: {got} against {want}"
                );
                for (x, y) in [(0, 0), (10, 12), (25, 30), (70, 60), (89, 69)] {
                    assert_eq!(
                        crop.holds_pixel(&m, x, y),
                        placed.get(x as u32, y as u32),
                        "{crop:?} ({x}, {y})"
                    );
                }
            }
        }
        // Nothing in either: 0, as hard_iou says.
        let empty = Mask::empty(w, h);
        let c = Crop { x0: 0, y0: 0, side: 10 };
        assert_eq!(c.iou_in_image(&Mask::empty(10, 10), &empty, 0), 0.0);
    }
}
