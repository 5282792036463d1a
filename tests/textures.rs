//! Textures in the renderers, on small scenes made here: a textured quad
//! shows its texels' albedo, a cut-out card casts its mask's shadow, a
//! normal or height map shades as its tilted normal does, and the path
//! tracer and the point-based renderer agree on a textured, cut-out box.

use std::sync::Arc;

use glam::{Vec2, Vec3};
use pbgi::render::{ReferenceOptions, RenderOptions, render, render_reference};
use pbgi::scene::texture::{Encoding, Relief};
use pbgi::scene::{AlphaMap, Camera, FovAxis, Light, Material, Mesh, NormalMap, Scene, Texture, TextureMap};

/// The square `[−h, h]²` at height `z`, facing +z, texture coordinates
/// `u = x`, `v = −y` across it (0 to 1, `v` down the image: the image
/// upright seen from above with +y up).
fn square(h: f32, z: f32, material: usize) -> Mesh {
    let p = |x: f32, y: f32| Vec3::new(x * h, y * h, z);
    Mesh {
        name: "square".into(),
        positions: vec![p(-1.0, -1.0), p(1.0, -1.0), p(1.0, 1.0), p(-1.0, 1.0)],
        triangles: vec![[0, 1, 2], [0, 2, 3]],
        uvs: vec![vec![
            Vec2::new(0.0, 1.0),
            Vec2::new(1.0, 1.0),
            Vec2::new(1.0, 0.0),
            Vec2::new(0.0, 0.0),
        ]],
        material,
        ..Mesh::default()
    }
}

/// A camera straight down at `(x, y, 0)` from height `z`, its image `fov`
/// degrees wide, +y up the image.
fn looking_down(at: Vec2, z: f32, fov: f32, pixels: u32) -> Camera {
    Camera {
        origin: Vec3::new(at.x, at.y, z),
        target: Vec3::new(at.x, at.y, 0.0),
        up: Vec3::Y,
        fov_degrees: fov,
        fov_axis: FovAxis::X,
        width: pixels,
        height: pixels,
    }
}

fn scene(meshes: Vec<Mesh>, materials: Vec<Material>, sun: Vec3, camera: Camera) -> Scene {
    let scene = Scene {
        name: "textures".into(),
        meshes,
        materials,
        lights: vec![Light::Directional {
            direction: sun.normalize(),
            irradiance: Vec3::splat(3.0),
        }],
        environment: None,
        camera,
        warnings: Vec::new(),
        file_settings: Default::default(),
    };
    scene.validate().unwrap();
    scene
}

/// A grey card cut out by an 8×8 mask: opaque where `opaque(x, y)` (texel
/// column, row), in its alpha channel, cut at ½.
fn card(opaque: impl Fn(usize, usize) -> bool) -> Material {
    let mask: Vec<[u8; 4]> = (0..64)
        .map(|i| [255, 255, 255, if opaque(i % 8, i / 8) { 255 } else { 0 }])
        .collect();
    let texture = Texture::from_bytes("mask", 8, 8, mask, Encoding::Srgb, true).unwrap();
    Material {
        alpha: Some(AlphaMap {
            map: TextureMap::new(Arc::new(texture)),
            channel: 3,
            factor: 1.0,
            cutoff: 0.5,
        }),
        ..Material::diffuse("card", Vec3::splat(0.5))
    }
}

fn srgb(b: u8) -> f32 {
    let c = b as f64 / 255.0;
    (if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }) as f32
}

/// A 4×4 texture of distinct colours on a square lit straight from above:
/// each pixel is `ρ(u, v) E/π` with `ρ` the bilinear interpolation of the
/// texels (the image is magnified, 16 pixels a texel: no mip level enters),
/// and a pixel within one cell of the interpolation averages to its value
/// at the pixel's centre.
#[test]
fn a_textured_quad_shows_its_texels() {
    let texels: Vec<[u8; 4]> = (0..16u8)
        .map(|i| [20 + 14 * i, 230 - 13 * i, if i % 2 == 0 { 60 } else { 200 }, 255])
        .collect();
    let texture = Texture::from_bytes("colours", 4, 4, texels.clone(), Encoding::Srgb, false).unwrap();
    let material = Material {
        albedo: Vec3::ONE,
        albedo_map: Some(TextureMap::new(Arc::new(texture))),
        ..Material::diffuse("textured", Vec3::ZERO)
    };
    // The square fills the image: 64 px, 16 per texel.
    let camera = looking_down(Vec2::ZERO, 4.0, 2.0 * (1.0f32 / 4.0).atan().to_degrees(), 64);
    let s = scene(vec![square(1.0, 0.0, 0)], vec![material], -Vec3::Z, camera);
    let o = RenderOptions {
        spp: 4,
        ..Default::default()
    };
    let image = render(&s, &o, &|_, _| {}).unwrap().image;
    let texel = |x: usize, y: usize| {
        let t = texels[(y % 4) * 4 + x % 4];
        Vec3::new(srgb(t[0]), srgb(t[1]), srgb(t[2]))
    };
    let mut checked = 0;
    for py in 0..64 {
        for px in 0..64 {
            // Texel coordinates of the pixel's centre, less ½: between texel centres.
            let (fx, fy) = ((px as f32 + 0.5) / 16.0 - 0.5, (py as f32 + 0.5) / 16.0 - 0.5);
            let (x0, y0) = (fx.floor(), fy.floor());
            let (tx, ty) = (fx - x0, fy - y0);
            let inside = 1.0 / 32.0..=31.0 / 32.0;
            if !inside.contains(&tx) || !inside.contains(&ty) {
                continue; // the pixel straddles two cells
            }
            let (x, y) = (
                (x0 as i32).rem_euclid(4) as usize,
                (y0 as i32).rem_euclid(4) as usize,
            );
            let rho = (texel(x, y) * (1.0 - tx) + texel(x + 1, y) * tx) * (1.0 - ty)
                + (texel(x, y + 1) * (1.0 - tx) + texel(x + 1, y + 1) * tx) * ty;
            let want = rho * 3.0 / std::f32::consts::PI;
            // The camera samples lie within the pixel: their mean is off its
            // centre's value by at most half the change across it.
            let slope_x =
                (texel(x + 1, y) - texel(x, y)) * (1.0 - ty) + (texel(x + 1, y + 1) - texel(x, y + 1)) * ty;
            let slope_y =
                (texel(x, y + 1) - texel(x, y)) * (1.0 - tx) + (texel(x + 1, y + 1) - texel(x + 1, y)) * tx;
            let spread = (slope_x.abs() + slope_y.abs()) / 16.0 * 0.5 * 3.0 / std::f32::consts::PI;
            let got = image.pixels[py * 64 + px];
            let ok = ((got - want).abs() - spread).cmple(want * 1e-3).all();
            assert!(ok, "pixel ({px}, {py}): {got} against {want} ± {spread}");
            checked += 1;
        }
    }
    assert!(checked > 3000, "{checked} pixels checked");
}

/// An 8×8 mask (a cross of two-texel bars and a corner block opaque) on a card above a
/// white floor, the sun slanted along +x: each floor pixel is in shadow
/// exactly where the mask is opaque at the point its sun ray crosses the card.
#[test]
fn a_cut_out_card_casts_its_masks_shadow() {
    let opaque = |x: usize, y: usize| (3..=4).contains(&x) || (4..=5).contains(&y) || (x >= 6 && y >= 6);
    let card = Material {
        two_sided: true,
        ..card(opaque)
    };
    let floor = Material::diffuse("floor", Vec3::splat(0.8));
    // Card [−0.5, 0.5]² at z = 1; sun along (1, 0, −1): the shadow lies on [0.5, 1.5] × [−0.5, 0.5].
    let camera = looking_down(
        Vec2::new(1.0, 0.0),
        5.0,
        2.0 * (0.4f32 / 5.0).atan().to_degrees(),
        64,
    );
    let s = scene(
        vec![square(4.0, 0.0, 1), square(0.5, 1.0, 0)],
        vec![card, floor],
        Vec3::new(1.0, 0.0, -1.0),
        camera,
    );
    let o = RenderOptions {
        spp: 4,
        ..Default::default()
    };
    let image = render(&s, &o, &|_, _| {}).unwrap().image;
    let lit = 3.0 * std::f32::consts::FRAC_1_SQRT_2 * 0.8 / std::f32::consts::PI;
    let (mut shadowed, mut checked) = (0, 0);
    for py in 0..64 {
        for px in 0..64 {
            // The floor point at the pixel's centre, and where its sun ray crosses the card.
            let x = 1.0 + (px as f32 + 0.5 - 32.0) / 32.0 * 0.4;
            let y = (32.0 - py as f32 - 0.5) / 32.0 * 0.4;
            let (u, v) = (x - 1.0 + 0.5, 0.5 - y);
            let (tu, tv) = (u * 8.0, v * 8.0);
            // Only where the texels within 0.6 of the point agree: the
            // bilinear alpha's ½ contour rounds the mask's corners.
            let near = |t: f32| ((t - 0.6).max(0.0) as usize)..=((t + 0.6).min(7.99) as usize);
            let in_shadow = opaque(tu as usize, tv as usize);
            if near(tu).any(|x| near(tv).any(|y| opaque(x, y) != in_shadow)) {
                continue;
            }
            let value = image.pixels[py * 64 + px].x;
            checked += 1;
            shadowed += in_shadow as u32;
            assert_eq!(
                value < 0.5 * lit,
                in_shadow,
                "pixel ({px}, {py}) at texel ({tu:.2}, {tv:.2}): {value} against lit {lit}"
            );
        }
    }
    eprintln!("{shadowed} of {checked} pixels in shadow");
    assert!(
        shadowed > 200 && checked - shadowed > 200,
        "{shadowed} of {checked} shadowed"
    );
}

/// A plane whose map tilts every normal to `n` (a constant normal map, or a
/// height ramp `h = u` displaced by `s`: `n ∝ (−s, 0, 1)`), lit by the sun
/// from `l`: every pixel is `ρ E/π · max(0, n·l)`, where the unmapped plane
/// would show `ρ E/π · l_z`.
#[test]
fn a_normal_mapped_plane_shades_as_its_tilted_normal() {
    let rho = 0.5;
    let l = Vec3::new(0.6, 0.3, 1.0).normalize();
    let tilted = Vec3::new(0.3, -0.4, 0.8).normalize();
    let encoded = (tilted * 0.5 + Vec3::splat(0.5)).extend(1.0).to_array();
    let normals = Texture::from_floats("normals", 2, 2, vec![encoded; 4], false).unwrap();
    let w = 64;
    let ramp: Vec<[f32; 4]> = (0..w * w)
        .map(|i| [((i % w) as f32 + 0.5) / w as f32; 4])
        .collect();
    let heights = Texture::from_floats("ramp", w as u32, w as u32, ramp, false).unwrap();
    let s_height = 0.7;
    for (map, relief, scale, n) in [
        (normals, Relief::Normals, 1.0, tilted),
        (
            heights,
            Relief::Heights,
            s_height,
            Vec3::new(-s_height, 0.0, 2.0).normalize(),
        ),
    ] {
        let material = Material {
            normal_map: Some(NormalMap {
                map: TextureMap::new(Arc::new(map)),
                relief,
                scale,
            }),
            ..Material::diffuse("mapped", Vec3::splat(rho))
        };
        // The plane is 2 wide (u over 2 units: ∂h/∂x = 1/2): the middle half seen.
        let camera = looking_down(Vec2::ZERO, 4.0, 2.0 * (0.5f32 / 4.0).atan().to_degrees(), 16);
        let s = scene(vec![square(1.0, 0.0, 0)], vec![material], -l, camera);
        let want = rho * 3.0 / std::f32::consts::PI * n.dot(l).max(0.0);
        let flat = rho * 3.0 / std::f32::consts::PI * l.z;
        assert!(
            (want - flat).abs() > 0.05 * flat,
            "{relief:?}: the map must change the shading"
        );
        let o = ReferenceOptions {
            spp: 4,
            bounces: 0,
            ..Default::default()
        };
        let traced = render_reference(&s, &o, &|_, _| {}).unwrap().image;
        let rendered = render(&s, &RenderOptions::default(), &|_, _| {}).unwrap().image;
        for (name, image) in [("path tracer", traced), ("point-based", rendered)] {
            for (i, p) in image.pixels.iter().enumerate() {
                assert!(
                    (p.x - want).abs() < 0.01 * want,
                    "{relief:?}, {name}, pixel {i}: {} against {want} (flat {flat})",
                    p.x
                );
            }
        }
    }
}

/// The path tracer and the point-based renderer agree on the textured box
/// of `tests/data/textured-box` (a bitmap back wall, a tiled checker floor,
/// a cut-out card: Mitsuba's own XML, which Mitsuba 3 renders within 1.0 %
/// of the path tracer, `scripts/mitsuba-textured.py`), pixel by pixel as on
/// the Cornell box (`reference::point_based_and_path_traced_cornell_boxes_agree_pixel_by_pixel`):
/// within the two images' noise and the gather's error, up to 4 % of the
/// indirect light, in quadrature, with 25 % for the scatter of the estimates.
#[test]
fn the_path_tracer_and_the_point_based_renderer_agree_on_a_textured_cut_out_box() {
    use pbgi::report::{compare, emitter_mask, mean_reference};
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/textured-box/textured-box.xml");
    let mut scene = pbgi::scene::load(&path).unwrap();
    assert!(
        scene.materials.iter().any(|m| m.albedo_map.is_some())
            && scene.materials.iter().any(|m| m.alpha.is_some())
    );
    scene.camera.width = 32;
    scene.camera.height = 32;
    let mask = emitter_mask(&scene);
    let traced = |bounces: i32, seed| {
        let o = ReferenceOptions {
            spp: 4096,
            bounces,
            seed,
            ..Default::default()
        };
        render_reference(&scene, &o, &|_, _| {}).unwrap().image
    };
    let point_based = |seed| {
        let o = RenderOptions {
            spp: 16,
            seed,
            ..Default::default()
        };
        render(&scene, &o, &|_, _| {}).unwrap().image
    };
    let (direct, _) = mean_reference(&[traced(0, 11)], &mask).unwrap();
    let (truth, truth_noise) = mean_reference(&[traced(1, 11), traced(1, 12)], &mask).unwrap();
    let truth_noise = truth_noise.unwrap();
    let (a, b) = (point_based(1), point_based(2));
    let noise = compare(&a, &b, &mask).unwrap().rel_rmse / std::f64::consts::SQRT_2;
    let got = compare(&a, &truth, &mask).unwrap();
    let indirect = 1.0 - compare(&direct, &truth, &mask).unwrap().mean / got.reference_mean;
    let bound = 1.25 * (noise.powi(2) + truth_noise.powi(2) + (0.04 * indirect).powi(2)).sqrt();
    eprintln!(
        "relative RMSE {:.4} (bias {:+.4}); noise {noise:.4}, reference's {truth_noise:.4}, indirect {indirect:.3} of the light: bound {bound:.4}",
        got.rel_rmse, got.bias
    );
    assert!(
        got.rel_rmse <= bound,
        "relative RMSE {} above {bound}",
        got.rel_rmse
    );
}

/// No surfel stands on a cut-out's holes: baked, the card of the shadow
/// test keeps surfels on its opaque texels only, about as many per area as
/// the floor gets.
#[test]
fn no_surfel_stands_on_the_holes_of_a_cut_out() {
    use pbgi::render::{BakeOptions, Lights, Tracer, bake};
    let opaque = |x: usize, y: usize| (3..=4).contains(&x) || (4..=5).contains(&y);
    let card = card(opaque);
    let camera = looking_down(Vec2::ZERO, 5.0, 40.0, 8);
    let s = scene(vec![square(0.5, 1.0, 0)], vec![card], -Vec3::Z, camera);
    let tracer = Tracer::new(&s);
    let lights = Lights::new(&s);
    let o = BakeOptions {
        density: 20000.0,
        ..Default::default()
    };
    let baked = bake(&s, &tracer, &lights, &o).unwrap();
    let surfels = baked.cloud.surfels();
    for p in surfels.iter().map(|s| s.position) {
        let (tu, tv) = ((p.x + 0.5) * 8.0, (0.5 - p.y) * 8.0);
        // Bilinear alpha reaches ½ on texel edges: the edges themselves are left out.
        let near = |t: f32| ((t - 0.51).max(0.0) as usize)..=((t + 0.51).min(7.99) as usize);
        let all_holes = near(tu).all(|x| near(tv).all(|y| !opaque(x, y)));
        assert!(!all_holes, "a surfel at {p} on a hole (texel {tu:.2}, {tv:.2})");
    }
    // 28 of the 64 texels are opaque: that share of the card's 1 × 1 area.
    let want = 20000.0 * 28.0 / 64.0;
    let n = surfels.len() as f32;
    assert!((n - want).abs() < 0.1 * want, "{n} surfels, {want} expected");
}

/// A textured material on a mesh without texture coordinates (a Mitsuba
/// `cube`) loads with a warning naming the material, and renders with the
/// texture's mean.
#[test]
fn a_textured_mesh_without_coordinates_is_warned_of() {
    let data = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/textured-box");
    let dir = std::env::temp_dir().join(format!("pbgi-textures-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let xml = dir.join("cube.xml");
    let png = data.join("pattern.png");
    std::fs::write(
        &xml,
        format!(
            r#"<scene version="3.0.0"><shape type="cube"><bsdf type="diffuse" id="painted">
            <texture type="bitmap" name="reflectance"><string name="filename" value="{}"/></texture>
            </bsdf></shape></scene>"#,
            png.display()
        ),
    )
    .unwrap();
    let s = pbgi::scene::load(&xml).unwrap();
    let m = &s.materials[s.meshes[0].material];
    assert!(m.albedo_map.is_some() && s.meshes[0].uvs.is_empty());
    assert!(
        s.warnings
            .iter()
            .any(|w| w.contains("material painted") && w.contains("no texture coordinate set 0")),
        "{:?}",
        s.warnings
    );
    let at = pbgi::scene::SurfacePoint {
        triangle: 0,
        uv: Vec2::new(0.2, 0.3),
        width: 0.0,
    };
    let mean = m.albedo_map.as_ref().unwrap().texture.mean().truncate();
    assert_eq!(m.albedo_at(&s.meshes[0], &at), mean);
}
