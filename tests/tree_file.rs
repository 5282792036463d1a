//! The baked tree file (`pbgi::tree::file`): a round trip gives the same
//! bytes and the same image, bit for bit; each kind of damage is its own
//! error; no prefix and no one-byte change (checksum made right) panics,
//! and what loads is safe to traverse and shade; a tree baked from another
//! scene or with other settings is refused.

use std::panic::{AssertUnwindSafe, catch_unwind};

use glam::Vec3;
use pbgi::gather::{Gather, GatherOptions};
use pbgi::render::{Frame, RenderError, RenderOptions, bake_tree};
use pbgi::scene::Scene;
use pbgi::scene::builtin::cornell_box;
use pbgi::tree::file::checksum;
use pbgi::tree::{BakeRecord, Precision, TreeFile, TreeFileError};
use pbgi::{CutOptions, PointCloud, Receiver, Scheme, Surfel, Traversal, Tree};

/// A floor and a wall meeting at a corner, 8 surfels: mixed clusters.
fn corner_file() -> TreeFile {
    corner_file_at(Precision::Full)
}

/// [`corner_file`] with its tree at `precision`.
fn corner_file_at(precision: Precision) -> TreeFile {
    let mut surfels = Vec::new();
    for i in 0..4 {
        let t = i as f32 * 0.25;
        surfels.push(Surfel {
            position: Vec3::new(t, 0.0, 0.1),
            normal: Vec3::Y,
            radius: 0.1,
            radiance: Vec3::new(1.0, 0.5, 0.25),
        });
        surfels.push(Surfel {
            position: Vec3::new(0.0, t + 0.1, 0.1),
            normal: Vec3::X,
            radius: 0.1,
            radiance: Vec3::splat(0.5),
        });
    }
    let cloud = PointCloud::new(surfels).unwrap();
    let tree = Tree::build_with(&cloud, precision);
    TreeFile::new(cloud, tree, BakeRecord::default()).unwrap()
}

fn small_box() -> Scene {
    let mut s = cornell_box();
    (s.camera.width, s.camera.height) = (10, 7);
    s
}

fn quick() -> RenderOptions {
    RenderOptions {
        spp: 1,
        density: 60.0,
        ..RenderOptions::default()
    }
}

/// Writes the checksum of everything before it again.
fn fix_checksum(bytes: &mut [u8]) {
    let end = bytes.len() - 8;
    let sum = checksum(&bytes[..end]);
    bytes[end..].copy_from_slice(&sum.to_le_bytes());
}

/// Every scheme's cut and a gather of irradiance, occlusion and a glossy
/// lobe at a few receivers on and around the surfels: what a loaded tree
/// must survive.
fn exercise(file: &TreeFile) {
    let tree = file.tree();
    let mut pairs: Vec<(Vec3, Vec3)> = file
        .cloud()
        .surfels()
        .iter()
        .take(20)
        .map(|s| (s.position + s.normal * 0.01, s.normal))
        .collect();
    pairs.push((Vec3::new(0.3, 0.3, 0.3), Vec3::Y));
    let receivers = Receiver::from_pairs(pairs.iter().copied()).unwrap();
    let t = Traversal::new(tree, CutOptions::default()).unwrap();
    let scalar = t.cuts(Scheme::Scalar, &receivers);
    for scheme in Scheme::ALL {
        assert_eq!(t.cuts(scheme, &receivers), scalar, "{scheme}");
    }
    for c in &scalar {
        c.check(tree).expect("cut invariants");
    }
    let g = Gather::new(tree, &GatherOptions::default()).unwrap();
    let _ = g.irradiance(&pairs);
    let _ = g.occlusion(&pairs);
}

#[test]
fn round_trip_gives_the_same_bytes_and_image() {
    for precision in [Precision::Full, Precision::Compact] {
        let file = corner_file_at(precision);
        let bytes = file.to_bytes();
        let back = TreeFile::load(bytes.as_slice()).unwrap();
        assert_eq!(back.to_bytes(), bytes, "{precision:?}");
        assert_eq!(back.cloud(), file.cloud());
        assert_eq!(back.tree().precision(), precision);
        exercise(&back);
    }

    let scene = small_box();
    let mut sky = small_box();
    sky.environment = Some(pbgi::environment::Environment::uniform(Vec3::splat(0.3)).unwrap());
    let cases = [
        ("one bounce", &scene, quick()),
        (
            "two bounces",
            &scene,
            RenderOptions {
                bounces: 2,
                ..quick()
            },
        ),
        ("sky, one bounce", &sky, quick()),
        ("AO", &scene, RenderOptions { ao: true, ..quick() }),
        (
            "compact, sky",
            &sky,
            RenderOptions {
                tree_precision: Precision::Compact,
                ..quick()
            },
        ),
        (
            "direct only (empty tree)",
            &scene,
            RenderOptions {
                bounces: 0,
                ..quick()
            },
        ),
        (
            "direct only, compact (empty tree)",
            &scene,
            RenderOptions {
                bounces: 0,
                tree_precision: Precision::Compact,
                ..quick()
            },
        ),
    ];
    for (name, scene, opts) in cases {
        let baked = bake_tree(scene, &opts).unwrap();
        let mut bytes = Vec::new();
        baked.save(&mut bytes).unwrap();
        let loaded = TreeFile::load(bytes.as_slice()).unwrap();
        assert_eq!(loaded.to_bytes(), bytes, "{name}: re-saved bytes differ");
        assert_eq!(loaded.tree().precision(), opts.tree_precision, "{name}");
        let built = Frame::prepare(scene, &opts).unwrap().render(&|_, _| {}).unwrap();
        let frame = Frame::with_tree(scene, &opts, loaded).unwrap();
        let from_file = frame.render(&|_, _| {}).unwrap();
        assert_eq!(from_file.image, built.image, "{name}: image differs");
        assert_eq!(from_file.surfels, built.surfels, "{name}");
        assert!(
            from_file
                .stages
                .iter()
                .any(|s| s.skipped.as_deref() == Some("loaded with the tree"))
                || built.surfels == 0,
            "{name}: {:?}",
            from_file.stages
        );
    }
}

#[test]
fn each_kind_of_damage_has_its_error() {
    let good = corner_file().to_bytes();
    let n = good.len();
    let load = |b: &[u8]| TreeFile::from_bytes(b).unwrap_err();

    let mut b = good.clone();
    b[0] = b'X';
    assert!(matches!(load(&b), TreeFileError::BadMagic { .. }));

    let mut b = good.clone();
    b[8] = 1;
    let e = load(&b);
    assert!(
        matches!(
            e,
            TreeFileError::UnsupportedVersion {
                found: 1,
                supported: 4
            }
        ),
        "{e}"
    );

    let mut b = good.clone();
    b[n / 2] ^= 0x10;
    let e = load(&b);
    assert!(
        matches!(e, TreeFileError::Checksum { offset, .. } if offset as usize == n - 8),
        "{e}"
    );

    let e = load(&good[..n - 1]);
    assert!(
        matches!(e, TreeFileError::Truncated { offset, needed } if offset as usize == n - 1 && needed as usize == n),
        "{e}"
    );

    let mut b = good.clone();
    b.push(0);
    assert!(matches!(load(&b), TreeFileError::TrailingBytes { offset } if offset as usize == n));
    // A reader stops one byte past the end the header gives.
    let endless = std::io::Read::chain(good.as_slice(), std::io::repeat(7));
    let e = TreeFile::load(endless).unwrap_err();
    assert!(
        matches!(e, TreeFileError::TrailingBytes { offset } if offset as usize == n),
        "{e}"
    );

    // A child link out of range, checksum made right: node 0's child field.
    let (nodes_at, node) = (64 + 40 * 8, 96);
    let mut b = good.clone();
    b[nodes_at + 36..nodes_at + 40].copy_from_slice(&1000u32.to_le_bytes());
    fix_checksum(&mut b);
    let e = load(&b);
    assert!(
        matches!(&e, TreeFileError::Invalid { offset, .. } if *offset as usize == nodes_at),
        "{e}"
    );
    assert!(e.to_string().contains("node 0"), "{e}");

    // A radius that is not finite in node 2.
    let mut b = good.clone();
    b[nodes_at + 2 * node + 12..nodes_at + 2 * node + 16].copy_from_slice(&f32::NAN.to_le_bytes());
    fix_checksum(&mut b);
    let e = load(&b);
    assert!(
        matches!(&e, TreeFileError::Invalid { offset, .. } if *offset as usize == nodes_at + 2 * node),
        "{e}"
    );

    // A light centroid far outside node 2's sphere (its x, after the
    // area centroid).
    let mut b = good.clone();
    b[nodes_at + 2 * node + 84..nodes_at + 2 * node + 88].copy_from_slice(&1e6f32.to_le_bytes());
    fix_checksum(&mut b);
    let e = load(&b);
    assert!(
        matches!(&e, TreeFileError::Invalid { offset, .. } if *offset as usize == nodes_at + 2 * node),
        "{e}"
    );
    assert!(e.to_string().contains("light centroid"), "{e}");

    // Two leaves of one surfel.
    let tree = corner_file();
    let leaves: Vec<u32> = (0..tree.tree().len() as u32)
        .filter(|&k| tree.tree().is_leaf(k))
        .collect();
    let mut b = good.clone();
    let (a, c) = (leaves[0] as usize, leaves[1] as usize);
    let first = b[nodes_at + a * node + 36..nodes_at + a * node + 40].to_vec();
    b[nodes_at + c * node + 36..nodes_at + c * node + 40].copy_from_slice(&first);
    fix_checksum(&mut b);
    let e = load(&b);
    assert!(e.to_string().contains("in two leaves"), "{e}");

    // A surfel with a normal of length 2: surfel 3's normal x.
    let mut b = good.clone();
    let at = 64 + 40 * 3 + 12;
    b[at..at + 4].copy_from_slice(&2.0f32.to_le_bytes());
    b[at + 4..at + 12].fill(0);
    fix_checksum(&mut b);
    let e = load(&b);
    assert!(
        matches!(&e, TreeFileError::Invalid { offset, .. } if *offset as usize == 64 + 40 * 3),
        "{e}"
    );
    assert!(e.to_string().contains("surfel 3"), "{e}");
}

/// A compact tree's own checks: a record quantized against another sphere
/// than its parent's, and bytes the tree would not write (padding, a light
/// offset it does not derive), each refused at its place.
#[test]
fn a_compact_file_is_refused_where_it_is_not_as_built() {
    let good = corner_file_at(Precision::Compact).to_bytes();
    let load = |b: &[u8]| TreeFile::from_bytes(b).unwrap_err();
    // The surfels end at 64 + 40·8 = 384, a multiple of 64: pair records
    // from there, 64 bytes each. Record 1 (the root's children) has node
    // 0's sphere as its base, in its first 16 bytes.
    let (pairs, record) = (64 + 40 * 8, 64);
    let mut b = good.clone();
    b[pairs + record + 12..pairs + record + 16].copy_from_slice(&1.5f32.to_le_bytes());
    fix_checksum(&mut b);
    let e = load(&b);
    assert!(
        matches!(&e, TreeFileError::Invalid { offset, .. } if *offset as usize == pairs),
        "{e}"
    );
    assert!(e.to_string().contains("another sphere"), "{e}");

    // Record 1's light offset, slot 0: after the base (16 bytes), the centre
    // and axis steps (24) and the radius, cosine and sine (12).
    let at = pairs + record + 16 + 24 + 12;
    let mut b = good.clone();
    b[at] ^= 0x40;
    fix_checksum(&mut b);
    let e = load(&b);
    assert!(
        matches!(&e, TreeFileError::Invalid { offset, .. } if *offset as usize == pairs + record),
        "{e}"
    );
    assert!(e.to_string().contains("node 1: a light offset"), "{e}");

    // The padding of record 1's packed splat record (its last two bytes):
    // the packed splat records follow the 8 pair records.
    let at = pairs + 8 * record + 32 + 30;
    let mut b = good.clone();
    b[at] = 1;
    fix_checksum(&mut b);
    let e = load(&b);
    assert!(
        matches!(&e, TreeFileError::Invalid { offset, .. } if *offset as usize == at),
        "{e}"
    );
    assert!(e.to_string().contains("written again"), "{e}");
}

/// Every prefix is an error (truncated, or bad magic), never a panic; every
/// one-byte change with the checksum made right loads as an error, or as a
/// tree the traversals and the gather run on without a panic.
#[test]
fn prefixes_and_byte_changes_never_panic() {
    for precision in [Precision::Full, Precision::Compact] {
        prefixes_and_byte_changes_never_panic_at(precision);
    }
}

fn prefixes_and_byte_changes_never_panic_at(precision: Precision) {
    let good = corner_file_at(precision).to_bytes();
    for len in 0..good.len() {
        // Through `load` (a reader: header first, then the length it gives).
        let r = catch_unwind(|| TreeFile::load(&good[..len]));
        match r {
            Err(_) => panic!("prefix of {len} bytes panicked"),
            Ok(Ok(_)) => panic!("prefix of {len} bytes loaded"),
            Ok(Err(TreeFileError::Truncated { offset, .. })) => assert_eq!(offset as usize, len),
            Ok(Err(e)) => panic!("prefix of {len} bytes: {e}"),
        }
    }
    let (mut loaded, mut refused) = (0, 0);
    for at in 0..good.len() - 8 {
        for flip in [0x01u8, 0x80, 0xff] {
            let mut b = good.clone();
            b[at] ^= flip;
            fix_checksum(&mut b);
            let r = catch_unwind(AssertUnwindSafe(|| {
                if let Ok(file) = TreeFile::from_bytes(&b) {
                    assert_eq!(file.to_bytes(), b, "a loaded file re-saves as read");
                    exercise(&file);
                    true
                } else {
                    false
                }
            }));
            match r {
                Err(_) => panic!("byte {at} ^ {flip:#x} panicked"),
                Ok(true) => loaded += 1,
                Ok(false) => refused += 1,
            }
        }
    }
    eprintln!("{precision:?}: one-byte changes: {loaded} loaded and ran, {refused} refused");
    assert!(refused > 0 && loaded > 0);
}

#[test]
fn a_tree_from_another_scene_or_settings_is_refused() {
    let scene = small_box();
    let opts = quick();
    let bytes = bake_tree(&scene, &opts).unwrap().to_bytes();
    let file = || TreeFile::from_bytes(&bytes).unwrap();
    let mismatch = |scene: &Scene, opts: &RenderOptions| match Frame::with_tree(scene, opts, file()) {
        Err(RenderError::TreeMismatch { setting, .. }) => setting,
        Err(e) => panic!("{e}"),
        Ok(_) => panic!("accepted"),
    };
    let mut other = small_box();
    other.materials[0].albedo *= 0.5;
    assert!(mismatch(&other, &opts).starts_with("scene"));
    assert_eq!(
        mismatch(
            &scene,
            &RenderOptions {
                density: 61.0,
                ..opts
            }
        ),
        "--density"
    );
    assert_eq!(
        mismatch(&scene, &RenderOptions { bounces: 2, ..opts }),
        "--bounces"
    );
    assert_eq!(mismatch(&scene, &RenderOptions { ao: true, ..opts }), "--ao");
    assert_eq!(
        mismatch(
            &scene,
            &RenderOptions {
                drop_buried: !opts.drop_buried,
                ..opts
            }
        ),
        "--buried-surfels (dropped)"
    );
    // Free: the view, the samples, the scheme, the Ω of the render itself.
    let mut moved = small_box();
    moved.camera.origin.x += 0.1;
    let free = RenderOptions {
        spp: 2,
        cut: CutOptions {
            max_solid_angle: 0.1,
            ..opts.cut
        },
        ..opts
    };
    assert!(Frame::with_tree(&moved, &free, file()).is_ok());

    // Two bounces gather at the surfels: Ω and the microbuffer are baked in.
    let two = RenderOptions { bounces: 2, ..opts };
    let bytes = bake_tree(&scene, &two).unwrap().to_bytes();
    let r = Frame::with_tree(
        &scene,
        &RenderOptions {
            microbuffer: 16,
            ..two
        },
        TreeFile::from_bytes(&bytes).unwrap(),
    );
    assert!(
        matches!(r, Err(RenderError::TreeMismatch { setting, .. }) if setting.starts_with("--microbuffer"))
    );
}

/// A compact tree file opened by its map is used in place, renders what
/// the bytes read whole render, and keeps its tree when a new bake is
/// written over its name; a file cut short on disk is refused as truncated.
#[cfg(feature = "mmap")]
#[test]
fn a_mapped_compact_file_is_used_in_place_and_survives_a_new_bake() {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("tree-file-map");
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(format!("box-{}.pbgi", std::process::id()));
    let scene = small_box();
    let opts = RenderOptions {
        tree_precision: Precision::Compact,
        ..quick()
    };
    let baked = bake_tree(&scene, &opts).unwrap();
    baked.write_to(&path).unwrap();
    let mapped = TreeFile::open(&path).unwrap();
    assert!(mapped.tree().is_mapped() == cfg!(target_endian = "little"));
    let read = TreeFile::from_bytes(&std::fs::read(&path).unwrap()).unwrap();
    assert!(!read.tree().is_mapped());
    assert_eq!(mapped.to_bytes(), read.to_bytes());
    let render = |file: TreeFile| {
        Frame::with_tree(&scene, &opts, file)
            .unwrap()
            .render(&|_, _| {})
            .unwrap()
            .image
    };
    let before = mapped.tree().clone();
    let bytes = read.to_bytes();
    assert_eq!(render(mapped), render(read), "mapped against read whole");

    // A bake of another tree written over the name while one is mapped.
    let held = TreeFile::open(&path).unwrap();
    corner_file_at(Precision::Compact).write_to(&path).unwrap();
    assert_eq!(held.to_bytes(), bytes, "the mapped tree changed under a new bake");
    assert_eq!(
        format!("{:?}", held.tree().node(3)),
        format!("{:?}", before.node(3))
    );

    let cut = &std::fs::read(&path).unwrap()[..500];
    std::fs::write(&path, cut).unwrap();
    let e = TreeFile::open(&path).unwrap_err();
    assert!(matches!(e, TreeFileError::Truncated { offset: 500, .. }), "{e}");
    std::fs::remove_file(&path).unwrap();
}
