//! BOP scenes (FORMATS.md §2; bop_toolkit `docs/bop_datasets_format.md`) to the scene
//! form (SPEC §3): the views of one object in one scene.
//!
//! Input: a resolver over the dataset folder (paths such as
//! `test/000001/scene_gt.json`, `models/obj_000001.ply`) and [`BopOptions`]. Read:
//! `SPLIT/SCENE/scene_camera.json` (`cam_K`, optional `cam_R_w2c`/`cam_t_w2c`),
//! `scene_gt.json` (`cam_R_m2c`/`cam_t_m2c` per instance), the instance masks
//! `mask[_visib]/IMID_GTID.png`, optional `rgb/IMID.png|jpg`, and the PLY model (mm).
//! Output: an [`Imported`] scene (views named by the 6-digit image id, masks and
//! images copied, the mesh written beside the scene) with the ground truth pose.
//!
//! World frame: with `cam_R_w2c`/`cam_t_w2c` in every chosen image, the dataset's
//! world; the object's pose is `T_w2c⁻¹ · T_m2c` of the first image (the others are
//! checked against it). Without them, the camera frame of the first chosen image
//! (OpenCV axes): cameras `T_m2c(i) · T_m2c(first)⁻¹`, the first being the identity,
//! and the ground truth `T_m2c(first)`, BOP's own annotation of that image.
//!
//! Units: [`Units::Millimetres`] keeps BOP's numbers and copies the PLY model;
//! [`Units::Metres`] (SPEC's recommendation, the default) multiplies every
//! translation by 0.001 and writes the model converted to metres (`obj_ID_m.ply`), so
//! the true scale stays 1 and a to-scale CAD model stays to scale. `cam_K` is used as
//! it is: BOP follows OpenCV, whose pixel centres are at integers, as SPEC §2 does.

use crate::camera::{CameraJson, Convention};
use crate::error::{Error, Result};
use crate::io::mask::decode_mask;
use crate::io::nerf::Imported;
use crate::io::scene::{SceneJson, ViewJson};
use crate::io::{join, ply, Resolver};
use crate::pose::{mat3_from_rows, mat4_to_rows, Pose, PoseJson};
use crate::so3;
use glam::{DMat3, DMat4, DVec3};
use serde::Deserialize;
use std::collections::BTreeMap;

/// Length unit of the imported scene.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Units {
    /// BOP's own millimetres: numbers and model unchanged.
    Millimetres,
    /// Metres: translations × 0.001 and the model converted.
    #[default]
    Metres,
}

/// Which of BOP's instance masks to use.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum MaskKind {
    /// `mask/`: the full silhouette, what a rendered model matches (falls back to
    /// `mask_visib/` with a warning where absent).
    #[default]
    Full,
    /// `mask_visib/`: only the visible part (occluders cut it).
    Visible,
}

/// What to import from a BOP dataset.
#[derive(Debug, Clone, PartialEq)]
pub struct BopOptions {
    /// Split folder, e.g. `"test"`, `"val"`, `"train_pbr"`.
    pub split: String,
    /// Scene id (folder `SPLIT/{scene_id:06}`).
    pub scene_id: u32,
    /// Object id (`obj_id` in `scene_gt.json`, model `obj_{object_id:06}.ply`).
    pub object_id: u32,
    /// Images to use; `None`: every image of the scene that shows the object.
    pub image_ids: Option<Vec<u32>>,
    /// Which instance of the object, when an image shows several (0: the first listed).
    pub instance: usize,
    /// Models folder, e.g. `"models"` or `"models_eval"`.
    pub models_dir: String,
    /// Mask folder.
    pub masks: MaskKind,
    /// Unit of the imported scene.
    pub units: Units,
    /// Write, for each view, the union of the *other* annotated objects' visible
    /// masks (`mask_visib/`) as its ignore mask: occluders become unknown pixels.
    pub ignore_others: bool,
    /// Give views boxes (made from the annotated masks, as a person would drag them)
    /// and their photographs instead of the masks: to try the photograph path on an
    /// annotated dataset.
    pub boxes: Option<BoxHints>,
}

/// Boxes made from annotated masks (`BopOptions::boxes`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BoxHints {
    /// Margin added on each side, as a fraction of the tight box's side (e.g. 0.1).
    pub margin: f64,
    /// Each edge then moved by a uniform random amount up to this fraction of the side
    /// (e.g. 0.05).
    pub jitter: f64,
    /// The random generator's seed.
    pub seed: u64,
    /// Only the first this many views get a box; the others only their photograph (their
    /// box comes from the geometry). `usize::MAX`: every view.
    pub views_with_box: usize,
}

impl BopOptions {
    /// Defaults for one object of one scene: split `test`, every image, first
    /// instance, `models/`, full masks, metres.
    pub fn new(scene_id: u32, object_id: u32) -> Self {
        BopOptions {
            split: "test".into(),
            scene_id,
            object_id,
            image_ids: None,
            instance: 0,
            models_dir: "models".into(),
            masks: MaskKind::Full,
            units: Units::Metres,
            ignore_others: false,
            boxes: None,
        }
    }
}

#[derive(Debug, Deserialize)]
#[allow(non_snake_case)]
struct CameraEntry {
    cam_K: Option<[f64; 9]>,
    cam_R_w2c: Option<[f64; 9]>,
    cam_t_w2c: Option<[f64; 3]>,
}

#[derive(Debug, Deserialize)]
#[allow(non_snake_case)]
struct GtEntry {
    obj_id: u32,
    cam_R_m2c: [f64; 9],
    cam_t_m2c: [f64; 3],
}

/// One chosen image, with what the views need.
struct Chosen {
    id: u32,
    k: [f64; 9],
    w2c: Option<DMat4>,
    m2c: DMat4,
    mask_rel: String,
    mask_bytes: Vec<u8>,
    /// The ignore mask (path, PNG bytes), when asked for and not empty.
    ignore: Option<(String, Vec<u8>)>,
    width: u32,
    height: u32,
    image: Option<(String, Vec<u8>)>,
}

/// A rigid 4×4 from a row-major rotation and a translation. BOP stores ~7 digits,
/// and annotations are off SO(3) by up to ~1e-2: a rotation within
/// [`so3::SO3_TOLERANCE`] is projected onto the nearest one (with a warning naming
/// the image when it is off by more than rounding); a larger deviation is an error.
fn rigid(r: [f64; 9], t: [f64; 3], unit: f64, what: &str, warnings: &mut Vec<String>) -> Result<DMat4> {
    let m = mat3_from_rows([[r[0], r[1], r[2]], [r[3], r[4], r[5]], [r[6], r[7], r[8]]]);
    let (r, e) = so3::accept_rotation(m).map_err(|why| Error::Json {
        file: "scene_gt.json / scene_camera.json".into(),
        problem: format!("{what}: the rotation {why}"),
    })?;
    if e > so3::SO3_SILENT {
        warnings.push(format!(
            "{what}: the rotation is off SO(3) by {e:.2e}: projected onto the nearest rotation"
        ));
    }
    Ok(DMat4::from_cols(
        r.x_axis.extend(0.0),
        r.y_axis.extend(0.0),
        r.z_axis.extend(0.0),
        (DVec3::from_array(t) * unit).extend(1.0),
    ))
}

fn parse<T: for<'de> Deserialize<'de>>(files: Resolver, path: &str, referrer: &str) -> Result<T> {
    let bytes = files(path).ok_or_else(|| Error::MissingFile {
        file: path.into(),
        referrer: referrer.into(),
    })?;
    crate::limits::check_json_depth(path, &bytes)?;
    serde_json::from_slice(&bytes).map_err(|e| Error::Json {
        file: path.into(),
        problem: e.to_string(),
    })
}

/// Image ids keyed as strings ("0", "1", …) to numbers; other keys are an error.
fn by_id<T>(map: BTreeMap<String, T>, file: &str) -> Result<BTreeMap<u32, T>> {
    map.into_iter()
        .map(|(k, v)| {
            k.trim().parse::<u32>().map(|id| (id, v)).map_err(|_| Error::Json {
                file: file.into(),
                problem: format!("key '{k}' is not an image id"),
            })
        })
        .collect()
}

/// Imports the views of `opts.object_id` in scene `opts.scene_id`; see the module doc.
pub fn import(files: Resolver, opts: &BopOptions) -> Result<Imported> {
    let scene_dir = format!("{}/{:06}", opts.split, opts.scene_id);
    let cam_path = join(&scene_dir, "scene_camera.json");
    let gt_path = join(&scene_dir, "scene_gt.json");
    let cameras: BTreeMap<u32, CameraEntry> = by_id(parse(files, &cam_path, "the BOP import")?, &cam_path)?;
    let gts: BTreeMap<u32, Vec<GtEntry>> = by_id(parse(files, &gt_path, "the BOP import")?, &gt_path)?;
    let unit = match opts.units {
        Units::Millimetres => 1.0,
        Units::Metres => 0.001,
    };
    let mut warnings = Vec::new();
    let ids: Vec<u32> = match &opts.image_ids {
        Some(ids) => ids.clone(),
        None => gts
            .iter()
            .filter(|(_, g)| g.iter().any(|e| e.obj_id == opts.object_id))
            .map(|(id, _)| *id)
            .collect(),
    };
    let mut chosen = Vec::new();
    for id in ids {
        if let Some(c) = choose(files, opts, &scene_dir, id, &cameras, &gts, unit, &mut warnings)? {
            chosen.push(c);
        }
    }
    let Some(first) = chosen.first() else {
        return Err(Error::Json {
            file: gt_path,
            problem: format!(
                "no image of scene {} shows object {} with a usable mask",
                opts.scene_id, opts.object_id
            ),
        });
    };
    // World frame and the object's pose in it (module doc).
    let (world_to_cams, model_to_world): (Vec<DMat4>, DMat4) = if chosen.iter().all(|c| c.w2c.is_some()) {
        let w2c: Vec<DMat4> = chosen.iter().map(|c| c.w2c.unwrap_or(DMat4::IDENTITY)).collect();
        let m2w = w2c[0].inverse() * first.m2c;
        for (c, w) in chosen.iter().zip(&w2c).skip(1) {
            let other = w.inverse() * c.m2c;
            let deg = so3::geodesic_deg(DMat3::from_mat4(other), DMat3::from_mat4(m2w));
            let dist = (other.w_axis - m2w.w_axis).truncate().length() / unit;
            if deg > 0.5 || dist > 1.0 {
                warnings.push(format!(
                    "image {:06}: the object's world pose differs from image {:06}'s by {deg:.2}° and {dist:.1} mm \
                     (a moving object, or another instance)",
                    c.id, first.id
                ));
            }
        }
        (w2c, m2w)
    } else {
        if chosen.iter().any(|c| c.w2c.is_some()) {
            warnings.push(
                "cam_R_w2c/cam_t_w2c are missing in some images: cameras are placed from the object poses".into(),
            );
        }
        let first_inv = first.m2c.inverse();
        (chosen.iter().map(|c| c.m2c * first_inv).collect(), first.m2c)
    };
    let ground_truth = Pose {
        rotation: so3::orthonormalize(DMat3::from_mat4(model_to_world)),
        translation: model_to_world.w_axis.truncate(),
        scale: DVec3::ONE,
    };
    let mut files_out = Vec::new();
    let mut views = Vec::new();
    for (c, w2c) in chosen.into_iter().zip(world_to_cams) {
        let name = format!("{:06}", c.id);
        let camera = CameraJson {
            width: c.width,
            height: c.height,
            fx: c.k[0],
            fy: c.k[4],
            cx: c.k[2],
            cy: c.k[5],
            world_to_camera: Some(mat4_to_rows(w2c)),
            camera_to_world: None,
            convention: Convention::Opencv,
        };
        camera.to_camera(&name)?;
        if c.k[1] != 0.0 {
            warnings.push(format!("image {name}: cam_K skew {} is ignored", c.k[1]));
        }
        let image = c.image.map(|(path, bytes)| {
            let ext = path.rsplit_once('.').map_or("png", |(_, e)| e);
            let rel = format!("images/{name}.{ext}");
            files_out.push((rel.clone(), bytes));
            rel
        });
        let (mask, hint_box) = match opts.boxes {
            None => {
                files_out.push((c.mask_rel.clone(), c.mask_bytes));
                (Some(c.mask_rel), None)
            }
            Some(h) => {
                if image.is_none() {
                    return Err(Error::View {
                        view: name,
                        problem: "boxes instead of masks need the photograph (rgb/), which is not there".into(),
                    });
                }
                let b = (views.len() < h.views_with_box)
                    .then(|| hint_box(&c.mask_bytes, &c.mask_rel, &name, &h, views.len() as u64))
                    .transpose()?;
                (None, b)
            }
        };
        let ignore = c.ignore.map(|(rel, bytes)| {
            files_out.push((rel.clone(), bytes));
            rel
        });
        views.push(ViewJson {
            ignore,
            name,
            image,
            mask,
            hint_box,
            camera,
        });
    }
    let mesh_file = mesh_file(files, opts, unit, &mut files_out)?;
    Ok(Imported {
        scene: SceneJson {
            version: 1,
            mesh: mesh_file,
            views,
            initial_pose: None,
            ground_truth_pose: Some(PoseJson::from_pose(&ground_truth)),
            grasps: Vec::new(),
        },
        files: files_out,
        warnings,
    })
}

/// A box around an annotated mask as a person would drag it (`BoxHints`); `salt`
/// makes each view's draw its own.
fn hint_box(mask_png: &[u8], file: &str, view: &str, h: &BoxHints, salt: u64) -> Result<[f64; 4]> {
    use rand::{Rng, SeedableRng};
    let mask = decode_mask(mask_png, view, file)?;
    let b = crate::view::PixelBox::of_mask(&mask).ok_or_else(|| Error::EmptyMask {
        view: view.into(),
        file: file.into(),
        ignored: false,
    })?;
    let mut rng = rand::rngs::SmallRng::seed_from_u64(h.seed.wrapping_mul(1_000_003).wrapping_add(salt));
    let (w, ht) = (b.x1 - b.x0, b.y1 - b.y0);
    let mut edge =
        |v: f64, side: f64, out: f64| v + out * h.margin * side + h.jitter * side * rng.gen_range(-1.0..=1.0);
    let r = [
        edge(b.x0, w, -1.0),
        edge(b.y0, ht, -1.0),
        edge(b.x1, w, 1.0),
        edge(b.y1, ht, 1.0),
    ];
    Ok(r.map(|v| (v * 10.0).round() / 10.0))
}

/// Gathers one image's camera, pose and mask, or `None` (with a warning) when the
/// image cannot be used.
#[allow(clippy::too_many_arguments)]
fn choose(
    files: Resolver,
    opts: &BopOptions,
    scene_dir: &str,
    id: u32,
    cameras: &BTreeMap<u32, CameraEntry>,
    gts: &BTreeMap<u32, Vec<GtEntry>>,
    unit: f64,
    warnings: &mut Vec<String>,
) -> Result<Option<Chosen>> {
    let Some(gtid) = gts.get(&id).and_then(|g| {
        g.iter()
            .enumerate()
            .filter(|(_, e)| e.obj_id == opts.object_id)
            .nth(opts.instance)
            .map(|(i, _)| i)
    }) else {
        warnings.push(format!(
            "image {id:06}: scene_gt.json lists no instance {} of object {}; skipped",
            opts.instance, opts.object_id
        ));
        return Ok(None);
    };
    let gt = &gts[&id][gtid];
    let Some(cam) = cameras.get(&id) else {
        warnings.push(format!("image {id:06}: not in scene_camera.json; skipped"));
        return Ok(None);
    };
    let k = cam.cam_K.ok_or_else(|| Error::Json {
        file: join(scene_dir, "scene_camera.json"),
        problem: format!("image {id}: no cam_K (cam_model cameras are not supported)"),
    })?;
    let folders = match opts.masks {
        MaskKind::Full => ["mask", "mask_visib"].as_slice(),
        MaskKind::Visible => ["mask_visib"].as_slice(),
    };
    let file_name = format!("{id:06}_{gtid:06}.png");
    let found = folders.iter().find_map(|f| {
        let p = join(scene_dir, &format!("{f}/{file_name}"));
        files(&p).map(|b| (*f, p, b))
    });
    let Some((folder, mask_path, mask_bytes)) = found else {
        warnings.push(format!(
            "image {id:06}: mask {file_name} not found in {}; skipped",
            folders.join(" or ")
        ));
        return Ok(None);
    };
    if opts.masks == MaskKind::Full && folder != "mask" {
        warnings.push(format!("image {id:06}: no full mask, the visible-part mask is used"));
    }
    let name = format!("{id:06}");
    let mask = decode_mask(&mask_bytes, &name, &mask_path)?;
    if mask.area() == 0 {
        warnings.push(format!("image {id:06}: mask {mask_path} is empty; skipped"));
        return Ok(None);
    }
    let image = ["png", "jpg", "jpeg"]
        .iter()
        .find_map(|ext| {
            let p = join(scene_dir, &format!("rgb/{id:06}.{ext}"));
            files(&p).map(|b| (p, b))
        })
        .filter(|(_, b)| {
            let dims = image::ImageReader::new(std::io::Cursor::new(b))
                .with_guessed_format()
                .ok()
                .and_then(|r| r.into_dimensions().ok());
            dims == Some((mask.width, mask.height))
        });
    let w2c = match (cam.cam_R_w2c, cam.cam_t_w2c) {
        (Some(r), Some(t)) => Some(rigid(r, t, unit, &format!("image {id:06}: cam_R_w2c"), warnings)?),
        _ => None,
    };
    let m2c = rigid(
        gt.cam_R_m2c,
        gt.cam_t_m2c,
        unit,
        &format!("image {id:06}: cam_R_m2c"),
        warnings,
    )?;
    let ignore = if opts.ignore_others {
        others_mask(files, scene_dir, id, gtid, &gts[&id], &mask, warnings)?
            .map(|png| (format!("masks/{name}_ignore.png"), png))
    } else {
        None
    };
    Ok(Some(Chosen {
        id,
        k,
        w2c,
        m2c,
        mask_rel: format!("masks/{name}.png"),
        mask_bytes,
        ignore,
        width: mask.width,
        height: mask.height,
        image,
    }))
}

/// The union of the visible masks of the other instances annotated in image `id`
/// (all but `gtid`), as a PNG, or `None` when they cover nothing. Missing masks are
/// warned about; a mask of another size is an error.
fn others_mask(
    files: Resolver,
    scene_dir: &str,
    id: u32,
    gtid: usize,
    entries: &[GtEntry],
    mask: &crate::mask::Mask,
    warnings: &mut Vec<String>,
) -> Result<Option<Vec<u8>>> {
    let mut union = vec![0u8; mask.data.len()];
    for other in (0..entries.len()).filter(|&i| i != gtid) {
        let path = join(scene_dir, &format!("mask_visib/{id:06}_{other:06}.png"));
        let Some(bytes) = files(&path) else {
            warnings.push(format!("image {id:06}: {path} not found: that occluder is not ignored"));
            continue;
        };
        let m = crate::io::mask::decode_mask_sized(&bytes, &format!("{id:06}"), &path, mask.width, mask.height)?;
        for (u, &v) in union.iter_mut().zip(&m.data) {
            *u |= v;
        }
    }
    // The object's own pixels stay known.
    for (u, &v) in union.iter_mut().zip(&mask.data) {
        if v != 0 {
            *u = 0;
        }
    }
    if union.iter().all(|&v| v == 0) {
        return Ok(None);
    }
    let grey: Vec<u8> = union.iter().map(|&v| v * 255).collect();
    Ok(Some(crate::io::png::encode_gray(mask.width, mask.height, &grey)))
}

/// Validates the model and adds it to the files to write (converted to metres when
/// asked); returns its path relative to the scene.
fn mesh_file(files: Resolver, opts: &BopOptions, unit: f64, out: &mut Vec<(String, Vec<u8>)>) -> Result<String> {
    let name = format!("obj_{:06}", opts.object_id);
    let path = join(&opts.models_dir, &format!("{name}.ply"));
    let bytes = files(&path).ok_or_else(|| Error::MissingFile {
        file: path.clone(),
        referrer: format!("object {} of the BOP import", opts.object_id),
    })?;
    let mut mesh = ply::load(&path, &bytes)?;
    let (rel, data) = match opts.units {
        Units::Millimetres => (format!("{name}.ply"), bytes),
        Units::Metres => {
            mesh.positions.iter_mut().for_each(|p| *p *= unit);
            let comment = format!("{path} converted from mm to metres");
            (format!("{name}_m.ply"), ply::write_ascii(&mesh, &comment))
        }
    };
    out.push((rel.clone(), data));
    Ok(rel)
}
