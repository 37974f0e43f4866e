//! The boxes and points a person gives [`PhotoFit`] before and between the rounds: the
//! boxes drawn and those the geometry proposes ([`super::super::hints`]), the points
//! clicked on a view, and the first round's jobs warmed while the boxes are drawn.

use super::{PhotoFit, Slot, State};
use crate::camera::Camera;
use crate::error::{Error, Result};
use crate::segment::hints::{box_of_sphere, sphere_from_boxes};
use crate::segment::prompt::{Crop, PromptPoint, SegmentJob};
use crate::view::PixelBox;
use glam::DVec2;
use serde::Serialize;

/// A user's point clicked within this many pixels of an earlier one removes it.
pub const POINT_TOGGLE_PX: f64 = 6.0;

/// A drawn box whose longer side is more than this many times that of the box the
/// other views' geometry implies is too loose to prompt the segmenter with (a box
/// around the whole photograph says nothing of where the object is).
pub const LOOSE_BOX: f64 = 3.0;

/// One scene view's box, for a person drawing them (see [`PhotoFit::boxes`]).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ViewBox {
    /// The view's name.
    pub view: String,
    /// Whether the view has a mask already (given in the scene): it needs no box.
    pub has_mask: bool,
    /// The box drawn or given, image pixels `[x_min, y_min, x_max, y_max]`.
    pub given: Option<[f64; 4]>,
    /// For a view without one, the box the other views' geometry proposes (when at
    /// least two have a box or a mask).
    pub proposed: Option<[f64; 4]>,
    /// The user's points, `[x, y, 1 on the object | 0 off it]`, image pixel centres.
    pub points: Vec<[f64; 3]>,
}

impl PhotoFit {
    /// The views with a box or a mask: each one's camera, box (a mask's tight box) and name.
    pub(super) fn hinted(&self) -> Vec<(&Camera, PixelBox, &str)> {
        self.slots
            .iter()
            .filter_map(|s| match s {
                Slot::Given(v) => PixelBox::of_mask(v.mask()).map(|b| (v.camera(), b, v.name())),
                Slot::Made(m) => m.photo.hint.map(|b| (&m.photo.camera, b, m.photo.name.as_str())),
            })
            .collect()
    }

    /// For each view, when its drawn box is too loose ([`LOOSE_BOX`]) against the box
    /// the geometry of at least two other views with a box or a mask implies: that box
    /// (within the drawn one), and how many times longer the drawn box's longer side is.
    pub(super) fn loose_boxes(&self) -> Vec<Option<(PixelBox, f64)>> {
        let hinted = self.hinted();
        self.slots
            .iter()
            .map(|s| {
                let Slot::Made(m) = s else { return None };
                let drawn = m.photo.hint?;
                let others: Vec<_> = hinted.iter().filter(|h| h.2 != m.photo.name).copied().collect();
                if others.len() < 2 {
                    return None;
                }
                let (c, r) = sphere_from_boxes(&others).ok()?;
                let implied = box_of_sphere(&m.photo.name, &m.photo.camera, c, r).ok()?;
                let ratio = drawn.size().max_element() / implied.size().max_element();
                let within = PixelBox {
                    x0: implied.x0.max(drawn.x0),
                    y0: implied.y0.max(drawn.y0),
                    x1: implied.x1.min(drawn.x1),
                    y1: implied.y1.min(drawn.y1),
                };
                (ratio > LOOSE_BOX && within.x1 - within.x0 >= 1.0 && within.y1 - within.y0 >= 1.0)
                    .then_some((within, ratio))
            })
            .collect()
    }

    /// The sphere the hinted views' boxes and masks imply, when two or more have one.
    fn sphere(&self) -> Option<(glam::DVec3, f64)> {
        let hinted = self.hinted();
        (hinted.len() >= 2).then(|| sphere_from_boxes(&hinted).ok()).flatten()
    }

    /// Every view's box: given (drawn, or in the scene) or proposed by the geometry,
    /// and its points, in scene order.
    pub fn boxes(&self) -> Vec<ViewBox> {
        let sphere = self.sphere();
        self.slots
            .iter()
            .map(|s| match s {
                Slot::Given(v) => ViewBox {
                    view: v.name().into(),
                    has_mask: true,
                    given: None,
                    proposed: None,
                    points: Vec::new(),
                },
                Slot::Made(m) => ViewBox {
                    view: m.photo.name.clone(),
                    has_mask: false,
                    given: m.photo.hint.map(|b| b.to_array()),
                    proposed: match (m.photo.hint, sphere) {
                        (None, Some((c, r))) => box_of_sphere(&m.photo.name, &m.photo.camera, c, r)
                            .ok()
                            .map(|b| b.to_array()),
                        _ => None,
                    },
                    points: m
                        .points
                        .iter()
                        .map(|(p, on)| [p.x, p.y, f64::from(u8::from(*on))])
                        .collect(),
                },
            })
            .collect()
    }

    /// Draws (or, with `None`, removes) view `view`'s box, image pixels
    /// `[x_min, y_min, x_max, y_max]`. Before the first round it is the box the view
    /// is first prompted with; once the rounds are over, the view is segmented again
    /// from it (its points kept) and the masks refitted.
    ///
    /// Errors: a bad box (named by view), a view with a mask, or a round under way.
    pub fn set_box(&mut self, view: usize, b: Option<[f64; 4]>) -> Result<()> {
        let state = self.state;
        if !matches!(state, State::Boxes | State::Done) {
            return Err(Error::Settings(
                "photographs: boxes can be changed before the fit starts or once it is done".into(),
            ));
        }
        let margin = self.photo.crop_margin;
        let m = self.made(view)?;
        let b = b
            .map(|b| PixelBox::new(&m.photo.name, b, m.photo.camera.width, m.photo.camera.height))
            .transpose()?;
        if state == State::Done {
            let Some(b) = b else {
                return Err(Error::View {
                    view: m.photo.name.clone(),
                    problem: "once fitted, a view's box can be redrawn but not removed".into(),
                });
            };
            // The last round's crop while it frames the box: its encoding is kept.
            m.crop = Crop::kept_or_around(m.crop, &b, margin);
            m.reference = None;
            let mut job = SegmentJob::from_box(view, m.crop, &b);
            add_points(&mut job, &m.points);
            self.pending = vec![job];
            self.state = State::Segment;
        }
        let m = self.made(view)?;
        m.photo.hint = b;
        Ok(())
    }

    /// Adds a point on (`object`) or off the object at image pixel `(x, y)` of view
    /// `view` — or, within [`POINT_TOGGLE_PX`] of one of its points, removes that one.
    /// Before the first round the points join the first prompts; once the rounds are
    /// over, the view is segmented again (prompted from the fitted pose and all its
    /// points) and the masks refitted.
    ///
    /// Errors: a point off the image or not finite, a view with a mask, or a round
    /// under way.
    pub fn toggle_point(&mut self, view: usize, x: f64, y: f64, object: bool) -> Result<()> {
        let state = self.state;
        if !matches!(state, State::Boxes | State::Done) {
            return Err(Error::Settings(
                "photographs: points can be added before the fit starts or once it is done".into(),
            ));
        }
        self.made(view)?;
        let (mesh, fitted, margin) = (&self.mesh, self.fitted, self.photo.crop_margin);
        let Some(Slot::Made(m)) = self.slots.get_mut(view) else {
            unreachable!("made() errs for every other slot");
        };
        let (w, h) = (m.photo.camera.width as f64, m.photo.camera.height as f64);
        if !(x.is_finite() && y.is_finite() && x > -0.5 && y > -0.5 && x < w - 0.5 && y < h - 0.5) {
            return Err(Error::View {
                view: m.photo.name.clone(),
                problem: format!("point ({x}, {y}) is not on the {w}×{h} photograph"),
            });
        }
        let p = DVec2::new(x, y);
        match m.points.iter().position(|(q, _)| (*q - p).length() <= POINT_TOGGLE_PX) {
            Some(i) => {
                m.points.remove(i);
            }
            None => m.points.push((p, object)),
        }
        if state == State::Done {
            let Some(pose) = fitted else {
                unreachable!("a done fit has a pose");
            };
            let job = super::reprompt(mesh, &pose, view, m, margin);
            self.pending = vec![job];
            self.state = State::Segment;
        }
        Ok(())
    }

    /// Before [`PhotoFit::start`], the first round's jobs as they stand — the same
    /// crops and prompts `start` will ask for: of the views with a box (the geometry's
    /// within it when it is three times too loose), and, once two views have a box
    /// or a mask, of the others from the box the geometry proposes —
    /// so that a segmenter can encode their crops while the user still looks at the
    /// boxes. Empty once started.
    pub fn warm_jobs(&self) -> Vec<SegmentJob> {
        if self.state != State::Boxes {
            return Vec::new();
        }
        let sphere = self.sphere();
        self.slots
            .iter()
            .enumerate()
            .zip(self.loose_boxes())
            .filter_map(|((i, s), loose)| match s {
                Slot::Made(m) => {
                    let b = match (m.photo.hint, sphere, loose) {
                        (Some(_), _, Some((within, _))) => within,
                        (Some(b), _, None) => b,
                        (None, Some((c, r)), _) => box_of_sphere(&m.photo.name, &m.photo.camera, c, r).ok()?,
                        (None, None, _) => return None,
                    };
                    let mut job = SegmentJob::from_box(i, Crop::around(&b, self.photo.crop_margin), &b);
                    add_points(&mut job, &m.points);
                    Some(job)
                }
                Slot::Given(_) => None,
            })
            .collect()
    }
}

/// The user's points of a view, in a job's crop (those inside it).
pub(super) fn add_points(job: &mut SegmentJob, points: &[(DVec2, bool)]) {
    let side = job.crop.side as f64;
    for &(p, object) in points {
        let at = job.crop.to_crop(p);
        if at.x >= 0.0 && at.y >= 0.0 && at.x < side && at.y < side {
            job.points.push(PromptPoint {
                at: at.to_array(),
                object,
            });
        }
    }
}
