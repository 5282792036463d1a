//! Mitsuba XML, OBJ + MTL, PLY and OFF from arbitrary bytes: errors only, no
//! panic, no endless read, no unbounded allocation (run with libFuzzer's
//! `-rss_limit_mb` and `-malloc_limit_mb`).
//!
//! Input: byte 0 picks the main file's format (xml, obj, ply, off by `% 4`); the
//! rest is split at `\n@@\n` into the main file and up to three files it may
//! refer to, `a.ply`, `a.obj` and `m.mtl`, all written to a scratch
//! directory (the seeds in `fuzz/corpus/scene_parsers` use them).
#![no_main]

use libfuzzer_sys::fuzz_target;

const SEPARATOR: &[u8] = b"\n@@\n";
const SIDE_FILES: [&str; 3] = ["a.ply", "a.obj", "m.mtl"];

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
    let ext = ["xml", "obj", "ply", "off"][kind as usize % 4];
    let dir = std::env::temp_dir().join(format!("pbgi-fuzz-{}", std::process::id()));
    let _ = std::fs::create_dir_all(&dir);
    let parts = split(rest);
    for (name, bytes) in SIDE_FILES
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
});
