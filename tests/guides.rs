//! A denoiser's guides (`Frame::guides`): each pixel's albedo and normal
//! where its camera samples meet the scene, and a crop's the full frame's.

use glam::Vec3;
use pbgi::render::{Crop, Frame, RenderOptions};
use pbgi::scene::builtin::cornell_box;

fn options(spp: u32) -> RenderOptions {
    RenderOptions {
        spp,
        ..Default::default()
    }
}

#[test]
fn the_guides_show_each_surfaces_albedo_and_normal() {
    let scene = cornell_box();
    let frame = Frame::prepare(&scene, &options(4)).unwrap();
    let g = frame.guides();
    assert_eq!((g.albedo.width, g.albedo.height), (256, 256));
    let at = |img: &pbgi::render::Image, x: u32, y: u32| img.pixels[(y * 256 + x) as usize];
    let material = |name: &str| scene.materials.iter().find(|m| m.name == name).unwrap().albedo;
    // Mid-height on the left (red) wall, which faces +x, and on the right
    // (green) one, which faces -x; the floor's middle, facing +y.
    for (x, y, name, normal) in [
        (20, 128, "red", Vec3::X),
        (236, 128, "green", -Vec3::X),
        (128, 250, "white", Vec3::Y),
    ] {
        let (a, n) = (at(&g.albedo, x, y), at(&g.normal, x, y));
        assert!(
            a.abs_diff_eq(material(name), 1e-6),
            "({x}, {y}): albedo {a}, the {name} wall's"
        );
        assert!(
            n.abs_diff_eq(normal, 1e-5),
            "({x}, {y}): normal {n}, expected {normal}"
        );
    }
    // At the box's top-left corner the camera sees past the walls: nothing.
    assert_eq!(at(&g.albedo, 0, 0), Vec3::ZERO);
    assert_eq!(at(&g.normal, 0, 0), Vec3::ZERO);
}

#[test]
fn a_crops_guides_are_the_full_frames_bit_for_bit() {
    let scene = cornell_box();
    let full = Frame::prepare(&scene, &options(2)).unwrap().guides();
    let (x0, y0, x1, y1) = (37, 90, 131, 203);
    let crop = RenderOptions {
        crop: Some(Crop { x0, y0, x1, y1 }),
        ..options(2)
    };
    let part = Frame::prepare(&scene, &crop).unwrap().guides();
    assert_eq!((part.albedo.width, part.albedo.height), (x1 - x0, y1 - y0));
    for (full, part) in [(&full.albedo, &part.albedo), (&full.normal, &part.normal)] {
        for y in y0..y1 {
            for x in x0..x1 {
                let (a, b) = (
                    full.pixels[(y * 256 + x) as usize],
                    part.pixels[((y - y0) * (x1 - x0) + x - x0) as usize],
                );
                assert_eq!(
                    a.to_array().map(f32::to_bits),
                    b.to_array().map(f32::to_bits),
                    "pixel ({x}, {y})"
                );
            }
        }
    }
}
