//! [`PhotoSession`]: photographs in, pose out, as the page drives it — the core's
//! [`PhotoFit`] over a scene whose views give photographs instead of masks. The page
//! shows each photograph (`picture`), takes the boxes a person drags
//! (`setBox`; `boxes` says which the geometry proposes for the others), then starts
//! the rounds: `jobs()` are the segmentations to run (each a crop's RGB pixels and the
//! prompt, in the segmenter's coordinates, for the segmenter's own wasm module in the
//! page's Workers), `answer(answers)` takes them and returns the round's fit as a
//! [`Session`] to step like any other; when that fit is done, `advance(session)`
//! prompts again from its pose, or ends the rounds. Once done, `togglePoint` (a click
//! on a view) or `setBox` asks for one more round.

use super::{to_js, FileSet, Session};
use crate::error::{Error, Result};
use crate::estimator::FitSettings;
use crate::io::scene::Scene;
use crate::pose::Pose;
use crate::segment::{MaskCandidate, PhotoFit, PhotoSettings, SegmentJob, SegmentOutput};
use crate::Mask;
use serde::Serialize;
use wasm_bindgen::prelude::*;

/// The most readings one answer may carry.
const MAX_READINGS: usize = 16;
/// The segmenter's low-resolution logits per reading.
const LOGITS: usize = 256 * 256;

/// Photographs in, pose out (see the module doc).
#[wasm_bindgen]
pub struct PhotoSession {
    fit: PhotoFit,
    names: Vec<(String, u32, u32, bool)>,
    ground_truth: Option<Pose>,
    grasps: Vec<crate::app::grasp::Grasp>,
    warnings: Vec<String>,
}

#[derive(Serialize)]
struct PhotoViewInfo<'a> {
    name: &'a str,
    width: u32,
    height: u32,
    has_mask: bool,
}

impl PhotoSession {
    fn from_loaded(scene: Scene, warnings: Vec<String>) -> Result<PhotoSession> {
        let names = (0..scene.views.len() + scene.photos.len())
            .map(|i| match scene.photos.iter().find(|p| p.index == i) {
                Some(p) => (p.name.clone(), p.camera.width, p.camera.height, false),
                None => {
                    let k = i - scene.photos.iter().filter(|p| p.index < i).count();
                    let v = &scene.views[k];
                    (v.name().to_string(), v.camera().width, v.camera().height, true)
                }
            })
            .collect();
        let (ground_truth, grasps) = (scene.ground_truth_pose, scene.grasps.clone());
        let fit = PhotoFit::prepare(scene, FitSettings::default(), PhotoSettings::default())?;
        Ok(PhotoSession {
            fit,
            names,
            ground_truth,
            grasps,
            warnings,
        })
    }

    fn to_js_jobs(&self, jobs: &[SegmentJob]) -> Result<js_sys::Array, JsError> {
        let out = js_sys::Array::new();
        for job in jobs {
            let image = self
                .fit
                .image(job.view)
                .ok_or_else(|| JsError::new("internal error: a job for a view without a photograph"))?;
            let o = js_sys::Object::new();
            let b = job.prompt_box.map(|v| v as f32);
            let points: Vec<f32> = job.segmenter_points().into_iter().flatten().collect();
            let set = |key: &str, v: JsValue| {
                js_sys::Reflect::set(&o, &key.into(), &v)
                    .map(|_| ())
                    .map_err(|_| JsError::new("internal error: cannot build a job"))
            };
            set("view", job.view.into())?;
            set("side", job.crop.side.into())?;
            // Where the crop is (its pixels are `rgb`): the pool sends a crop it has
            // encoded before to the Worker that holds its encoding.
            set(
                "crop",
                format!("{},{},{}", job.crop.x0, job.crop.y0, job.crop.side).into(),
            )?;
            set("rgb", js_sys::Uint8Array::from(job.crop.rgb(image).as_slice()).into())?;
            set("box", js_sys::Float32Array::from(&b[..]).into())?;
            set("points", js_sys::Float32Array::from(points.as_slice()).into())?;
            let previous = match &job.previous {
                Some(p) => js_sys::Float32Array::from(p.as_slice()).into(),
                None => JsValue::UNDEFINED,
            };
            set("previous", previous)?;
            out.push(&o);
        }
        Ok(out)
    }

    fn output(view: &str, side: u32, answer: &JsValue) -> Result<SegmentOutput> {
        let bad = |problem: String| Error::View {
            view: view.into(),
            problem: format!("the segmenter's answer: {problem}"),
        };
        let get = |key: &str| js_sys::Reflect::get(answer, &key.into()).unwrap_or(JsValue::UNDEFINED);
        let number = |key: &str| -> Result<usize> {
            get(key)
                .as_f64()
                .filter(|v| v.fract() == 0.0 && *v >= 0.0 && *v <= 1e9)
                .map(|v| v as usize)
                .ok_or_else(|| bad(format!("'{key}' is not a whole number")))
        };
        let count = number("count")?;
        let preferred = number("preferred")?;
        if count == 0 || count > MAX_READINGS || preferred >= count {
            return Err(bad(format!("{count} readings, preferred {preferred}")));
        }
        let px = (side * side) as usize;
        let masks = get("masks")
            .dyn_into::<js_sys::Uint8Array>()
            .map_err(|_| bad("'masks' is not a Uint8Array".into()))?;
        let logits = get("logits")
            .dyn_into::<js_sys::Float32Array>()
            .map_err(|_| bad("'logits' is not a Float32Array".into()))?;
        let scores = get("scores")
            .dyn_into::<js_sys::Float32Array>()
            .map_err(|_| bad("'scores' is not a Float32Array".into()))?;
        if masks.length() as usize != count * px
            || logits.length() as usize != count * LOGITS
            || scores.length() as usize != count
        {
            return Err(bad(format!(
                "{} mask bytes, {} logits and {} scores for {count} readings of a {side}² crop",
                masks.length(),
                logits.length(),
                scores.length()
            )));
        }
        let (masks, logits, scores) = (masks.to_vec(), logits.to_vec(), scores.to_vec());
        let candidates = (0..count)
            .map(|k| MaskCandidate {
                mask: Mask {
                    width: side,
                    height: side,
                    data: masks[k * px..(k + 1) * px].iter().map(|&v| u8::from(v != 0)).collect(),
                },
                logits: logits[k * LOGITS..(k + 1) * LOGITS].to_vec(),
                score: scores[k],
            })
            .collect();
        Ok(SegmentOutput { candidates, preferred })
    }
}

#[wasm_bindgen]
impl PhotoSession {
    /// A photograph session from dropped or chosen files (as `Session.fromFiles`, but
    /// views may give a photograph instead of a mask; see `FileSet.needsSegmenter`).
    /// Throws an `Error` naming what is missing, or that every view has a mask.
    #[wasm_bindgen(js_name = fromFiles)]
    pub fn from_files(files: &FileSet) -> Result<PhotoSession, JsError> {
        let (scene, warnings, _) = files.inner().load()?;
        Ok(PhotoSession::from_loaded(scene, warnings)?)
    }

    /// A photograph session from a scene file's text and the files it names.
    #[wasm_bindgen(js_name = fromScene)]
    pub fn from_scene(scene_file: &str, scene_text: &str, files: &FileSet) -> Result<PhotoSession, JsError> {
        let (scene, warnings) = files.load_scene(scene_file, scene_text)?;
        Ok(PhotoSession::from_loaded(scene, warnings)?)
    }

    /// Each view's name and size, and whether it has a mask already.
    #[wasm_bindgen(unchecked_return_type = "PhotoViewInfo[]")]
    pub fn views(&self) -> Result<JsValue, JsError> {
        let info: Vec<PhotoViewInfo> = self
            .names
            .iter()
            .map(|(name, width, height, has_mask)| PhotoViewInfo {
                name,
                width: *width,
                height: *height,
                has_mask: *has_mask,
            })
            .collect();
        to_js(&info)
    }

    /// What was left out or changed when the session was made.
    pub fn warnings(&self) -> Vec<String> {
        let mut w = self.warnings.clone();
        w.extend(self.fit.warnings().iter().cloned());
        w
    }

    /// View `view`'s photograph as RGBA8, scaled down (by whole-pixel area averages)
    /// so that its longer side is at most `max_side` (at least 16): `{width, height,
    /// scale (picture pixels per image pixel), rgba}`. A view with a mask has none.
    #[wasm_bindgen(unchecked_return_type = "{ width: number; height: number; scale: number; rgba: Uint8Array }")]
    pub fn picture(&self, view: usize, max_side: u32) -> Result<JsValue, JsError> {
        let image = self
            .fit
            .image(view)
            .ok_or_else(|| JsError::new(&format!("view {view} has no photograph to show")))?;
        let (w, h) = (image.width, image.height);
        let k = ((w.max(h) as f64) / max_side.max(16) as f64).ceil().max(1.0) as u32;
        let (pw, ph) = (w.div_ceil(k), h.div_ceil(k));
        // An area average (each picture pixel the mean of the k² it covers).
        let full = image::RgbaImage::from_raw(w, h, image.data.clone())
            .ok_or_else(|| JsError::new(&format!("view {view}: the photograph's buffer is not {w}×{h} RGBA")))?;
        let rgba = if k == 1 {
            full.into_raw()
        } else {
            image::imageops::thumbnail(&full, pw, ph).into_raw()
        };
        let o = js_sys::Object::new();
        let set = |key: &str, v: JsValue| {
            js_sys::Reflect::set(&o, &key.into(), &v)
                .map(|_| ())
                .map_err(|_| JsError::new("internal error: cannot build the picture"))
        };
        set("width", pw.into())?;
        set("height", ph.into())?;
        set("scale", (1.0 / k as f64).into())?;
        set("rgba", js_sys::Uint8Array::from(rgba.as_slice()).into())?;
        Ok(o.into())
    }

    /// Every view's box: `[{view, has_mask, given, proposed, points}]` — the box drawn
    /// (or given in the scene), the one the other views' geometry proposes for a view
    /// without one (once two views have one), and the points clicked.
    #[wasm_bindgen(unchecked_return_type = "ViewBox[]")]
    pub fn boxes(&self) -> Result<JsValue, JsError> {
        to_js(&self.fit.boxes())
    }

    /// Draws view `view`'s box (`[x_min, y_min, x_max, y_max]`, image pixels) or, with
    /// `null`, removes it. Before `start` it is the view's first prompt; once the rounds
    /// are done, the view is segmented again from it (see `jobs`). Throws for a box off
    /// the photograph, inverted or empty, naming the view.
    #[wasm_bindgen(js_name = setBox)]
    pub fn set_box(&mut self, view: usize, b: Option<Vec<f64>>) -> Result<(), JsError> {
        let b = match b {
            None => None,
            Some(v) if v.len() == 4 => Some([v[0], v[1], v[2], v[3]]),
            Some(v) => return Err(JsError::new(&format!("setBox: a box is 4 numbers, not {}", v.len()))),
        };
        Ok(self.fit.set_box(view, b)?)
    }

    /// Adds a point on (`object`) or off the object at image pixel `(x, y)` of view
    /// `view`, or removes the view's point within 6 pixels of it. Once the rounds are
    /// done, the view is segmented again (see `jobs`).
    #[wasm_bindgen(js_name = togglePoint)]
    pub fn toggle_point(&mut self, view: usize, x: f64, y: f64, object: bool) -> Result<(), JsError> {
        Ok(self.fit.toggle_point(view, x, y, object)?)
    }

    /// Starts the rounds: boxes from the geometry for the views without one, and the
    /// first segmentations. Throws, naming the view, when a view has no box and fewer
    /// than two others have one.
    pub fn start(&mut self) -> Result<(), JsError> {
        Ok(self.fit.start()?)
    }

    /// Whether `start` has been called.
    #[wasm_bindgen(getter)]
    pub fn started(&self) -> bool {
        self.fit.is_started()
    }

    /// The segmentations to run now, in order: `[{view, side, rgb (side²·3 bytes),
    /// box (4), points ([x, y, label] triples), previous (256² logits, or undefined)}]`,
    /// in the segmenter's coordinates (pixel edges); empty while a round's fit runs or
    /// once done.
    pub fn jobs(&self) -> Result<js_sys::Array, JsError> {
        self.to_js_jobs(self.fit.pending())
    }

    /// Before `start`, the first round's segmentations of the views that have a box
    /// already (as `jobs` gives them; `start` asks for the same crops): a segmenter may
    /// encode them while the other boxes are drawn. Empty once started.
    #[wasm_bindgen(js_name = warmJobs)]
    pub fn warm_jobs(&self) -> Result<js_sys::Array, JsError> {
        self.to_js_jobs(&self.fit.warm_jobs())
    }

    /// Takes the answers to `jobs()`, in order — each `{count, preferred, masks
    /// (count·side² bytes, 1 = object), logits (count·65536), scores (count)}`, as the
    /// segmenter module's `Segmentation` gives them — and returns the round's fit to
    /// step. Throws for answers that do not fit the jobs (nothing is then taken).
    pub fn answer(&mut self, answers: Vec<JsValue>) -> Result<Session, JsError> {
        let pending = self.fit.pending();
        if answers.len() != pending.len() {
            return Err(JsError::new(&format!(
                "answer: {} answers for {} segmentations asked",
                answers.len(),
                pending.len()
            )));
        }
        let outputs = pending
            .iter()
            .zip(&answers)
            .map(|(job, a)| PhotoSession::output(&self.names[job.view].0, job.crop.side, a))
            .collect::<Result<Vec<_>>>()?;
        let est = self.fit.answer(outputs)?;
        let mut session = Session::with_estimator(est, self.ground_truth, self.grasps.clone());
        session.set_warnings(self.warnings());
        Ok(session)
    }

    /// After the round's fit (`session`, from `answer`) is done: prompts again from its
    /// pose (see `jobs`), or ends the rounds (`done`). Throws if it is not done.
    pub fn advance(&mut self, session: &Session) -> Result<(), JsError> {
        Ok(self.fit.advance(session.estimator())?)
    }

    /// Whether the rounds are over (until a point or a box asks for another).
    #[wasm_bindgen(getter)]
    pub fn done(&self) -> bool {
        self.fit.is_done()
    }

    /// Segmentation rounds answered so far.
    #[wasm_bindgen(getter)]
    pub fn rounds(&self) -> usize {
        self.fit.rounds()
    }

    /// The result of `session` (the last round's fit) with the made masks' reports
    /// (SPEC §3), as pretty JSON text.
    #[wasm_bindgen(js_name = resultJson)]
    pub fn result_json(&self, session: &Session) -> Result<String, JsError> {
        let r = self
            .fit
            .result(session.estimator(), session.seconds(), self.ground_truth.as_ref());
        serde_json::to_string_pretty(&r).map_err(|e| JsError::new(&format!("internal error: {e}")))
    }

    /// The result of `session` with the made masks' reports, as an object.
    #[wasm_bindgen(unchecked_return_type = "FitResult")]
    pub fn result(&self, session: &Session) -> Result<JsValue, JsError> {
        to_js(
            &self
                .fit
                .result(session.estimator(), session.seconds(), self.ground_truth.as_ref()),
        )
    }
}
