//! Stability: the whole kernel chain (surfels → tree → cut → microbuffer →
//! irradiance and AO) at the edges of `f32`. This file is the one list of the
//! stability cases; the few checked elsewhere are named here with their test.
//!
//! Every case below checks, besides what its doc comment says, that nothing
//! non-finite leaves the library (every node field, every irradiance and AO
//! value) and the energy bounds: irradiance per channel in `[0, π·max L]`,
//! ambient occlusion in `[0, 1]` (`common::check_bounded`); and, where it
//! traverses, that every scheme on every path this CPU runs gives the scalar
//! cut and, through both shading pipelines (scalar `shade_cuts`, 16-lane
//! `shade_packet`), bitwise the scalar shading: irradiance, occlusion and
//! glossy radiance for two lobes (`common::shade_everywhere`; docs/design.md
//! §3). The second bounce (`gather_bounce`) is compared across pipelines on
//! whole renders: `render.rs` `images_of_every_scheme_and_path_are_bit_identical`.
//!
//! | case | test |
//! | --- | --- |
//! | scale by 2^k, k ∈ −40..=40: identical cuts and shading, bit for bit | [`scaling_by_powers_of_two_keeps_cuts_and_shading_bitwise`] |
//! | translation by 10⁴ … 10⁷: error bounds | [`far_translation_error_is_bounded`] |
//! | a receiver moved by 2·10⁻⁴: its shading changes by at most 1 % | [`a_small_move_of_a_receiver_changes_its_shading_a_little`] |
//! | receivers on a surfel, inside a cluster's sphere, on an edge and a corner | [`receivers_on_surfels_inside_clusters_and_on_edges`], [`on_a_surfel_of_a_closed_glowing_sphere`] |
//! | 10⁵ coincident surfels | [`hundred_thousand_coincident_surfels`] |
//! | collinear and coplanar clouds | [`collinear_and_coplanar_clouds`] |
//! | chains and the depth bound `MAX_DEPTH` | [`deep_chains_stay_within_max_depth`] |
//! | radiance 1e-30 … 1e30 in one scene, f64 aggregation, `MAX_RADIANCE` | [`radiance_over_sixty_orders_of_magnitude`] |
//! | denormal positions, normals, radii and radiance | [`denormal_inputs`] |
//! | Ω = 0, tiny, huge; microbuffer N = 1 … 256 | [`every_solid_angle_and_resolution`] |
//! | an empty cloud, one surfel (shading) | [`empty_cloud_and_one_surfel`]; cuts: `inputs.rs` `empty_cloud_gives_empty_cuts_everywhere`, `one_surfel_on_every_path` |
//! | radii differing by 10⁶, a receiver 1e-6 from a huge emitter | [`stiff_mixes`] |
//! | extreme coordinates (1e15) and radii (1e-40 … 1e14) in random clouds | `cut_equivalence.rs` (`Shape::Extreme`) |
//! | bad input: typed errors, never a panic | `inputs.rs`, `bad_input.rs` |
//!
//! `PBGI_QC_TESTS` below 50 (emulated runs) makes the clouds smaller.

use crate::common;

use common::{
    CloudSpec, ReceiverSpec, Rng, Shape, all_paths_agree, check_bounded, invariants, irradiance_in_sphere,
    max_radiance, path_names, reduced, shade, shade_everywhere, tree_is_finite,
};
use glam::{DVec3, Vec3};
use pbgi::synthetic::{box_with_blocks, receivers as box_receivers};
use pbgi::tree::MAX_DEPTH;
use pbgi::{Cut, Isa, PointCloud, Receiver, Scheme, Surfel, Tree};

use std::f32::consts::PI;

/// Builds the tree and checks it is finite.
fn build(surfels: &[Surfel]) -> Tree {
    let tree = Tree::build(&PointCloud::new(surfels.to_vec()).expect("valid surfels"));
    tree_is_finite(&tree).unwrap();
    tree
}

/// Cuts agree on every path and scheme and satisfy the invariants; shading
/// agrees bitwise everywhere and is bounded. Returns the shading.
fn check_all(
    surfels: &[Surfel],
    tree: &Tree,
    receivers: &[Receiver],
    omega: f32,
    res: usize,
) -> Vec<(Vec3, f32)> {
    let cuts = all_paths_agree(tree, receivers, omega, 0.0, 2).unwrap();
    let parents = tree.parents();
    for (i, c) in cuts.iter().enumerate() {
        invariants(tree, &parents, c).unwrap_or_else(|e| panic!("receiver {i} {:?}: {e}", receivers[i]));
    }
    let shading = shade_everywhere(tree, receivers, omega, res).unwrap();
    check_bounded(&shading, max_radiance(surfels)).unwrap();
    shading
}

fn bits(shading: &[(Vec3, f32)]) -> Vec<u32> {
    shading
        .iter()
        .flat_map(|(e, ao)| [e.x, e.y, e.z, *ao].map(f32::to_bits))
        .collect()
}

/// Inward-facing surfels on a Fibonacci sphere of radius `r` around `c`,
/// the disks' areas summing to the sphere's; radiance of surfel `i` from `radiance(i)`.
fn sphere(n: usize, c: Vec3, r: f32, mut radiance: impl FnMut(usize) -> Vec3) -> Vec<Surfel> {
    let golden = PI * (3.0 - 5f32.sqrt());
    let disk = r * (4.0 / n as f32).sqrt();
    (0..n)
        .map(|i| {
            let z = 1.0 - 2.0 * (i as f32 + 0.5) / n as f32;
            let s = (1.0 - z * z).sqrt();
            let d = Vec3::new(s * (golden * i as f32).cos(), s * (golden * i as f32).sin(), z);
            let d = d.as_dvec3().normalize().as_vec3();
            Surfel {
                position: c + d * r,
                normal: -d,
                radius: disk,
                radiance: radiance(i),
            }
        })
        .collect()
}

/// Scaling surfels and receivers by 2^k for every k in −40..=40 gives the
/// identical cut (every scheme, every path) and the identical irradiance and
/// AO, bit for bit. Why bitwise: every quantity of the tree build, the node
/// test and the microbuffer is homogeneous in the coordinates (differences,
/// products, square roots, ratios of like powers), and multiplying by a power
/// of two is exact in `f32` away from overflow and the subnormal range (the
/// box's smallest area at k = −40 is about 1e-28, its largest squared
/// distance at k = 40 about 1e25). Irradiance is a sum of radiance times solid
/// angles, which do not change with the scale, so with radiance fixed it is
/// scale invariant.
#[test]
fn scaling_by_powers_of_two_keeps_cuts_and_shading_bitwise() {
    let surfels = box_with_blocks(if reduced() { 300 } else { 2000 }, 3).into_surfels();
    let mut receivers = box_receivers(if reduced() { 1 } else { 2 }, 0.05, 0.5, 9);
    // On a surfel (d = 0 for its leaf), at the box centre, in a corner.
    receivers.extend(
        Receiver::from_pairs([
            (surfels[7].position, surfels[7].normal),
            (Vec3::ZERO, Vec3::Y),
            (Vec3::splat(-1.0), Vec3::splat(1.0 / 3f32.sqrt())),
        ])
        .unwrap(),
    );
    let tree = build(&surfels);
    let (omega, res) = (0.05, 8);
    let cuts = all_paths_agree(&tree, &receivers, omega, 0.0, 2).unwrap();
    let shading = shade_everywhere(&tree, &receivers, omega, res).unwrap();
    check_bounded(&shading, max_radiance(&surfels)).unwrap();
    assert!(
        shading.iter().any(|(e, _)| e.x > 0.0),
        "no light: the test proves nothing"
    );
    // Every k; emulated runs every fourth (still ±40).
    for k in (-40..=40).step_by(if reduced() { 4 } else { 1 }) {
        let s = 2f32.powi(k);
        let scaled = common::scale_cloud(&surfels, s);
        let tree_s = build(&scaled);
        let recs_s: Vec<Receiver> = receivers
            .iter()
            .map(|r| Receiver::new(r.position() * s, r.normal()).unwrap())
            .collect();
        let cuts_s = all_paths_agree(&tree_s, &recs_s, omega, 0.0, 2).unwrap();
        if let Some(i) = (0..cuts.len()).find(|&i| cuts[i] != cuts_s[i]) {
            panic!("2^{k}: the cut of receiver {i} changes");
        }
        let shading_s = shade(&tree_s, &recs_s, omega, res, Scheme::Hybrid, Isa::best()).unwrap();
        if let Some(i) = (0..shading.len()).find(|&i| bits(&shading[i..=i]) != bits(&shading_s[i..=i])) {
            panic!(
                "2^{k}: receiver {i} shades {:?}, unscaled {:?}",
                shading_s[i], shading[i]
            );
        }
    }
    eprintln!(
        "2^k scaling: k −40..=40, {} receivers, paths {}",
        receivers.len(),
        path_names()
    );
}

/// Irradiance as one number per receiver (the sum of the channels).
fn luminance(shading: &[(Vec3, f32)]) -> Vec<f64> {
    shading.iter().map(|(e, _)| e.element_sum() as f64).collect()
}

/// `(RMS of a − b) / RMS of b`, and the largest `|a − b|` over the RMS of b.
fn relative_errors(a: &[f64], b: &[f64]) -> (f64, f64) {
    let rms = (b.iter().map(|x| x * x).sum::<f64>() / b.len() as f64).sqrt();
    let diff = a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum::<f64>() / b.len() as f64;
    let max = a.iter().zip(b).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max);
    (diff.sqrt() / rms, max / rms)
}

/// Translating the scene far from the origin. Surfel and receiver positions
/// are `f32`, so at distance `T` every input is already rounded to half an
/// ulp of `T` (ulp 2⁻¹⁰ ≈ 1e-3 at 10⁴, 2⁻⁷ at 10⁵, 2⁻⁴ at 10⁶, 1 at 10⁷):
/// at 10⁷ the unit box is a grid of whole units before the library sees it.
/// On the box (radiance varying smoothly over it), receivers 0.05 above its
/// surfaces, Ω 0.05, N 8, the test separates the sources of error:
///
/// * **library**: the translated scene against the *same* rounded scene moved
///   back to the origin (exactly: the rounded coordinates minus `T` are `f32`
///   values). The node test and the microbuffer subtract nearby `f32` values
///   (`c − x`), which is exact (Sterbenz), so leaves are handled identically:
///   with Ω = 0 (leaves only) the shading is **bit for bit** the same at every
///   `T` (asserted). Only inner nodes' centres, computed in `f64` and stored
///   in `f32`, round to half an ulp of `T`, like the input itself, which can
///   flip borderline node tests and move a cluster's depth interval, which
///   the microbuffer's composition layers by. Asserted at every `T`: smaller
///   than the input's own rounding causes; and ≤ 1 % RMS wherever that
///   rounding is itself at most 1 % (10⁴ … 10⁶). At 10⁷ a stored centre is
///   off by up to half a unit in this unit box, a large part of a cluster's
///   radius, and the layering follows it. Measured RMS (max):
///   10⁴ 0.071 % (0.41 %), 10⁵ 0.28 % (1.05 %), 10⁶ 0.58 % (2.3 %),
///   10⁷ 1.8 %.
/// * **input rounding**: the rounded scene at the origin against the
///   unrounded one: 0.20 %, 0.54 %, 0.89 % at 10⁴ … 10⁶; tens of % at 10⁷.
/// * **total**: the translated scene against the unrounded one at the origin,
///   asserted ≤ 0.5 % at 10⁴, ≤ 1 % at 10⁵, ≤ 2.5 % at 10⁶ (measured 0.22 %,
///   0.51 %, 0.91 %; with the smaller cloud of emulated runs 0.21 %, 0.46 %,
///   1.45 %); at 10⁷ it is the input's rounding, and only finiteness and
///   the energy bounds are asserted. The input's rounding is bounded because
///   the shading is continuous in the positions: a splat whose disk only
///   grazed a pixel once hid nothing behind it until the disk caught one of
///   the pixel's sub-samples, then a dozen sub-samples at once, and a move of
///   10⁻⁴ changed a receiver's occlusion by 3 % (the total here was 0.52 %
///   at 10⁴); [`a_small_move_of_a_receiver_changes_its_shading_a_little`].
///
/// Receiver-relative coordinates would not help: the subtractions are already
/// exact, and the input's rounding, which no library can undo, is the larger
/// error at every distance. (With the box's small bright light, 0.01 under
/// the ceiling, every one of these errors is 10–50× larger: the z-buffer's
/// choice between light and ceiling jumps under any perturbation, a property
/// of the estimator rather than of the arithmetic.)
#[test]
fn far_translation_error_is_bounded() {
    // Radiance varying smoothly (see above for the box's own light).
    let mut surfels = box_with_blocks(if reduced() { 500 } else { 3000 }, 5).into_surfels();
    for s in &mut surfels {
        s.radiance = Vec3::splat(1.5) + s.position * 0.5;
    }
    let receivers: Vec<Receiver> = box_receivers(if reduced() { 2 } else { 5 }, 0.1, 0.0, 3)
        .iter()
        .map(|r| Receiver::new(r.position() + r.normal() * 0.05, r.normal()).unwrap())
        .collect();
    let (omega, res) = (0.05, 8);
    let lmax = max_radiance(&surfels);
    let tree = build(&surfels);
    let hybrid = |tree: &Tree, recs: &[Receiver], omega: f32| {
        let s = shade(tree, recs, omega, res, Scheme::Hybrid, Isa::best()).unwrap();
        check_bounded(&s, lmax).unwrap();
        s
    };
    let original = luminance(&hybrid(&tree, &receivers, omega));
    for t in [1e4f64, 1e5, 1e6, 1e7] {
        let o = DVec3::new(t, t * 0.75, -t * 0.5);
        let far = |p: Vec3| (p.as_dvec3() + o).as_vec3();
        let back = |p: Vec3| {
            let q = p.as_dvec3() - o;
            assert_eq!(q.as_vec3().as_dvec3(), q, "moving back is exact");
            q.as_vec3()
        };
        let moved: Vec<Surfel> = surfels
            .iter()
            .map(|s| Surfel {
                position: far(s.position),
                ..*s
            })
            .collect();
        let recs_far: Vec<Receiver> = receivers
            .iter()
            .map(|r| Receiver::new(far(r.position()), r.normal()).unwrap())
            .collect();
        let rounded: Vec<Surfel> = moved
            .iter()
            .map(|s| Surfel {
                position: back(s.position),
                ..*s
            })
            .collect();
        let recs_rounded: Vec<Receiver> = recs_far
            .iter()
            .map(|r| Receiver::new(back(r.position()), r.normal()).unwrap())
            .collect();
        let (tree_far, tree_rounded) = (build(&moved), build(&rounded));
        // Leaves only: bit for bit.
        let leaves_far = check_all(&moved, &tree_far, &recs_far, 0.0, res);
        let leaves_rounded = hybrid(&tree_rounded, &recs_rounded, 0.0);
        assert_eq!(
            bits(&leaves_far),
            bits(&leaves_rounded),
            "translation {t:e}, Ω = 0"
        );
        let shading_far = luminance(&check_all(&moved, &tree_far, &recs_far, omega, res));
        let shading_rounded = luminance(&hybrid(&tree_rounded, &recs_rounded, omega));
        let (lib, lib_max) = relative_errors(&shading_far, &shading_rounded);
        let (input, _) = relative_errors(&shading_rounded, &original);
        let (total, total_max) = relative_errors(&shading_far, &original);
        eprintln!(
            "translation {t:e}: library error RMS {lib:.2e} (max {lib_max:.2e}); input rounding {input:.2e}; \
             total RMS {total:.2e} (max {total_max:.2e})"
        );
        if input <= 0.01 {
            assert!(lib <= 0.01, "translation {t:e}: library error {lib:e}");
        }
        assert!(
            lib < input,
            "translation {t:e}: library error {lib:e} ≥ input rounding {input:e}"
        );
        let total_bound = [(1e4, 0.005), (1e5, 0.01), (1e6, 0.025)]
            .iter()
            .find(|b| b.0 == t)
            .map(|b| b.1);
        if let Some(bound) = total_bound {
            assert!(
                total <= bound,
                "translation {t:e}: total error {total:e} > {bound}"
            );
        }
    }
}

/// Continuity in the receiver's position: each receiver of the box (500
/// surfels, radiance varying smoothly, receivers 0.05 above the surfaces)
/// moved by δ = 2·10⁻⁴ along each axis both ways, at Ω 0 (leaves) and
/// 0.05, N 8. What a receiver sees at distance `h` subtends solid angles
/// that change by about `2δ/h` = 0.8 % under such a move, so occlusion
/// (a fraction of one) and irradiance (relative) may change by 1 % at most.
/// Measured: 0.46 % of occlusion, 0.67 % of irradiance. When a splat's
/// grown disk hid nothing until its own disk caught a sub-sample, one
/// receiver's occlusion changed by 2.9 %, its irradiance by 3.4 %.
#[test]
fn a_small_move_of_a_receiver_changes_its_shading_a_little() {
    let mut surfels = box_with_blocks(500, 5).into_surfels();
    for s in &mut surfels {
        s.radiance = Vec3::splat(1.5) + s.position * 0.5;
    }
    let receivers: Vec<Receiver> = box_receivers(2, 0.1, 0.0, 3)
        .iter()
        .map(|r| Receiver::new(r.position() + r.normal() * 0.05, r.normal()).unwrap())
        .collect();
    let tree = build(&surfels);
    let delta = 2e-4;
    for omega in [0.0, 0.05] {
        let base = shade(&tree, &receivers, omega, 8, Scheme::Hybrid, Isa::best()).unwrap();
        let (mut occlusion, mut irradiance) = (0.0f32, 0.0f32);
        for d in [Vec3::X, Vec3::Y, Vec3::Z, -Vec3::X, -Vec3::Y, -Vec3::Z] {
            let moved: Vec<Receiver> = receivers
                .iter()
                .map(|r| Receiver::new(r.position() + d * delta, r.normal()).unwrap())
                .collect();
            let shading = shade(&tree, &moved, omega, 8, Scheme::Hybrid, Isa::best()).unwrap();
            for ((e, ao), (e0, ao0)) in shading.iter().zip(&base) {
                occlusion = occlusion.max((ao - ao0).abs());
                irradiance = irradiance.max(((e.element_sum() - e0.element_sum()) / e0.element_sum()).abs());
            }
        }
        eprintln!(
            "Ω {omega}: {} receivers moved by {delta:e}: occlusion changed by {occlusion:.4} at most, irradiance by {:.2} %",
            receivers.len(),
            irradiance * 100.0
        );
        assert!(occlusion <= 0.01, "Ω {omega}: occlusion changed by {occlusion}");
        assert!(
            irradiance <= 0.01,
            "Ω {omega}: irradiance changed by {irradiance}"
        );
    }
}

/// Receivers exactly on surfels (`d² = 0` for their leaf: the microbuffer
/// skips a node without direction), with the surfel's normal, the opposite
/// one and a random one; at the centres of inner nodes' bounding spheres and
/// at random points inside them; on the edges between the box's walls and
/// in its corners, with either wall's normal and the bisector.
#[test]
fn receivers_on_surfels_inside_clusters_and_on_edges() {
    let surfels = box_with_blocks(if reduced() { 400 } else { 3000 }, 11).into_surfels();
    let tree = build(&surfels);
    let mut rng = Rng::new(17);
    let mut pairs = Vec::new();
    for s in surfels.iter().step_by(surfels.len() / 12) {
        pairs.push((s.position, s.normal));
        pairs.push((s.position, -s.normal));
        pairs.push((s.position, rng.unit()));
    }
    for k in (0..tree.len() as u32)
        .filter(|&k| !tree.is_leaf(k))
        .step_by(tree.len() / 24)
    {
        let (c, r) = tree.sphere(k);
        pairs.push((c, rng.unit()));
        pairs.push((c + rng.unit() * r * rng.range(0.0, 1.0), rng.unit()));
    }
    let bisector = |a: Vec3, b: Vec3| (a + b).as_dvec3().normalize().as_vec3();
    for z in [-1.0, -0.5, 0.0, 0.999] {
        // Floor (y = −1, normal +y) meets the left wall (x = −1, normal +x).
        let p = Vec3::new(-1.0, -1.0, z);
        for n in [Vec3::Y, Vec3::X, bisector(Vec3::X, Vec3::Y)] {
            pairs.push((p, n));
        }
        // Back wall (z = −1) meets the ceiling (y = 1).
        let p = Vec3::new(z, 1.0, -1.0);
        for n in [-Vec3::Y, Vec3::Z, bisector(Vec3::Z, -Vec3::Y)] {
            pairs.push((p, n));
        }
    }
    pairs.push((Vec3::splat(-1.0), Vec3::splat(1.0 / 3f32.sqrt())));
    pairs.push((
        Vec3::new(1.0, 1.0, -1.0),
        Vec3::new(-1.0, -1.0, 1.0) / 3f32.sqrt(),
    ));
    let receivers = Receiver::from_pairs(pairs).unwrap();
    for omega in [0.0, 0.05, 0.5] {
        let shading = check_all(&surfels, &tree, &receivers, omega, 8);
        assert!(
            shading.iter().any(|(e, _)| e.x > 0.0),
            "no light: the test proves nothing"
        );
    }
    eprintln!("special receivers: {} on paths {}", receivers.len(), path_names());
}

/// Receivers exactly on surfels of a closed sphere glowing inside, facing
/// inwards: the sphere fills their hemisphere, so what is missing is at
/// most the surfel under the receiver and its neighbours cut by the tangent
/// plane. The glow is uneven, `2 + d_z + d_x/2` at direction `d` from the
/// centre, so that an over-estimate is not hidden by the clamp at `π·max L`
/// (a uniform glow's exact answer). Against quadrature: measured −0.06 to
/// −0.19 % (4,000 or 20,000 surfels), occlusion 0.9985; asserted within
/// 0.5 % and above 0.995 (were 15 % and 0.85).
#[test]
fn on_a_surfel_of_a_closed_glowing_sphere() {
    let n = if reduced() { 4000 } else { 20_000 };
    let (c, r) = (Vec3::new(3.0, -2.0, 1.0), 2.0);
    let glow = |d: Vec3| 2.0 + d.z as f64 + 0.5 * d.x as f64;
    let mut surfels = sphere(n, c, r, |_| Vec3::ZERO);
    for s in &mut surfels {
        s.radiance = Vec3::splat(glow(-s.normal) as f32);
    }
    let tree = build(&surfels);
    let pairs: Vec<_> = surfels
        .iter()
        .step_by(n / 16)
        .map(|s| (s.position, s.normal))
        .collect();
    let receivers = Receiver::from_pairs(pairs.iter().copied()).unwrap();
    let shading = check_all(&surfels, &tree, &receivers, 0.02, 8);
    for (i, ((e, ao), (q, normal))) in shading.iter().zip(&pairs).enumerate() {
        let want = irradiance_in_sphere((*q - c) / r, *normal, glow);
        assert!(
            (e.x as f64 / want - 1.0).abs() < 0.005,
            "receiver {i}: E = {e} vs {want}"
        );
        assert!(*ao > 0.995, "receiver {i}: AO {ao}");
    }
}

/// 10⁵ surfels at one point: the build terminates with depth ⌈log₂ 10⁵⌉ = 17
/// (the index breaks ties); from above, the whole cluster is one splat; facing
/// away or from below, one discard; at the point itself (`d = 0`) every leaf
/// is splatted and none has a direction, so the shading is exactly zero.
#[test]
fn hundred_thousand_coincident_surfels() {
    let s = Surfel {
        position: Vec3::splat(0.5),
        normal: Vec3::Z,
        radius: 0.01,
        radiance: Vec3::ONE,
    };
    let n = if reduced() { 10_000 } else { 100_000 };
    let surfels = vec![s; n];
    let tree = build(&surfels);
    assert_eq!(tree.depth(), (n as f64).log2().ceil() as usize);
    let r = Receiver::from_pairs([
        (Vec3::new(0.5, 0.5, 1.0), -Vec3::Z),
        (Vec3::new(0.5, 0.5, 1.0), Vec3::Z),
        (Vec3::new(0.5, 0.5, 0.0), Vec3::Z),
        (Vec3::new(0.5, 0.5, 0.5), Vec3::Z),
    ])
    .unwrap();
    let cuts = all_paths_agree(&tree, &r, 0.05, 0.0, 2).unwrap();
    let parents = tree.parents();
    for c in &cuts {
        invariants(&tree, &parents, c).unwrap();
    }
    // From above, the cluster subtends π(0.01)²/0.25 < Ω: the root is the cut.
    let root = |splat: bool| Cut {
        splats: if splat { vec![0] } else { vec![] },
        discards: if splat { vec![] } else { vec![0] },
    };
    assert_eq!(cuts[0], root(true));
    // Facing away from it: below the tangent plane; below it, it faces away.
    assert_eq!(cuts[1], root(false));
    assert_eq!(cuts[2], root(false));
    // At the cluster itself (d = 0): every leaf.
    assert_eq!(cuts[3].splats.len(), n);
    let shading = shade_everywhere(&tree, &r, 0.05, 8).unwrap();
    check_bounded(&shading, Vec3::ONE).unwrap();
    assert!(shading[0].0.x > 0.0, "the cluster above is seen");
    assert_eq!(shading[3], (Vec3::ZERO, 0.0), "no node has a direction at d = 0");
    eprintln!("coincident surfels: {n} on paths {}", path_names());
}

/// Collinear and coplanar clouds (evenly spaced and random, normals in the
/// plane, flipped or random), with receivers on their surfels, in their plane
/// (edge on), on the line, around and far away: cuts, invariants, bounded
/// and bitwise identical shading.
#[test]
fn collinear_and_coplanar_clouds() {
    let seeds = if reduced() { 2 } else { 8 };
    let mut count = 0;
    for shape in [Shape::Coplanar, Shape::Collinear] {
        for seed in 0..seeds {
            let spec = CloudSpec {
                shape,
                n: if reduced() { 100 } else { 600 },
                seed: 1000 + seed,
            };
            let mut surfels = common::cloud(&spec);
            for s in &mut surfels {
                s.radiance = Vec3::new(1.0, 0.5, 0.25); // some light everywhere
            }
            let tree = build(&surfels);
            let pairs = common::receivers(
                &ReceiverSpec {
                    count: 40,
                    seed: seed * 7,
                },
                &surfels,
            );
            let receivers = Receiver::from_pairs(pairs).unwrap();
            for omega in [0.0, 0.05] {
                check_all(&surfels, &tree, &receivers, omega, 4);
            }
            count += receivers.len();
        }
    }
    eprintln!(
        "collinear and coplanar: {count} receivers × 2 Ω on paths {}",
        path_names()
    );
}

/// The depth bound. The median split puts ⌊n/2⌋ surfels left and ⌈n/2⌉
/// right whatever the positions, so a cloud facing one way (no hollow
/// solid's two sides to part by orientation) is exactly ⌈log₂ n⌉ deep — chains
/// that would make a spatial split degenerate (positions 2^i, 1.001^i,
/// alternating in sign, reversed) included — hence at most
/// `MAX_DEPTH` = 30 for the largest cloud `PointCloud::MAX_SURFELS` = 2³⁰.
/// The traversal stacks are fixed arrays of `MAX_DEPTH + 2` entries (scalar
/// and packet; single's pair stack grows as needed), enough for a depth-first
/// walk that pushes both children: at most depth + 1 entries. The deepest
/// walks (Ω = 0 with every leaf splatted) run on every scheme and path.
#[test]
fn deep_chains_stay_within_max_depth() {
    assert_eq!(PointCloud::MAX_SURFELS, 1 << MAX_DEPTH);
    let log2 = |n: usize| (n as f64).log2().ceil() as usize;
    let chain = |n: usize, f: &dyn Fn(usize) -> f32| -> Vec<Surfel> {
        (0..n)
            .map(|i| Surfel {
                position: Vec3::new(f(i), 0.0, 0.0),
                normal: Vec3::Y,
                radius: 1e-4 * f(i).abs().max(1.0),
                radiance: Vec3::ONE,
            })
            .collect()
    };
    let shapes: [(&str, &dyn Fn(usize) -> f32); 4] = [
        ("2^i", &|i| 2f32.powi(i as i32 % 120)),
        ("1.001^i", &|i| 1.001f32.powi(i as i32)),
        (
            "±2^i",
            &|i| if i % 2 == 0 { 1.0 } else { -1.0 } * 2f32.powi((i / 2) as i32 % 120),
        ),
        ("2^-i", &|i| 2f32.powi(-((i as i32) % 120))),
    ];
    for n in [1, 2, 3, 4, 5, 7, 8, 9, 100, 127, 128, 129, 1000, 4097] {
        for (name, f) in &shapes {
            let tree = build(&chain(n, f));
            assert_eq!(tree.depth(), log2(n), "{name}, n = {n}");
        }
    }
    // The deepest tree here: 2^17 + 1 surfels, depth 18; every leaf splatted.
    let n = if reduced() { (1 << 12) + 1 } else { (1 << 17) + 1 };
    let surfels = chain(n, &|i| 1.0001f32.powi(i as i32));
    let tree = build(&surfels);
    assert_eq!(tree.depth(), log2(n));
    assert!(tree.depth() <= MAX_DEPTH);
    let r = Receiver::from_pairs([
        (Vec3::new(1.0, 1.0, 0.0), -Vec3::Y),
        (Vec3::new(3.0, 1.0, 0.0), -Vec3::Y),
    ])
    .unwrap();
    let cuts = all_paths_agree(&tree, &r, 0.0, 0.0, 2).unwrap();
    assert_eq!(cuts[0].splats.len(), n);
    eprintln!(
        "deep chain: {n} surfels, depth {} on paths {}",
        tree.depth(),
        path_names()
    );
}

/// Radiance from 1e-30 to 1e30 in one scene. The tree aggregates the
/// area-weighted radiance in `f64` (an `f32` sum of 1e30 × area would
/// overflow or swamp the small terms), so each node's mean is the `f64` mean
/// rounded once: checked against an independent `f64` sum at the root
/// (relative 1e-6). The irradiance stays finite and within `π·max L` per
/// channel; a channel lit only at 1e-30 still gets light (no flush to zero),
/// and a channel at `MAX_RADIANCE` does not overflow.
#[test]
fn radiance_over_sixty_orders_of_magnitude() {
    let n = if reduced() { 3000 } else { 12_000 };
    let mut rng = Rng::new(5);
    let levels: Vec<f32> = (-30..=30).step_by(5).map(|e| 10f32.powi(e)).collect();
    let surfels = sphere(n, Vec3::ZERO, 1.0, |_| {
        Vec3::new(
            rng.pick(&levels),
            1e-30 * rng.range(1.0, 2.0),
            pbgi::points::MAX_RADIANCE,
        )
    });
    let tree = build(&surfels);
    // The root's mean radiance against an f64 sum.
    let (mut sum, mut area) = (DVec3::ZERO, 0.0f64);
    for s in &surfels {
        let a = (s.radius as f64).powi(2);
        sum += s.radiance.as_dvec3() * a;
        area += a;
    }
    let want = sum / area;
    let got = tree.radiance(0).as_dvec3();
    assert!(
        ((got - want) / want).abs().max_element() < 1e-6,
        "root radiance {got} vs f64 mean {want}"
    );
    let receivers = Receiver::from_pairs([
        (Vec3::ZERO, Vec3::Z),
        (Vec3::new(0.2, 0.1, -0.3), Vec3::new(0.6, 0.0, 0.8)),
        (surfels[0].position, surfels[0].normal),
    ])
    .unwrap();
    let lmax = max_radiance(&surfels);
    for omega in [0.0, 0.02, 1.0] {
        let shading = check_all(&surfels, &tree, &receivers, omega, 8);
        for (e, _) in &shading {
            assert!(e.y > 0.0 && e.x > 0.0, "Ω {omega}: {e}: a channel went dark");
            assert!(
                e.z > 0.5 * PI * lmax.z,
                "Ω {omega}: {e}: the MAX_RADIANCE channel"
            );
        }
    }
}

/// Denormal (subnormal) inputs: positions with components 1e-40, radii 1e-40
/// and `f32::MIN_POSITIVE`, normals with subnormal components, radiance 1e-40;
/// receivers at subnormal offsets. Areas underflow to zero in `f32` (the tree
/// keeps them in `f64` until the end), so such nodes are invisible in the
/// microbuffer: nothing may be NaN.
#[test]
fn denormal_inputs() {
    let tiny = 1e-40f32;
    let mut rng = Rng::new(9);
    let mut surfels = Vec::new();
    for i in 0..400 {
        let position = match i % 4 {
            0 => Vec3::new(tiny, -tiny, 0.0) * (i as f32),
            1 => rng.cube() * 1e-38,
            2 => rng.cube(),
            _ => Vec3::new(tiny, 0.5, -tiny),
        };
        let normal = match i % 3 {
            0 => Vec3::new(tiny, 0.0, 1.0),
            1 => Vec3::new(0.0, -1.0, tiny),
            _ => rng.unit(),
        };
        let radius = [tiny, f32::MIN_POSITIVE, 1e-3, 0.2][i % 4];
        let radiance = [Vec3::splat(tiny), Vec3::new(1.0, tiny, 0.0), Vec3::ONE][i % 3];
        surfels.push(Surfel {
            position,
            normal,
            radius,
            radiance,
        });
    }
    let tree = build(&surfels);
    let receivers = Receiver::from_pairs([
        (Vec3::ZERO, Vec3::Z),
        (Vec3::splat(tiny), Vec3::new(tiny, 0.0, 1.0)),
        (Vec3::new(0.0, 0.0, f32::MIN_POSITIVE), -Vec3::Z),
        (surfels[0].position, surfels[0].normal),
        (Vec3::new(0.0, 3.0, 0.0), -Vec3::Y),
    ])
    .unwrap();
    for omega in [0.0, tiny, 0.05] {
        check_all(&surfels, &tree, &receivers, omega, 4);
    }
}

/// Ω = 0 (leaves only), subnormal, tiny, typical, 4π (the root is splatted
/// from anywhere it is not culled), 1e3 and `f32::MAX` (`Ω·d²` overflows to
/// infinity: still splats), with microbuffers of resolution 1, 2, 8 and 256
/// (the largest; 32 under emulation); receivers in the box and on a surfel.
#[test]
fn every_solid_angle_and_resolution() {
    let surfels = box_with_blocks(if reduced() { 300 } else { 1500 }, 4).into_surfels();
    let tree = build(&surfels);
    let mut receivers = box_receivers(1, 0.2, 0.3, 5);
    receivers.truncate(if reduced() { 2 } else { 6 });
    receivers.push(Receiver::new(surfels[3].position, surfels[3].normal).unwrap());
    let omegas = [0.0, 1e-40, 1e-9, 0.05, 4.0 * PI, 1e3, f32::MAX];
    // Emulated runs (PBGI_QC_TESTS < 50) stop at 32: the table of N = 256
    // alone takes minutes under qemu.
    let resolutions: &[usize] = if reduced() {
        &[1, 2, 8, 32]
    } else {
        &[1, 2, 8, 256]
    };
    for &res in resolutions {
        // The largest raster costs 200× the smallest: fewer receivers there.
        let receivers = &receivers[receivers.len() - if res > 8 { 2 } else { receivers.len() }..];
        for &omega in &omegas {
            let shading = check_all(&surfels, &tree, receivers, omega, res);
            assert!(
                shading.iter().any(|(e, _)| e.x > 0.0),
                "Ω {omega:e} N {res}: no light"
            );
        }
    }
    eprintln!("Ω × N: {} × 4 on paths {}", omegas.len(), path_names());
}

/// An empty cloud shades to exactly zero; one surfel of radiance L seen on
/// its axis at distance d gives `πL r²/(r² + d²)` (a disk). Measured at
/// d = 10⁻³, 0.1, 1, 10: N 12 within 3.1 % (pixels 15° wide, the disk's edge
/// resolved by their 16 sub-samples), N 64 within 1.1 %; asserted 4 % and
/// 1.5 % (were 50 %). N 1, one pixel for the hemisphere, is only bounded.
#[test]
fn empty_cloud_and_one_surfel() {
    let empty = build(&[]);
    let r = Receiver::from_pairs([(Vec3::ZERO, Vec3::Z), (Vec3::new(1.0, 2.0, 3.0), -Vec3::Y)]).unwrap();
    for res in [1, 8] {
        assert_eq!(
            shade_everywhere(&empty, &r, 0.05, res).unwrap(),
            vec![(Vec3::ZERO, 0.0); 2]
        );
    }
    let l = 3.0;
    let one = [Surfel {
        position: Vec3::ZERO,
        normal: Vec3::Z,
        radius: 0.5,
        radiance: Vec3::splat(l),
    }];
    let tree = build(&one);
    for d in [1e-3f32, 0.1, 1.0, 10.0] {
        let recs = Receiver::from_pairs([
            (Vec3::new(0.0, 0.0, d), -Vec3::Z),
            (Vec3::new(0.0, 0.0, -d), Vec3::Z),
        ])
        .unwrap();
        for (res, tolerance) in [(1, f32::INFINITY), (12, 0.04), (64, 0.015)] {
            let shading = check_all(&one, &tree, &recs, 0.05, res);
            let exact = PI * l * 0.25 / (0.25 + d * d);
            let e = shading[0].0.x;
            assert!(
                (e / exact - 1.0).abs() <= tolerance,
                "d {d} N {res}: E = {e} vs {exact}"
            );
            assert_eq!(shading[1], (Vec3::ZERO, 0.0), "behind the disk");
        }
    }
}

/// Stiff mixes. Radii differing by 10⁶ in one cloud: a floor of 10³-sized
/// disks with 10⁻³-sized ones scattered over it. A receiver 1e-6 in front of a
/// huge emitter (a disk of radius 10³, a 2·10³-wide square of surfels, and a
/// disk of radius `MAX_COORDINATE`, whose area saturates at `f32::MAX`): it
/// sees nothing else, so the irradiance is π·L (asserted within 2 % for the
/// disks and the square) and the occlusion 1 (≥ 0.95); tilted 37°,
/// 0.9·πL and 0.9 (within 3 % at N 8: measured +2.2 % for the disks, where
/// the horizon crosses the pixels, −0.8 % for the square).
///
/// Not asserted, by design: with Ω ≥ π the node test `π R² < Ω d²` splats a
/// node even when the receiver is inside its sphere (`d < R ≤ 2d` at Ω = 4π),
/// and the microbuffer sees such a cluster from its centre only; 1e-6 above
/// the square, Ω = 4π leaves the receiver dark. Those runs are checked for
/// the bounds in `every_solid_angle_and_resolution`.
#[test]
fn stiff_mixes() {
    let mut rng = Rng::new(3);
    let mut surfels = Vec::new();
    for i in 0..if reduced() { 200 } else { 2000 } {
        let big = i % 10 == 0;
        surfels.push(Surfel {
            position: Vec3::new(
                rng.range(-1e3, 1e3),
                if big { 0.0 } else { rng.range(0.0, 1.0) },
                rng.range(-1e3, 1e3),
            ),
            normal: if big { Vec3::Y } else { rng.unit() },
            radius: if big { 1e3 } else { 1e-3 },
            radiance: if big {
                Vec3::new(1.0, 0.0, 0.0)
            } else {
                Vec3::new(0.0, 5.0, 0.0)
            },
        });
    }
    let tree = build(&surfels);
    let receivers = Receiver::from_pairs([
        (Vec3::new(0.0, 2.0, 0.0), -Vec3::Y),
        (Vec3::new(1.0, 0.5, 1.0), Vec3::Y),
        (surfels[1].position, surfels[1].normal),
        (surfels[0].position + Vec3::Y * 1e-6, Vec3::Y),
    ])
    .unwrap();
    for omega in [0.0, 0.05] {
        check_all(&surfels, &tree, &receivers, omega, 8);
    }

    let l = 7.0;
    let disk = [Surfel {
        position: Vec3::new(5.0, 0.0, -3.0),
        normal: Vec3::Y,
        radius: 1e3,
        radiance: Vec3::splat(l),
    }];
    let square = coarse_floor(l);
    let largest = [Surfel {
        radius: pbgi::points::MAX_COORDINATE,
        ..disk[0]
    }];
    for (name, emitter, tolerance) in [
        ("disk", &disk[..], 0.02),
        ("square", &square[..], 0.02),
        ("largest disk", &largest[..], 0.02),
    ] {
        let tree = build(emitter);
        let c = emitter[(emitter.len() / 2 + 50).min(emitter.len() - 1)].position;
        let recs = Receiver::from_pairs([
            (c + Vec3::Y * 1e-6, -Vec3::Y),
            (c + Vec3::new(0.3, 1e-6, 0.1), Vec3::new(0.0, -0.8, 0.6)),
        ])
        .unwrap();
        for omega in [0.0, 0.05] {
            let shading = check_all(emitter, &tree, &recs, omega, 8);
            let (e, ao) = shading[0];
            assert!(
                (e.x / (PI * l) - 1.0).abs() < tolerance,
                "{name}, Ω {omega}: E = {e} vs πL = {}",
                PI * l
            );
            assert!(ao >= 0.95, "{name}, Ω {omega}: AO {ao}");
            // Tilted by 37°, the plane fills all but a sliver of the
            // hemisphere: `E = πL(1 + cos 37°)/2 = 0.9·πL`, below the clamp.
            let (e, ao) = shading[1];
            assert!(
                (e.x / (0.9 * PI * l) - 1.0).abs() < 0.03 && (ao - 0.9).abs() < 0.03,
                "{name}, Ω {omega}, tilted: E = {e} vs 0.9·πL = {}, AO {ao} vs 0.9",
                0.9 * PI * l
            );
        }
    }
}

/// A 2,000 × 2,000 floor at y = 0 facing up: 100 × 100 disks 20 apart of
/// radiance `l`, their areas summing to the floor's.
fn coarse_floor(l: f32) -> Vec<Surfel> {
    (0..100 * 100)
        .map(|i| Surfel {
            position: Vec3::new(
                (i % 100) as f32 * 20.0 - 990.0,
                0.0,
                (i / 100) as f32 * 20.0 - 990.0,
            ),
            normal: Vec3::Y,
            radius: 20.0 / PI.sqrt(),
            radiance: Vec3::splat(l),
        })
        .collect()
}

/// Receivers just above a floor of coarse disks (radius 11.3, 20 apart),
/// 0.32 from a disk's centre, facing down or tilted 37°: the floor fills
/// their hemisphere but a sliver, `E = πL` and `0.9·πL`. Seen from there a
/// disk's centre lies at the horizon, and its far-field `Ω = A·cos/d²`
/// (0.01 at a height of 10⁻⁶) drew it as a small splat: dark at N 8 and 16
/// below a height of 10⁻⁴, 2.6 % dark at 10⁻². Measured now: within 0.8 %
/// at N 8, 0.22 % at N 16 and 32 from heights 10⁻⁶ to 1 (asserted 1.5 %
/// and 0.5 %), facing down exact. Higher up the discretisation shows: at a
/// height of 10, N 8, facing down, −9 % (N 16 exact; not yet explained).
#[test]
fn a_receiver_just_above_a_coarse_floor_off_a_disk_centre() {
    let l = 7.0;
    let square = coarse_floor(l);
    let tree = build(&square);
    let c = square[5050].position;
    let heights: &[f32] = if reduced() {
        &[1e-6, 0.1]
    } else {
        &[1e-6, 1e-4, 1e-2, 0.1, 1.0]
    };
    for &h in heights {
        let p = c + Vec3::new(0.3, h, 0.1);
        let recs = Receiver::from_pairs([(p, Vec3::new(0.0, -0.8, 0.6)), (p, -Vec3::Y)]).unwrap();
        for (res, tolerance) in [(8, 0.015), (16, 0.005), (32, 0.005)] {
            let shading = check_all(&square, &tree, &recs, 0.05, res);
            let (tilted, down) = (shading[0].0.x / (0.9 * PI * l), shading[1].0.x / (PI * l));
            assert!(
                (tilted - 1.0).abs() < tolerance && (down - 1.0).abs() < 1e-3,
                "height {h}, N {res}: tilted {:+.2} %, facing down {:+.2} %",
                (tilted - 1.0) * 100.0,
                (down - 1.0) * 100.0
            );
        }
    }
}
