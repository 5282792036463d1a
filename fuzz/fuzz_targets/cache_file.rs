//! The cache file reader (`pbgi::cache::Cache::from_bytes`): arbitrary bytes
//! are a typed error or a cache, never a panic. Byte 0 is a switch. Bit 1
//! set: the rest are edits (offset u16, xor byte) to a good file of a fixed
//! small scene, so the fuzzer reaches the entry checks behind the header
//! without a corpus; clear: the rest is the file. Bit 0 set: its checksum is
//! written again, so damage reaches the structure checks. A cache that
//! loads re-saves to the same bytes and serves every point of the scene
//! finite light, without a panic.
#![no_main]

use std::sync::OnceLock;

use glam::Vec3;
use libfuzzer_sys::fuzz_target;
use pbgi::Tree;
use pbgi::cache::{Cache, CacheOptions, Lookup};
use pbgi::gather::{Gather, GatherOptions};
use pbgi::microbuffer::Convolution;
use pbgi::tree::file::checksum;

const SETTINGS: u64 = 0x5eed;

struct Good {
    tree: Tree,
    points: Vec<(Vec3, Vec3)>,
    bytes: Vec<u8>,
}

fn good() -> &'static Good {
    static GOOD: OnceLock<Good> = OnceLock::new();
    GOOD.get_or_init(|| {
        let tree = Tree::build(&pbgi::synthetic::box_with_blocks(800, 3));
        let points: Vec<(Vec3, Vec3)> = pbgi::synthetic::receivers(2, 0.05, 0.0, 5)
            .iter()
            .map(|r| (r.position(), r.normal()))
            .collect();
        let mut o = GatherOptions {
            microbuffer: 6,
            threads: Some(1),
            ..GatherOptions::default()
        };
        o.cut.max_solid_angle = 0.3;
        let gather = Gather::new(&tree, &o).expect("valid options");
        let mut cache = Cache::new(&tree, CacheOptions::default());
        cache
            .prepare(&points, &gather, Convolution::Irradiance)
            .expect("gathers");
        let bytes = cache.to_bytes(SETTINGS);
        Good { tree, points, bytes }
    })
}

fuzz_target!(|data: &[u8]| {
    let Some((&switch, rest)) = data.split_first() else {
        return;
    };
    let g = good();
    let mut bytes = if switch & 2 == 2 {
        let mut b = g.bytes.clone();
        for e in rest.chunks_exact(3) {
            let at = usize::from(u16::from_le_bytes([e[0], e[1]])) % b.len();
            b[at] ^= e[2];
        }
        b
    } else {
        rest.to_vec()
    };
    if switch & 1 == 1 && bytes.len() >= 8 {
        let end = bytes.len() - 8;
        let sum = checksum(&bytes[..end]);
        bytes[end..].copy_from_slice(&sum.to_le_bytes());
    }
    let Ok(cache) = Cache::from_bytes(&bytes, &g.tree, CacheOptions::default(), SETTINGS) else {
        return;
    };
    assert_eq!(cache.to_bytes(SETTINGS), bytes, "a loaded file re-saves as read");
    for &(p, n) in &g.points {
        if let Lookup::Light(e) = cache.lookup(p, n) {
            assert!(e.is_finite() && e.min_element() >= 0.0, "light {e} at {p}");
        }
    }
});
