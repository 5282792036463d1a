//! The whole chain (surfels → tree → cut → microbuffer → irradiance) against
//! analytic irradiance, and bitwise identical shading for every scheme and path.

use crate::common;

use common::{Pipeline, irradiance_in_sphere, irradiance_with};
use glam::Vec3;
use pbgi::microbuffer::{MicroBuffer, MicroBufferSink};
use pbgi::{CutOptions, Isa, PointCloud, Receiver, Scheme, Surfel, Traversal, Tree};

const L: f32 = 2.0;

/// Irradiance at each receiver through `scheme` on `isa`.
fn irradiance(
    tree: &Tree,
    receivers: &[Receiver],
    omega: f32,
    res: usize,
    scheme: Scheme,
    isa: Isa,
) -> Vec<Vec3> {
    let t = Traversal::new(
        tree,
        CutOptions {
            max_solid_angle: omega,
            isa: Some(isa),
            ..Default::default()
        },
    )
    .unwrap();
    let mut out = Vec::new();
    for chunk in receivers.chunks(16) {
        let mut buffers = vec![MicroBuffer::new(res).unwrap(); chunk.len()];
        for (b, r) in buffers.iter_mut().zip(chunk) {
            b.reset(r.position(), r.normal());
        }
        t.run(
            scheme,
            chunk,
            &mut MicroBufferSink {
                tree,
                buffers: &mut buffers,
            },
        );
        out.extend(buffers.iter().map(|b| b.irradiance(tree)));
    }
    out
}

/// Irradiance through the renderer's two shading pipelines on `isa`: the
/// scalar one (each receiver's cut, one node at a time) and the 16-lane one
/// (the packet's cut, gathered from `scheme`'s splats).
fn irradiance_pipelines(
    tree: &Tree,
    receivers: &[Receiver],
    omega: f32,
    res: usize,
    scheme: Scheme,
    isa: Isa,
) -> (Vec<Vec3>, Vec<Vec3>) {
    let [scalar, lanes] = [Pipeline::Scalar, Pipeline::Lanes]
        .map(|pipeline| irradiance_with(tree, receivers, omega, res, scheme, isa, pipeline).unwrap());
    (scalar, lanes)
}

/// Inward-facing surfels on a Fibonacci sphere of radius 1 with radiance
/// `radiance(p)` at the surfel at `p`, the disks' areas summing to the
/// sphere's (disks 5 % wider gave irradiance 10 % above the exact answer:
/// they stand for 10 % more surface).
fn sphere(n: usize, radiance: impl Fn(Vec3) -> Vec3) -> Tree {
    let golden = std::f32::consts::PI * (3.0 - 5f32.sqrt());
    let radius = (4.0 / n as f32).sqrt();
    let surfels = (0..n)
        .map(|i| {
            let z = 1.0 - 2.0 * (i as f32 + 0.5) / n as f32;
            let r = (1.0 - z * z).sqrt();
            let p = Vec3::new(r * (golden * i as f32).cos(), r * (golden * i as f32).sin(), z);
            Surfel {
                position: p,
                normal: -p.normalize(),
                radius,
                radiance: radiance(p),
            }
        })
        .collect();
    Tree::build(&PointCloud::new(surfels).unwrap())
}

/// A square `side × side` of surfels in the plane z = 0 facing +z (centre at the origin).
fn square(side: f32, m: usize) -> Tree {
    let cell = side / m as f32;
    let surfels = (0..m * m)
        .map(|i| Surfel {
            position: Vec3::new(
                ((i % m) as f32 + 0.5) * cell - side / 2.0,
                ((i / m) as f32 + 0.5) * cell - side / 2.0,
                0.0,
            ),
            normal: Vec3::Z,
            radius: cell / std::f32::consts::PI.sqrt(),
            radiance: Vec3::splat(L),
        })
        .collect();
    Tree::build(&PointCloud::new(surfels).unwrap())
}

fn rel(a: f32, b: f32) -> f32 {
    (a - b).abs() / b
}

/// A sphere lit unevenly, `L(p) = 2 + p_z + p_x/2` (1 to 3.1), so that
/// no receiver's answer is the bound `π·max L` the irradiance is clamped
/// at (a uniform sphere's is, and an over-estimate could not show): against
/// quadrature, from the centre and off it. Measured: within 0.16 % at
/// Ω 0.02 and 0.84 % at Ω 0.1 (a cluster's one radiance over its curved
/// patch), at N 8 and 16; asserted 0.5 % and 1.5 %.
#[test]
fn inside_an_unevenly_lit_sphere_irradiance_is_its_integral() {
    let radiance = |p: Vec3| 2.0 + p.z as f64 + 0.5 * p.x as f64;
    let tree = sphere(40_000, |p| Vec3::splat(radiance(p) as f32));
    let pairs = [
        (Vec3::ZERO, Vec3::Z),
        (Vec3::ZERO, -Vec3::Z),
        (Vec3::ZERO, Vec3::new(0.6, 0.0, 0.8)),
        (Vec3::new(0.3, -0.2, 0.1), Vec3::new(0.0, -1.0, 0.0)),
        (Vec3::new(-0.4, 0.2, -0.5), Vec3::new(0.0, 0.6, 0.8)),
        (Vec3::new(0.1, 0.6, 0.3), Vec3::new(-0.8, 0.0, -0.6)),
    ];
    let want: Vec<f64> = pairs
        .iter()
        .map(|&(q, n)| irradiance_in_sphere(q, n, radiance))
        .collect();
    let recs = Receiver::from_pairs(pairs).unwrap();
    for res in [8, 16] {
        for (omega, tolerance) in [(0.02, 0.005), (0.1, 0.015)] {
            for scheme in [Scheme::Packet, Scheme::Single] {
                let got = irradiance(&tree, &recs, omega, res, scheme, Isa::best());
                for (i, (e, want)) in got.iter().zip(&want).enumerate() {
                    let err = e.x as f64 / want - 1.0;
                    assert!(
                        err.abs() < tolerance,
                        "N {res}, Ω {omega}, {scheme:?}, receiver {i}: E = {} vs {want:.4} ({:+.2} %)",
                        e.x,
                        err * 100.0
                    );
                }
            }
        }
    }
}

/// Form factor from a point at height 1 above a corner of an `a × b`
/// rectangle parallel to its tangent plane.
fn corner_form_factor(a: f64, b: f64) -> f64 {
    let (sa, sb) = ((1.0 + a * a).sqrt(), (1.0 + b * b).sqrt());
    (a / sa * (b / sa).atan() + b / sb * (a / sb).atan()) / (2.0 * std::f64::consts::PI)
}

#[test]
fn facing_a_square_irradiance_is_pi_l_times_its_form_factor() {
    // A 2 × 2 square of coarse surfels (cell 0.1) 0.5 in front of the
    // receiver: its nearest leaves are drawn as disks a pixel or two wide.
    // Exact: πL times the four corner rectangles' form factors (F ≈ 0.82,
    // so the cap at πL, which a square filling the hemisphere would read,
    // plays no part). The disks' rim ramps once overstated them: +3.3 %
    // at N 12 and 16 (mean of these receivers), +8 % at N 24; now −0.2 and
    // −0.7 %. Above N 16 an erratic ±2 % is left (docs/lab/exact/findings.md).
    let (side, h) = (2.0f64, 0.5f64);
    let tree = square(side as f32, 20);
    let receivers: Vec<(f64, f64)> = (0..8)
        .map(|i| {
            let t = i as f64 * 0.618_034;
            ((t.fract() - 0.5) * 0.4, ((t * 1.7).fract() - 0.5) * 0.4)
        })
        .collect();
    for res in [12, 16] {
        let s = side / 2.0;
        within_one_percent(&tree, &receivers, h, res, |px, py| {
            corner_form_factor((s - px) / h, (s - py) / h)
                + corner_form_factor((s - px) / h, (s + py) / h)
                + corner_form_factor((s + px) / h, (s - py) / h)
                + corner_form_factor((s + px) / h, (s + py) / h)
        });
    }
}

/// Asserts that the irradiance at receivers `(x, y, h)` facing −z, at
/// Ω 0.02 and resolution `res`, is `πL` times `form_factor(x, y)` within
/// 1 %, in the mean and RMS over them.
fn within_one_percent(
    tree: &Tree,
    receivers: &[(f64, f64)],
    h: f64,
    res: usize,
    form_factor: impl Fn(f64, f64) -> f64,
) {
    let mut errors = Vec::new();
    for &(px, py) in receivers {
        let recs = Receiver::from_pairs([(Vec3::new(px as f32, py as f32, h as f32), -Vec3::Z)]).unwrap();
        let e = irradiance(tree, &recs, 0.02, res, Scheme::Hybrid, Isa::best())[0].x as f64;
        errors.push(e / (std::f64::consts::PI * L as f64 * form_factor(px, py)) - 1.0);
    }
    let mean = errors.iter().sum::<f64>() / errors.len() as f64;
    let rms = (errors.iter().map(|e| e * e).sum::<f64>() / errors.len() as f64).sqrt();
    assert!(
        mean.abs() < 0.01 && rms < 0.01,
        "N {res}: mean {mean:+.4}, rms {rms:.4}, {errors:?}"
    );
}

/// Surfels on a grid of cells `cell` over the rectangle `origin + [0, 1]²`
/// of edge vectors `u`, `v`, facing `normal`, showing `radiance`.
fn rectangle(origin: Vec3, u: Vec3, v: Vec3, normal: Vec3, cell: f32, radiance: f32) -> Vec<Surfel> {
    let (mu, mv) = (
        (u.length() / cell).round().max(1.0) as usize,
        (v.length() / cell).round().max(1.0) as usize,
    );
    let area = u.length() * v.length() / (mu * mv) as f32;
    (0..mu * mv)
        .map(|i| Surfel {
            position: origin
                + u * (((i % mu) as f32 + 0.5) / mu as f32)
                + v * (((i / mu) as f32 + 0.5) / mv as f32),
            normal,
            radius: (area / std::f32::consts::PI).sqrt(),
            radiance: Vec3::splat(radiance),
        })
        .collect()
}

/// `∫ cosθ dω / π` (θ from `n`) of the convex polygon `poly` seen from
/// `p`, wholly above `p`'s tangent plane: Lambert's formula.
fn polygon_form_factor(poly: &[[f64; 3]], p: [f64; 3], n: [f64; 3]) -> f64 {
    let sub = |a: [f64; 3]| [a[0] - p[0], a[1] - p[1], a[2] - p[2]];
    let unit = |a: [f64; 3]| {
        let l = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
        [a[0] / l, a[1] / l, a[2] / l]
    };
    let mut sum = 0.0;
    for i in 0..poly.len() {
        let (a, b) = (unit(sub(poly[i])), unit(sub(poly[(i + 1) % poly.len()])));
        let cross = [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ];
        let dot = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        let theta = dot.clamp(-1.0, 1.0).acos();
        let g = unit(cross);
        sum += theta * (g[0] * n[0] + g[1] * n[1] + g[2] * n[2]);
    }
    (sum / (2.0 * std::f64::consts::PI)).abs()
}

#[test]
fn a_dark_box_in_front_of_a_lit_square_hides_it_at_every_resolution() {
    // A dark box (0.5 × 0.5, 0.2 high) on a lit 2 × 2 square, seen from
    // beside its top: its top and one side show, so the exact irradiance
    // is πL times the square's form factor less theirs. The clusters along
    // the box's edges hold surfels of two faces (two facets): drawn as one
    // round cone `±R` deep they let some of the square's light through,
    // +1.2 / +1.1 % at N 48 / 96; as the disks of their facets on their
    // planes, +0.8 / +0.8 % (+1.0 % at N 24, +1.4 % before).
    // The Cornell box's floor, seen past the blocks, was +6.8 % too bright
    // at N 48 (docs/lab/BENCHMARKS.md, "Facets on their planes").
    let (side, top, height, h) = (2.0f32, 0.5f32, 0.2f32, 0.8f64);
    let (x, y, z) = (Vec3::X, Vec3::Y, Vec3::Z);
    let c = Vec3::new(-top / 2.0, -top / 2.0, 0.0);
    let mut surfels = rectangle(
        Vec3::new(-side / 2.0, -side / 2.0, 0.0),
        x * side,
        y * side,
        z,
        0.05,
        L,
    );
    surfels.extend(rectangle(c + z * height, x * top, y * top, z, 0.02, 0.0));
    surfels.extend(rectangle(c, x * top, z * height, -y, 0.02, 0.0));
    surfels.extend(rectangle(c + y * top, x * top, z * height, y, 0.02, 0.0));
    surfels.extend(rectangle(c, y * top, z * height, -x, 0.02, 0.0));
    surfels.extend(rectangle(c + x * top, y * top, z * height, x, 0.02, 0.0));
    let tree = Tree::build(&PointCloud::new(surfels).unwrap());
    let (s, t, hb) = (side as f64 / 2.0, top as f64 / 2.0, height as f64);
    let square = [[-s, -s, 0.0], [s, -s, 0.0], [s, s, 0.0], [-s, s, 0.0]];
    let lid = [[-t, -t, hb], [t, -t, hb], [t, t, hb], [-t, t, hb]];
    let flank = [[t, -t, 0.0], [t, t, 0.0], [t, t, hb], [t, -t, hb]];
    let receivers: Vec<(f64, f64)> = (0..8)
        .map(|i| {
            let u = i as f64 * 0.618_034;
            (0.35 + u.fract() * 0.15, ((u * 1.7).fract() - 0.5) * 0.3)
        })
        .collect();
    for res in [48, 96] {
        within_one_percent(&tree, &receivers, h, res, |px, py| {
            let (p, n) = ([px, py, h], [0.0, 0.0, -1.0]);
            polygon_form_factor(&square, p, n)
                - polygon_form_factor(&lid, p, n)
                - polygon_form_factor(&flank, p, n)
        });
    }
}

#[test]
fn on_the_axis_of_a_disk() {
    // A disk of radius r made of a fine square grid clipped to the disk.
    for (r, d) in [(1.0f32, 1.0f32), (0.5, 2.0), (2.0, 0.5)] {
        let m = 300;
        let cell = 2.0 * r / m as f32;
        let surfels: Vec<_> = (0..m * m)
            .filter_map(|i| {
                let p = Vec3::new(
                    ((i % m) as f32 + 0.5) * cell - r,
                    ((i / m) as f32 + 0.5) * cell - r,
                    0.0,
                );
                (p.length() <= r).then(|| Surfel {
                    position: p,
                    normal: Vec3::Z,
                    radius: cell / std::f32::consts::PI.sqrt(),
                    radiance: Vec3::splat(L),
                })
            })
            .collect();
        let tree = Tree::build(&PointCloud::new(surfels).unwrap());
        let recs = Receiver::from_pairs([(Vec3::new(0.0, 0.0, d), -Vec3::Z)]).unwrap();
        let e = irradiance(&tree, &recs, 0.01, 32, Scheme::Single, Isa::best())[0].x;
        let expect = std::f32::consts::PI * L * r * r / (r * r + d * d);
        assert!(rel(e, expect) < 0.01, "r {r} d {d}: E = {e} vs {expect}"); // tolerance 1 % (measured ≤ 0.26 %)
    }
}

/// Reduced sizes when `PBGI_QC_TESTS` asks for few cases (emulated runs).
fn quick() -> bool {
    std::env::var("PBGI_QC_TESTS")
        .ok()
        .and_then(|s| s.parse::<u64>().ok())
        .is_some_and(|n| n < 50)
}

#[test]
fn every_scheme_and_path_shades_bit_identically() {
    let tree = Tree::build(&pbgi::synthetic::box_with_blocks(
        if quick() { 3_000 } else { 20_000 },
        2,
    ));
    let resolutions: &[usize] = if quick() { &[1, 8] } else { &[1, 4, 8, 16] };
    // Emulated, jittered receivers only: this test was 477 s of the ARM
    // stage's 869 s suite under qemu (two threads), the longest by far.
    let jitters: &[f32] = if quick() { &[1.0] } else { &[0.0, 1.0] };
    // 24 packets of receivers in CI (four minutes here), 6 elsewhere: every
    // case still runs, on fewer receivers.
    let packets = match (quick(), common::deep()) {
        (true, _) => 3,
        (false, true) => 24,
        (false, false) => 6,
    };
    for &jitter in jitters {
        let recs = pbgi::synthetic::receivers(packets, 0.01, jitter, 4);
        for omega in [0.01, 0.1] {
            for &res in resolutions {
                let reference = irradiance(&tree, &recs, omega, res, Scheme::Scalar, Isa::Portable);
                assert!(reference.iter().all(|e| e.is_finite()));
                assert!(
                    reference.iter().any(|e| e.max_element() > 0.0),
                    "no light reached: the test proves nothing"
                );
                let bits = |v: &[Vec3]| {
                    v.iter()
                        .flat_map(|x| x.to_array().map(f32::to_bits))
                        .collect::<Vec<_>>()
                };
                for isa in Isa::available() {
                    for scheme in Scheme::ALL {
                        let e = irradiance(&tree, &recs, omega, res, scheme, isa);
                        assert_eq!(
                            bits(&e),
                            bits(&reference),
                            "{scheme} on {isa}, Ω {omega}, N {res}"
                        );
                        let (scalar, lanes) = irradiance_pipelines(&tree, &recs, omega, res, scheme, isa);
                        assert_eq!(
                            bits(&scalar),
                            bits(&reference),
                            "scalar shading of {scheme} cuts on {isa}, Ω {omega}, N {res}"
                        );
                        assert_eq!(
                            bits(&lanes),
                            bits(&reference),
                            "16-lane shading of {scheme} cuts on {isa}, Ω {omega}, N {res}"
                        );
                    }
                }
            }
        }
    }
}

#[test]
fn splat_order_does_not_matter() {
    let tree = Tree::build(&pbgi::synthetic::box_with_blocks(5_000, 8));
    let recs = pbgi::synthetic::receivers(2, 0.01, 0.5, 6);
    let t = Traversal::new(&tree, CutOptions::default()).unwrap();
    for (r, cut) in recs.iter().zip(t.cuts(Scheme::Scalar, &recs)) {
        let mut a = MicroBuffer::new(8).unwrap();
        let mut b = a.clone();
        a.reset(r.position(), r.normal());
        b.reset(r.position(), r.normal());
        for &k in &cut.splats {
            a.splat(&tree, k);
        }
        for &k in cut.splats.iter().rev() {
            b.splat(&tree, k);
        }
        assert_eq!(
            a.irradiance(&tree).to_array().map(f32::to_bits),
            b.irradiance(&tree).to_array().map(f32::to_bits)
        );
    }
}

#[test]
fn occlusion_is_one_inside_a_closed_sphere_and_zero_outside_everything() {
    let tree = sphere(20_000, |_| Vec3::splat(L));
    let t = Traversal::new(
        &tree,
        CutOptions {
            max_solid_angle: 0.02,
            ..Default::default()
        },
    )
    .unwrap();
    let r = Receiver::new(Vec3::ZERO, Vec3::Y).unwrap();
    let mut mb = vec![MicroBuffer::new(16).unwrap()];
    mb[0].reset(r.position(), r.normal());
    t.run(
        Scheme::Packet,
        &[r],
        &mut MicroBufferSink {
            tree: &tree,
            buffers: &mut mb,
        },
    );
    // The disks' areas sum to the sphere's, so their coverage of the
    // hemisphere is one on average (overlaps make up for gaps): measured
    // 0.9991 (disks 5 % wider once hid the gaps' loss behind a clamp at 1).
    let ao = mb[0].occlusion(&tree);
    assert!(ao > 0.997, "AO {ao}");
    // Looking away from the sphere, from outside: nothing.
    let out = Receiver::new(Vec3::new(0.0, 3.0, 0.0), Vec3::Y).unwrap();
    let mut mb = vec![MicroBuffer::new(16).unwrap()];
    mb[0].reset(out.position(), out.normal());
    t.run(
        Scheme::Packet,
        &[out],
        &mut MicroBufferSink {
            tree: &tree,
            buffers: &mut mb,
        },
    );
    assert_eq!(mb[0].occlusion(&tree), 0.0);
}

#[test]
fn no_nan_in_extreme_cases() {
    let tree = Tree::build(&pbgi::synthetic::box_with_blocks(2_000, 1));
    let s = tree.node(tree.len() as u32 - 1); // a leaf
    let on_surfel = Receiver::new(s.center, s.normal.normalize()).unwrap();
    for omega in [0.0, 1e-6, 1e3] {
        for res in [1, 256] {
            let e = irradiance(&tree, &[on_surfel], omega, res, Scheme::Hybrid, Isa::best());
            assert!(
                e[0].is_finite() && e[0].min_element() >= 0.0,
                "Ω {omega} N {res}: {}",
                e[0]
            );
        }
    }
    let empty = Tree::build(&PointCloud::default());
    assert_eq!(
        irradiance(&empty, &[on_surfel], 0.1, 8, Scheme::Packet, Isa::best())[0],
        Vec3::ZERO
    );
    assert!(MicroBuffer::new(0).is_err() && MicroBuffer::new(257).is_err());
}
