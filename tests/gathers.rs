//! Gathers decoupled from camera samples (`RenderOptions::gathers`): a
//! pixel gathers at a few of its camera samples and its other samples reuse
//! that irradiance on the same surface. The image stays within 1 % of the
//! dense render (a gather per camera sample) at a fraction of the gathers,
//! and asking for a gather per sample is the dense render bit for bit.

use pbgi::render::{RenderOptions, RenderOutput, render};
use pbgi::scene::Scene;
use pbgi::scene::builtin::{cornell_box, cornell_box_glossy};

fn scene(mut s: Scene, width: u32, height: u32) -> Scene {
    s.camera.width = width;
    s.camera.height = height;
    s
}

/// The middle `width`×`width` pixels of `s`'s own frame: each pixel the
/// footprint it has at the scene's resolution (the field of view narrowed
/// in proportion), since how much the irradiance varies across a pixel is
/// what reuse within a pixel can miss.
fn middle(mut s: Scene, width: u32) -> Scene {
    let half = (s.camera.fov_degrees.to_radians() * 0.5).tan() * width as f32 / s.camera.width as f32;
    s.camera.fov_degrees = (2.0 * half.atan()).to_degrees();
    scene(s, width, width)
}

fn run(scene: &Scene, gathers: Option<u32>, density: f32) -> RenderOutput {
    let opts = RenderOptions {
        gathers,
        density,
        ..Default::default()
    };
    render(scene, &opts, &|_, _| {}).expect("renders")
}

fn luminance(img: &pbgi::render::Image) -> Vec<f64> {
    img.pixels
        .iter()
        .map(|p| (p.x as f64 + p.y as f64 + p.z as f64) / 3.0)
        .collect()
}

/// Relative RMSE and bias of `a` against `b`, over the pixels that do not
/// see the light (whose radiance dwarfs the rest and holds no gather).
fn relative_error(a: &[f64], b: &[f64]) -> (f64, f64) {
    let keep: Vec<(f64, f64)> = a
        .iter()
        .zip(b)
        .filter(|(_, b)| **b < 5.0)
        .map(|(a, b)| (*a, *b))
        .collect();
    let n = keep.len() as f64;
    let mean = keep.iter().map(|(_, b)| b).sum::<f64>() / n;
    let rmse = (keep.iter().map(|(a, b)| (a - b).powi(2)).sum::<f64>() / n).sqrt();
    let bias = keep.iter().map(|(a, b)| a - b).sum::<f64>() / n;
    (rmse / mean, bias / mean)
}

#[test]
fn one_gather_per_pixel_stays_within_one_percent_of_the_dense_image() {
    // The defaults: 4 camera samples, one gather per pixel. The glossy box
    // gathers at every sample on its glossy surfaces.
    for (name, s) in [
        ("cornell-box", cornell_box()),
        ("cornell-box-glossy", cornell_box_glossy()),
    ] {
        // Under emulation (few property cases asked), fewer pixels.
        let quick = std::env::var("PBGI_QC_TESTS")
            .ok()
            .and_then(|s| s.parse::<u64>().ok())
            .is_some_and(|n| n < 50);
        let s = middle(s, if quick { 16 } else { 64 });
        let density = RenderOptions::default().density;
        let dense = run(&s, None, density);
        let sparse = run(&s, Some(1), density);
        let (rmse, bias) = relative_error(&luminance(&sparse.image), &luminance(&dense.image));
        println!(
            "{name}: {} of {} receivers gathered, relative RMSE {:.4}, bias {:+.5}",
            sparse.receivers, dense.receivers, rmse, bias
        );
        assert!(
            rmse <= 0.01,
            "{name}: relative RMSE {rmse} against the dense image"
        );
        assert!(bias.abs() <= 0.002, "{name}: bias {bias} against the dense image");
        assert!(
            sparse.receivers < dense.receivers,
            "{name}: {} gathers, the dense render {}",
            sparse.receivers,
            dense.receivers
        );
        if name == "cornell-box" {
            // Diffuse only: one gather per pixel, and a few more where a
            // pixel straddles two surfaces.
            assert!(
                (sparse.receivers as f64) < 0.35 * dense.receivers as f64,
                "{name}: {} gathers, the dense render {}",
                sparse.receivers,
                dense.receivers
            );
        }
    }
}

#[test]
fn a_gather_per_camera_sample_is_the_dense_render_bit_for_bit() {
    let s = scene(cornell_box(), 24, 20);
    let bits = |o: &RenderOutput| -> Vec<u32> {
        o.image
            .pixels
            .iter()
            .flat_map(|p| p.to_array().map(f32::to_bits))
            .collect()
    };
    let dense = run(&s, None, 300.0);
    let every = run(&s, Some(RenderOptions::default().spp), 300.0);
    assert_eq!(bits(&dense), bits(&every));
    assert_eq!(dense.receivers, every.receivers);
    // And fewer gathers give another image (the option is not ignored).
    assert_ne!(bits(&run(&s, Some(1), 300.0)), bits(&dense));
}

#[test]
fn gathers_outside_one_to_spp_are_errors() {
    let s = scene(cornell_box(), 8, 8);
    for g in [0, RenderOptions::default().spp + 1] {
        let opts = RenderOptions {
            gathers: Some(g),
            ..Default::default()
        };
        let Err(err) = render(&s, &opts, &|_, _| {}) else {
            panic!("{g} gathers rendered");
        };
        let err = err.to_string();
        assert!(err.contains("gathers"), "{g} gathers: {err}");
    }
}
