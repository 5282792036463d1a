//! Tiles for a render farm, through the command line: `pbgi bake` once,
//! four `pbgi render --tree … --crop …` processes, the tiles stitched; the
//! frame is the one `pbgi render` gives without the tree, bit for bit. The
//! tiles' edges are not on the 4×4 packet grid, so packets are split.

use crate::common;
use std::path::{Path, PathBuf};

/// The measured Cornell box at 30 × 22 pixels (its meshes from tests/data).
fn small_scene(dir: &Path) -> PathBuf {
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/cornell-box");
    let xml = std::fs::read_to_string(data.join("cbox.xml")).unwrap();
    let meshes = format!("{}/", data.join("meshes").display());
    let xml = xml
        .replace("name=\"resx\" value=\"256\"", "name=\"resx\" value=\"30\"")
        .replace("name=\"resy\" value=\"256\"", "name=\"resy\" value=\"22\"")
        .replace("value=\"meshes/", &format!("value=\"{meshes}"));
    assert!(xml.contains("value=\"30\"") && xml.contains("value=\"22\""));
    let path = dir.join("small.xml");
    std::fs::write(&path, xml).unwrap();
    path
}

/// Runs `pbgi ARGS`, which must succeed; its stdout.
fn pbgi(args: &[&str]) -> String {
    let out = common::pbgi_command().args(args).output().unwrap();
    assert!(
        out.status.success(),
        "pbgi {args:?} failed:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

/// Runs `pbgi ARGS`, which must fail with `want` in its error.
fn fails(args: &[&str], want: &str) {
    let out = common::pbgi_command().args(args).output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains(want),
        "pbgi {args:?}: {err}"
    );
}

/// Width, height and the RGB bits of an EXR the CLI wrote (linear radiance).
fn read_exr(path: &Path) -> (usize, usize, Vec<[u32; 3]>) {
    use exr::prelude::*;
    let img = read_first_rgba_layer_from_file(
        path,
        |res, _| (res.width(), vec![[0u32; 3]; res.width() * res.height()]),
        |(w, px): &mut (usize, Vec<[u32; 3]>), pos, (r, g, b, _a): (f32, f32, f32, f32)| {
            px[pos.y() * *w + pos.x()] = [r.to_bits(), g.to_bits(), b.to_bits()];
        },
    )
    .unwrap();
    let size = img.layer_data.size;
    (size.width(), size.height(), img.layer_data.channel_data.pixels.1)
}

#[test]
fn four_tiles_in_four_processes_stitch_into_the_frame() {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("tiles");
    std::fs::create_dir_all(&dir).unwrap();
    let scene = small_scene(&dir);
    let scene = scene.to_str().unwrap();
    let tree = dir.join("small.pbgi");
    let tree = tree.to_str().unwrap();
    let settings = ["--density", "300", "--bounces", "2", "--microbuffer", "12"];
    let baked = pbgi(&[&["bake", scene, "-o", tree][..], &settings[..]].concat());
    assert!(baked.contains("wrote"), "{baked}");

    let full = dir.join("full.exr");
    let full_s = full.to_str().unwrap();
    pbgi(&[&["render", scene, "--spp", "2", "-o", full_s][..], &settings[..]].concat());
    let (w, h, frame) = read_exr(&full);
    assert_eq!((w, h), (30, 22));

    // Split at x = 13, y = 9: neither on the packet grid.
    let tiles = [(0, 0, 13, 9), (13, 0, 30, 9), (0, 9, 13, 22), (13, 9, 30, 22)];
    let mut stitched = vec![None; w * h];
    for (i, &(x0, y0, x1, y1)) in tiles.iter().enumerate() {
        let out = dir.join(format!("tile{i}.exr"));
        let crop = format!("{x0},{y0},{x1},{y1}");
        let args = [
            "render",
            scene,
            "--spp",
            "2",
            "--tree",
            tree,
            "--crop",
            &crop,
            "-o",
            out.to_str().unwrap(),
        ];
        let printed = pbgi(&[&args[..], &settings[..]].concat());
        assert!(printed.contains("surfels + tree loaded from"), "{printed}");
        let (tw, th, px) = read_exr(&out);
        assert_eq!((tw, th), (x1 - x0, y1 - y0), "tile {crop}");
        for y in y0..y1 {
            for x in x0..x1 {
                assert!(stitched[y * w + x].is_none(), "tiles overlap at ({x}, {y})");
                stitched[y * w + x] = Some(px[(y - y0) * tw + x - x0]);
            }
        }
    }
    for (i, (s, f)) in stitched.iter().zip(&frame).enumerate() {
        assert_eq!(s.as_ref(), Some(f), "pixel ({}, {}) differs", i % w, i / w);
    }
}

#[test]
fn bad_crops_and_trees_are_errors_naming_them() {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("tiles-bad");
    std::fs::create_dir_all(&dir).unwrap();
    let scene = small_scene(&dir);
    let scene = scene.to_str().unwrap();
    let o = dir.join("x.exr");
    let o = o.to_str().unwrap();
    fails(&["render", scene, "-o", o, "--crop", "4,4,4,8"], "empty window");
    fails(
        &["render", scene, "-o", o, "--crop", "0,0,31,8"],
        "outside the 30×22 frame",
    );
    fails(
        &["render", scene, "-o", o, "--crop", "0,0,8"],
        "expected x0,y0,x1,y1",
    );
    let tree = dir.join("t.pbgi");
    let tree = tree.to_str().unwrap();
    pbgi(&["bake", scene, "-o", tree, "--density", "50"]);
    fails(
        &["render", scene, "-o", o, "--tree", tree, "--density", "60"],
        "baked with --density 50, this render has 60",
    );
    fails(
        &["render", scene, "-o", o, "--tree", "/dev/zero"],
        "/dev/zero: not a regular file",
    );
    std::fs::write(dir.join("junk.pbgi"), b"not a tree").unwrap();
    let junk = dir.join("junk.pbgi");
    fails(
        &["render", scene, "-o", o, "--tree", junk.to_str().unwrap()],
        "junk.pbgi: not a pbgi tree file",
    );
}

/// A farm's shot: one bake, then each frame's tiles of a 3 × 2 grid as
/// separate `pbgi render --frames K --tiles 3,2 --tile T` processes, joined
/// by `pbgi stitch`: every frame's file is byte for byte the file of one
/// `pbgi render --camera-path` of the whole shot.
#[test]
fn a_shots_tiles_from_one_bake_stitch_into_the_frames_of_one_render() {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("tiles-shot");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let scene = small_scene(&dir);
    let scene = scene.to_str().unwrap();
    let path = dir.join("shot.json");
    std::fs::write(
        &path,
        r#"{"frames": [{"origin": [0, 0, 3.9], "target": [0, 0, 2.9]},
                       {"origin": [0.05, 0.02, 3.6], "target": [0.02, 0, 2.9]}]}"#,
    )
    .unwrap();
    let path = path.to_str().unwrap();
    let tree = dir.join("shot.pbgi");
    let tree = tree.to_str().unwrap();
    let settings = ["--density", "300", "--spp", "2"];
    pbgi(&[&["bake", scene, "-o", tree, "--density", "300"][..]].concat());
    let single = dir.join("single/frame-{}.exr");
    let args = [
        "render",
        scene,
        "--camera-path",
        path,
        "-o",
        single.to_str().unwrap(),
    ];
    pbgi(&[&args[..], &settings[..]].concat());
    let tiles = dir.join("tiles/frame-{}-tile-{tile}.exr");
    for frame in ["0", "1"] {
        for tile in 0..6 {
            let out = tiles.to_str().unwrap().replace("{tile}", &tile.to_string());
            let tile = tile.to_string();
            let args = [
                "render",
                scene,
                "--tree",
                tree,
                "--camera-path",
                path,
                "--frames",
                frame,
                "--tiles",
                "3,2",
                "--tile",
                &tile,
                "-o",
                &out,
            ];
            pbgi(&[&args[..], &settings[..]].concat());
        }
    }
    let frames = dir.join("frames/frame-{}.exr");
    let args = [
        "stitch",
        tiles.to_str().unwrap(),
        "--tiles",
        "3,2",
        "--frames",
        "0-1",
        "-o",
    ];
    let printed = pbgi(&[&args[..], &[frames.to_str().unwrap()]].concat());
    assert_eq!(printed.matches("(30×22, 6 tiles").count(), 2, "{printed}");
    for k in ["0000", "0001"] {
        let name = |p: &PathBuf| PathBuf::from(p.to_str().unwrap().replace("{}", k));
        let (a, b) = (
            std::fs::read(name(&frames)).unwrap(),
            std::fs::read(name(&single)).unwrap(),
        );
        assert!(a == b, "frame {k}: the stitched file differs from one render's");
    }
    // The last tile of frame 1 is the bottom right one: 10 × 11 pixels.
    let last = tiles
        .to_str()
        .unwrap()
        .replace("{}", "0001")
        .replace("{tile}", "5");
    assert_eq!(read_exr(Path::new(&last)).0, 10);

    // A frame past the path, a tile past the grid, and a missing tile are
    // errors naming them.
    let o = dir.join("x-{}.exr");
    let o = o.to_str().unwrap();
    fails(
        &["render", scene, "--camera-path", path, "--frames", "2", "-o", o],
        "--frames 2: the camera path has frames 0 to 1",
    );
    fails(
        &["render", scene, "--tiles", "3,2", "--tile", "6", "-o", "x.exr"],
        "tile 6: a 3,2 grid has tiles 0 to 5",
    );
    let missing = dir.join("none-{tile}.exr");
    fails(
        &[
            "stitch",
            missing.to_str().unwrap(),
            "--tiles",
            "2,1",
            "-o",
            "x.exr",
        ],
        "none-0.exr",
    );
}
