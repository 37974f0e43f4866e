//! [`WorkerShard`] (`Shard` in JavaScript): one member of a pool of Web Workers that
//! compute a [`Session`](super::Session)'s work — the views it owns of each
//! refinement iteration, and any slice of a search batch. It is built once from the
//! same files as the session (so its mesh, views and settings are the session's),
//! then answers requests: `session.request()` → `session.splitRequest(req, n)` → each
//! shard's `work(part)` → `session.respond(responses)`. Requests and responses are
//! plain JavaScript objects (serde-wasm-bindgen), to be posted between Workers as
//! they are and treated as opaque.

use super::{to_js, FileSet};
use crate::error::{Error, Result};
use crate::estimator::{FitSettings, Request, Shard};
use crate::io::scene::Scene;
use wasm_bindgen::prelude::*;

/// A shard of a session's fit, in a pool Worker (see the module doc).
#[wasm_bindgen(js_name = Shard)]
pub struct WorkerShard {
    inner: Shard,
    views: usize,
}

/// The most shards a request is split for.
pub const MAX_SHARDS: u32 = 64;

impl WorkerShard {
    fn from_scene(scene: Scene, mine: Vec<usize>) -> Result<WorkerShard> {
        scene.require_masks("a pool worker")?;
        let views = scene.views.len();
        if mine.is_empty() {
            return Err(Error::Settings("shard: it owns no view".into()));
        }
        let mut sorted = mine.clone();
        sorted.sort_unstable();
        if sorted.windows(2).any(|w| w[0] == w[1]) {
            return Err(Error::Settings("shard: a view is named twice".into()));
        }
        // The session's settings: `Session` fits with the one default.
        let inner = Shard::new(scene.mesh, scene.views, mine, FitSettings::default())?;
        Ok(WorkerShard { inner, views })
    }
}

#[wasm_bindgen(js_class = Shard)]
impl WorkerShard {
    /// A shard from the files a session was made from with `Session.fromFiles` (the
    /// same files give the same mesh, views and settings), owning views `mine` (0-based
    /// session view indices, e.g. `[0, 2]`). Throws an `Error` for files that do not
    /// load or a view index beyond the views.
    #[wasm_bindgen(js_name = fromFiles)]
    pub fn from_files(files: &FileSet, mine: Vec<usize>) -> Result<WorkerShard, JsError> {
        let (scene, _, _) = files.inner().load()?;
        Ok(WorkerShard::from_scene(scene, mine)?)
    }

    /// A shard from a scene file's text and its files, as `Session.fromScene` takes
    /// them, owning views `mine`.
    #[wasm_bindgen(js_name = fromScene)]
    pub fn from_scene_text(
        scene_file: &str,
        scene_text: &str,
        files: &FileSet,
        mine: Vec<usize>,
    ) -> Result<WorkerShard, JsError> {
        let (scene, _) = files.load_scene(scene_file, scene_text)?;
        Ok(WorkerShard::from_scene(scene, mine)?)
    }

    /// The number of views of the session (all of them: a search slice scores every view).
    #[wasm_bindgen(getter, js_name = viewCount)]
    pub fn view_count(&self) -> usize {
        self.views
    }

    /// The views whose parts this shard computes.
    pub fn views(&self) -> Vec<usize> {
        self.inner.views().to_vec()
    }

    /// Computes this shard's share of a request (one element of
    /// `Session.splitRequest`): a response for `Session.respond`. Throws an `Error` for
    /// anything that is not such a request.
    pub fn work(&mut self, request: JsValue) -> Result<JsValue, JsError> {
        let request = parse_request(request)?;
        let response = self.inner.work(&request)?;
        to_js(&response)
    }
}

/// A request as JavaScript hands it back.
pub(crate) fn parse_request(value: JsValue) -> Result<Request> {
    serde_wasm_bindgen::from_value(value).map_err(|e| Error::Settings(format!("not a request: {e}")))
}
