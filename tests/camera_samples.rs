//! Adaptive camera samples (`RenderOptions::first_samples`): the pixels on
//! an edge, a surface's or a hard shadow's, take the rest of the samples,
//! and a tile decides as the whole frame does, bit for bit.

use glam::Vec3;
use pbgi::render::{Component, Crop, Frame, Image, RenderOptions};
use pbgi::scene::Light;
use pbgi::scene::builtin::cornell_box;

fn options(spp: u32, first_samples: Option<u32>) -> RenderOptions {
    RenderOptions {
        spp,
        first_samples,
        ..Default::default()
    }
}

fn render(opts: &RenderOptions) -> Image {
    let scene = cornell_box();
    Frame::prepare(&scene, opts)
        .unwrap()
        .render(&|_, _| {})
        .unwrap()
        .image
}

/// RMSE over `pixels` of `image` against `truth`.
fn rmse(image: &Image, truth: &Image, pixels: &[usize]) -> f32 {
    let sum: f32 = pixels
        .iter()
        .map(|&i| (image.pixels[i] - truth.pixels[i]).length_squared())
        .sum();
    (sum / pixels.len() as f32).sqrt()
}

/// On `edges`, 2 then 16 samples leave under half of 2 spp's error against
/// `truth`, and about 16 spp's.
fn refined_like_sixteen(
    render: impl Fn(&RenderOptions) -> Image,
    truth: &Image,
    edges: &[usize],
    what: &str,
) {
    let two = rmse(&render(&options(2, None)), truth, edges);
    let sixteen = rmse(&render(&options(16, None)), truth, edges);
    let adaptive = rmse(&render(&options(16, Some(2))), truth, edges);
    assert!(
        adaptive < 0.5 * two && adaptive < 1.3 * sixteen,
        "RMSE on {what}: 2 spp {two:.4}, 16 spp {sixteen:.4}, 2 then 16 {adaptive:.4}"
    );
}

#[test]
fn the_pixels_on_an_edge_take_the_rest_of_the_samples() {
    let scene = cornell_box();
    let truth = render(&options(64, None));
    // Edge pixels: the 64-sample albedo guide is no single material's (nor
    // the black of a miss): the pixel holds two surfaces.
    let guides = Frame::prepare(&scene, &options(64, None)).unwrap().guides();
    let pure = |a: Vec3| a == Vec3::ZERO || scene.materials.iter().any(|m| a.abs_diff_eq(m.albedo, 1e-4));
    let edges: Vec<usize> = (0..guides.albedo.pixels.len())
        .filter(|&i| !pure(guides.albedo.pixels[i]))
        .collect();
    assert!(edges.len() > 1000, "{} edge pixels", edges.len());
    refined_like_sixteen(render, &truth, &edges, "the edges");
}

#[test]
fn an_adaptive_tile_is_its_part_of_the_full_frame_bit_for_bit() {
    let mut area_lit = cornell_box();
    (area_lit.camera.width, area_lit.camera.height) = (96, 96);
    // Under the point light the decision also reads the hard shadows.
    for scene in [area_lit, box_under_a_point_light(96)] {
        let full_opts = options(8, Some(2));
        let full = Frame::prepare(&scene, &full_opts)
            .unwrap()
            .render(&|_, _| {})
            .unwrap()
            .image;
        let (x0, y0, x1, y1) = (21, 30, 70, 77);
        let crop = RenderOptions {
            crop: Some(Crop { x0, y0, x1, y1 }),
            ..full_opts
        };
        let part = Frame::prepare(&scene, &crop)
            .unwrap()
            .render(&|_, _| {})
            .unwrap()
            .image;
        for y in y0..y1 {
            for x in x0..x1 {
                let a = full.pixels[(y * 96 + x) as usize];
                let b = part.pixels[((y - y0) * (x1 - x0) + x - x0) as usize];
                assert_eq!(
                    a.to_array().map(f32::to_bits),
                    b.to_array().map(f32::to_bits),
                    "pixel ({x}, {y})"
                );
            }
        }
    }
}

/// The box lit by a point light under its ceiling instead of its area
/// light: hard shadows fall across single surfaces (the floor, the walls),
/// where no material, normal or depth tells their two sides apart, and no
/// light sample's noise either.
fn box_under_a_point_light(size: u32) -> pbgi::scene::Scene {
    let mut scene = cornell_box();
    (scene.camera.width, scene.camera.height) = (size, size);
    for m in &mut scene.meshes {
        m.emission = None;
    }
    scene.lights.push(Light::Point {
        position: Vec3::new(-0.35, 0.8, 0.3),
        intensity: Vec3::splat(0.6),
    });
    scene
}

#[test]
fn the_pixels_on_a_hard_shadows_edge_take_the_rest_of_the_samples() {
    let n = 128usize;
    let scene = box_under_a_point_light(n as u32);
    let render = |opts: &RenderOptions| {
        Frame::prepare(&scene, opts)
            .unwrap()
            .render(&|_, _| {})
            .unwrap()
            .image
    };
    // The shadow's edge: pixels the light leaves dark beside one it
    // lights, both of one material (the albedo guide pure).
    let direct = render(&RenderOptions {
        component: Component::Direct,
        ..options(64, None)
    });
    let guides = Frame::prepare(&scene, &options(64, None)).unwrap().guides();
    let pure = |i: usize| {
        scene
            .materials
            .iter()
            .any(|m| guides.albedo.pixels[i].abs_diff_eq(m.albedo, 1e-4))
    };
    let edges: Vec<usize> = (0..n * n)
        .filter(|&i| {
            let (x, y) = (i % n, i / n);
            let beside = [
                (x.wrapping_sub(1), y),
                (x + 1, y),
                (x, y.wrapping_sub(1)),
                (x, y + 1),
            ];
            pure(i)
                && beside.into_iter().any(|(a, b)| {
                    let j = b * n + a;
                    a < n
                        && b < n
                        && pure(j)
                        && (direct.pixels[i] == Vec3::ZERO) != (direct.pixels[j] == Vec3::ZERO)
                })
        })
        .collect();
    assert!(edges.len() > 200, "{} pixels on the shadow's edge", edges.len());
    let truth = render(&options(64, None));
    refined_like_sixteen(render, &truth, &edges, "the shadow's edge");
}
