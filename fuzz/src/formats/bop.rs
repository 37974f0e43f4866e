//! BOP folders: the spec, its files and the BOP importer's driver.

use super::{
    check_imported, dump, dump_files, nums, ply_bytes, resolver, Files, ImageSpec, MaskSpec, MeshSpec, PlyOpts,
};
use localisebot::io;
use localisebot::io::bop::{BopOptions, BoxHints, MaskKind, Units};
use localisebot::io::nerf::Imported;

// ---------------------------------------------------------------------------------
// BOP

#[derive(Debug, Clone, PartialEq)]
pub struct BopInstance {
    pub obj_id: i64,
    pub r: [f64; 9],
    pub t: [f64; 3],
    /// `mask/IMID_GTID.png`, `mask_visib/IMID_GTID.png`.
    pub mask: Option<MaskSpec>,
    pub visib: Option<MaskSpec>,
}

#[derive(Debug, Clone, PartialEq)]
pub struct BopImage {
    pub id: i64,
    /// In `scene_camera.json`, with `cam_K` (when given) and `cam_R_w2c`/`cam_t_w2c`.
    pub listed: bool,
    pub k: Option<[f64; 9]>,
    pub w2c: Option<([f64; 9], [f64; 3])>,
    pub instances: Vec<BopInstance>,
    /// `rgb/IMID.png`.
    pub rgb: Option<ImageSpec>,
}

#[derive(Debug, Clone, PartialEq)]
pub struct BopSpec {
    pub scene_id: u32,
    pub object_id: u32,
    pub images: Vec<BopImage>,
    pub model: MeshSpec,
    pub model_ply: PlyOpts,
    pub image_ids: Option<Vec<u32>>,
    pub instance: usize,
    pub visible: bool,
    pub metres: bool,
    pub ignore_others: bool,
    pub boxes: Option<BoxHints>,
}

/// The dataset's files and the import's options.
pub fn bop_files(s: &BopSpec) -> (Files, BopOptions) {
    let mut files = Files::new();
    let dir = format!("test/{:06}", s.scene_id);
    let mut cams = Vec::new();
    let mut gts = Vec::new();
    for im in &s.images {
        if im.listed {
            let mut parts = Vec::new();
            if let Some(k) = im.k {
                parts.push(format!("\"cam_K\": {}", nums(&k)));
            }
            if let Some((r, t)) = im.w2c {
                parts.push(format!("\"cam_R_w2c\": {}, \"cam_t_w2c\": {}", nums(&r), nums(&t)));
            }
            parts.push("\"depth_scale\": 1.0".into());
            cams.push(format!("\"{}\": {{{}}}", im.id, parts.join(", ")));
        }
        let mut inst = Vec::new();
        for (g, i) in im.instances.iter().enumerate() {
            inst.push(format!(
                "{{\"cam_R_m2c\": {}, \"cam_t_m2c\": {}, \"obj_id\": {}}}",
                nums(&i.r),
                nums(&i.t),
                i.obj_id
            ));
            if let Some(m) = &i.mask {
                files.insert(format!("{dir}/mask/{:06}_{g:06}.png", im.id), m.png());
            }
            if let Some(m) = &i.visib {
                files.insert(format!("{dir}/mask_visib/{:06}_{g:06}.png", im.id), m.png());
            }
        }
        gts.push(format!("\"{}\": [{}]", im.id, inst.join(", ")));
        if let Some(rgb) = &im.rgb {
            files.insert(format!("{dir}/rgb/{:06}.png", im.id), rgb.png());
        }
    }
    files.insert(
        format!("{dir}/scene_camera.json"),
        format!("{{{}}}", cams.join(",\n")).into_bytes(),
    );
    files.insert(
        format!("{dir}/scene_gt.json"),
        format!("{{{}}}", gts.join(",\n")).into_bytes(),
    );
    files.insert(
        format!("models/obj_{:06}.ply", s.object_id),
        ply_bytes(&s.model, &s.model_ply),
    );
    let opts = BopOptions {
        image_ids: s.image_ids.clone(),
        instance: s.instance,
        masks: if s.visible { MaskKind::Visible } else { MaskKind::Full },
        units: if s.metres { Units::Metres } else { Units::Millimetres },
        ignore_others: s.ignore_others,
        boxes: s.boxes,
        ..BopOptions::new(s.scene_id, s.object_id)
    };
    (files, opts)
}

/// The BOP import as `localisebot import-bop` runs it; checks what it makes.
pub fn drive_bop(files: &Files, opts: &BopOptions) -> localisebot::Result<Imported> {
    dump_files(files);
    dump("options.txt", format!("{opts:#?}").as_bytes());
    let r = io::bop::import(&resolver(files), opts);
    if let Ok(im) = &r {
        check_imported(im);
    }
    r
}
