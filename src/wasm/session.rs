//! [`Session`]: the fit as JavaScript drives it — stepping (by count or by time
//! budget, timed with `Date.now()`), progress with the pose and full-resolution IoUs,
//! per-view overlays for `ImageData`, the loss trace and the result (SPEC §3).

use super::shard::{parse_request, MAX_SHARDS};
use super::{to_js, FileSet};
use crate::app::overlay;
use crate::error::Result;
use crate::estimator::{Estimator, FitSettings, PoseOut, Progress, Response, ViewFigures};
use crate::mesh::Mesh;
use crate::pose::Pose;
use crate::view::View;
use serde::Serialize;
use wasm_bindgen::prelude::*;
use wasm_bindgen::Clamped;

/// A fit in progress: the estimator, the time spent stepping it, the loss of every
/// refinement iteration, and the views' IoUs and figures at the current pose (each
/// cached until the next step).
#[wasm_bindgen]
pub struct Session {
    est: Estimator,
    initial_pose: Option<Pose>,
    ground_truth: Option<Pose>,
    seconds: f64,
    losses: Vec<f64>,
    iteration: usize,
    figures: Option<Vec<ViewFigures>>,
    ious: Option<Vec<f64>>,
    /// When the pending [`Session::request`] was made (`Date.now()`, ms), for the time
    /// a pool's step takes.
    requested_at: Option<f64>,
    warnings: Vec<String>,
    grasps: Vec<crate::app::grasp::Grasp>,
}

/// Progress as JavaScript sees it: the core's, plus the pose and full-resolution IoUs.
#[derive(Serialize)]
struct ProgressOut<'a> {
    #[serde(flatten)]
    core: &'a Progress,
    pose: PoseOut,
    /// The pose's object-to-world 4×4, rows.
    matrix: [[f64; 4]; 4],
    stages: usize,
    done: bool,
    seconds: f64,
    iou: Vec<f64>,
    verdict_reasons: Vec<String>,
    doubted_views: Vec<String>,
}

#[derive(Serialize)]
struct ViewInfo<'a> {
    name: &'a str,
    width: u32,
    height: u32,
    has_image: bool,
}

impl Session {
    /// A session over a loaded mesh and views.
    pub fn new(
        mesh: Mesh,
        views: Vec<View>,
        initial_pose: Option<Pose>,
        ground_truth: Option<Pose>,
    ) -> Result<Session> {
        let est = Estimator::new(mesh, views, initial_pose, FitSettings::default())?;
        Ok(Session {
            est,
            initial_pose,
            ground_truth,
            seconds: 0.0,
            losses: Vec::new(),
            iteration: 0,
            figures: None,
            ious: None,
            requested_at: None,
            warnings: Vec::new(),
            grasps: Vec::new(),
        })
    }

    /// A session over an estimator made elsewhere (a round of a photograph session).
    pub fn with_estimator(
        est: Estimator,
        ground_truth: Option<Pose>,
        grasps: Vec<crate::app::grasp::Grasp>,
    ) -> Session {
        Session {
            est,
            initial_pose: None,
            ground_truth,
            seconds: 0.0,
            losses: Vec::new(),
            iteration: 0,
            figures: None,
            ious: None,
            requested_at: None,
            warnings: Vec::new(),
            grasps,
        }
    }

    /// Sets what `warnings()` reports.
    pub fn set_warnings(&mut self, warnings: Vec<String>) {
        self.warnings = warnings;
    }

    fn from_loaded(scene: crate::io::scene::Scene, warnings: Vec<String>) -> Result<Session> {
        scene.require_masks("the page")?;
        let mut session = Session::new(scene.mesh, scene.views, scene.initial_pose, scene.ground_truth_pose)?;
        session.warnings = warnings;
        session.grasps = scene.grasps;
        Ok(session)
    }

    /// The estimator.
    pub fn estimator(&self) -> &Estimator {
        &self.est
    }

    /// The estimator, to change what it may change before the fit ends.
    pub fn estimator_mut(&mut self) -> &mut Estimator {
        &mut self.est
    }

    /// One step, with the bookkeeping of every step.
    fn step_once(&mut self) -> Result<Progress> {
        let p = self.est.step()?;
        self.requested_at = None;
        self.stepped(&p);
        Ok(p)
    }

    /// The bookkeeping after a step, done here or by a pool of shards: the loss of an
    /// optimiser iteration recorded, the views' figures invalidated.
    fn stepped(&mut self, p: &Progress) {
        if p.iteration > self.iteration {
            self.iteration = p.iteration;
            self.losses.push(p.loss);
        }
        self.figures = None;
        self.ious = None;
    }

    /// The views' full-resolution figures at the current pose
    /// ([`Estimator::view_figures`], computed once per step).
    fn figures(&mut self) -> &[ViewFigures] {
        let est = &self.est;
        self.figures.get_or_insert_with(|| est.view_figures(&est.pose()))
    }

    /// Full-resolution hard IoU per view at the current pose ([`Estimator::view_ious`]:
    /// without the contour distances, which a frame does not show).
    pub fn full_ious(&mut self) -> Vec<f64> {
        let est = &self.est;
        self.ious.get_or_insert_with(|| est.view_ious(&est.pose())).clone()
    }

    fn progress_out(&mut self, p: &Progress) -> Result<JsValue, JsError> {
        let iou = self.full_ious();
        to_js(&ProgressOut {
            core: p,
            pose: PoseOut::from_pose(&p.pose),
            matrix: crate::pose::mat4_to_rows(p.pose.matrix()),
            stages: self.est.settings().stages.len(),
            done: self.est.is_done(),
            seconds: self.seconds,
            iou,
            verdict_reasons: self.est.judgement().map(|j| j.reasons.clone()).unwrap_or_default(),
            doubted_views: self
                .est
                .judgement()
                .map(|j| j.doubted_views.clone())
                .unwrap_or_default(),
        })
    }
}

#[wasm_bindgen]
impl Session {
    /// A session from a scene file's text and the files it names (mesh, masks, images),
    /// matched by path relative to the scene file, then by file name.
    #[wasm_bindgen(js_name = fromScene)]
    pub fn from_scene(scene_file: &str, scene_text: &str, files: &FileSet) -> Result<Session, JsError> {
        let (scene, warnings) = files.load_scene(scene_file, scene_text)?;
        Ok(Session::from_loaded(scene, warnings)?)
    }

    /// A session from dropped or chosen files, whatever they are: a `scene.json` and
    /// the files it names, or one camera JSON per view with masks (and images) and the
    /// mesh; which file is which is decided in Rust (`io::fileset`). Throws an `Error`
    /// naming what is missing or ambiguous, or, for a mesh alone, that it lacks a scene.
    #[wasm_bindgen(js_name = fromFiles)]
    pub fn from_files(files: &FileSet) -> Result<Session, JsError> {
        let (scene, warnings, _) = files.inner().load()?;
        Ok(Session::from_loaded(scene, warnings)?)
    }

    /// The number of views.
    #[wasm_bindgen(getter, js_name = viewCount)]
    pub fn view_count(&self) -> usize {
        self.est.views().len()
    }

    /// Each view's name and size.
    #[wasm_bindgen(unchecked_return_type = "ViewInfo[]")]
    pub fn views(&self) -> Result<JsValue, JsError> {
        let info: Vec<ViewInfo> = self
            .est
            .views()
            .iter()
            .map(|v| ViewInfo {
                name: v.name(),
                width: v.camera().width,
                height: v.camera().height,
                has_image: v.image().is_some(),
            })
            .collect();
        to_js(&info)
    }

    /// Does `n` units of work (each a batch of search candidates or one optimiser
    /// iteration; fewer once the fit is done) and reports where the fit stands.
    #[wasm_bindgen(unchecked_return_type = "Progress")]
    pub fn step(&mut self, n: u32) -> Result<JsValue, JsError> {
        let t0 = js_sys::Date::now();
        let mut p = None;
        for _ in 0..n {
            if self.est.is_done() {
                break;
            }
            p = Some(self.step_once()?);
        }
        self.seconds += (js_sys::Date::now() - t0) / 1000.0;
        let p = p.unwrap_or_else(|| self.est.progress());
        self.progress_out(&p)
    }

    /// Steps until `budget_ms` milliseconds have passed (at least one step) or the fit
    /// is done; reports where the fit stands.
    #[wasm_bindgen(js_name = stepFor, unchecked_return_type = "Progress")]
    pub fn step_for(&mut self, budget_ms: f64) -> Result<JsValue, JsError> {
        let t0 = js_sys::Date::now();
        let mut p = None;
        while !self.est.is_done() {
            p = Some(self.step_once()?);
            if js_sys::Date::now() - t0 >= budget_ms {
                break;
            }
        }
        self.seconds += (js_sys::Date::now() - t0) / 1000.0;
        let p = p.unwrap_or_else(|| self.est.progress());
        self.progress_out(&p)
    }

    /// The work the next step needs, for a pool of Workers each holding a `Shard` (the
    /// same step `step(1)` would do here): an opaque plain object to split with
    /// `splitRequest` and hand to the shards; `undefined` once the fit is done. The time
    /// until `respond` counts as stepping time.
    pub fn request(&mut self) -> Result<JsValue, JsError> {
        match self.est.request() {
            Some(r) => {
                self.requested_at = Some(js_sys::Date::now());
                to_js(&r)
            }
            None => Ok(JsValue::UNDEFINED),
        }
    }

    /// `request` split for `n` shards (1–64), in shard order: a search batch into up to
    /// `n` contiguous slices (fewer when it is small: the first shards take them), an
    /// evaluation `n` times (each shard computes the views it owns).
    #[wasm_bindgen(js_name = splitRequest)]
    pub fn split_request(&self, request: JsValue, n: u32) -> Result<Vec<JsValue>, JsError> {
        if n == 0 || n > MAX_SHARDS {
            return Err(JsError::new(&format!("splitRequest: {n} shards (1 to {MAX_SHARDS})")));
        }
        let request = parse_request(request)?;
        request.split(n as usize).iter().map(to_js).collect()
    }

    /// Completes the step `request` asked for with the shards' responses (every view's
    /// part of an evaluation, once; every rotation of a search batch), with the same
    /// bookkeeping as `step` (loss trace, iteration count, time); returns whether the
    /// fit is done. Unlike `step`, it reports no `Progress`: that renders every view at
    /// full resolution (its IoUs), which a pool stepping many times per frame would pay at
    /// every step; ask `progress()` when showing a frame. Throws an `Error` for
    /// responses that do not answer the current request (the fit then stays where it was).
    pub fn respond(&mut self, responses: Vec<JsValue>) -> Result<bool, JsError> {
        let t0 = js_sys::Date::now();
        let responses = responses
            .into_iter()
            .map(|r| {
                serde_wasm_bindgen::from_value::<Response>(r)
                    .map_err(|e| JsError::new(&format!("respond: not a response: {e}")))
            })
            .collect::<Result<Vec<_>, _>>()?;
        let p = self.est.respond(responses)?;
        let since = self.requested_at.take().unwrap_or(t0);
        self.seconds += (js_sys::Date::now() - since) / 1000.0;
        self.stepped(&p);
        Ok(self.est.is_done())
    }

    /// Where the fit stands, without stepping.
    #[wasm_bindgen(unchecked_return_type = "Progress")]
    pub fn progress(&mut self) -> Result<JsValue, JsError> {
        let p = self.est.progress();
        self.progress_out(&p)
    }

    /// What was left out when the session was made (images not given).
    pub fn warnings(&self) -> Vec<String> {
        self.warnings.clone()
    }

    /// Whether the fit has finished.
    #[wasm_bindgen(getter)]
    pub fn done(&self) -> bool {
        self.est.is_done()
    }

    /// Seconds spent stepping so far.
    #[wasm_bindgen(getter)]
    pub fn seconds(&self) -> f64 {
        self.seconds
    }

    /// The current pose (the best so far once done).
    #[wasm_bindgen(unchecked_return_type = "PoseOut")]
    pub fn pose(&self) -> Result<JsValue, JsError> {
        to_js(&PoseOut::from_pose(&self.est.pose()))
    }

    /// The loss of every refinement iteration so far, all candidates, in order.
    pub fn losses(&self) -> Vec<f64> {
        self.losses.clone()
    }

    /// Full-resolution hard IoU per view at the current pose.
    #[wasm_bindgen(js_name = viewIou)]
    pub fn view_iou(&mut self) -> Vec<f64> {
        self.full_ious()
    }

    /// View `view`'s overlay at the current pose: its image (or mask), the mask's
    /// outline and the rendered contour, RGBA8, the view's width × height, for `ImageData`.
    pub fn overlay(&mut self, view: usize) -> Result<Clamped<Vec<u8>>, JsError> {
        let n = self.est.views().len();
        if view >= n {
            return Err(JsError::new(&format!("no view {view}: the session has {n} views")));
        }
        let rendered = self.figures()[view].rendered.clone();
        let v = &self.est.views()[view];
        let mut img = overlay::overlay(v, Some(&rendered));
        // The scene's grasps, carried by the current pose into this view.
        crate::app::grasp::draw_grasps(&mut img, &self.grasps, &self.est.pose(), v.camera());
        Ok(Clamped(img.data))
    }

    /// Each view's window (image pixels, pixel centres at integers: the window covers
    /// `[x0, x0 + width] × [y0, y0 + height]`): `overlayWindow(v, size)`'s canvas pixel
    /// `(x, y)` shows image point `(x0 + (x + ½)·width/size, y0 + (y + ½)·height/size)`.
    #[wasm_bindgen(unchecked_return_type = "{ x0: number; y0: number; width: number; height: number }[]")]
    pub fn windows(&self) -> Result<JsValue, JsError> {
        #[derive(Serialize)]
        struct W {
            x0: f64,
            y0: f64,
            width: f64,
            height: f64,
        }
        let w: Vec<W> = self
            .est
            .windows()
            .iter()
            .map(|w| W {
                x0: w.x0,
                y0: w.y0,
                width: w.width,
                height: w.height,
            })
            .collect();
        to_js(&w)
    }

    /// View `view`'s object window at the current pose, `size`×`size` RGBA8 (8–2048):
    /// the window's part of the image enlarged, the mask's outline and the contour of
    /// the mesh rendered through the window at that size, and the grasps.
    #[wasm_bindgen(js_name = overlayWindow)]
    pub fn overlay_window(&mut self, view: usize, size: u32) -> Result<Clamped<Vec<u8>>, JsError> {
        let n = self.est.views().len();
        if view >= n {
            return Err(JsError::new(&format!("no view {view}: the session has {n} views")));
        }
        let pose = self.est.pose();
        let v = &self.est.views()[view];
        let window = self.est.windows()[view];
        let (mut img, cam) = overlay::overlay_window(
            v,
            &window,
            size,
            Some((self.est.mesh(), &pose)),
            &overlay::OverlayStyle::default(),
        );
        crate::app::grasp::draw_grasps(&mut img, &self.grasps, &pose, &cam);
        Ok(Clamped(img.data))
    }

    /// The result (SPEC §3) at the current pose, as an object.
    #[wasm_bindgen(unchecked_return_type = "FitResult")]
    pub fn result(&self) -> Result<JsValue, JsError> {
        to_js(&self.est.result(self.seconds, self.ground_truth.as_ref()))
    }

    /// The result (SPEC §3) at the current pose, as pretty JSON text.
    #[wasm_bindgen(js_name = resultJson)]
    pub fn result_json(&self) -> Result<String, JsError> {
        let r = self.est.result(self.seconds, self.ground_truth.as_ref());
        serde_json::to_string_pretty(&r).map_err(|e| JsError::new(&format!("internal error: {e}")))
    }

    /// Starts the fit again from the beginning (same inputs, time and losses cleared).
    pub fn reset(&mut self) -> Result<(), JsError> {
        let est = Estimator::new(
            self.est.mesh().clone(),
            self.est.input_views().to_vec(),
            self.initial_pose,
            self.est.settings().clone(),
        )?;
        self.est = est;
        self.seconds = 0.0;
        self.losses.clear();
        self.iteration = 0;
        self.figures = None;
        self.ious = None;
        self.requested_at = None;
        Ok(())
    }
}
