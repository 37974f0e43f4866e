//! The native [`Segmenter`]: the `localisebot-segment` crate's model (a MobileSAM-class
//! network run by tract), its jobs in parallel over the machine's cores (rayon), an
//! image's encoding kept while later rounds prompt the same crop again. Built from the
//! weights' bytes: where they come from (a folder, a download the user made) is the
//! caller's business.

use super::photo::Segmenter;
use super::prompt::{Crop, MaskCandidate, SegmentJob, SegmentOutput};
use crate::error::{Error, Result};
use crate::mask::Mask;
use crate::view::Rgba;
use localisebot_segment::{Embedding, Prompt, Sam};
use rayon::prelude::*;
use std::collections::HashMap;
use std::hash::{Hash, Hasher};

/// A crop and the hash of its pixels.
type Key = (Crop, u64);

pub use localisebot_segment::{DECODER_FILE, DECODER_SHA256, ENCODER_FILE, ENCODER_SHA256, PACKAGE};

/// The segmenter, from the model's files (checked against their pinned SHA-256).
pub struct SamSegmenter {
    sam: Sam,
    embeddings: HashMap<Key, Embedding>,
    /// Images encoded so far (a figure for the log).
    pub encoded: usize,
    /// Encoder runs so far (fewer than `encoded` with `mosaic`).
    pub runs: usize,
    /// Whether crops to encode together share one run of the encoder, up to four as the
    /// 512² tiles of a mosaic (default), rather than one 1024² run each.
    pub mosaic: bool,
}

impl SamSegmenter {
    /// The model from the encoder's and the decoder's bytes; `names` name them in errors.
    ///
    /// Errors: a file that is not the pinned one (its hash), or that tract cannot load.
    pub fn new(encoder: &[u8], decoder: &[u8], names: [&str; 2]) -> Result<SamSegmenter> {
        let sam = Sam::new(encoder, decoder, names).map_err(|e| Error::Settings(e.to_string()))?;
        Ok(SamSegmenter {
            sam,
            embeddings: HashMap::new(),
            encoded: 0,
            runs: 0,
            mosaic: true,
        })
    }
}

impl SamSegmenter {
    /// The model itself (for timing its encoder).
    pub fn model(&self) -> &Sam {
        &self.sam
    }
}

impl Segmenter for SamSegmenter {
    fn segment(&mut self, jobs: &[SegmentJob], images: &[&Rgba]) -> Result<Vec<SegmentOutput>> {
        let fail =
            |job: &SegmentJob, e: localisebot_segment::SegmentError| Error::Settings(format!("view {}: {e}", job.view));
        // Each job's crop, and its key: the crop and a hash of its pixels (so a cached
        // encoding is never another photograph's).
        let crops: Vec<(Vec<u8>, Key)> = jobs
            .iter()
            .zip(images)
            .map(|(j, im)| {
                let rgb = j.crop.rgb(im);
                let mut h = std::collections::hash_map::DefaultHasher::new();
                rgb.hash(&mut h);
                let key = (j.crop, h.finish());
                (rgb, key)
            })
            .collect();
        // New encodings first: in mosaics of up to four crops (or one run each), the
        // runs in parallel.
        let mut seen = std::collections::HashSet::new();
        let missing: Vec<usize> = (0..jobs.len())
            .filter(|&i| !self.embeddings.contains_key(&crops[i].1) && seen.insert(crops[i].1))
            .collect();
        let per_run = if self.mosaic { localisebot_segment::MAX_TILES } else { 1 };
        let groups: Vec<&[usize]> = missing.chunks(per_run).collect();
        let sam = &self.sam;
        let made: Vec<Result<Vec<Embedding>>> = groups
            .par_iter()
            .map(|g| {
                let tiles: Vec<(&[u8], u32)> = g.iter().map(|&i| (crops[i].0.as_slice(), jobs[i].crop.side)).collect();
                sam.embed_group(&tiles).map_err(|e| fail(&jobs[g[0]], e))
            })
            .collect();
        for (g, e) in groups.iter().zip(made) {
            for (&i, e) in g.iter().zip(e?) {
                self.embeddings.insert(crops[i].1, e);
                self.encoded += 1;
            }
            self.runs += 1;
        }
        let embeddings = &self.embeddings;
        jobs.par_iter()
            .enumerate()
            .map(|(i, job)| {
                let emb = &embeddings[&crops[i].1];
                let b = job.prompt_box;
                let prompt = Prompt {
                    bbox: Some([b[0] as f32, b[1] as f32, b[2] as f32, b[3] as f32]),
                    points: job
                        .segmenter_points()
                        .into_iter()
                        .map(|[x, y, label]| (x, y, label > 0.5))
                        .collect(),
                    mask_input: job.previous.clone(),
                };
                let d = sam.decode(emb, &prompt).map_err(|e| fail(job, e))?;
                let side = job.crop.side;
                let candidates = d
                    .candidates
                    .into_iter()
                    .map(|c| MaskCandidate {
                        mask: Mask {
                            width: side,
                            height: side,
                            data: c.mask,
                        },
                        logits: c.low_res,
                        score: c.score,
                    })
                    .collect();
                Ok(SegmentOutput {
                    candidates,
                    preferred: d.preferred,
                })
            })
            .collect()
    }
}
