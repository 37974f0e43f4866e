//! `Session.setRefineCameras(on, rotationDeg, distance)`: the page's camera-correction
//! switch (`fit --refine-cameras`): each view's camera is corrected jointly with the
//! pose under a prior, at the end of the fit; the result then lists
//! `camera_corrections` and `camera_test` (applied only when they explain at least
//! 15 % of the loss).

use super::session::Session;
use crate::estimator::CameraPrior;
use wasm_bindgen::prelude::*;

#[wasm_bindgen]
impl Session {
    /// Turns the camera correction on or off before the fit ends; `rotationDeg` and
    /// `distance` (a fraction of each camera's distance to the object) are the prior's
    /// standard deviations, 1° and 0.01 when omitted. Throws an `Error` once the fit is
    /// done or for a prior that is not positive.
    #[wasm_bindgen(js_name = setRefineCameras)]
    pub fn set_refine_cameras(
        &mut self,
        on: bool,
        rotation_deg: Option<f64>,
        distance: Option<f64>,
    ) -> Result<(), JsError> {
        let prior = on.then(|| {
            let d = CameraPrior::default();
            CameraPrior {
                rotation_deg: rotation_deg.unwrap_or(d.rotation_deg),
                distance: distance.unwrap_or(d.distance),
                ..d
            }
        });
        self.estimator_mut().set_refine_cameras(prior)?;
        Ok(())
    }
}
