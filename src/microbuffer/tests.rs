//! Unit tests of the map, its tables, the footprints and the two draws.
use glam::Vec3;

use super::buffer::*;
use super::compose::{at_least_zero, at_most};
use super::locate::*;
use super::plan::*;
use super::table::*;
use crate::rng::Rng;
use crate::tree::{LEAF, NodeId, PLANAR, SplatRecord};

/// The light of the test nodes: one normal, radiance one.
fn flat(rec: &SplatRecord) -> NodeLight<'static> {
    NodeLight::flat(rec.kind, Vec3::ONE)
}

const ONE: [f32; 3] = [1.0; 3];

/// A unit-area cluster at `c` facing the origin.
fn record(c: Vec3) -> SplatRecord {
    SplatRecord {
        centroid: c.to_array(),
        area: 1.0,
        normal: (-c).to_array(),
        kind: PLANAR,
        light_centroid: c.to_array(),
        ..SplatRecord::default()
    }
}

/// A node around the receiver at the origin (normal +z), of every kind
/// the draws meet: far and near, tiny and huge, facing, edge-on, and
/// coplanar with the receiver a rounding error above or below its plane.
fn node_around(rng: &mut Rng, leaf: bool) -> SplatRecord {
    let kind = (rng.f32() * 4.0) as u32;
    let d = 10f32.powf(rng.f32() * 4.0 - 3.0);
    let (center, normal) = match kind {
        0 => {
            // On the receiver's plane, normal nearly its own.
            let c = rng.unit_vector() * Vec3::new(1.0, 1.0, 0.0);
            let z = (rng.f32() - 0.5) * 1e-6 * d;
            (
                c * d + Vec3::Z * z,
                (Vec3::Z + rng.unit_vector() * 1e-4).normalize(),
            )
        }
        1 => {
            // Near the horizon, any normal.
            let c = (rng.unit_vector() * Vec3::new(1.0, 1.0, 0.05)).normalize_or(Vec3::X);
            (c * d, rng.unit_vector())
        }
        _ => (rng.unit_vector() * d, rng.unit_vector()),
    };
    SplatRecord {
        centroid: center.to_array(),
        area: d * d * 10f32.powf(rng.f32() * 5.0 - 4.0),
        normal: normal.to_array(),
        kind: if leaf { LEAF } else { PLANAR },
        light_centroid: center.to_array(),
        ..SplatRecord::default()
    }
}

/// The same fragments, in any order (the composition sorts them).
fn same_pixels(a: &MicroBuffer, b: &MicroBuffer) -> bool {
    let set = |m: &MicroBuffer| {
        let f = &m.frags;
        let mut v: Vec<_> = (0..f.len())
            .map(|i| (f.pixel[i], f.key[i], f.cover[i].to_bits()))
            .collect();
        v.sort_unstable();
        v
    };
    set(a) == set(b)
}

#[test]
fn tiled_draws_write_the_pixels_of_the_scalar_draws() {
    let mut rng = Rng::new(1);
    let (mut drawn, mut hits) = (0, 0);
    for n in [1, 2, 3, 4, 5, 7, 8, 9, 12, 16, 17, 33, 64] {
        let mut a = MicroBuffer::new(n).unwrap();
        let mut b = MicroBuffer::new(n).unwrap();
        for i in 0..600 {
            let (frame_n, node) = (Vec3::Z, i as NodeId);
            a.reset(Vec3::ZERO, frame_n);
            b.reset(Vec3::ZERO, frame_n);
            let leaf = i % 2 == 0;
            let rec = node_around(&mut rng, leaf);
            let Some(l) = a.locate(&rec, &flat(&rec)) else {
                continue;
            };
            let t = a.table.clone();
            let pixel = pixel_of(&t, l.x, l.y);
            let visible = 0.0 < l.wz;
            drawn += 1;
            if leaf {
                let plan = plan_disk(&t, &a.frame_lanes(), &NodeSplat::of(&rec), l.x, l.y, pixel, l.d);
                let hit = a.draw_disk(&plan, node, ONE);
                assert_eq!(hit, b.draw_disk_tiles(&plan, node, ONE), "N {n}, node {rec:?}");
                assert!(same_pixels(&a, &b), "disk: N {n}, node {rec:?}");
                // The cull of disks that cannot face any pixel drops no hit.
                let mut c = MicroBuffer::new(n).unwrap();
                c.reset(Vec3::ZERO, frame_n);
                let unculled = DiskPlan { fronts: true, ..plan };
                assert_eq!(
                    hit,
                    c.draw_disk(&unculled, node, ONE),
                    "cull: N {n}, node {rec:?}"
                );
                assert!(same_pixels(&a, &c), "cull: N {n}, node {rec:?}");
                hits += usize::from(hit);
            } else {
                let plan = plan_cone(&t, l.x, l.y, pixel, l.omega, visible);
                let w = Vec3::new(l.wx, l.wy, l.wz);
                let target = if visible { l.omega * l.wz } else { 0.0 };
                a.draw_cone(w, &plan, key(l.d, node), target, ONE);
                b.draw_cone_tiles(w, &plan, key(l.d, node), target, ONE);
                assert!(same_pixels(&a, &b), "cone: N {n}, node {rec:?}");
                hits += usize::from(a.frags.len() > 0);
            }
        }
    }
    // The cases must draw something, or the comparison proves nothing.
    assert!(drawn > 3000 && hits > 1000, "{drawn} drawn, {hits} with pixels");
}

#[test]
fn pixels_integrate_to_the_hemisphere_exactly() {
    for n in [1, 2, 3, 8, 17, 64, 256] {
        let t = Table::new(n);
        let total: f64 = t.solid_angle.iter().map(|&x| x as f64).sum();
        let cosine: f64 = t.cos_weight.iter().map(|&x| x as f64).sum();
        assert!(
            (total / (2.0 * std::f64::consts::PI) - 1.0).abs() < 1e-5,
            "n {n}: Σ ΔΩ = {total}"
        );
        assert!(
            (cosine / std::f64::consts::PI - 1.0).abs() < 1e-5,
            "n {n}: Σ ∫cos dω = {cosine}"
        );
    }
}

#[test]
fn pixel_integrals_match_a_fine_quadrature() {
    let n = 6;
    let t = Table::new(n);
    let h = 2.0 / n as f64;
    let m = 400;
    // Pixels off the diagonals u = ±v (where the map has a kink the
    // midpoint rule converges slowly across), then pixels on them.
    for (p, tol) in [
        (1, 1e-4),
        (2, 1e-4),
        (9, 1e-4),
        (12, 1e-4),
        (26, 1e-4),
        (0, 5e-3),
        (7, 5e-3),
        (20, 5e-3),
    ] {
        let (c, r) = (p % n, p / n);
        let (mut omega, mut projected) = (0.0, 0.0);
        let g = h / m as f64;
        for i in 0..m {
            for j in 0..m {
                let (u, v) = (
                    -1.0 + c as f64 * h + (i as f64 + 0.5) * g,
                    -1.0 + r as f64 * h + (j as f64 + 0.5) * g,
                );
                // Area element of the map by finite differences.
                let e = 1e-7;
                let d = unmap(u, v);
                let du = (unmap(u + e, v) - d) / e;
                let dv = (unmap(u, v + e) - d) / e;
                let da = du.cross(dv).length() * g * g;
                omega += da;
                projected += da * d.z;
            }
        }
        assert!(
            (omega / t.solid_angle[p] as f64 - 1.0).abs() < tol,
            "pixel {p}: {omega} vs {}",
            t.solid_angle[p]
        );
        assert!(
            (projected / t.cos_weight[p] as f64 - 1.0).abs() < tol,
            "pixel {p}: {projected} vs {}",
            t.cos_weight[p]
        );
    }
}

#[test]
fn every_pixel_centre_lands_in_its_pixel() {
    for n in [1, 4, 8, 13] {
        let mut mb = MicroBuffer::new(n).unwrap();
        mb.reset(Vec3::ZERO, Vec3::Z);
        for (p, d) in mb.table.dir.clone().iter().enumerate() {
            let l = mb
                .locate(&record(*d), &flat(&record(*d)))
                .expect("upper hemisphere");
            assert_eq!(pixel_of(&mb.table, l.x, l.y), p as f32, "n {n} pixel {p} dir {d}");
        }
    }
}

#[test]
fn footprints_reach_every_pixel_within_their_angle() {
    let n = 16;
    let mut mb = MicroBuffer::new(n).unwrap();
    mb.reset(Vec3::ZERO, Vec3::Z);
    let t = mb.table.clone();
    for (i, w) in t.dir.iter().enumerate().step_by(3) {
        let l = mb.locate(&record(*w), &flat(&record(*w))).unwrap();
        let pixel = pixel_of(&t, l.x, l.y);
        for angle in [0.05f32, 0.2, 0.5, 1.0] {
            let b = footprint(&t, l.x, l.y, pixel, angle);
            let (c0, c1, r0, r1) = (b.c0 as usize, b.c1 as usize, b.r0 as usize, b.r1 as usize);
            for (p, d) in t.dir.iter().enumerate() {
                if d.dot(*w).clamp(-1.0, 1.0).acos() < angle * 0.999 {
                    let (c, r) = (p % n, p / n);
                    assert!(
                        (c0..=c1).contains(&c) && (r0..=r1).contains(&r),
                        "pixel {p} is {:.3} rad from pixel {i}, outside the box of angle {angle}",
                        d.dot(*w).acos()
                    );
                }
            }
        }
    }
}

/// A cluster spanning a corner (a lit floor and a dim wall) shows a receiver
/// behind the wall the floor alone: the floor's radiance and projected area,
/// not the blend of one mean normal and one mean radiance.
#[test]
fn a_corner_cluster_shows_only_the_facets_facing_the_receiver() {
    use crate::points::{PointCloud, Surfel};
    let m = 8;
    let mut surfels = Vec::new();
    for i in 0..m * m {
        let (u, v) = ((i % m) as f32 + 0.5, (i / m) as f32 + 0.5);
        let r = 0.5 / std::f32::consts::PI.sqrt() / m as f32;
        let s = |position, normal, radiance| Surfel {
            position,
            normal,
            radiance,
            radius: r,
        };
        surfels.push(s(
            Vec3::new(u / m as f32, 0.0, v / m as f32),
            Vec3::Y,
            Vec3::splat(2.0),
        ));
        surfels.push(s(
            Vec3::new(0.0, u / m as f32, v / m as f32),
            Vec3::X,
            Vec3::splat(0.5),
        ));
    }
    let tree = crate::tree::Tree::build(&PointCloud::new(surfels.clone()).unwrap());
    let (rec, light) = NodeLight::of(&tree, 0).unwrap();
    assert_eq!(rec.kind, crate::tree::MIXED);
    // Above the floor, behind the wall's back (x < 0): the wall faces away.
    let at = Vec3::new(-3.0, 4.0, 0.5);
    let mut mb = MicroBuffer::new(8).unwrap();
    mb.reset(at, (Vec3::new(0.5, 0.0, 0.5) - at).normalize());
    let l = mb.locate(&rec, &light).expect("the floor faces the receiver");
    let c = Vec3::from_array(rec.centroid);
    let (d, u) = ((at - c).length(), (at - c).normalize());
    let floor: Vec<&Surfel> = surfels.iter().filter(|s| s.normal == Vec3::Y).collect();
    let floor_area: f32 = floor
        .iter()
        .map(|s| std::f32::consts::PI * s.radius * s.radius)
        .sum();
    let want = floor_area * u.y / (d * d);
    assert!(
        (l.omega / want - 1.0).abs() < 1e-4,
        "Ω {} against the floor's {want}",
        l.omega
    );
    // What it covers, `∫cosθ dω`, is the floor's `A·G` at the floor's own
    // centroid, not at the node's (halfway up the wall: there the floor
    // is seen more obliquely); the light it sends, that times `L`, is the
    // floor's alone (its light centroid: the floor is uniform), no share
    // of the wall's dim light.
    let n = (Vec3::new(0.5, 0.0, 0.5) - at).normalize();
    let g = |p: Vec3| {
        let (v, l2) = ((p - at).normalize(), (p - at).length_squared());
        (-v.y).max(0.0) * n.dot(v).max(0.0) / l2
    };
    let centroid = floor.iter().map(|s| s.position).sum::<Vec3>() / floor.len() as f32;
    let covers = floor_area * g(centroid);
    // To first order in `r/d`: the second-order term (`locate::near_field`,
    // a disk's `A/(πd²)` times a factor of order 1) is left to it.
    let x = floor_area / (std::f32::consts::PI * d * d);
    assert!(
        (l.projected / covers - 1.0).abs() < 2.0 * x,
        "covers {}, the floor {covers}",
        l.projected
    );
    assert!((l.projected / (l.omega * (-u).dot(n)) - 1.0).abs() > 0.01);
    let sent = l.projected * l.radiance[0];
    let floor_sends = floor_area * 2.0 * g(centroid);
    assert!(
        (sent / floor_sends - 1.0).abs() < 1e-3,
        "sends {sent}, the floor {floor_sends}"
    );
    assert!(l.radiance[0] == l.radiance[1] && l.radiance[1] == l.radiance[2]);
}

/// A corner cluster as bright as a cloud may be, and so large that its area
/// times that radiance overflows f32 (its distances still do not): its
/// facets' weights times their radiance stay finite (they overflowed to ∞
/// when the weights were in the units of the area).
#[test]
fn the_largest_brightest_corner_cluster_shades_finite() {
    use crate::points::{MAX_RADIANCE, PointCloud, Surfel};
    let r = 1e18;
    let s = |position: Vec3, normal| Surfel {
        position: position * r,
        normal,
        radiance: Vec3::splat(MAX_RADIANCE),
        radius: r,
    };
    let surfels: Vec<Surfel> = (0..4)
        .flat_map(|i| {
            let u = i as f32 * 2.0;
            [
                s(Vec3::new(u, 0.0, 1.0), Vec3::Y),
                s(Vec3::new(0.0, u + 1.0, 1.0), Vec3::X),
            ]
        })
        .collect();
    let tree = crate::tree::Tree::build(&PointCloud::new(surfels).unwrap());
    let (rec, _) = NodeLight::of(&tree, 0).unwrap();
    assert_eq!(rec.kind, crate::tree::MIXED);
    let mut mb = MicroBuffer::new(8).unwrap();
    mb.reset(
        Vec3::new(4.0, 4.0, 1.0) * r,
        Vec3::new(-1.0, -1.0, 0.0).normalize(),
    );
    mb.splat(&tree, 0);
    let e = mb.irradiance(&tree);
    assert!(
        e.is_finite()
            && e.min_element() > 0.0
            && e.max_element() <= std::f32::consts::PI * MAX_RADIANCE * 1.0001,
        "irradiance {e}"
    );
}

#[test]
fn a_pieces_transfer_is_a_finite_number_at_any_distance() {
    // Facing a receiver of normal +z from 45° above its horizon.
    let m = [
        -std::f32::consts::FRAC_1_SQRT_2,
        0.0,
        -std::f32::consts::FRAC_1_SQRT_2,
    ];
    let n = [0.0, 0.0, 1.0];
    for d in [
        0.0,
        1e-30,
        1e-20,
        1e-10,
        1.0,
        1e10,
        1e19,
        1e30,
        f32::MAX,
        f32::INFINITY,
        f32::NAN,
    ] {
        let g = transfer(m, [d, 0.0, d], n);
        assert!(g.is_finite() && g >= 0.0, "G = {g} at distance {d}·√2");
    }
    // Head-on (facing 1), at 45° to the receiver's normal, at distance² 2.
    let g = transfer(m, [1.0, 0.0, 1.0], n);
    assert!((g - std::f32::consts::FRAC_1_SQRT_2 / 2.0).abs() < 1e-6, "{g}");
}

/// The bounds keep a finite value within them and let a NaN or an
/// infinity through, for the renderer's checks to name the receiver
/// (glam's `min`/`max` would return the bound).
#[test]
fn the_bounds_let_a_nan_through() {
    let b = Vec3::splat(3.0);
    assert_eq!(at_most(Vec3::new(1.0, 5.0, 3.0), b), Vec3::new(1.0, 3.0, 3.0));
    assert_eq!(at_least_zero(Vec3::new(-1.0, 2.0, 0.0)), Vec3::new(0.0, 2.0, 0.0));
    assert!(at_most(Vec3::new(f32::NAN, 1.0, 1.0), b).x.is_nan());
    assert_eq!(at_most(Vec3::splat(f32::INFINITY), b).x, f32::INFINITY);
    assert!(at_least_zero(Vec3::new(1.0, f32::NAN, 1.0)).y.is_nan());
}
