//! The `pbgi` binary as a shell runs it.

use std::process::{Command, Stdio};

#[test]
fn a_reader_that_closes_the_pipe_ends_pbgi_without_a_panic() {
    // `pbgi scenes | head -0`: the pipe's read end is closed before pbgi
    // writes its first line.
    let mut child = Command::new(env!("CARGO_BIN_EXE_pbgi"))
        .arg("scenes")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("pbgi starts");
    drop(child.stdout.take());
    let out = child.wait_with_output().expect("pbgi ends");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("panicked"), "pbgi panicked: {stderr}");
    // Ended by SIGPIPE, as `ls | head -0` ends `ls`, or without an error.
    #[cfg(unix)]
    {
        use std::os::unix::process::ExitStatusExt;
        assert!(
            out.status.signal() == Some(13) || out.status.success(),
            "pbgi ended with {:?}: {stderr}",
            out.status
        );
    }
}

/// A folder of its own for a test's files.
fn scratch(tag: &str) -> std::path::PathBuf {
    let d = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("pbgi-cli-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A `k`×`k` grid of quads (2k² triangles) on a unit square, as OFF.
fn grid_off(k: usize) -> String {
    let mut s = format!("OFF\n{} {} 0\n", (k + 1) * (k + 1), 2 * k * k);
    for i in 0..=k {
        for j in 0..=k {
            s += &format!("{} {} 0\n", i as f32 / k as f32, j as f32 / k as f32);
        }
    }
    let v = |i: usize, j: usize| i * (k + 1) + j;
    for i in 0..k {
        for j in 0..k {
            s += &format!(
                "3 {} {} {}\n3 {} {} {}\n",
                v(i, j),
                v(i + 1, j),
                v(i + 1, j + 1),
                v(i, j),
                v(i + 1, j + 1),
                v(i, j + 1)
            );
        }
    }
    s
}

#[test]
fn bench_scale_times_each_part_of_each_case() {
    let dir = scratch("scale");
    let (small, large) = (dir.join("small.off"), dir.join("large.off"));
    std::fs::write(&small, grid_off(2)).unwrap();
    std::fs::write(&large, grid_off(60)).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_pbgi"))
        .args([
            "bench",
            "--scale",
            "--copies",
            "3",
            "--max-surfels",
            "10000",
            "--out",
        ])
        .arg(&dir)
        .arg(&small)
        .arg(&large)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout).into_owned() + &String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{text}");
    let csv = std::fs::read_to_string(dir.join("scale.csv")).unwrap();
    let rows: Vec<Vec<&str>> = csv.lines().skip(1).map(|l| l.split(',').collect()).collect();
    // The two meshes and three copies of the last at the default budget,
    // then the last at 10⁴ surfels.
    let triangles: Vec<&str> = rows.iter().map(|r| r[1]).collect();
    assert_eq!(triangles, ["8", "7200", "21600", "7200"], "{csv}");
    let budget = pbgi::render::DEFAULT_SURFEL_BUDGET.to_string();
    let budgets: Vec<&str> = rows.iter().map(|r| r[2]).collect();
    assert_eq!(budgets, [budget.as_str(), &budget, &budget, "10000"], "{csv}");
    for r in &rows {
        let (budget, surfels): (f64, f64) = (r[2].parse().unwrap(), r[3].parse().unwrap());
        assert!((surfels / budget - 1.0).abs() < 0.03, "{r:?}");
        // Each part took some time, and they add up to at most the total.
        let parts: Vec<f64> = r[4..10].iter().map(|x| x.parse().unwrap()).collect();
        let total: f64 = r[10].parse().unwrap();
        assert!(
            parts.iter().all(|&t| t >= 0.0) && parts.iter().sum::<f64>() <= total * 1.001,
            "{r:?}"
        );
        #[cfg(target_os = "linux")]
        assert!(
            r[11].parse::<u64>().unwrap() > 1 << 20,
            "a peak of at least 1 MB: {r:?}"
        );
    }
    assert!(std::fs::metadata(dir.join("scale.png")).unwrap().len() > 1000);
    // Each stage's peak, one column a stage; no growth fitted, since no
    // budget reaches pbgi::report::GROWTH_FROM.
    let md = std::fs::read_to_string(dir.join("scale.md")).unwrap();
    #[cfg(target_os = "linux")]
    for stage in ["ray-tracing BVH", "surfels + direct light", "tree", "frame"] {
        assert!(
            md.lines()
                .any(|l| l.starts_with("| scene | surfels |") && l.contains(stage)),
            "{stage}'s peak: {md}"
        );
    }
    assert!(!md.contains("grows as surfels^k"), "{md}");
}

#[test]
fn render_seed_chooses_the_noise_and_only_it() {
    let dir = scratch("seed");
    let digest = |seed: &str| {
        let out = Command::new(env!("CARGO_BIN_EXE_pbgi"))
            .args(["render", "--spp", "1", "--seed", seed, "-o"])
            .arg(dir.join(format!("box-{seed}.exr")))
            .output()
            .unwrap();
        let text = String::from_utf8_lossy(&out.stdout).into_owned();
        assert!(
            out.status.success(),
            "{text}{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let line = text
            .lines()
            .find(|l| l.contains("image digest"))
            .unwrap_or_else(|| panic!("{text}"));
        line.rsplit(' ').next().unwrap().to_string()
    };
    let (a, b, c) = (digest("7"), digest("7"), digest("8"));
    assert_eq!(a, b, "the same seed, the same image");
    assert_ne!(a, c, "another seed, other noise");
}

#[test]
fn resolution_sizes_the_image_and_compare_follows() {
    let dir = scratch("resolution");
    let run = |args: &[&str]| {
        let out = Command::new(env!("CARGO_BIN_EXE_pbgi"))
            .args(args)
            .output()
            .unwrap();
        let text = String::from_utf8_lossy(&out.stdout).into_owned() + &String::from_utf8_lossy(&out.stderr);
        (out.status.success(), text)
    };
    let (image, reference) = (dir.join("box.exr"), dir.join("ref.exr"));
    let (ok, text) = run(&[
        "render",
        "--spp",
        "1",
        "--resolution",
        "40x24",
        "-o",
        image.to_str().unwrap(),
    ]);
    assert!(ok && text.contains("40×24"), "{text}");
    let size = |p: &std::path::Path| {
        let img =
            exr::prelude::read_first_rgba_layer_from_file(p, |_, _| (), |_, _, _: (f32, f32, f32, f32)| ())
                .unwrap();
        (img.layer_data.size.width(), img.layer_data.size.height())
    };
    assert_eq!(size(&image), (40, 24));
    let (ok, text) = run(&[
        "reference",
        "--spp",
        "4",
        "--resolution",
        "40x24",
        "-o",
        reference.to_str().unwrap(),
    ]);
    assert!(ok, "{text}");
    assert_eq!(size(&reference), (40, 24));
    let (i, r) = (image.to_str().unwrap(), reference.to_str().unwrap());
    let (ok, text) = run(&["compare", i, r]);
    assert!(
        !ok && text.contains("--resolution"),
        "the scene's own size refused: {text}"
    );
    let (ok, text) = run(&["compare", "--resolution", "40x24", i, r]);
    assert!(ok && text.contains("relative RMSE"), "{text}");
    for bad in ["0x10", "40", "40xten", "99999x10"] {
        let (ok, text) = run(&["render", "--resolution", bad]);
        assert!(!ok && text.contains("--resolution"), "{bad}: {text}");
    }
}

/// A Mitsuba file's `sample_count` and `max_depth` are used where the
/// command line gives no `--spp` or `--bounces`, and the summary says which won.
#[test]
fn the_files_spp_and_max_depth_are_used_unless_the_command_line_says() {
    let dir = scratch("settings");
    let xml =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/textured-box/textured-box.xml");
    let run = |args: &[&str]| {
        let out = Command::new(env!("CARGO_BIN_EXE_pbgi"))
            .args(args)
            .arg(&xml)
            .args(["--resolution", "16x16", "-o"])
            .arg(dir.join("out.exr"))
            .output()
            .unwrap();
        let text = String::from_utf8_lossy(&out.stdout).into_owned() + &String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "{text}");
        text
    };
    // The file: `$spp` 64, `$max_depth` 3 (one bounce).
    let text = run(&["render"]);
    assert!(
        text.contains(", 64 spp,") && text.contains(", 1 bounce(s)"),
        "{text}"
    );
    assert!(
        text.contains(
            "settings: 64 spp from the file's sample_count; 1 bounce(s) from the file's max_depth 3"
        ),
        "{text}"
    );
    assert!(
        !text.contains("sample_count=") && !text.contains("max_depth="),
        "no longer named ignored: {text}"
    );
    let text = run(&["render", "--spp", "2", "--bounces", "0"]);
    assert!(
        text.contains(", 2 spp,") && text.contains(", 0 bounce(s)"),
        "{text}"
    );
    assert!(
        text.contains("--spp 2 over the file's sample_count 64; --bounces 0 over the file's max_depth 3"),
        "{text}"
    );
    let text = run(&["reference", "--spp", "2"]);
    assert!(
        text.contains("2 spp, 1 bounce(s)") && text.contains("1 bounce(s) from the file's max_depth 3"),
        "{text}"
    );
}

/// `--camera-origin`, `--camera-target` and `--fov` move the camera; a
/// camera looking at its own origin is refused, named.
#[test]
fn the_camera_options_move_the_camera() {
    let dir = scratch("camera");
    let run = |args: &[&str]| {
        let out = Command::new(env!("CARGO_BIN_EXE_pbgi"))
            .args(["render", "--spp", "1", "--resolution", "24x24"])
            .args(args)
            .arg("-o")
            .arg(dir.join("out.png"))
            .output()
            .unwrap();
        let text = String::from_utf8_lossy(&out.stdout).into_owned() + &String::from_utf8_lossy(&out.stderr);
        (out.status.success(), text)
    };
    let digest = |text: &str| {
        text.lines()
            .find(|l| l.contains("image digest"))
            .map(str::to_string)
    };
    let (ok, plain) = run(&[]);
    assert!(ok, "{plain}");
    for moved in [
        &["--camera-origin", "0.3,0.2,3.9"][..],
        &["--camera-target", "0.2,0,0"],
        &["--fov", "60"],
    ] {
        let (ok, text) = run(moved);
        assert!(ok && digest(&text) != digest(&plain), "{moved:?}: {text}");
    }
    let (ok, text) = run(&["--camera-origin", "0,0,0", "--camera-target", "0,0,0"]);
    assert!(!ok && text.contains("camera"), "{text}");
    let (ok, text) = run(&["--camera-origin", "1,2"]);
    assert!(!ok && text.contains("X,Y,Z"), "{text}");
}

/// One exit status per class of error (`pbgi --help`): 2 for the command
/// line (clap's own errors, and options the render refuses, both kinds of
/// bad crop alike), 3 for an input, 4 for an output.
#[test]
fn each_class_of_error_has_its_exit_status() {
    let dir = scratch("exit");
    // A folder is made where missing, but not under a file.
    std::fs::write(dir.join("a-file"), b"").unwrap();
    let missing_dir = dir.join("a-file").join("out.png");
    let cases: [(&[&str], i32); 8] = [
        (&["render", "--no-such-option"], 2),
        (&["render", "--spp", "0", "--resolution", "8x8"], 2),
        (&["render", "--crop", "0,0,4", "--resolution", "8x8"], 2),
        (&["render", "--crop", "0,0,64,64", "--resolution", "8x8"], 2),
        (&["render", "--resolution", "8x8", "-o", "image.txt"], 2),
        (&["render", "no-such-scene.obj"], 3),
        (&["compare", "no-such-image.exr", "no-such-reference.exr"], 3),
        (
            &[
                "render",
                "--resolution",
                "8x8",
                "--spp",
                "1",
                "-o",
                missing_dir.to_str().unwrap(),
            ],
            4,
        ),
    ];
    for (args, want) in cases {
        let out = Command::new(env!("CARGO_BIN_EXE_pbgi"))
            .args(args)
            .current_dir(&dir)
            .output()
            .expect("pbgi runs");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(want), "pbgi {}: {stderr}", args.join(" "));
        assert!(!stderr.contains("panicked"), "pbgi {}: {stderr}", args.join(" "));
    }
}

/// `--denoise` denoises in a build with the `denoise` feature; in one
/// without, `render` and `report` refuse it as a usage error that names
/// the feature, before any work.
#[test]
fn denoise_denoises_or_names_the_feature_it_needs() {
    let dir = scratch("denoise");
    let run = |args: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_pbgi"))
            .args(args)
            .current_dir(&dir)
            .output()
            .expect("pbgi runs")
    };
    let render = [
        "render",
        "--resolution",
        "32x32",
        "--spp",
        "1",
        "-o",
        "d.png",
        "--denoise",
    ];
    let out = run(&render);
    let (stdout, stderr) = (
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr),
    );
    if cfg!(feature = "denoise") {
        assert!(out.status.success(), "{stderr}");
        assert!(stdout.contains("denoised by Intel OIDN"), "{stdout}");
        assert!(dir.join("d.png").exists());
        return;
    }
    let report = [
        "report",
        "--denoise",
        "--out",
        "r",
        "--spp",
        "1",
        "--path-tracer-spp",
        "1",
    ];
    for (args, out) in [(&render[..], out), (&report[..], run(&report))] {
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "pbgi {}: {stderr}", args.join(" "));
        assert!(
            stderr.contains("denoise feature"),
            "pbgi {}: {stderr}",
            args.join(" ")
        );
    }
    assert!(
        !dir.join("d.png").exists() && !dir.join("r").exists(),
        "no work before the error"
    );
}

#[test]
fn render_cache_serves_a_later_run_and_frozen_leaves_the_file_as_it_was() {
    let dir = scratch("cache");
    let file = dir.join("box.cache");
    let render = |gathers: &str, extra: &[&str]| {
        let out = Command::new(env!("CARGO_BIN_EXE_pbgi"))
            .args([
                "render",
                "--spp",
                "1",
                "--resolution",
                "64x64",
                "--surfels",
                "4000",
            ])
            .args(["--gathers", gathers, "-o"])
            .arg(dir.join("box.exr"))
            .args(extra)
            .output()
            .unwrap();
        let text = String::from_utf8_lossy(&out.stdout).into_owned() + &String::from_utf8_lossy(&out.stderr);
        (out.status.code(), text)
    };
    let run = |extra: &[&str]| render("cache", extra);
    let digest = |text: &str| {
        let line = text.lines().find(|l| l.contains("image digest"));
        line.unwrap_or_else(|| panic!("{text}"))
            .rsplit(' ')
            .next()
            .unwrap()
            .to_string()
    };
    let path = file.to_str().unwrap();
    // The file holds the records of the frame's left half.
    let half = ["--crop", "0,0,32,64"];
    let (code, made) = run(&[&["--cache", path][..], &half].concat());
    assert_eq!(code, Some(0), "{made}");
    assert!(made.contains("cache: wrote"), "{made}");
    let bytes = std::fs::read(&file).unwrap();
    let (code, again) = run(&[&["--cache", path, "--frozen-cache"][..], &half].concat());
    assert_eq!(code, Some(0), "{again}");
    assert!(again.contains("records read from"), "{again}");
    assert!(
        again.contains("cache: 0 records gathered that the frozen"),
        "{again}"
    );
    assert_eq!(
        digest(&again),
        digest(&made),
        "the cache's records give the same bits"
    );
    // The whole frame needs records the file lacks: gathered, and not
    // written. (A wider view of the box needs none: the records of the
    // whole frame serve it.)
    let (code, wider) = run(&["--cache", path, "--frozen-cache"]);
    assert_eq!(code, Some(0), "{wider}");
    assert!(!wider.contains("cache: 0 records gathered"), "{wider}");
    assert_eq!(
        std::fs::read(&file).unwrap(),
        bytes,
        "a frozen cache is not written"
    );

    // Another Ω: the file's records are refused by name, and no image made.
    let (code, other) = run(&["--cache", path, "--max-solid-angle", "0.05"]);
    assert_eq!(code, Some(3), "{other}");
    assert!(
        other.contains("box.cache") && other.contains("settings"),
        "{other}"
    );
    let missing = dir.join("missing.cache");
    let (code, text) = run(&["--cache", missing.to_str().unwrap(), "--frozen-cache"]);
    assert_eq!(code, Some(3), "a frozen cache must exist: {text}");
    let (code, text) = render("sparse", &["--cache", path]);
    assert_eq!(code, Some(2), "{text}");
    assert!(text.contains("serves a render with --gathers cache"), "{text}");

    // `cache:T` is `cache --gather-threshold T`; a threshold must be above 0.
    let (_, a) = render("cache:0.2", &[]);
    let (_, b) = run(&["--gather-threshold", "0.2"]);
    assert_eq!(digest(&a), digest(&b));
    // `wider` is the whole frame at the default threshold.
    assert_ne!(digest(&a), digest(&wider), "another threshold, another image");
    let (code, text) = render("cache:0", &[]);
    assert_eq!(code, Some(2), "{text}");
}
