//! `localisebot import nerf|bop …`: dataset folders to a scene folder (SPEC §3):
//! `scene.json`, masks, images and the mesh, with the importer's warnings on stderr.

use super::files::{write, CliResult};
use super::synth::copy_mesh;
use clap::{Args, Subcommand, ValueEnum};
use localisebot::io::bop::{self, BopOptions, MaskKind, Units};
use localisebot::io::nerf::{self, Imported};
use std::path::{Path, PathBuf};

/// The importers.
#[derive(Subcommand)]
pub enum ImportCommand {
    /// A NeRF synthetic folder (transforms_*.json; RGBA images whose alpha is the mask).
    Nerf(NerfArgs),
    /// One object of one scene of a BOP dataset.
    Bop(BopArgs),
}

/// Arguments of `import nerf`.
#[derive(Args)]
pub struct NerfArgs {
    /// The folder holding transforms_*.json and the images.
    dir: PathBuf,
    /// The object's mesh (NeRF folders have none); copied into the output.
    #[arg(long)]
    mesh: PathBuf,
    /// Which transforms file (default: transforms_train.json, else transforms.json, else the first transforms*.json).
    #[arg(long)]
    transforms: Option<String>,
    /// Output folder.
    #[arg(long)]
    out: PathBuf,
}

/// Length unit of an imported BOP scene.
#[derive(Clone, Copy, ValueEnum)]
pub enum UnitArg {
    /// Metres (translations × 0.001, model converted).
    M,
    /// BOP's millimetres, unchanged.
    Mm,
}

/// Mask folder of a BOP import.
#[derive(Clone, Copy, ValueEnum)]
pub enum MaskArg {
    /// `mask/`: full silhouettes.
    Full,
    /// `mask_visib/`: visible parts only.
    Visib,
}

/// What `import bop --ignore` ignores.
#[derive(Clone, Copy, ValueEnum)]
pub enum IgnoreArg {
    /// The other annotated objects' visible masks.
    Others,
}

/// Arguments of `import bop`.
#[derive(Args)]
pub struct BopArgs {
    /// The dataset folder (holding SPLIT/ and models/).
    dataset: PathBuf,
    /// Scene id.
    #[arg(long)]
    scene: u32,
    /// Object id.
    #[arg(long)]
    object: u32,
    /// Image ids, comma-separated (default: every image showing the object).
    #[arg(long, value_delimiter = ',')]
    images: Option<Vec<u32>>,
    /// Split folder.
    #[arg(long, default_value = "test")]
    split: String,
    /// Models folder.
    #[arg(long, default_value = "models")]
    models: String,
    /// Which instance of the object when an image shows several (0 = first listed).
    #[arg(long, default_value_t = 0)]
    instance: usize,
    /// Output length unit.
    #[arg(long, value_enum, default_value = "m")]
    units: UnitArg,
    /// Mask folder.
    #[arg(long, value_enum, default_value = "full")]
    masks: MaskArg,
    /// `others`: each view's ignore mask is the union of the other annotated objects'
    /// visible masks (occluders become unknown pixels).
    #[arg(long, value_enum)]
    ignore: Option<IgnoreArg>,
    /// Give the views boxes made from the annotated masks (10 % margin, edges moved by
    /// up to ±5 %, as a person drags them) and their photographs instead of masks: the
    /// photograph path on an annotated dataset.
    #[arg(long)]
    boxes: bool,
    /// With --boxes: only the first N views get a box (the others' boxes come from the
    /// geometry).
    #[arg(long, requires = "boxes")]
    boxes_in: Option<usize>,
    /// With --boxes: the seed of the edges' random moves.
    #[arg(long, default_value_t = 1, requires = "boxes")]
    box_seed: u64,
    /// Output folder.
    #[arg(long)]
    out: PathBuf,
}

/// Runs `import`.
pub fn run(cmd: &ImportCommand) -> CliResult {
    match cmd {
        ImportCommand::Nerf(a) => {
            let name = match &a.transforms {
                Some(n) => n.clone(),
                None => find_transforms(&a.dir)?,
            };
            let path = a.dir.join(&name);
            let text = super::files::read_text(&path)?;
            let mesh_name = copy_mesh(&a.mesh, &a.out)?;
            let dir = a.dir.clone();
            let disk = super::files::Disk::default();
            let imported = nerf::import(&name, &text, &|p| disk.get(&dir.join(p)), &mesh_name)
                .map_err(|e| format!("{}: {}", a.dir.display(), disk.explain(e)))?;
            finish(imported, &a.out)
        }
        ImportCommand::Bop(a) => {
            let mut o = BopOptions::new(a.scene, a.object);
            o.split = a.split.clone();
            o.image_ids = a.images.clone();
            o.instance = a.instance;
            o.models_dir = a.models.clone();
            o.units = match a.units {
                UnitArg::M => Units::Metres,
                UnitArg::Mm => Units::Millimetres,
            };
            o.ignore_others = matches!(a.ignore, Some(IgnoreArg::Others));
            o.boxes = a.boxes.then_some(bop::BoxHints {
                margin: 0.1,
                jitter: 0.05,
                seed: a.box_seed,
                views_with_box: a.boxes_in.unwrap_or(usize::MAX),
            });
            o.masks = match a.masks {
                MaskArg::Full => MaskKind::Full,
                MaskArg::Visib => MaskKind::Visible,
            };
            let dir = a.dataset.clone();
            let disk = super::files::Disk::default();
            let imported = bop::import(&|p| disk.get(&dir.join(p)), &o)
                .map_err(|e| format!("{}: {}", a.dataset.display(), disk.explain(e)))?;
            finish(imported, &a.out)
        }
    }
}

fn find_transforms(dir: &Path) -> CliResult<String> {
    for n in ["transforms_train.json", "transforms.json"] {
        if dir.join(n).is_file() {
            return Ok(n.into());
        }
    }
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .map_err(|e| format!("{}: cannot list: {e}", dir.display()))?
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|n| n.starts_with("transforms") && n.ends_with(".json"))
        .collect();
    names.sort();
    names
        .into_iter()
        .next()
        .ok_or_else(|| format!("{}: no transforms*.json found", dir.display()))
}

fn finish(imported: Imported, out: &Path) -> CliResult {
    for w in &imported.warnings {
        eprintln!("warning: {w}");
    }
    for (rel, bytes) in &imported.files {
        write(&out.join(rel), bytes)?;
    }
    write(&out.join("scene.json"), imported.scene.to_json_string().as_bytes())?;
    eprintln!(
        "wrote {} ({} views)",
        out.join("scene.json").display(),
        imported.scene.views.len()
    );
    Ok(())
}
