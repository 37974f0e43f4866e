//! Photographs as a phone gives them: JPEG, stored sideways with an EXIF orientation
//! tag. The LM-O ape's three photographs (`../shared/data/real/lmo`, boxes as in
//! `photos.rs`) are turned a quarter anticlockwise as stored and tagged "turn a quarter
//! clockwise to show" (EXIF 6, what a phone held upright writes), JPEG-compressed at
//! quality 90, and fitted from their boxes through the command line, beside the same
//! scene with the PNGs: the pictures as shown are the same, so the poses must be too.

use crate::data;
use image::ImageEncoder;

/// An EXIF block (little-endian TIFF) holding only the orientation tag `value`.
fn exif_orientation(value: u8) -> Vec<u8> {
    let mut t = b"II*\0".to_vec();
    t.extend_from_slice(&8u32.to_le_bytes());
    t.extend_from_slice(&1u16.to_le_bytes());
    t.extend_from_slice(&[0x12, 0x01, 3, 0, 1, 0, 0, 0, value, 0, 0, 0]);
    t.extend_from_slice(&0u32.to_le_bytes());
    t
}

#[test]
fn phone_jpegs_stored_sideways_fit_like_the_pngs() {
    let d = std::env::temp_dir().join(format!("localisebot-jpeg-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    let bin = env!("CARGO_BIN_EXE_localisebot");
    let run = |args: &[&str]| {
        let o = std::process::Command::new(bin).args(args).output().unwrap();
        assert!(o.status.success(), "{args:?}: {}", String::from_utf8_lossy(&o.stderr));
    };
    let pngs = d.join("pngs");
    run(&[
        "import",
        "bop",
        data("real/lmo").to_str().unwrap(),
        "--scene",
        "2",
        "--object",
        "1",
        "--images",
        "263,310,819",
        "--masks",
        "visib",
        "--boxes",
        "--out",
        pngs.to_str().unwrap(),
    ]);
    // The same scene with each photograph a sideways JPEG beside the PNG.
    let text = std::fs::read_to_string(pngs.join("scene.json")).unwrap();
    let mut scene: serde_json::Value = serde_json::from_str(&text).unwrap();
    for v in scene["views"].as_array_mut().unwrap() {
        assert!(v.get("mask").is_none() && v.get("box").is_some(), "{v}");
        let png = v["image"].as_str().unwrap().to_string();
        let shown = image::open(pngs.join(&png)).unwrap().to_rgb8();
        // Stored a quarter anticlockwise: EXIF 6 turns it back clockwise to show.
        let stored = image::imageops::rotate270(&shown);
        assert_eq!((stored.width(), stored.height()), (shown.height(), shown.width()));
        let mut bytes = Vec::new();
        let mut enc = image::codecs::jpeg::JpegEncoder::new_with_quality(&mut bytes, 90);
        enc.set_exif_metadata(exif_orientation(6)).unwrap();
        enc.write_image(
            stored.as_raw(),
            stored.width(),
            stored.height(),
            image::ExtendedColorType::Rgb8,
        )
        .unwrap();
        let jpg = png.replace(".png", ".jpg");
        std::fs::write(pngs.join(&jpg), bytes).unwrap();
        v["image"] = jpg.into();
    }
    let jpegs = pngs.join("jpegs.json");
    std::fs::write(&jpegs, scene.to_string()).unwrap();
    let fit = |scene: &std::path::Path, out: &str| {
        let out = d.join(out);
        run(&["fit", scene.to_str().unwrap(), "--out", out.to_str().unwrap()]);
        serde_json::from_str::<serde_json::Value>(&std::fs::read_to_string(out).unwrap()).unwrap()
    };
    let from_png = fit(&pngs.join("scene.json"), "png.json");
    let from_jpeg = fit(&jpegs, "jpeg.json");
    let add = |r: &serde_json::Value| r["errors"]["add_rel"].as_f64().unwrap();
    let rotation = |r: &serde_json::Value| r["errors"]["rotation_deg"].as_f64().unwrap();
    println!(
        "LM-O ape from boxes: PNGs ADD {:.2} % d, rotation {:.1}°, verdict {}; sideways JPEGs ADD {:.2} % d, \
         rotation {:.1}°, verdict {}",
        100.0 * add(&from_png),
        rotation(&from_png),
        from_png["verdict"],
        100.0 * add(&from_jpeg),
        rotation(&from_jpeg),
        from_jpeg["verdict"]
    );
    // Read sideways (the tag ignored), the photographs would not match their cameras'
    // 640×480 and the load would fail; read turned, the JPEGs fit as the PNGs do.
    assert!(add(&from_jpeg) < 0.1, "{}", from_jpeg["errors"]);
    assert!(
        (add(&from_jpeg) - add(&from_png)).abs() < 0.02,
        "PNG {} against JPEG {}",
        add(&from_png),
        add(&from_jpeg)
    );
    let _ = std::fs::remove_dir_all(&d);
}
