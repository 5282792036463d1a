//! The baked tree file reader (`pbgi::tree::TreeFile`): arbitrary bytes are
//! a typed error or a tree, never a panic. Byte 0 is a switch: odd, the
//! rest gets its checksum written again, so the fuzzer reaches the
//! structure checks behind it; with its top bit set, the bytes are written
//! to a file and mapped (`TreeFile::open`, as `pbgi render --tree` reads a
//! file), so a compact tree is used where it lies in the map. A tree that loads re-saves to the same bytes,
//! and every scheme on every path this CPU runs gives the scalar cut on it
//! (the cut invariants hold), and the gather shades it (irradiance,
//! occlusion) without a panic: the kernels index by its child links
//! unchecked, so the reader must have refused every broken one.
#![no_main]

use glam::Vec3;
use libfuzzer_sys::fuzz_target;
use pbgi::gather::{Gather, GatherOptions};
use pbgi::tree::{TreeFile, TreeFileError};
use pbgi::tree::file::checksum;
use pbgi::{CutOptions, Isa, Receiver, Scheme, Traversal};

fuzz_target!(|data: &[u8]| {
    let Some((&switch, rest)) = data.split_first() else {
        return;
    };
    let mut bytes = rest.to_vec();
    if switch & 1 == 1 && bytes.len() >= 8 {
        let end = bytes.len() - 8;
        let sum = checksum(&bytes[..end]);
        bytes[end..].copy_from_slice(&sum.to_le_bytes());
    }
    let loaded = if switch & 0x80 != 0 {
        mapped(&bytes)
    } else {
        TreeFile::from_bytes(&bytes)
    };
    let Ok(file) = loaded else {
        return;
    };
    assert_eq!(file.to_bytes(), bytes, "a loaded file re-saves as read");
    let tree = file.tree();
    if tree.is_empty() {
        return;
    }
    // Receivers just above some surfels, and one at the root's centre.
    let mut pairs: Vec<(Vec3, Vec3)> = file
        .cloud()
        .surfels()
        .iter()
        .take(20)
        .map(|s| (s.position + s.normal * s.radius, s.normal))
        .collect();
    pairs.push((tree.sphere(0).0, Vec3::Y));
    let Ok(receivers) = Receiver::from_pairs(pairs.iter().copied()) else {
        return;
    };
    let omega = [0.0, 0.05, 1.0][switch as usize / 2 % 3];
    let mut reference = None;
    for isa in Isa::available() {
        let opts = CutOptions {
            max_solid_angle: omega,
            isa: Some(isa),
            ..CutOptions::default()
        };
        let t = Traversal::new(tree, opts).expect("valid options");
        let scalar = t.cuts(Scheme::Scalar, &receivers);
        for c in &scalar {
            c.check(tree).expect("cut invariants");
        }
        for scheme in Scheme::ALL {
            assert_eq!(t.cuts(scheme, &receivers), scalar, "{scheme} on {isa} differs from scalar");
        }
        match &reference {
            None => reference = Some(scalar),
            Some(r) => assert_eq!(r, &scalar, "scalar on {isa} differs from the first path"),
        }
    }
    let gopts = GatherOptions {
        cut: CutOptions {
            max_solid_angle: omega,
            ..CutOptions::default()
        },
        microbuffer: 8,
        ..GatherOptions::default()
    };
    let g = Gather::new(tree, &gopts).expect("valid options");
    let _ = g.irradiance(&pairs);
    let _ = g.occlusion(&pairs);
});

/// `bytes` through a file and its map. The name goes at once; the map keeps
/// the file for as long as the tree lives.
fn mapped(bytes: &[u8]) -> Result<TreeFile, TreeFileError> {
    let path = std::env::temp_dir().join(format!("pbgi-fuzz-tree-{}.pbgi", std::process::id()));
    std::fs::write(&path, bytes).expect("a temporary file");
    let file = TreeFile::open(&path);
    std::fs::remove_file(&path).expect("the temporary file");
    file
}
