use glam::DVec3;

use super::*;
use crate::polygon::projected_solid_angle;
use crate::scene::{Camera, FovAxis, Material, Mesh};

fn quad(name: &str, corners: [Vec3; 4], emission: f32) -> Mesh {
    Mesh {
        name: name.into(),
        positions: corners.to_vec(),
        triangles: vec![[0, 1, 2], [0, 2, 3]],
        normals: None,
        uvs: Vec::new(),
        material: 0,
        emission: Some(Vec3::splat(emission)),
    }
}

/// A scene of `meshes` alone, one grey material, no occluder.
fn emitters(name: &str, meshes: Vec<Mesh>) -> Scene {
    Scene {
        name: name.into(),
        meshes,
        materials: vec![Material::diffuse("grey", Vec3::splat(0.5))],
        lights: vec![],
        environment: None,
        camera: Camera {
            origin: Vec3::new(0.0, 1.0, 3.0),
            target: Vec3::ZERO,
            up: Vec3::Y,
            fov_degrees: 40.0,
            fov_axis: FovAxis::Smaller,
            width: 8,
            height: 8,
        },
        warnings: vec![],
        file_settings: Default::default(),
    }
}

/// Three emitters over an open floor: a bright panel just above the
/// receivers (its corner within a few of its sizes), a dim distant
/// one, and one that faces away; no occluder. The estimate of
/// `∫ L cosθ dω` matches Lambert's formula at receivers beside, under
/// and far from the near panel, whichever emitters a receiver picks.
#[test]
fn irradiance_matches_lamberts_formula() {
    let near = [
        Vec3::new(0.0, 0.3, 0.0),
        Vec3::new(0.0, 0.3, 1.0),
        Vec3::new(1.0, 0.3, 1.0),
        Vec3::new(1.0, 0.3, 0.0),
    ];
    let far = [
        Vec3::new(-6.0, 4.0, -6.0),
        Vec3::new(-6.0, 4.0, -5.0),
        Vec3::new(-5.0, 4.0, -5.0),
        Vec3::new(-5.0, 4.0, -6.0),
    ];
    // Wound to face down, except `away`.
    let away = far.map(|v| v + Vec3::new(8.0, 0.0, 0.0));
    let (mut near, mut far) = (near, far);
    near.reverse();
    far.reverse();
    let scene = emitters(
        "three panels",
        vec![
            quad("near", near, 5.0),
            quad("far", far, 1.0),
            quad("away", away, 3.0),
        ],
    );
    let lights = Lights::new(&scene);
    assert_eq!(lights.groups.len(), 3);
    let tracer = Tracer::new(&scene);
    let n = Vec3::Y;
    for p in [
        Vec3::new(0.5, 0.0, 0.5),
        Vec3::new(1.05, 0.0, 1.1),
        Vec3::new(-0.2, 0.0, 0.4),
        Vec3::new(3.0, 0.0, -1.0),
    ] {
        let origin = p + n * tracer.epsilon();
        let exact: f64 = [(near, 5.0), (far, 1.0)]
            .iter()
            .map(|(q, l)| l * projected_solid_angle(&q.map(|v| (v - origin).as_dvec3()), DVec3::Y))
            .sum();
        let got = irradiance(&lights, &tracer, p, n, 1 << 14, [0x9e37_79b9, 0x85eb_ca6b], false);
        approx::assert_relative_eq!(got, exact, max_relative = 2e-3);
        // Unshadowed, the ratio estimator is the formula itself.
        let got = irradiance(&lights, &tracer, p, n, 2, [5, 6], true);
        approx::assert_relative_eq!(got, exact, max_relative = 1e-5);
    }
}

/// A triangle is kept only while its area is a normal `f32`: one of
/// area 4.5e-46 (subnormal) made a group of emitters of area zero,
/// whose centroid and estimate were 0/0 at every receiver.
#[test]
fn triangles_whose_area_is_not_a_normal_f32_are_left_out() {
    let tiny = [Vec3::ZERO, Vec3::new(3e-23, 0.0, 0.0), Vec3::new(0.0, 3e-23, 0.0)];
    assert!(triangle(tiny).is_none());
    let small = [Vec3::ZERO, Vec3::new(1e-18, 0.0, 0.0), Vec3::new(0.0, 1e-18, 0.0)];
    assert!(triangle(small).is_some_and(|(twice, n)| twice.is_normal() && n == Vec3::Z));
    let huge = [
        Vec3::new(-1e37, 0.0, 0.0),
        Vec3::new(1e37, 0.0, 0.0),
        Vec3::new(0.0, 3e38, 1e37),
    ];
    assert!(triangle(huge).is_none());
    // A light holding the tiny triangle beside a real one: every
    // receiver's estimate stays finite.
    let mut light = quad(
        "light",
        [
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(1.0, 1.0, 1.0),
            Vec3::new(0.0, 1.0, 1.0),
        ],
        4.0,
    );
    light.positions.extend(tiny);
    light.triangles.push([4, 5, 6]);
    let scene = emitters("tiny emitter", vec![light]);
    let lights = Lights::new(&scene);
    assert_eq!(lights.triangles.len(), 2);
    let tracer = Tracer::new(&scene);
    let got = irradiance(
        &lights,
        &tracer,
        Vec3::new(0.5, 0.0, 0.5),
        Vec3::Y,
        8,
        [1, 2],
        false,
    );
    assert!(got.is_finite() && got > 0.0, "{got}");
}

/// `∫ Li cosθ dω` at `p` (normal `n`) from `count` area-light samples:
/// their mean, or with `ratio` the closed form times their shadow ratio.
fn irradiance(
    lights: &Lights,
    tracer: &Tracer,
    p: Vec3,
    n: Vec3,
    count: u32,
    scramble: [u32; 2],
    ratio: bool,
) -> f64 {
    let samples = LightSamples {
        count,
        first: 0,
        scramble,
        ratio,
    };
    let brdf = Brdf {
        diffuse: Vec3::ONE,
        lobe: None::<fn(Vec3) -> Vec3>,
    };
    f64::from(lights.reflected(tracer, p, n, samples, brdf).x)
}

/// A unit panel of radiance 2 at height 1 facing down, over a floor, and an
/// opaque sheet at height ½ over `x < ½`. A receiver at `x`, tilted by
/// `n`, sees the panel's part beyond the line through the sheet's edge:
/// all of it, half of it, or none.
fn half_shadowed() -> (Scene, f32) {
    // Wound to face down.
    let panel = [
        Vec3::new(0.0, 1.0, 0.0),
        Vec3::new(1.0, 1.0, 0.0),
        Vec3::new(1.0, 1.0, 1.0),
        Vec3::new(0.0, 1.0, 1.0),
    ];
    let mut sheet = quad(
        "sheet",
        [
            Vec3::new(-8.0, 0.5, -8.0),
            Vec3::new(0.5, 0.5, -8.0),
            Vec3::new(0.5, 0.5, 8.0),
            Vec3::new(-8.0, 0.5, 8.0),
        ],
        0.0,
    );
    sheet.emission = None;
    (
        emitters("half-shadowed panel", vec![quad("panel", panel, 2.0), sheet]),
        2.0,
    )
}

/// The exact irradiance at `origin` (normal `n`) from the part of the
/// panel of [`half_shadowed`] the sheet leaves in view.
fn half_shadowed_exact(origin: Vec3, n: Vec3, radiance: f32) -> f64 {
    let o = origin.as_dvec3();
    // The sheet's edge (x = ½ at height ½) seen from `o`, carried up to the panel.
    let t = (0.5 - o.y) / (1.0 - o.y);
    let edge = (o.x + (0.5 - o.x) / t).clamp(0.0, 1.0);
    let visible = [
        DVec3::new(edge, 1.0, 0.0),
        DVec3::new(1.0, 1.0, 0.0),
        DVec3::new(1.0, 1.0, 1.0),
        DVec3::new(edge, 1.0, 1.0),
    ]
    .map(|q| q - o);
    let above = crate::polygon::clip(&visible, |q| q.dot(n.as_dvec3()));
    f64::from(radiance) * projected_solid_angle(&above, n.as_dvec3())
}

/// Lit wholly, the ratio estimator is Lambert's formula from one sample or
/// two, without noise; shadowed wholly it is zero; in the penumbra it
/// converges to the light the sheet leaves, where each sample weighs by
/// its unshadowed light (the receiver is tilted, so the panel's halves
/// send unequal light: counting the lit samples alone is 16 % off).
#[test]
fn the_shadow_ratio_is_exact_where_lit_or_shadowed_and_converges_between() {
    let (scene, radiance) = half_shadowed();
    let lights = Lights::new(&scene);
    let tracer = Tracer::new(&scene);
    let tilted = Vec3::new(-0.6, 1.0, 0.2).normalize();
    for (x, n) in [(3.0, Vec3::Y), (2.2, tilted)] {
        let p = Vec3::new(x, 0.0, 0.5);
        let exact = half_shadowed_exact(p + n * tracer.epsilon(), n, radiance);
        assert!(exact > 0.0);
        for (count, scramble) in [(1, [1, 2]), (2, [7, 9]), (1, [0xdead, 0xbeef])] {
            approx::assert_relative_eq!(
                irradiance(&lights, &tracer, p, n, count, scramble, true),
                exact,
                max_relative = 1e-5
            );
        }
    }
    for n in [Vec3::Y, tilted] {
        assert_eq!(
            irradiance(&lights, &tracer, Vec3::new(-2.0, 0.0, 0.5), n, 4, [3, 4], true),
            0.0
        );
    }
    for n in [Vec3::Y, tilted] {
        let p = Vec3::new(0.5, 0.0, 0.5);
        let exact = half_shadowed_exact(p + n * tracer.epsilon(), n, radiance);
        let got = irradiance(&lights, &tracer, p, n, 1 << 14, [0x9e37_79b9, 0x85eb_ca6b], true);
        approx::assert_relative_eq!(got, exact, max_relative = 2e-3);
    }
}

/// A receiver tilted almost edge-on to the panel, lit but seeing only a
/// sliver of it above its horizon: most single samples fall below it and
/// say nothing of the shadow. One point on the sliver decides, so the
/// receiver still gets Lambert's formula, not zero.
#[test]
fn a_receiver_whose_samples_fall_below_its_horizon_asks_the_part_above_it() {
    let (scene, radiance) = half_shadowed();
    let lights = Lights::new(&scene);
    let tracer = Tracer::new(&scene);
    let n = Vec3::new(1.0, 0.05, 0.0).normalize();
    let p = Vec3::new(0.9, 0.0, 0.5);
    let exact = half_shadowed_exact(p + n * tracer.epsilon(), n, radiance);
    assert!(exact > 0.0);
    for k in 0..64u32 {
        let got = irradiance(
            &lights,
            &tracer,
            p,
            n,
            1,
            [k.wrapping_mul(0x9e37_79b9), k ^ 0x5bd1_e995],
            true,
        );
        approx::assert_relative_eq!(got, exact, max_relative = 1e-5);
    }
}
