//! `localisebot synth`: a synthetic scene folder from a mesh — `scene.json` with its
//! `ground_truth_pose`, `masks/*.png` and a copy of the mesh (with its `.bin` buffers),
//! or from one of the project's procedural shapes (`--shape toy`), written as `.glb`,
//! `.gltf` + `.bin` or `.ply`. The web page's examples are made this way
//! (`scripts/build-examples.sh`).

use super::files::{load_mesh, load_pose, read, write, CliResult};
use clap::Args;
use localisebot::app::grasp::antipodal_grasps;
use localisebot::app::shapes;
use localisebot::app::synth::{synthesize, SynthSettings};
use localisebot::io::png::{encode_gray, encode_rgba};
use localisebot::io::{gltf_write, ply};
use localisebot::Mesh;
use localisebot::{CameraJson, PoseJson, SceneJson, ViewJson};
use std::path::{Path, PathBuf};

/// Arguments of `synth`.
#[derive(Args)]
pub struct SynthArgs {
    /// Mesh file (.glb, .gltf, .obj, .ply), copied into the scene folder.
    #[arg(long, required_unless_present = "shape", conflicts_with = "shape")]
    mesh: Option<PathBuf>,
    /// A procedural shape instead of a mesh file: toy (an aeroplane, 0.32 m long),
    /// blob or cube; written into the scene folder as NAME.glb (see --mesh-format).
    #[arg(long, value_parser = clap::builder::PossibleValuesParser::new(shapes::NAMES))]
    shape: Option<String>,
    /// How to write a --shape: glb, gltf (NAME.gltf + NAME.bin) or ply (ASCII).
    #[arg(long, requires = "shape", value_parser = clap::builder::PossibleValuesParser::new(["glb", "gltf", "ply"]))]
    mesh_format: Option<String>,
    /// Number of views.
    #[arg(long, default_value_t = 4)]
    views: usize,
    /// Random seed (pose and cameras).
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Image width in pixels.
    #[arg(long, default_value_t = 256)]
    width: u32,
    /// Image height in pixels.
    #[arg(long, default_value_t = 256)]
    height: u32,
    /// Pose file to render at, instead of a random pose.
    #[arg(long)]
    pose: Option<PathBuf>,
    /// Add this many antipodal grasp candidates (pairs of opposed surface points no
    /// farther apart than the object's diameter) to the scene.
    #[arg(long, default_value_t = 0)]
    grasps: usize,
    /// Also write shaded renders as the views' images.
    #[arg(long)]
    images: bool,
    /// Occlude a view: `VIEW:FRACTION` hides that fraction of view VIEW's object
    /// behind a rectangular occluder, cut from its mask and written as its ignore mask
    /// (`masks/viewK_ignore.png`); repeatable.
    #[arg(long, value_parser = parse_occlusion)]
    occlude: Vec<(usize, f64)>,
    /// Output folder.
    #[arg(long)]
    out: PathBuf,
}

/// Runs `synth`.
pub fn run(a: &SynthArgs) -> CliResult {
    if a.shape.is_none() && a.mesh_format.is_some() {
        return Err("--mesh-format writes a --shape: it does not convert a --mesh".into());
    }
    let (mesh, source) = match (&a.shape, &a.mesh) {
        (Some(name), _) => (
            shapes::by_name(name).ok_or_else(|| format!("unknown shape '{name}'"))?,
            name.clone(),
        ),
        (None, Some(path)) => (load_mesh(path)?, path.display().to_string()),
        (None, None) => return Err("give --mesh FILE or --shape NAME".into()),
    };
    let pose = a.pose.as_deref().map(load_pose).transpose()?;
    let settings = SynthSettings {
        views: a.views,
        width: a.width,
        height: a.height,
        seed: a.seed,
        images: a.images,
        ..Default::default()
    };
    let scene = synthesize(&mesh, &settings, pose).map_err(|e| e.to_string())?;
    let mesh_name = match (&a.shape, &a.mesh) {
        (Some(name), _) => write_shape(&mesh, name, a.mesh_format.as_deref().unwrap_or("glb"), &a.out)?,
        (None, Some(path)) => copy_mesh(path, &a.out)?,
        (None, None) => unreachable!("checked above"),
    };
    let grasps = antipodal_grasps(&mesh, mesh.diameter(), a.grasps, a.seed);
    if grasps.len() < a.grasps {
        eprintln!(
            "warning: {source}: found {} of {} antipodal grasps",
            grasps.len(),
            a.grasps
        );
    }
    if let Some((v, _)) = a.occlude.iter().find(|(v, _)| *v >= scene.cameras.len()) {
        return Err(format!(
            "--occlude: no view {v} (the scene has {})",
            scene.cameras.len()
        ));
    }
    let mut views = Vec::new();
    for (i, (cam, mask)) in scene.cameras.iter().zip(&scene.masks).enumerate() {
        let name = format!("view{i}");
        let rel = format!("masks/{name}.png");
        let (mask, ignore) = match a.occlude.iter().find(|(v, _)| *v == i) {
            Some(&(_, f)) => {
                let (cut, occluder) = localisebot::app::synth::occlude(mask, f, a.seed + i as u64);
                let rel = format!("masks/{name}_ignore.png");
                let grey: Vec<u8> = occluder.data.iter().map(|&v| v * 255).collect();
                write(&a.out.join(&rel), &encode_gray(mask.width, mask.height, &grey))?;
                (cut, Some(rel))
            }
            None => (mask.clone(), None),
        };
        let grey: Vec<u8> = mask.data.iter().map(|&v| v * 255).collect();
        write(&a.out.join(&rel), &encode_gray(mask.width, mask.height, &grey))?;
        let image = match scene.images.get(i) {
            Some(img) => {
                let rel = format!("images/{name}.png");
                write(&a.out.join(&rel), &encode_rgba(img))?;
                Some(rel)
            }
            None => None,
        };
        views.push(ViewJson {
            ignore,
            name,
            image,
            mask: Some(rel),
            hint_box: None,
            camera: CameraJson::from_camera(cam),
        });
    }
    let json = SceneJson {
        version: 1,
        mesh: mesh_name,
        views,
        initial_pose: None,
        ground_truth_pose: Some(PoseJson::from_pose(&scene.pose)),
        grasps: grasps.iter().map(|g| g.to_json()).collect(),
    };
    write(&a.out.join("scene.json"), json.to_json_string().as_bytes())?;
    eprintln!(
        "wrote {} ({} views)",
        a.out.join("scene.json").display(),
        scene.cameras.len()
    );
    Ok(())
}

fn parse_occlusion(s: &str) -> Result<(usize, f64), String> {
    let bad = || format!("expected VIEW:FRACTION (e.g. 1:0.3), got '{s}'");
    let (v, f) = s.split_once(':').ok_or_else(bad)?;
    let v: usize = v.parse().map_err(|_| bad())?;
    let f: f64 = f.parse().map_err(|_| bad())?;
    if !(0.0..1.0).contains(&f) {
        return Err(format!("the occluded fraction must be in [0, 1), got {f}"));
    }
    Ok((v, f))
}

/// Writes a procedural shape into `out` as `NAME.glb`, `NAME.gltf` + `NAME.bin` or
/// `NAME.ply`; returns the mesh's file name.
fn write_shape(mesh: &Mesh, name: &str, format: &str, out: &Path) -> CliResult<String> {
    let file = format!("{name}.{format}");
    let err = |e: localisebot::Error| e.to_string();
    match format {
        "glb" => write(&out.join(&file), &gltf_write::glb(mesh, &file).map_err(err)?)?,
        "gltf" => {
            let bin = format!("{name}.bin");
            let (text, bytes) = gltf_write::gltf_and_bin(mesh, &file, &bin).map_err(err)?;
            write(&out.join(&file), text.as_bytes())?;
            write(&out.join(&bin), &bytes)?;
        }
        "ply" => write(
            &out.join(&file),
            &ply::write_ascii(mesh, &format!("localisebot procedural shape '{name}'")),
        )?,
        other => return Err(format!("--mesh-format: unknown format '{other}'")),
    }
    Ok(file)
}

/// Copies the mesh file, and a `.gltf`'s external buffers and images, into `out`.
/// Returns the mesh's name relative to `out`.
pub(super) fn copy_mesh(mesh: &Path, out: &Path) -> CliResult<String> {
    let name = mesh
        .file_name()
        .ok_or_else(|| format!("{}: not a file", mesh.display()))?
        .to_string_lossy()
        .to_string();
    let bytes = read(mesh)?;
    write(&out.join(&name), &bytes)?;
    if name.to_ascii_lowercase().ends_with(".gltf") {
        let dir = mesh.parent().unwrap_or(Path::new(""));
        let v: serde_json::Value = serde_json::from_slice(&bytes).map_err(|e| format!("{}: {e}", mesh.display()))?;
        let uris = ["buffers", "images"]
            .iter()
            .filter_map(|k| v.get(*k).and_then(|a| a.as_array()))
            .flatten()
            .filter_map(|b| b.get("uri").and_then(|u| u.as_str()))
            .filter(|u| !u.starts_with("data:"));
        for uri in uris {
            // Images are optional for a silhouette; buffers must be there.
            if let Ok(b) = std::fs::read(dir.join(uri)) {
                write(&out.join(uri), &b)?;
            }
        }
    }
    Ok(name)
}
