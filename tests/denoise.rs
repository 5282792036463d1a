//! Intel OIDN through the `denoise` feature (CI's denoise stage builds it):
//! a noisy render comes nearer the converged one, and guides of another
//! size are a typed error.

use pbgi::render::{DenoiseError, Direct, Frame, Image, RenderOptions, denoise};
use pbgi::report::{compare, emitter_mask};
use pbgi::scene::builtin::cornell_box;

/// The direct light sampled: the noise the denoiser is measured on. With
/// the ratio estimator (the default) the 1-spp box has less of it (0.0751
/// against the 64-spp render), and the denoiser takes it to 0.0534, 0.71×:
/// what is left is the edges' coverage, which one sample a pixel cannot
/// tell the denoiser.
fn frame_options(spp: u32) -> RenderOptions {
    RenderOptions {
        spp,
        direct: Direct::Sampled,
        ..Default::default()
    }
}

#[test]
fn denoising_brings_a_noisy_render_nearer_the_converged_one() {
    let scene = cornell_box();
    let converged = Frame::prepare(&scene, &frame_options(64))
        .unwrap()
        .render(&|_, _| {})
        .unwrap()
        .image;
    let frame = Frame::prepare(&scene, &frame_options(1)).unwrap();
    let noisy = frame.render(&|_, _| {}).unwrap().image;
    let clean = denoise(&noisy, &frame.guides()).unwrap();
    // The report's measure: relative RMSE over the pixels that see no
    // emitter. Guides that show no albedo leave 0.68 of the error.
    let mask = emitter_mask(&scene);
    let error = |i: &Image| compare(i, &converged, &mask).unwrap().rel_rmse;
    let (before, after) = (error(&noisy), error(&clean));
    assert!(
        after < 0.65 * before,
        "1 spp against 64: {before:.4} before the denoiser, {after:.4} after"
    );
}

#[test]
fn guides_of_another_size_are_a_typed_error() {
    let scene = cornell_box();
    let frame = Frame::prepare(&scene, &frame_options(1)).unwrap();
    let guides = frame.guides();
    let small = Image {
        width: 8,
        height: 8,
        pixels: vec![glam::Vec3::ONE; 64],
    };
    match denoise(&small, &guides) {
        Err(DenoiseError::Size { image, guides }) => assert_eq!((image, guides), ((8, 8), (256, 256))),
        r => panic!("expected a size error, got {:?}", r.map(|i| i.digest())),
    }
}

/// `pbgi report --camera-path … --denoise`: each point-based row has a row
/// of its frames through OIDN beside it, measured against the same
/// references.
#[test]
fn the_flicker_report_measures_the_denoised_frames_too() {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("denoise-flicker");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("shot.json");
    std::fs::write(
        &path,
        r#"{"frames": [{"origin": [0, 0, 3.9], "target": [0, 0, 2.9]},
                       {"origin": [0.02, 0, 3.8], "target": [0, 0, 2.9]}]}"#,
    )
    .unwrap();
    let (path, out) = (path.to_str().unwrap(), dir.to_str().unwrap());
    let run = crate::common::pbgi_command()
        .args([
            "report",
            "cornell-box",
            "--camera-path",
            path,
            "--resolution",
            "24x24",
        ])
        .args([
            "--reference-spp",
            "16",
            "--spp",
            "1",
            "--path-tracer-spp",
            "1",
            "--bounces",
            "1",
        ])
        .args(["--denoise", "--out", out])
        .output()
        .unwrap();
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    let table = std::fs::read_to_string(dir.join("flicker.md")).unwrap();
    // A row's figures, after its label and spp.
    let row = |label: &str| {
        let start = format!("| {label} | 1 |");
        table
            .lines()
            .find_map(|l| l.strip_prefix(&start))
            .unwrap_or_else(|| panic!("no {label} row in\n{table}"))
            .split(" | ")
            .take(2)
            .collect::<Vec<_>>()
            .join(" | ")
    };
    // Another image, so another error: the denoiser ran on the frames.
    assert_ne!(row("pbgi"), row("pbgi + OIDN"), "{table}");
}
