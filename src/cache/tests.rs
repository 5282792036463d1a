use super::*;
use crate::brdf::GlossyLobe;
use crate::cut::Receiver;
use crate::gather::GatherOptions;
use crate::microbuffer::Gradients;
use crate::tree::Precision;
use crate::{PointCloud, Surfel};

/// A cache over `tree` with one level, whose cells hold `records` (each in
/// the cell of its position, the first of each facing), as `prepare` would
/// have filed them.
fn filed(tree: &Tree, records: &[Record]) -> Cache {
    let mut c = Cache::new(tree, CacheOptions::default());
    c.grid.levels = 1;
    // Every cell of the cube was asked for (most hold nothing).
    let n = Grid::across(0);
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                for f in 0..6 {
                    c.cells.insert(key([x, y, z], 0, f), NONE);
                }
            }
        }
    }
    // The first record of each cell and facing.
    for r in records {
        let k = key(c.grid.cell(r.position, 0).expect("inside"), 0, facing(r.normal));
        if c.cells[&k] == NONE {
            c.cells.insert(k, c.records.len() as u32);
            c.records.push(*r);
        }
    }
    c
}

/// A floor (y = 0, up) and a wall (x = 0, facing +x) meeting at the origin,
/// as surfels 0.1 apart over [0, 4]².
fn corner() -> Tree {
    let mut s = Vec::new();
    for i in 0..40 {
        for j in 0..40 {
            let (u, v) = (0.05 + 0.1 * i as f32, 0.05 + 0.1 * j as f32);
            for (position, normal) in [(Vec3::new(u, 0.0, v), Vec3::Y), (Vec3::new(0.0, u, v), Vec3::X)] {
                s.push(Surfel {
                    position,
                    normal,
                    radius: 0.05,
                    radiance: Vec3::ZERO,
                });
            }
        }
    }
    Tree::build(&PointCloud::new(s).unwrap())
}

#[test]
fn records_of_another_surface_never_blend() {
    let tree = corner();
    let h = {
        let c = Cache::new(&tree, CacheOptions::default());
        c.grid.cell_size(0)
    };
    // Records on the floor (light 1) and on the wall (light 10) along the
    // edge, one per cell, some within a cell's side of the floor point below.
    let mut records = Vec::new();
    for k in 0..40 {
        let z = 0.05 + 0.1 * k as f32;
        records.push(Record {
            position: Vec3::new(0.2, 0.0, z),
            normal: Vec3::Y,
            e: Vec3::splat(1.0),
            gradients: Default::default(),
        });
        records.push(Record {
            position: Vec3::new(0.0, 0.2, z),
            normal: Vec3::X,
            e: Vec3::splat(10.0),
            gradients: Default::default(),
        });
    }
    let cache = filed(&tree, &records);
    let p = Vec3::new(0.05, 0.0, 1.4);
    let near = |n: Vec3| {
        cache
            .records
            .iter()
            .any(|r| r.normal == n && (p - r.position).length() < h)
    };
    assert!(
        near(Vec3::Y) && near(Vec3::X),
        "records of both surfaces are near enough to count"
    );
    let light = |p: Vec3, n: Vec3| match cache.lookup(p, n) {
        Lookup::Light(e) => e,
        other => panic!("{other:?} at {p}"),
    };
    assert!((light(p, Vec3::Y) - Vec3::ONE).abs().max_element() < 1e-5);
    assert!(
        (light(Vec3::new(0.0, 0.05, 1.4), Vec3::X) - Vec3::splat(10.0))
            .abs()
            .max_element()
            < 1e-4
    );
    // A step: a floor 0.2 higher is another surface.
    assert_eq!(cache.lookup(Vec3::new(0.3, 0.2, 1.4), Vec3::Y), Lookup::Uncovered);
}

/// A sample whose normal leans from its record's takes the record turned
/// by its rotational gradient, `E + (n_i × n)·∇_r E`, and one with the
/// record's own normal takes `E` itself.
#[test]
fn a_record_is_turned_to_the_samples_normal_by_its_rotational_gradient() {
    let tree = corner();
    let turn = Vec3::new(0.0, 0.0, 3.0);
    let record = Record {
        position: Vec3::new(1.0, 0.0, 1.0),
        normal: Vec3::Y,
        e: Vec3::splat(2.0),
        gradients: Gradients {
            translation: [Vec3::splat(100.0); 3],
            rotation: [turn, turn * 2.0, Vec3::ZERO],
            distance: 1.0,
        },
    };
    let cache = filed(&tree, &[record]);
    let p = record.position + Vec3::new(0.05, 0.0, 0.02);
    let n = Vec3::new(0.1, 1.0, 0.0).normalize();
    let want = Vec3::splat(2.0) + Vec3::new(1.0, 2.0, 0.0) * Vec3::Y.cross(n).dot(turn);
    match cache.lookup(p, n) {
        Lookup::Light(e) => assert!((e - want).abs().max_element() < 1e-5, "{e} against {want}"),
        other => panic!("{other:?}"),
    }
    assert_eq!(cache.lookup(p, Vec3::Y), Lookup::Light(Vec3::splat(2.0)));
}

/// Light that changes linearly along a surface is blended exactly: the
/// records' weighted least-squares plane is read at the point, where their
/// weighted mean leans to the nearest record.
#[test]
fn a_blend_is_exact_for_light_linear_along_the_surface() {
    let tree = corner();
    let cache0 = Cache::new(&tree, CacheOptions::default());
    let h = cache0.grid.cell_size(0);
    let origin = cache0.grid.origin;
    let linear = |p: Vec3| Vec3::new(1.0, 2.0, 0.5) * (1.0 + 0.2 * p.x - 0.1 * p.z);
    // One floor record at the centre of each level-0 cell.
    let mut records = Vec::new();
    for i in 0..8 {
        for k in 0..8 {
            let position = Vec3::new(
                origin.x + h * (i as f32 + 0.5),
                0.0,
                origin.z + h * (k as f32 + 0.5),
            );
            records.push(Record {
                position,
                normal: Vec3::Y,
                e: linear(position),
                gradients: Default::default(),
            });
        }
    }
    let cache = filed(&tree, &records);
    let mut leaned = 0.0f32;
    for p in [
        Vec3::new(1.1, 0.0, 1.1),
        Vec3::new(2.3, 0.0, 0.9),
        Vec3::new(1.7, 0.0, 2.6),
    ] {
        let e = match cache.lookup(p, Vec3::Y) {
            Lookup::Light(e) => e,
            other => panic!("{other:?} at {p}"),
        };
        let want = linear(p);
        assert!(
            ((e - want) / want).abs().max_element() < 1e-5,
            "{e} against {want} at {p}"
        );
        let b = cache.blend(p, Vec3::Y, 0, &mut Around::default());
        leaned = leaned.max(((b.sum / b.weight - want) / want).abs().max_element());
    }
    assert!(
        leaned > 1e-3,
        "the points lie where a mean would lean ({leaned}): the test would prove little"
    );
}

/// Fewer surfels under emulation (`PBGI_QC_TESTS` below 50, as the ARM
/// stage sets it).
fn emulated() -> bool {
    std::env::var("PBGI_QC_TESTS")
        .ok()
        .and_then(|s| s.trim().parse::<u64>().ok())
        .is_some_and(|n| n < 50)
}

/// The synthetic box, its gather (with the renderer's irradiance settings)
/// and receivers on its surfaces (facing as they do).
fn scene(n: usize) -> (Tree, Vec<(Vec3, Vec3)>) {
    let tree = Tree::build(&crate::synthetic::box_with_blocks(n, 7));
    let points = crate::synthetic::receivers(40, 0.02, 0.0, 3)
        .iter()
        .map(|r| (r.position(), r.normal()))
        .collect();
    (tree, points)
}

fn options(threads: usize) -> GatherOptions {
    let mut o = GatherOptions {
        microbuffer: 12,
        threads: Some(threads),
        ..GatherOptions::default()
    };
    o.cut.max_solid_angle = 0.15;
    o
}

fn bits_of(l: Lookup) -> [u32; 4] {
    match l {
        Lookup::Light(e) => [0, e.x.to_bits(), e.y.to_bits(), e.z.to_bits()],
        Lookup::Uncovered => [1, 0, 0, 0],
        Lookup::Changing => [2, 0, 0, 0],
    }
}

fn bits(cache: &Cache, points: &[(Vec3, Vec3)]) -> Vec<[u32; 4]> {
    points.iter().map(|&(p, n)| bits_of(cache.lookup(p, n))).collect()
}

#[test]
fn records_and_lookups_are_the_same_bits_for_any_threads_order_or_subset() {
    let (tree, points) = scene(6_000);
    let run = |threads: usize, points: &[(Vec3, Vec3)], parts: usize| {
        let gather = Gather::new(&tree, &options(threads)).unwrap();
        let mut cache = Cache::new(&tree, CacheOptions::default());
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            for part in points.chunks(points.len().div_ceil(parts)) {
                let made = cache.prepare(part, &gather, Convolution::Irradiance).unwrap();
                // What each point settled on while its records were made
                // is what `lookup` finds once they are (the tiles take it).
                let settled: Vec<[u32; 4]> = made.lookups.into_iter().map(bits_of).collect();
                assert_eq!(settled, bits(&cache, part), "{threads} threads, {parts} parts");
            }
        });
        cache
    };
    let one = run(1, &points, 1);
    let want = bits(&one, &points);
    assert!(
        want.iter().filter(|b| b[0] == 0).count() * 2 > points.len(),
        "most points are served: the test would prove little"
    );
    for threads in if emulated() { &[2][..] } else { &[2, 7] } {
        let c = run(*threads, &points, 1);
        assert_eq!(bits(&c, &points), want, "{threads} threads");
    }
    // Reversed, and asked for in three parts (as three frames would).
    let mut rev = points.clone();
    rev.reverse();
    let c = run(2, &rev, 3);
    assert_eq!(bits(&c, &points), want, "reversed, in three parts");
    // A subset (a crop) gets the same light at its points.
    let half = &points[..points.len() / 2];
    let c = run(2, half, 1);
    assert_eq!(bits(&c, half), want[..half.len()].to_vec(), "a subset");
    assert!(c.len() < one.len(), "a subset needs fewer records");
}

#[test]
fn the_cache_converges_to_the_gathers_as_its_threshold_shrinks() {
    let (tree, points) = scene(20_000);
    let gather = Gather::new(&tree, &options(2)).unwrap();
    let exact = gather.irradiance(&points).unwrap();
    let error = |threshold: f32| {
        let mut cache = Cache::new(
            &tree,
            CacheOptions {
                threshold,
                incident: false,
            },
        );
        cache.prepare(&points, &gather, Convolution::Irradiance).unwrap();
        let (mut num, mut den, mut served) = (0.0f64, 0.0f64, 0);
        for (&(p, n), e) in points.iter().zip(&exact) {
            let got = match cache.lookup(p, n) {
                Lookup::Light(l) => {
                    served += 1;
                    l
                }
                // Gathered at the point itself.
                _ => *e,
            };
            num += f64::from((got - *e).length_squared());
            den += f64::from(e.length_squared());
        }
        ((num / den).sqrt(), cache.len(), served)
    };
    // Thresholds eight times apart: between nearer ones (0.3 and 0.1) the
    // error can hold still to 0.5 % of itself while the records change,
    // since the truth here, a gather at each point, carries the gathers'
    // own point-to-point noise (1.66 and 1.67 % there; 1.74, 1.67 and
    // 0.98 % at these three).
    let coarse = error(0.8);
    let mid = error(0.1);
    let fine = error(0.0125);
    eprintln!("threshold 0.8 / 0.1 / 0.0125: (rel. RMS error, records, served) {coarse:?} {mid:?} {fine:?}");
    assert!(coarse.0 > mid.0 && mid.0 > fine.0, "{coarse:?} {mid:?} {fine:?}");
    assert!(mid.0 < 0.05, "{mid:?}");
    assert!(coarse.1 < mid.1 && mid.1 < fine.1);
}

/// `bytes` with its checksum made right again: damage the checksum does
/// not see, as a writer with a defect would leave it.
fn sealed(mut bytes: Vec<u8>) -> Vec<u8> {
    let end = bytes.len() - 8;
    let sum = crate::tree::file::checksum(&bytes[..end]);
    bytes[end..].copy_from_slice(&sum.to_le_bytes());
    bytes
}

#[test]
fn a_cache_file_gives_back_its_records_and_refuses_a_damaged_or_foreign_one() {
    use file::CacheFileError as E;
    let (tree, points) = scene(3_000);
    let gather = Gather::new(&tree, &options(2)).unwrap();
    let opts = CacheOptions::default();
    let mut cache = Cache::new(&tree, opts);
    cache.prepare(&points, &gather, Convolution::Irradiance).unwrap();
    let bytes = cache.to_bytes(7);
    let back = Cache::from_bytes(&bytes, &tree, opts, 7).unwrap();
    assert!(back.len() > 100, "{} records prove little", back.len());
    assert_eq!(back.len(), cache.len());
    assert_eq!(bits(&back, &points), bits(&cache, &points));
    assert_eq!(back.to_bytes(7), bytes, "the bytes depend on the records alone");
    // Taken up, it gathers nothing more for the same points.
    let mut again = back;
    assert_eq!(
        again
            .prepare(&points, &gather, Convolution::Irradiance)
            .unwrap()
            .records,
        0
    );

    let load = |b: &[u8]| Cache::from_bytes(b, &tree, opts, 7).err().expect("refused");
    for n in (0..bytes.len()).step_by(97).chain([7, 55, bytes.len() - 1]) {
        assert!(matches!(load(&bytes[..n]), E::Truncated { .. }), "cut at {n}");
    }
    let mut longer = bytes.clone();
    longer.push(0);
    assert!(matches!(load(&longer), E::TrailingBytes { .. }));
    let mut flipped = bytes.clone();
    flipped[100] ^= 4;
    assert!(matches!(load(&flipped), E::Checksum { .. }));
    assert!(matches!(load(b"PBGITREE...."), E::BadMagic { .. }));
    assert!(matches!(
        Cache::from_bytes(&bytes, &tree, opts, 8),
        Err(E::Mismatch { what: "settings", .. })
    ));
    // A surface moved by a hundredth: a record of the old tree is stale.
    let cloud = crate::synthetic::box_with_blocks(3_000, 7);
    let moved: Vec<Surfel> = cloud
        .surfels()
        .iter()
        .map(|s| Surfel {
            position: s.position + Vec3::new(0.0, if s.normal.y > 0.9 { 0.01 } else { 0.0 }, 0.0),
            ..*s
        })
        .collect();
    let other = Tree::build(&PointCloud::new(moved).unwrap());
    assert!(matches!(
        Cache::from_bytes(&bytes, &other, opts, 7),
        Err(E::Mismatch { what: "tree", .. })
    ));

    // Damage behind a good checksum, each at the first record (byte 56).
    let invalid = |edit: &dyn Fn(&mut Vec<u8>)| {
        let mut b = bytes.clone();
        edit(&mut b);
        match load(&sealed(b)) {
            E::Invalid { offset, .. } => offset,
            e => panic!("{e}"),
        }
    };
    let put = |b: &mut Vec<u8>, at: usize, x: f32| b[at..at + 4].copy_from_slice(&x.to_le_bytes());
    assert_eq!(invalid(&|b| put(b, 56 + 8, 0.123)), 56, "a record off its surfel");
    assert_eq!(invalid(&|b| put(b, 56 + 32, f32::NAN)), 56, "a NaN light");
    assert_eq!(invalid(&|b| put(b, 56 + 32, -1.0)), 56, "a negative light");
    assert_eq!(
        invalid(&|b| put(b, 56 + 44, f32::INFINITY)),
        56,
        "an infinite gradient"
    );
    assert_eq!(invalid(&|b| b[56 + 7] = 0xF0), 56, "a level past the cube's");
    // The second record's key moved before the first's.
    assert_eq!(invalid(&|b| b.copy_within(56..64, 176)), 176, "keys out of order");
}

/// A record that keeps its incident light reflects it through a lobe, at
/// its own place and normal, exactly as a glossy gather there does, and
/// weighs it about a tilted normal as a tilted gather does: the same
/// pixels, directions and weights, bit for bit (no sky here, whose sum a
/// gather holds at least zero).
#[test]
fn a_records_incident_light_reflects_a_lobe_as_its_own_gather_does() {
    // The corner with its floor lit: the wall sees it.
    let mut s = Vec::new();
    for i in 0..30 {
        for j in 0..30 {
            let (u, v) = (0.05 + 0.1 * i as f32, 0.05 + 0.1 * j as f32);
            s.push(Surfel {
                position: Vec3::new(u, 0.0, v),
                normal: Vec3::Y,
                radius: 0.05,
                radiance: Vec3::new(1.0, 0.5, 0.25 + u / 3.0),
            });
            s.push(Surfel {
                position: Vec3::new(0.0, u, v),
                normal: Vec3::X,
                radius: 0.05,
                radiance: Vec3::ZERO,
            });
        }
    }
    let tree = Tree::build(&PointCloud::new(s).unwrap());
    let gather = Gather::new(
        &tree,
        &GatherOptions {
            microbuffer: 12,
            ..GatherOptions::default()
        },
    )
    .unwrap();
    let mut cache = Cache::new(
        &tree,
        CacheOptions {
            threshold: 0.1,
            incident: true,
        },
    );
    let points = [
        (Vec3::new(0.0, 0.7, 1.3), Vec3::X),
        (Vec3::new(0.0, 2.1, 2.2), Vec3::X),
    ];
    cache.prepare(&points, &gather, Convolution::Irradiance).unwrap();
    let table = cache.table.clone().expect("records made");
    let pixels = table.dir.len();
    let all = cache.incident.as_ref().unwrap();
    assert_eq!(all.len(), cache.len() * pixels, "every record keeps its pixels");
    let lobe = GlossyLobe {
        specular: Vec3::new(0.9, 0.6, 0.3),
        roughness: 0.4,
    };
    let mut lit = 0;
    for (i, r) in cache
        .records()
        .iter()
        .enumerate()
        .filter(|(_, r)| r.normal == Vec3::X)
    {
        let wo = Vec3::new(0.8, -0.3, 0.5).normalize();
        let want = gather
            .glossy(&[crate::GlossyReceiver {
                position: r.position,
                normal: r.normal,
                wo,
                lobe,
            }])
            .unwrap()[0];
        let got = reflect(
            &table,
            r.normal,
            &all[i * pixels..(i + 1) * pixels],
            &lobe,
            r.normal,
            wo,
        );
        assert_eq!(
            got.to_array().map(f32::to_bits),
            want.to_array().map(f32::to_bits),
            "record at {}",
            r.position
        );
        lit += usize::from(want.min_element() > 0.0);
        // Its irradiance about a normal a map tilts: a tilted gather's.
        let tilt = (r.normal + Vec3::new(0.2, -0.4, 0.3)).normalize();
        let mut g = gather.gatherer();
        g.cut(&[Receiver::new(r.position, r.normal).unwrap()]).unwrap();
        let want = g.shade_tilted(Convolution::Irradiance, [tilt].into_iter())[0];
        let got = tilted(&table, r.normal, &all[i * pixels..(i + 1) * pixels], tilt);
        assert_eq!(
            got.to_array().map(f32::to_bits),
            want.to_array().map(f32::to_bits),
            "tilted at {}",
            r.position
        );
    }
    assert!(lit > 0, "no wall record saw the lit floor");
}

/// A wall at 45° whose normal leans a rounding error towards `−z` (as
/// Sponza's octagonal piers' do), over a lit floor: the compact tree's
/// leaves keep `−z` their dominant axis, so the records on the wall face as
/// the points on it do and serve them, as the full tree's do.
#[test]
fn a_wall_at_45_degrees_is_served_by_a_compact_tree_as_by_a_full_one() {
    let n = Vec3::new(-0.707_105_46, 0.0, -0.707_108_1);
    let along = n.cross(Vec3::Y).normalize();
    let corner = Vec3::new(3.0, 0.0, 3.0);
    let mut s = Vec::new();
    let mut points = Vec::new();
    for i in 0..40 {
        for j in 0..40 {
            let (u, v) = (0.05 + 0.1 * i as f32, 0.05 + 0.1 * j as f32);
            let lit = Vec3::splat(1.0);
            let p = corner + along * (u - 2.0) + Vec3::Y * v;
            for (position, normal, radiance) in [(Vec3::new(u, 0.0, v), Vec3::Y, lit), (p, n, Vec3::ZERO)] {
                s.push(Surfel {
                    position,
                    normal,
                    radius: 0.05,
                    radiance,
                });
            }
            points.push((p + along * 0.03 + Vec3::Y * 0.02, n));
        }
    }
    let cloud = PointCloud::new(s).unwrap();
    let kinds = |precision| {
        let tree = Tree::build_with(&cloud, precision);
        let gather = Gather::new(&tree, &options(2)).unwrap();
        let mut cache = Cache::new(&tree, CacheOptions::default());
        let made = cache.prepare(&points, &gather, Convolution::Irradiance).unwrap();
        made.lookups
            .into_iter()
            .map(|l| bits_of(l)[0])
            .collect::<Vec<_>>()
    };
    let (full, compact) = (kinds(Precision::Full), kinds(Precision::Compact));
    let uncovered = |k: &[u32]| k.iter().filter(|&&k| k == 1).count();
    assert!(
        uncovered(&full) * 10 < points.len(),
        "{} of {} points find no record with the full tree",
        uncovered(&full),
        points.len()
    );
    assert_eq!(
        uncovered(&compact),
        uncovered(&full),
        "points on the wall that find no record, compact against full"
    );
}
