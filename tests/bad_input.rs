//! A corpus of malformed input through every public constructor and loader,
//! each run under `catch_unwind`: nothing panics, and each gets a typed error
//! whose message names the place (the surfel or receiver index, the
//! parameter, the file and line, the mesh and item). `inputs.rs` checks the
//! kernel types' errors in depth (random defects at random indices);
//! `scene_loaders.rs` a few loader errors and mutated Cornell boxes; this
//! file is the broad corpus, scene files written to a temporary directory.

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};

use glam::Vec3;
use pbgi::microbuffer::MicroBuffer;
use pbgi::points::{MAX_COORDINATE, MAX_RADIANCE};
use pbgi::render::{BakeOptions, ReferenceOptions, RenderOptions, bake, render, render_reference};
use pbgi::scene::builtin::cornell_box;
use pbgi::scene::load;
use pbgi::scene::{Glossy, Light, Scene};
use pbgi::{CutOptions, Isa, PointCloud, Receiver, Scheme, Surfel, Traversal, Tree};

/// What a corpus entry must give.
enum Want {
    /// An error whose message contains each of these.
    Error(Vec<String>),
    /// Either way, without a panic (malformed input that is legitimately accepted).
    NoPanic,
}

/// Runs `f` under `catch_unwind`; the error's message (Display) must contain
/// every string of `want`. Returns a failure description, if any.
fn check(name: &str, want: &Want, f: impl FnOnce() -> Result<(), String>) -> Option<String> {
    match (catch_unwind(AssertUnwindSafe(f)), want) {
        (Err(_), _) => Some(format!("{name}: panicked")),
        (Ok(Ok(())), Want::Error(w)) => Some(format!("{name}: accepted, expected an error naming {w:?}")),
        (Ok(Err(msg)), Want::Error(w)) => {
            let missing: Vec<_> = w.iter().filter(|s| !msg.contains(s.as_str())).collect();
            (!missing.is_empty()).then(|| format!("{name}: error {msg:?} does not name {missing:?}"))
        }
        (Ok(_), Want::NoPanic) => None,
    }
}

fn err<T, E: std::fmt::Display>(r: Result<T, E>) -> Result<(), String> {
    r.map(|_| ()).map_err(|e| e.to_string())
}

fn want(parts: &[&str]) -> Want {
    Want::Error(parts.iter().map(|s| s.to_string()).collect())
}

fn report(failures: Vec<String>, count: usize) {
    assert!(
        failures.is_empty(),
        "{} of {count} failed:\n{}",
        failures.len(),
        failures.join("\n")
    );
    eprintln!("{count} malformed inputs: typed errors naming the place, no panic");
}

/// A named edit that breaks a value, and what the error must say.
type Defect<T, W> = (&'static str, Box<dyn Fn(&mut T)>, W);

fn ok_surfel(i: usize) -> Surfel {
    Surfel {
        position: Vec3::new(i as f32 * 0.1, 0.0, 0.0),
        normal: Vec3::Z,
        radius: 0.05,
        radiance: Vec3::ONE,
    }
}

/// Every field of a surfel out of range, at several indices of a cloud of 100.
#[test]
fn surfels_receivers_and_options() {
    let defects: Vec<Defect<Surfel, &str>> = vec![
        (
            "NaN position",
            Box::new(|s| s.position.y = f32::NAN),
            "position is not finite",
        ),
        (
            "infinite position",
            Box::new(|s| s.position.z = f32::NEG_INFINITY),
            "position is not finite",
        ),
        (
            "position beyond MAX_COORDINATE",
            Box::new(|s| s.position.x = 2e37),
            "position 2e37 exceeds 1e37",
        ),
        (
            "NaN normal",
            Box::new(|s| s.normal.x = f32::NAN),
            "normal is not finite",
        ),
        (
            "zero normal",
            Box::new(|s| s.normal = Vec3::ZERO),
            "normal has zero length",
        ),
        (
            "long normal",
            Box::new(|s| s.normal = Vec3::new(1.0, 1.0, 0.0)),
            "normal has length 1.414",
        ),
        (
            "NaN radius",
            Box::new(|s| s.radius = f32::NAN),
            "radius is not finite",
        ),
        (
            "infinite radius",
            Box::new(|s| s.radius = f32::INFINITY),
            "radius is not finite",
        ),
        (
            "zero radius",
            Box::new(|s| s.radius = 0.0),
            "radius 0 is not positive",
        ),
        (
            "negative zero radius",
            Box::new(|s| s.radius = -0.0),
            "radius -0 is not positive",
        ),
        (
            "negative radius",
            Box::new(|s| s.radius = -3.0),
            "radius -3 is not positive",
        ),
        (
            "radius beyond MAX_COORDINATE",
            Box::new(|s| s.radius = 1e38),
            "radius 1e38 exceeds 1e37",
        ),
        (
            "NaN radiance",
            Box::new(|s| s.radiance.z = f32::NAN),
            "radiance is not finite",
        ),
        (
            "infinite radiance",
            Box::new(|s| s.radiance.x = f32::INFINITY),
            "radiance is not finite",
        ),
        (
            "negative radiance",
            Box::new(|s| s.radiance.y = -1e-30),
            "radiance has a negative component",
        ),
        (
            "radiance beyond MAX_RADIANCE",
            Box::new(|s| s.radiance.y = 2e30),
            "radiance 2e30 exceeds 1e30",
        ),
        (
            "radiance f32::MAX",
            Box::new(|s| s.radiance = Vec3::splat(f32::MAX)),
            "exceeds 1e30",
        ),
    ];
    let mut failures = Vec::new();
    let mut count = 0;
    for (name, defect, reason) in &defects {
        for index in [0, 7, 99] {
            let mut surfels: Vec<Surfel> = (0..100).map(ok_surfel).collect();
            defect(&mut surfels[index]);
            count += 1;
            failures.extend(check(
                &format!("surfel {index}: {name}"),
                &want(&[&format!("surfel {index}: "), reason]),
                || err(PointCloud::new(surfels)),
            ));
        }
    }
    // The limits themselves are accepted.
    let edge = Surfel {
        position: Vec3::splat(-MAX_COORDINATE),
        radius: MAX_COORDINATE,
        radiance: Vec3::splat(MAX_RADIANCE),
        ..ok_surfel(0)
    };
    assert!(PointCloud::new(vec![edge]).is_ok());

    let receivers: [(&str, Vec3, Vec3, &str); 5] = [
        (
            "NaN position",
            Vec3::new(0.0, f32::NAN, 0.0),
            Vec3::Z,
            "position is not finite",
        ),
        (
            "infinite position",
            Vec3::splat(f32::INFINITY),
            Vec3::Z,
            "position is not finite",
        ),
        (
            "NaN normal",
            Vec3::ZERO,
            Vec3::new(f32::NAN, 0.0, 1.0),
            "normal is not finite",
        ),
        ("zero normal", Vec3::ZERO, Vec3::ZERO, "normal has zero length"),
        (
            "short normal",
            Vec3::ZERO,
            Vec3::new(0.0, 0.0, 0.9),
            "normal has length 0.9",
        ),
    ];
    for (name, p, n, reason) in receivers {
        for index in [0, 3, 40] {
            let mut pairs: Vec<(Vec3, Vec3)> = (0..41).map(|i| (Vec3::splat(i as f32), Vec3::Y)).collect();
            pairs[index] = (p, n);
            count += 1;
            failures.extend(check(
                &format!("receiver {index}: {name}"),
                &want(&[&format!("receiver {index}: "), reason]),
                || err(Receiver::from_pairs(pairs)),
            ));
        }
        count += 1;
        failures.extend(check(
            &format!("Receiver::new: {name}"),
            &want(&["receiver 0: ", reason]),
            || err(Receiver::new(p, n)),
        ));
    }

    let tree = Tree::build(&PointCloud::new((0..10).map(ok_surfel).collect()).unwrap());
    let options = |max_solid_angle, light_offset, hybrid_threshold| CutOptions {
        max_solid_angle,
        light_offset,
        hybrid_threshold,
        isa: None,
    };
    for (omega, k, threshold, place) in [
        (f32::NAN, 0.0, 2, "max_solid_angle"),
        (-1.0, 0.0, 2, "max_solid_angle"),
        (f32::INFINITY, 0.0, 2, "max_solid_angle"),
        (0.05, f32::NAN, 2, "light_offset"),
        (0.05, -1.0, 2, "light_offset"),
        (0.05, f32::INFINITY, 2, "light_offset"),
        (0.05, 0.0, 18, "hybrid_threshold"),
        (0.05, 0.0, u32::MAX, "hybrid_threshold"),
    ] {
        count += 1;
        failures.extend(check(
            &format!("CutOptions Ω {omega} light offset {k} threshold {threshold}"),
            &want(&[place]),
            || err(Traversal::new(&tree, options(omega, k, threshold))),
        ));
    }
    for n in [0, 257, usize::MAX] {
        count += 1;
        failures.extend(check(
            &format!("MicroBuffer::new({n})"),
            &want(&["microbuffer resolution", &n.to_string()]),
            || err(MicroBuffer::new(n)),
        ));
    }
    for text in ["avx9", "", "neon 2"] {
        count += 1;
        failures.extend(check(
            &format!("Isa {text:?}"),
            &want(&[&format!("{text:?}")]),
            || err(text.parse::<Isa>()),
        ));
        count += 1;
        failures.extend(check(
            &format!("Scheme {text:?}"),
            &want(&[&format!("{text:?}")]),
            || err(text.parse::<Scheme>()),
        ));
    }
    report(failures, count);
}

/// A small Cornell box: 8×6 pixels.
fn small_box() -> Scene {
    let mut s = cornell_box();
    s.camera.width = 8;
    s.camera.height = 6;
    s
}

fn quick(o: RenderOptions) -> RenderOptions {
    RenderOptions {
        spp: 1,
        density: 50.0,
        ..o
    }
}

/// Render, reference and bake options, and scenes built in code with bad
/// fields (each named in the error: mesh and item, material, light, camera).
#[test]
fn render_options_and_scenes() {
    let mut failures = Vec::new();
    let mut count = 0;
    let scene = small_box();
    let d = RenderOptions::default();
    let renders: Vec<(&str, RenderOptions, &str)> = vec![
        ("spp 0", RenderOptions { spp: 0, ..d }, "spp"),
        (
            "microbuffer 0",
            quick(RenderOptions { microbuffer: 0, ..d }),
            "microbuffer resolution",
        ),
        (
            "microbuffer 1000",
            quick(RenderOptions {
                microbuffer: 1000,
                ..d
            }),
            "microbuffer resolution",
        ),
        (
            "Ω NaN",
            quick(RenderOptions {
                cut: CutOptions {
                    max_solid_angle: f32::NAN,
                    ..d.cut
                },
                ..d
            }),
            "max_solid_angle",
        ),
        (
            "Ω −1",
            quick(RenderOptions {
                cut: CutOptions {
                    max_solid_angle: -1.0,
                    ..d.cut
                },
                ..d
            }),
            "max_solid_angle",
        ),
        (
            "hybrid threshold 99",
            quick(RenderOptions {
                cut: CutOptions {
                    hybrid_threshold: 99,
                    ..d.cut
                },
                ..d
            }),
            "hybrid_threshold",
        ),
        (
            "density NaN",
            RenderOptions {
                density: f32::NAN,
                ..quick(d)
            },
            "density",
        ),
        (
            "density −1",
            RenderOptions {
                density: -1.0,
                ..quick(d)
            },
            "density",
        ),
        (
            "density 0",
            RenderOptions {
                density: 0.0,
                ..quick(d)
            },
            "density",
        ),
        (
            "density ∞",
            RenderOptions {
                density: f32::INFINITY,
                ..quick(d)
            },
            "density",
        ),
        // More surfels than a cloud holds: refused before anything is allocated.
        (
            "density 1e30",
            RenderOptions {
                density: 1e30,
                ..quick(d)
            },
            "surfels given, at most",
        ),
    ];
    for (name, o, place) in renders {
        count += 1;
        failures.extend(check(&format!("render {name}"), &want(&[place]), || {
            err(render(&scene, &o, &|_, _| {}))
        }));
    }
    for (name, o, place) in [
        (
            "spp 0",
            ReferenceOptions {
                spp: 0,
                ..Default::default()
            },
            "spp",
        ),
        (
            "bounces −2",
            ReferenceOptions {
                bounces: -2,
                spp: 1,
                ..Default::default()
            },
            "bounces",
        ),
    ] {
        count += 1;
        failures.extend(check(&format!("reference {name}"), &want(&[place]), || {
            err(render_reference(&scene, &o, &|_, _| {}))
        }));
    }
    let tracer = pbgi::render::Tracer::new(&scene);
    let lights = pbgi::render::Lights::new(&scene);
    count += 1;
    failures.extend(check("bake density NaN", &want(&["density"]), || {
        let o = BakeOptions {
            density: f32::NAN,
            ..Default::default()
        };
        err(bake(&scene, &tracer, &lights, &o))
    }));

    let bad_scenes: Vec<Defect<Scene, Vec<&str>>> = vec![
        (
            "NaN vertex",
            Box::new(|s| s.meshes[1].positions[2].y = f32::NAN),
            vec!["mesh 1", "vertex 2 is not finite"],
        ),
        (
            "index out of range",
            Box::new(|s| s.meshes[0].triangles[1][2] = 999),
            vec!["mesh 0", "triangle 1"],
        ),
        (
            "missing material",
            Box::new(|s| s.meshes[2].material = 99),
            vec!["mesh 2", "material 99"],
        ),
        (
            "NaN emission",
            Box::new(|s| s.meshes[0].emission = Some(Vec3::NAN)),
            vec!["mesh 0", "emission"],
        ),
        (
            "emission beyond MAX_RADIANCE",
            Box::new(|s| s.meshes[0].emission = Some(Vec3::splat(1e31))),
            vec!["mesh 0", "emission"],
        ),
        (
            "negative emission",
            Box::new(|s| s.meshes[3].emission = Some(-Vec3::ONE)),
            vec!["mesh 3", "emission"],
        ),
        (
            "normals count",
            Box::new(|s| s.meshes[0].normals = Some(vec![Vec3::Y])),
            vec!["mesh 0", "1 normals"],
        ),
        (
            "NaN normal",
            Box::new(|s| {
                let n = s.meshes[0].positions.len();
                let mut normals = vec![Vec3::Y; n];
                normals[1] = Vec3::NAN;
                s.meshes[0].normals = Some(normals);
            }),
            vec!["mesh 0", "normal 1"],
        ),
        (
            "albedo 1",
            Box::new(|s| s.materials[0].albedo = Vec3::ONE),
            vec!["albedo"],
        ),
        (
            "NaN albedo",
            Box::new(|s| s.materials[1].albedo.x = f32::NAN),
            vec!["albedo"],
        ),
        (
            "glossy roughness 0",
            Box::new(|s| {
                s.materials[0].glossy = Some(Glossy {
                    specular: Vec3::splat(0.5),
                    roughness: 0.0,
                })
            }),
            vec!["glossy"],
        ),
        (
            "glossy specular NaN",
            Box::new(|s| {
                s.materials[0].glossy = Some(Glossy {
                    specular: Vec3::NAN,
                    roughness: 0.3,
                })
            }),
            vec!["glossy"],
        ),
        (
            "point light NaN",
            Box::new(|s| {
                s.lights.push(Light::Point {
                    position: Vec3::NAN,
                    intensity: Vec3::ONE,
                })
            }),
            vec!["light 0"],
        ),
        (
            "directional light zero",
            Box::new(|s| {
                s.lights.push(Light::Directional {
                    direction: Vec3::ZERO,
                    irradiance: Vec3::ONE,
                })
            }),
            vec!["light 0"],
        ),
        (
            "camera width 0",
            Box::new(|s| s.camera.width = 0),
            vec!["camera 0×6"],
        ),
        (
            "camera too large",
            Box::new(|s| s.camera.width = 100_000),
            vec!["camera 100000×6"],
        ),
        (
            "camera fov 180",
            Box::new(|s| s.camera.fov_degrees = 180.0),
            vec!["camera", "fov 180"],
        ),
        (
            "camera NaN origin",
            Box::new(|s| s.camera.origin.x = f32::NAN),
            vec!["camera origin"],
        ),
        (
            "camera infinite target",
            Box::new(|s| s.camera.target.z = f32::INFINITY),
            vec!["camera origin"],
        ),
        (
            "camera looks along up",
            Box::new(|s| s.camera.up = s.camera.target - s.camera.origin),
            vec!["camera looks along its up"],
        ),
    ];
    for (name, edit, places) in bad_scenes {
        let mut s = small_box();
        edit(&mut s);
        let o = quick(d);
        count += 1;
        failures.extend(check(&format!("scene {name}: render"), &want(&places), || {
            err(render(&s, &o, &|_, _| {}))
        }));
        count += 1;
        failures.extend(check(&format!("scene {name}: reference"), &want(&places), || {
            err(render_reference(
                &s,
                &ReferenceOptions {
                    spp: 1,
                    ..Default::default()
                },
                &|_, _| {},
            ))
        }));
    }
    report(failures, count);
}

/// Valid but degenerate geometry renders without a panic and without NaN.
/// Regression: a sliver triangle (edges 0.5 and 2e-21 high) has a cross
/// product whose `f32` length is subnormal and too coarse: its surfel's
/// normal failed the unit-length check and `bake` panicked ("baked surfels
/// are finite with unit normals"). Now normalized in `f64`. And a triangle of
/// the light's mesh whose area overflows `f32` made every direct-light sample
/// NaN, which the renderer then painted black; it is now left out of the
/// emitters as it is of the surfels, and a value that is not finite is a
/// typed error in both renderers. The "tiny" triangle (area 4.5e-46,
/// subnormal in `f32`) went into the light's emitters with an area that
/// halved to zero: its group's centroid and estimate were 0/0, which made
/// every surfel's direct light NaN. A triangle whose area is not a normal
/// `f32` is now left out like the others.
#[test]
fn degenerate_triangles_render() {
    for (name, a, b, c) in [
        (
            "sliver",
            Vec3::ZERO,
            Vec3::new(0.5, 0.0, 0.0),
            Vec3::new(0.25, 2e-21, 0.0),
        ),
        (
            "tiny",
            Vec3::ZERO,
            Vec3::new(3e-23, 0.0, 0.0),
            Vec3::new(0.0, 3e-23, 0.0),
        ),
        ("collinear", Vec3::ZERO, Vec3::X, Vec3::X * 2.0),
        ("point", Vec3::ONE, Vec3::ONE, Vec3::ONE),
        (
            "huge",
            Vec3::new(-1e37, 0.0, 0.0),
            Vec3::new(1e37, 0.0, 0.0),
            Vec3::new(0.0, 3e38, 1e37),
        ),
    ] {
        let mut s = small_box();
        let m = &mut s.meshes[0];
        let base = m.positions.len() as u32;
        m.positions.extend([a, b, c]);
        m.triangles.push([base, base + 1, base + 2]);
        let r = catch_unwind(AssertUnwindSafe(|| {
            render(&s, &quick(RenderOptions::default()), &|_, _| {})
        }));
        let out = r.unwrap_or_else(|_| panic!("{name}: render panicked"));
        let out = out.unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(
            out.image.pixels.iter().all(|p| p.min_element() >= 0.0),
            "{name}: a pixel is negative"
        );
        // The path tracer too: a value that is not finite is an error there.
        let opts = ReferenceOptions {
            spp: 4,
            ..Default::default()
        };
        render_reference(&s, &opts, &|_, _| {}).unwrap_or_else(|e| panic!("{name}: path tracer: {e}"));
    }
}

/// A scratch directory per test process.
fn dir() -> PathBuf {
    let d = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("pbgi-bad-input-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn write(name: &str, bytes: &[u8]) -> PathBuf {
    let p = dir().join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

/// A scene with `body` inside `<scene>` on line 2 onwards.
fn xml(body: &str) -> String {
    format!("<scene version=\"3.0.0\">\n{body}\n</scene>\n")
}

const PLY_HEADER: &str = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";

/// Malformed Mitsuba XML, OBJ, PLY and glTF files, missing files, directories and
/// devices, unsupported features: each a typed error naming file and line
/// (or the item), never a panic, never an endless read.
#[test]
fn scene_files() {
    let mut failures = Vec::new();
    let mut count = 0;
    // Mesh files the XML scenes refer to.
    write(
        "ok.ply",
        format!("{PLY_HEADER}0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n").as_bytes(),
    );
    std::fs::create_dir_all(dir().join("adir.ply")).unwrap();
    let zero_link = dir().join("zero.ply");
    let _ = std::fs::remove_file(&zero_link);
    #[cfg(unix)]
    std::os::unix::fs::symlink("/dev/zero", &zero_link).unwrap();
    let shape = |inner: &str| xml(&format!("<shape type=\"ply\">\n{inner}\n</shape>"));

    // (file name, content, strings the error must contain: the file and line)
    let files: Vec<(&str, String, Vec<String>)> = vec![
        ("syntax.xml", "<scene>\n<bsdf type=\"diffuse\"\n</scene>\n".into(), vec![":3:".into()]),
        ("empty.xml", String::new(), vec!["empty.xml:1:".into()]),
        ("root.xml", "<?xml version=\"1.0\"?>\n<film/>\n".into(), vec!["root.xml:2:".into(), "<scene>".into()]),
        ("bad-float.xml", xml("<shape type=\"sphere\">\n<float name=\"radius\" value=\"abc\"/>\n</shape>"), vec!["bad-float.xml:3:".into()]),
        ("nan-float.xml", xml("<shape type=\"sphere\">\n<float name=\"radius\" value=\"nan\"/>\n</shape>"), vec!["nan-float.xml:3:".into()]),
        ("huge-float.xml", xml("<shape type=\"sphere\">\n<float name=\"radius\" value=\"1e39\"/>\n</shape>"), vec!["huge-float.xml:3:".into()]),
        ("rgb.xml", xml("<bsdf type=\"diffuse\">\n<rgb name=\"reflectance\" value=\"0.5 0.5\"/>\n</bsdf>"), vec!["rgb.xml:3:".into()]),
        ("param.xml", xml("<shape type=\"sphere\">\n<float name=\"radius\" value=\"$r\"/>\n</shape>"), vec!["param.xml:3:".into(), "$r".into()]),
        ("no-type.xml", xml("<shape>\n</shape>"), vec!["no-type.xml:2:".into(), "type".into()]),
        ("no-filename.xml", shape(""), vec!["no-filename.xml:2:".into(), "filename".into()]),
        ("missing-mesh.xml", shape("<string name=\"filename\" value=\"nope.ply\"/>"), vec!["nope.ply".into(), "missing-mesh.xml:3".into()]),
        ("dir-mesh.xml", shape("<string name=\"filename\" value=\"adir.ply\"/>"), vec!["adir.ply".into(), "not a regular file".into()]),
        ("device-mesh.xml", shape("<string name=\"filename\" value=\"/dev/zero\"/>"), vec!["/dev/zero".into(), "not a regular file".into()]),
        ("linked-device.xml", shape("<string name=\"filename\" value=\"zero.ply\"/>"), vec!["zero.ply".into(), "not a regular file".into()]),
        ("ref.xml", xml("<shape type=\"cube\">\n<ref id=\"nothing\"/>\n</shape>"), vec!["ref.xml:3:".into(), "nothing".into()]),
        ("rotate.xml", xml("<shape type=\"cube\">\n<transform name=\"to_world\">\n<rotate angle=\"30\"/>\n</transform>\n</shape>"), vec!["rotate.xml:4:".into()]),
        ("matrix.xml", xml("<shape type=\"cube\">\n<transform name=\"to_world\">\n<matrix value=\"1 0 0 0 0 1 0 0 0 0 1 0 0 0 0\"/>\n</transform>\n</shape>"), vec!["matrix.xml:4:".into()]),
        ("lookat.xml", xml("<sensor type=\"perspective\">\n<transform name=\"to_world\">\n<lookat origin=\"0 0 0\" target=\"0 1 0\" up=\"0 1 0\"/>\n</transform>\n</sensor>"), vec!["lookat.xml:4:".into()]),
        ("skew.xml", xml("<shape type=\"cube\">\n<transform name=\"to_world\">\n<skew value=\"1\"/>\n</transform>\n</shape>"), vec!["skew.xml:4:".into(), "unsupported".into()]),
        ("ortho.xml", xml("<shape type=\"cube\"/>\n<sensor type=\"orthographic\"/>"), vec!["ortho.xml:3:".into(), "unsupported".into()]),
        ("fov-axis.xml", xml("<shape type=\"cube\"/>\n<sensor type=\"perspective\">\n<string name=\"fov_axis\" value=\"diagonal\"/>\n</sensor>"), vec!["fov-axis.xml:3:".into()]),
        ("blackbody.xml", xml("<shape type=\"cube\">\n<emitter type=\"area\">\n<blackbody name=\"radiance\" temperature=\"3000\"/>\n</emitter>\n</shape>"), vec!["blackbody.xml:4:".into(), "unsupported".into()]),
        ("twosided.xml", xml("<bsdf type=\"twosided\">\n</bsdf>"), vec!["twosided.xml:2:".into()]),
        ("film.xml", xml("<shape type=\"cube\"/>\n<sensor type=\"perspective\">\n<film type=\"hdrfilm\">\n<integer name=\"width\" value=\"1000000\"/>\n</film>\n</sensor>"), vec!["camera 1000000×".into()]),
        ("bright.xml", xml("<shape type=\"cube\">\n<emitter type=\"area\">\n<rgb name=\"radiance\" value=\"1e35\"/>\n</emitter>\n</shape>"), vec!["emission".into()]),
        ("bad-obj-vertex.obj", "v 0 0 0\nv 1 nope 0\n".into(), vec!["bad-obj-vertex.obj:2:".into()]),
        ("short-vertex.obj", "v 0 0 0\nv 1 0\nv 0 1 0\nf 1 2 3\n".into(), vec!["short-vertex.obj:2:".into()]),
        ("nan-vertex.obj", "v 0 0 0\nv 1 0 0\nv nan 1 0\nf 1 2 3\n".into(), vec!["nan-vertex.obj:3:".into()]),
        ("face-range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n".into(), vec!["face-range.obj:4:".into()]),
        ("face-zero.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n".into(), vec!["face-zero.obj:4:".into()]),
        // Its one face has two vertices: left out (a warning), nothing is left.
        ("face-two.obj", "v 0 0 0\nv 1 0 0\nf 1 2\n".into(), vec!["face-two.obj".into(), "no triangles".into()]),
        ("face-text.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x\n".into(), vec!["face-text.obj:4:".into()]),
        ("face-huge.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 99999999999999999999999\n".into(), vec!["face-huge.obj:4:".into()]),
        ("no-faces.obj", "v 0 0 0\n".into(), vec!["no-faces.obj".into(), "no triangles".into()]),
        ("no-header.ply", "ply\nformat ascii 1.0\n".into(), vec!["no-header.ply:1:".into()]),
        ("format.ply", "ply\nformat bogus 1.0\nend_header\n".into(), vec!["format.ply:2:".into()]),
        ("no-format.ply", "ply\nelement vertex 0\nend_header\n".into(), vec!["no-format.ply:1:".into()]),
        ("count.ply", "ply\nformat ascii 1.0\nelement vertex many\nend_header\n".into(), vec!["count.ply:3:".into()]),
        ("huge-count.ply", "ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty float x\nend_header\n".into(), vec!["huge-count.ply:3:".into()]),
        ("orphan.ply", "ply\nformat ascii 1.0\nproperty float x\nend_header\n".into(), vec!["orphan.ply:3:".into()]),
        ("prop-type.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty quad x\nend_header\n".into(), vec!["prop-type.ply:4:".into()]),
        ("list-type.ply", "ply\nformat ascii 1.0\nelement face 1\nproperty list uchar\nend_header\n".into(), vec!["list-type.ply:4:".into()]),
        ("keyword.ply", "ply\nformat ascii 1.0\nbogus\nend_header\n".into(), vec!["keyword.ply:3:".into()]),
        ("trunc.ply", format!("{PLY_HEADER}0 0 0\n1 0 0\n"), vec!["trunc.ply:".into(), "ends early".into()]),
        ("word.ply", format!("{PLY_HEADER}0 0 0\n1 zero 0\n0 1 0\n3 0 1 2\n"), vec!["word.ply:11:".into()]),
        ("beyond.ply", format!("{PLY_HEADER}0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n"), vec!["beyond.ply".into(), "face 0".into()]),
        ("negative.ply", format!("{PLY_HEADER}0 0 0\n1 0 0\n0 1 0\n3 0 -1 2\n"), vec!["negative.ply:13:".into()]),
        ("fraction.ply", format!("{PLY_HEADER}0 0 0\n1 0 0\n0 1 0\n3 0 1.5 2\n"), vec!["fraction.ply:13:".into()]),
        ("list-length.ply", format!("{PLY_HEADER}0 0 0\n1 0 0\n0 1 0\n10000000 0 1 2\n"), vec!["list-length.ply:13:".into()]),
        ("nan.ply", format!("{PLY_HEADER}0 0 0\nnan 0 0\n0 1 0\n3 0 1 2\n"), vec!["mesh 0".into(), "vertex 1 is not finite".into()]),
        ("binary-trunc.ply", "ply\nformat binary_little_endian 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\nend_header\n\0\0\0\0\0\0".into(), vec!["binary-trunc.ply:".into(), "byte".into()]),
        ("mesh.stl", "solid x\nendsolid x\n".into(), vec!["mesh.stl".into(), "unsupported".into()]),
        ("bad-json.gltf", "{\"asset\":{\"version\":\"2.0\"},\n\"meshes\":[}\n".into(), vec!["bad-json.gltf:2:".into()]),
        ("accessor.gltf", r#"{"asset":{"version":"2.0"},"meshes":[{"primitives":[{"attributes":{"POSITION":3}}]}]}"#.into(), vec!["accessor.gltf".into(), "meshes[0].primitives[0].attributes[\"POSITION\"]".into(), "(3)".into()]),
        ("missing-bin.gltf", r#"{"asset":{"version":"2.0"},"buffers":[{"byteLength":36,"uri":"gone.bin"}]}"#.into(), vec!["gone.bin".into(), "missing-bin.gltf".into()]),
        ("trunc.glb", "glTF\u{2}\0\0\0\u{7f}\0\0\0".into(), vec!["trunc.glb".into(), "GLB byte 8".into()]),
    ];
    for (name, text, places) in &files {
        let p = write(name, text.as_bytes());
        count += 1;
        failures.extend(check(name, &Want::Error(places.clone()), || err(load(&p))));
    }
    // Bytes that are not UTF-8, in each format.
    for name in [
        "binary.xml",
        "binary.obj",
        "binary.ply",
        "binary.gltf",
        "binary.glb",
    ] {
        let p = write(name, &[0xff, 0xfe, 0x00, 0x80, b'\n', 0xc3]);
        count += 1;
        failures.extend(check(name, &want(&[name]), || err(load(&p))));
    }
    // Legitimately accepted or not, but never a panic: deep nesting, entity
    // expansion, a material library that is a device.
    let deep = format!("<scene>{}{}</scene>", "<a>".repeat(5000), "</a>".repeat(5000));
    let laughs = "<?xml version=\"1.0\"?>\n<!DOCTYPE scene [\n<!ENTITY a \"aaaaaaaaaa\">\n<!ENTITY b \"&a;&a;&a;&a;&a;&a;&a;&a;&a;&a;\">\n<!ENTITY c \"&b;&b;&b;&b;&b;&b;&b;&b;&b;&b;\">\n<!ENTITY d \"&c;&c;&c;&c;&c;&c;&c;&c;&c;&c;\">\n<!ENTITY e \"&d;&d;&d;&d;&d;&d;&d;&d;&d;&d;\">\n<!ENTITY f \"&e;&e;&e;&e;&e;&e;&e;&e;&e;&e;\">\n]>\n<scene><default name=\"x\" value=\"&f;\"/></scene>\n";
    for (name, text) in [
        ("deep.xml", deep.as_str()),
        ("laughs.xml", laughs),
        (
            "mtl-device.obj",
            "mtllib /dev/zero\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
        ),
        (
            "mtl-missing.obj",
            "mtllib none.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
        ),
    ] {
        let p = write(name, text.as_bytes());
        count += 1;
        failures.extend(check(name, &Want::NoPanic, || err(load(&p))));
    }
    // Files that are not there, directories, devices.
    let missing = Path::new("/no/such/dir/scene.xml");
    for (name, p, places) in [
        (
            "missing xml",
            missing.to_path_buf(),
            vec!["/no/such/dir/scene.xml"],
        ),
        ("missing obj", PathBuf::from("/no/such.obj"), vec!["/no/such.obj"]),
        ("missing ply", PathBuf::from("/no/such.ply"), vec!["/no/such.ply"]),
        (
            "directory",
            dir().join("adir.ply"),
            vec!["adir.ply", "not a regular file"],
        ),
        (
            "device",
            zero_link.clone(),
            vec!["zero.ply", "not a regular file"],
        ),
        (
            "no extension",
            PathBuf::from("/dev/zero"),
            vec!["/dev/zero", "unsupported"],
        ),
    ] {
        count += 1;
        failures.extend(check(name, &want(&places), || err(load(&p))));
    }
    report(failures, count);
}

/// Tree files (`pbgi bake`, `TreeFile::load`) broken every way the format
/// tells apart, read from disk, and crop windows and trees that do not fit
/// the render: each a typed error naming the byte offset (or the window, the
/// setting), never a panic.
#[test]
fn tree_files_and_crops() {
    use pbgi::render::{Crop, Frame, bake_tree};
    use pbgi::tree::TreeFile;
    use pbgi::tree::file::checksum;

    let mut failures = Vec::new();
    let mut count = 0;
    let scene = small_box();
    // The full file's records, whose places the edits below name (a
    // compact file's are edited in tests/tree_file.rs).
    let opts = quick(RenderOptions {
        tree_precision: pbgi::tree::Precision::Full,
        ..RenderOptions::default()
    });
    let good = bake_tree(&scene, &opts).unwrap().to_bytes();
    let n = good.len();
    let with_checksum = |mut b: Vec<u8>| {
        let end = b.len() - 8;
        let sum = checksum(&b[..end]);
        b[end..].copy_from_slice(&sum.to_le_bytes());
        b
    };
    let edit = |at: usize, bytes: &[u8]| {
        let mut b = good.clone();
        b[at..at + bytes.len()].copy_from_slice(bytes);
        b
    };
    let surfels = u32::from_le_bytes(good[52..56].try_into().unwrap()) as usize;
    let nodes_at = 64 + 40 * surfels;
    // The last node is the deepest rightmost leaf.
    // A node record is 96 bytes (tree file version 3).
    let node = 96;
    let last_node = nodes_at + node * (2 * surfels - 2);
    let files: Vec<(&str, Vec<u8>, Vec<String>)> = vec![
        (
            "empty.pbgi",
            Vec::new(),
            vec!["truncated".into(), "ends at byte 0".into()],
        ),
        (
            "text.pbgi",
            b"not a tree".to_vec(),
            vec!["not a pbgi tree file".into()],
        ),
        (
            "magic-only.pbgi",
            good[..8].to_vec(),
            vec!["ends at byte 8".into()],
        ),
        (
            "version.pbgi",
            edit(8, &9u32.to_le_bytes()),
            vec!["version 9 at byte 8".into()],
        ),
        (
            "header.pbgi",
            good[..40].to_vec(),
            vec!["ends at byte 40, 64 bytes expected".into()],
        ),
        (
            "short.pbgi",
            good[..n - 100].to_vec(),
            vec![format!("ends at byte {}, {n} bytes", n - 100)],
        ),
        (
            "huge-count.pbgi",
            edit(52, &u32::MAX.to_le_bytes()),
            vec!["truncated".into()],
        ),
        (
            "trailing.pbgi",
            [&good[..], b"x"].concat(),
            vec![format!("continues past its end at byte {n}")],
        ),
        (
            "flipped.pbgi",
            edit(n / 2, &[good[n / 2] ^ 4]),
            vec![format!("checksum at byte {}", n - 8)],
        ),
        (
            "flags.pbgi",
            with_checksum(edit(40, &[0x80])),
            vec!["byte 40: unknown flags".into()],
        ),
        (
            "child.pbgi",
            with_checksum(edit(nodes_at + 36, &7u32.to_le_bytes())),
            vec![format!(
                "byte {nodes_at}: node 0: children in pair record 7, expected 1"
            )],
        ),
        (
            "nan-centre.pbgi",
            with_checksum(edit(nodes_at + node, &f32::NAN.to_le_bytes())),
            vec![format!("byte {}: node 1: centre", nodes_at + node)],
        ),
        (
            "kind.pbgi",
            with_checksum(edit(nodes_at + node + 56, &[5])),
            vec!["byte 56:".into(), "mixed nodes".into()],
        ),
        (
            "leaf-kind.pbgi",
            with_checksum(edit(last_node + 56, &[0])),
            vec![format!(
                "byte {last_node}: node {}: kind does not match",
                2 * surfels - 2
            )],
        ),
        (
            "surfel-radius.pbgi",
            with_checksum(edit(64 + 40 * 2 + 24, &(-1.0f32).to_le_bytes())),
            vec![format!("byte {}: surfel 2: radius -1", 64 + 80)],
        ),
        (
            "depth.pbgi",
            with_checksum(edit(60, &31u32.to_le_bytes())),
            vec!["byte 60: depth 31 recorded".into()],
        ),
    ];
    for (name, bytes, places) in &files {
        let p = write(name, bytes);
        count += 1;
        failures.extend(check(name, &Want::Error(places.clone()), || {
            err(TreeFile::load(std::fs::File::open(&p).unwrap()))
        }));
    }
    // An endless stream: its header is not a tree's, and nothing more is read.
    count += 1;
    failures.extend(check("/dev/zero", &want(&["not a pbgi tree file"]), || {
        err(TreeFile::load(std::fs::File::open("/dev/zero").unwrap()))
    }));
    let d = RenderOptions::default();
    for (name, crop, place) in [
        (
            "empty crop",
            Crop {
                x0: 4,
                y0: 0,
                x1: 4,
                y1: 6,
            },
            "crop 4,0,4,6: empty window",
        ),
        (
            "crop past the edge",
            Crop {
                x0: 0,
                y0: 0,
                x1: 9,
                y1: 6,
            },
            "crop 0,0,9,6: outside the 8×6 frame",
        ),
        (
            "crop past the foot",
            Crop {
                x0: 0,
                y0: 5,
                x1: 8,
                y1: 7,
            },
            "outside the 8×6 frame",
        ),
        (
            "crop upside down",
            Crop {
                x0: 0,
                y0: 5,
                x1: 8,
                y1: 2,
            },
            "empty window",
        ),
    ] {
        count += 1;
        let o = RenderOptions {
            crop: Some(crop),
            ..quick(d)
        };
        failures.extend(check(name, &want(&[place]), || {
            err(render(&scene, &o, &|_, _| {}))
        }));
    }
    for text in ["", "1,2,3", "1,2,3,x", "-1,0,4,4", "0,0,4,4,4"] {
        count += 1;
        failures.extend(check(
            &format!("crop {text:?}"),
            &want(&["expected x0,y0,x1,y1"]),
            || err(text.parse::<Crop>()),
        ));
    }
    let mut other = small_box();
    other.lights.push(Light::Point {
        position: Vec3::ZERO,
        intensity: Vec3::ONE,
    });
    for (name, scene, o, place) in [
        ("tree of another scene", &other, opts, "baked with scene"),
        (
            "tree of another density",
            &scene,
            RenderOptions {
                density: 40.0,
                ..opts
            },
            "--density 50, this render has 40",
        ),
        (
            "tree without bounces",
            &scene,
            RenderOptions { bounces: 3, ..opts },
            "--bounces 1, this render has 3",
        ),
    ] {
        count += 1;
        let file = TreeFile::from_bytes(&good).unwrap();
        failures.extend(check(name, &want(&[place]), || {
            err(Frame::with_tree(scene, &o, file))
        }));
    }
    report(failures, count);
}

/// Inputs on which `fuzz/fuzz_targets/scene_parsers.rs` crashed, replayed the
/// way the target reads them (byte 0 picks xml/obj/ply/off by `% 4`, `\n@@\n` separates
/// the side files `a.ply`, `a.obj`, `m.mtl`). Each must load or fail with an
/// error, without a panic.
///
/// * `scene_parsers-mtl-ks-two-numbers`: an OBJ whose material library has
///   `Ks 0.58 0.8`; tobj 4.0.5 unwraps a three-number parse and panicked.
///   The loader now refuses such a library (a warning: default materials).
#[test]
fn fuzz_regressions() {
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/fuzz");
    let mut count = 0;
    for entry in std::fs::read_dir(&data).unwrap() {
        let file = entry.unwrap().path();
        let name = file.file_name().unwrap().to_string_lossy().to_string();
        if !name.starts_with("scene_parsers-") {
            continue;
        }
        let bytes = std::fs::read(&file).unwrap();
        let case = dir().join(&name);
        std::fs::create_dir_all(&case).unwrap();
        let ext = ["xml", "obj", "ply", "off"][bytes[0] as usize % 4];
        let mut parts = bytes[1..].splitn_at(b"\n@@\n", 4);
        let main = parts.remove(0);
        for (side, part) in ["a.ply", "a.obj", "m.mtl"]
            .iter()
            .zip(parts.iter().chain(std::iter::repeat(&Vec::new())))
        {
            std::fs::write(case.join(side), part).unwrap();
        }
        let path = case.join(format!("input.{ext}"));
        std::fs::write(&path, main).unwrap();
        let r = catch_unwind(|| load(&path));
        assert!(r.is_ok(), "{name}: panicked");
        if name == "scene_parsers-mtl-ks-two-numbers" {
            let scene = r.unwrap().unwrap();
            assert!(
                scene
                    .warnings
                    .iter()
                    .any(|w| w.contains("material library not read")),
                "{:?}",
                scene.warnings
            );
        }
        count += 1;
    }
    assert!(count >= 1, "no regression inputs found in {}", data.display());
}

/// `splitn` on a byte separator.
trait SplitAt {
    fn splitn_at(&self, sep: &[u8], n: usize) -> Vec<Vec<u8>>;
}

impl SplitAt for [u8] {
    fn splitn_at(&self, sep: &[u8], n: usize) -> Vec<Vec<u8>> {
        let mut out = Vec::new();
        let mut rest = self;
        while out.len() + 1 < n {
            match rest.windows(sep.len()).position(|w| w == sep) {
                Some(i) => {
                    out.push(rest[..i].to_vec());
                    rest = &rest[i + sep.len()..];
                }
                None => break,
            }
        }
        out.push(rest.to_vec());
        out
    }
}
