//! Mitsuba XML, OBJ + MTL, PLY, OFF, glTF and GLB from arbitrary bytes:
//! errors only, no panic, no endless read, no unbounded allocation (run with
//! libFuzzer's `-rss_limit_mb` and `-malloc_limit_mb`).
//!
//! Input: byte 0 picks the main file's format: 0xF0–0xF7 glTF, 0xF8–0xFF
//! GLB, any other xml, obj, ply, off by `% 4` (as before glTF came: only the
//! corpus inputs starting with 0xF0 or above changed parser). The rest is
//! split at `\n@@\n` into the main file and up to three files it may refer
//! to, `a.ply` (`a.bin` for glTF and GLB, their external buffer), `a.obj`
//! and `m.mtl`, all written to a scratch directory (the seeds in
//! `fuzz/corpus/scene_parsers` use them).
#![no_main]

use libfuzzer_sys::fuzz_target;

const SEPARATOR: &[u8] = b"\n@@\n";
const SIDE_FILES: [&str; 3] = ["a.ply", "a.obj", "m.mtl"];
const GLTF_SIDE_FILES: [&str; 3] = ["a.bin", "a.obj", "m.mtl"];

fn split(mut data: &[u8]) -> Vec<&[u8]> {
    let mut parts = Vec::new();
    while parts.len() < SIDE_FILES.len() {
        match data.windows(SEPARATOR.len()).position(|w| w == SEPARATOR) {
            Some(i) => {
                parts.push(&data[..i]);
                data = &data[i + SEPARATOR.len()..];
            }
            None => break,
        }
    }
    parts.push(data);
    parts
}

fuzz_target!(|data: &[u8]| {
    let Some((&kind, rest)) = data.split_first() else {
        return;
    };
    let (ext, side_files) = match kind {
        0xF0..=0xF7 => ("gltf", GLTF_SIDE_FILES),
        0xF8..=0xFF => ("glb", GLTF_SIDE_FILES),
        k => (["xml", "obj", "ply", "off"][k as usize % 4], SIDE_FILES),
    };
    let dir = std::env::temp_dir().join(format!("pbgi-fuzz-{}", std::process::id()));
    let _ = std::fs::create_dir_all(&dir);
    let parts = split(rest);
    for (name, bytes) in side_files
        .iter()
        .zip(parts.iter().skip(1).chain(std::iter::repeat(&&b""[..])))
    {
        let _ = std::fs::write(dir.join(name), bytes);
    }
    let path = dir.join(format!("input.{ext}"));
    if std::fs::write(&path, parts[0]).is_ok()
        && let Ok(scene) = pbgi::scene::load(&path)
    {
        // What loads is valid.
        scene.validate().expect("a loaded scene validates");
    }
    // libFuzzer ends the process with `exit`, so nothing would remove the
    // folder after the last input: each input removes it.
    let _ = std::fs::remove_dir_all(&dir);
});
