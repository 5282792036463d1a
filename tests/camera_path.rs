//! `pbgi render --camera-path`: the frames of a shot from one bake, each the
//! image a single render from its camera gives, bit for bit, on any number
//! of threads and any path.

use std::path::{Path, PathBuf};

use crate::common;

fn scratch(tag: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("pbgi-path-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Runs `pbgi` with `args` (and `env`); success, stdout, stderr.
fn run(args: &[&str], env: &[(&str, &str)]) -> (bool, String, String) {
    let mut c = common::pbgi_command();
    c.args(args);
    for (k, v) in env {
        c.env(k, v);
    }
    let o = c.output().unwrap();
    (
        o.status.success(),
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

/// The digests of the frames the output names, in frame order.
fn frame_digests(stdout: &str) -> Vec<String> {
    stdout
        .lines()
        .filter(|l| l.starts_with("frame ") && l.contains("image digest"))
        .map(|l| l.trim_end_matches(')').rsplit(' ').next().unwrap().to_string())
        .collect()
}

// The built-in Cornell box's camera: origin (0, 0, 3.9), target (0, 0, 2.9).
const PATH: &str = r#"{"frames": [
    {"origin": [0, 0, 3.9], "target": [0, 0, 2.9], "up": [0, 1, 0]},
    {"origin": [0, 0, 3.9], "target": [0, 0, 2.9]},
    {"origin": [0.2, 0.1, 3.4], "target": [0.1, 0, 2.4], "fov": 35}
]}"#;

#[test]
fn a_path_renders_each_frame_from_one_bake_as_a_single_render_would() {
    let dir = scratch("frames");
    let path = dir.join("path.json");
    std::fs::write(&path, PATH).unwrap();
    let frames = dir.join("f-{}.exr");
    let common_args = ["render", "--spp", "1", "--resolution", "24x24"];
    let render_path = |out: &Path, extra: &[&str], env: &[(&str, &str)]| {
        let mut args: Vec<&str> = common_args.to_vec();
        let (p, o) = (path.to_str().unwrap(), out.to_str().unwrap());
        args.extend(["--camera-path", p, "-o", o]);
        args.extend(extra);
        let (ok, stdout, stderr) = run(&args, env);
        assert!(ok, "{stdout}{stderr}");
        (stdout, stderr)
    };
    let (stdout, stderr) = render_path(&frames, &["--threads", "2"], &[]);
    // Off a terminal each stage of the bake prints one line when done: the
    // surfels and their light were made once for the three frames.
    let surfel_stages = stderr
        .lines()
        .filter(|l| l.contains("surfels") && l.contains("done in"))
        .count();
    assert_eq!(surfel_stages, 1, "{stderr}");
    assert!(
        stdout.contains("camera path: 3 frame(s) from one bake"),
        "{stdout}"
    );
    assert!(stdout.contains("frames after the first"), "{stdout}");
    let digests = frame_digests(&stdout);
    assert_eq!(digests.len(), 3, "{stdout}");
    for k in 0..3 {
        assert!(dir.join(format!("f-{k:04}.exr")).is_file(), "frame {k} written");
    }
    assert_eq!(digests[0], digests[1], "two frames of one camera: one image");
    assert_ne!(digests[0], digests[2], "the camera moved");

    // Frame 2 is the image a render from its camera gives alone.
    let single = dir.join("single.exr");
    let (ok, stdout_single, stderr_single) = run(
        &[
            &common_args[..],
            &[
                "--camera-origin",
                "0.2,0.1,3.4",
                "--camera-target",
                "0.1,0,2.4",
                "--fov",
                "35",
                "-o",
                single.to_str().unwrap(),
            ],
        ]
        .concat(),
        &[],
    );
    assert!(ok, "{stdout_single}{stderr_single}");
    assert!(
        stdout_single.contains(&format!("image digest {})", digests[2])),
        "{stdout_single}\n{stdout}"
    );

    // One thread, and the portable path: the same bits.
    let (one, _) = render_path(&dir.join("t-{}.exr"), &["--threads", "1"], &[]);
    assert_eq!(frame_digests(&one), digests, "one thread");
    let (portable, _) = render_path(&dir.join("p-{}.exr"), &[], &[("PBGI_ISA", "portable")]);
    assert_eq!(frame_digests(&portable), digests, "portable path");
}

#[test]
fn bad_paths_and_patterns_are_errors_naming_them() {
    let dir = scratch("bad");
    let case = |json: &str, out: &str| {
        let path = dir.join("path.json");
        std::fs::write(&path, json).unwrap();
        let out = dir.join(out);
        let (ok, stdout, stderr) = run(
            &[
                "render",
                "--spp",
                "1",
                "--resolution",
                "8x8",
                "--camera-path",
                path.to_str().unwrap(),
                "-o",
                out.to_str().unwrap(),
            ],
            &[],
        );
        assert!(!ok, "{stdout}{stderr}");
        stderr
    };
    let e = case(PATH, "no-pattern.exr");
    assert!(e.contains("put {} where the frame number goes"), "{e}");
    let e = case("{\"frames\": [\n{\"origin\": [0, 0, 3.9],\n}]}", "f-{}.exr");
    assert!(e.contains("path.json:3"), "a syntax error names its line: {e}");
    let e = case(
        r#"{"frames": [{"origin": [0, 0, 3.9], "target": [0, 0, 2.9]}, {"origin": [0, 0, 1]}]}"#,
        "f-{}.exr",
    );
    assert!(e.contains("frame 1 has no \"target\""), "{e}");
    let e = case(
        r#"{"frames": [{"origin": [0, 0, 1], "target": [0, 0, 1]}]}"#,
        "f-{}.exr",
    );
    assert!(e.contains("frame 0") && e.contains("its own origin"), "{e}");
    let e = case(r#"{"frames": []}"#, "f-{}.exr");
    assert!(e.contains("no frames"), "{e}");
    let e = case(
        r#"{"frames": [{"origin": [0, 0, "x"], "target": [0, 0, 2.9]}]}"#,
        "f-{}.exr",
    );
    assert!(e.contains("frame 0: \"origin\""), "{e}");
}
