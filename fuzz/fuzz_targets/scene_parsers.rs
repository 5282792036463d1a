//! Mitsuba XML, OBJ and PLY from arbitrary bytes: errors only, no panic.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if data.is_empty() {
        return;
    }
    let ext = ["xml", "obj", "ply"][data[0] as usize % 3];
    let dir = std::env::temp_dir().join(format!("pbgi-fuzz-{}", std::process::id()));
    let _ = std::fs::create_dir_all(&dir);
    let path = dir.join(format!("input.{ext}"));
    if std::fs::write(&path, &data[1..]).is_ok() {
        let _ = pbgi::scene::load::load(&path);
    }
});
