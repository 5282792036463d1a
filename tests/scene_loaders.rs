//! Scene files: the shared Cornell box loads exactly as the built-in one;
//! malformed files are typed errors naming file and line; nothing panics.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use pbgi::scene::SceneError;
use pbgi::scene::builtin::cornell_box;
use pbgi::scene::{load, load_with, resolve};

/// Mitsuba's Cornell box as the project's scene folder ships it (committed
/// copy: tests/data/cornell-box).
fn cbox() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/cornell-box/cbox.xml")
}

fn write(name: &str, text: &str) -> PathBuf {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("pbgi-loader-tests-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

#[test]
fn shared_cornell_box_equals_the_builtin() {
    let path = cbox();
    let file = load(&path).unwrap();
    let builtin = cornell_box();
    assert_eq!(file.camera.width, 256);
    assert_eq!(file.camera.fov_axis, builtin.camera.fov_axis);
    assert!((file.camera.fov_degrees - builtin.camera.fov_degrees).abs() < 1e-5);
    assert!(file.camera.origin.abs_diff_eq(builtin.camera.origin, 1e-6));
    assert!(file.camera.frame().0.abs_diff_eq(builtin.camera.frame().0, 1e-6));
    assert!(
        file.camera.frame().1.abs_diff_eq(builtin.camera.frame().1, 1e-6),
        "image right must agree"
    );
    assert_eq!(file.meshes.len(), builtin.meshes.len());
    for b in &builtin.meshes {
        let f = file
            .meshes
            .iter()
            .find(|m| m.name == b.name)
            .unwrap_or_else(|| panic!("mesh {} missing", b.name));
        assert_eq!(f.triangles, b.triangles, "{}", b.name);
        assert_eq!(f.emission, b.emission, "{}", b.name);
        assert!(
            f.positions
                .iter()
                .zip(&b.positions)
                .all(|(x, y)| x.abs_diff_eq(*y, 1e-6)),
            "{}",
            b.name
        );
        assert_eq!(
            file.materials[f.material].albedo, builtin.materials[b.material].albedo,
            "{}",
            b.name
        );
    }
    // Rendering settings are read (the integrator's and sampler's) or
    // named, not dropped silently.
    assert_eq!(
        (file.file_settings.max_depth, file.file_settings.sample_count),
        (Some(-1), Some(64))
    );
    assert!(
        file.warnings
            .iter()
            .any(|w| w.contains("film <rfilter type=box>")),
        "{:?}",
        file.warnings
    );
}

fn parse_line(e: SceneError) -> usize {
    match e {
        SceneError::Parse { line, .. } => line,
        other => panic!("expected a parse error, got {other}"),
    }
}

#[test]
fn malformed_xml_names_the_line() {
    let p = write("syntax.xml", "<scene>\n  <bsdf type=\"diffuse\"\n</scene>\n");
    assert_eq!(parse_line(load(&p).unwrap_err()), 3);
    let p = write(
        "number.xml",
        "<scene>\n<bsdf type=\"diffuse\" id=\"a\">\n<rgb name=\"reflectance\" value=\"0.5 x 1\"/>\n</bsdf>\n</scene>",
    );
    assert_eq!(parse_line(load(&p).unwrap_err()), 3);
    let p = write(
        "param.xml",
        "<scene>\n\n<default name=\"a\" value=\"1\"/>\n<shape type=\"cube\">\n<float name=\"x\" value=\"$b\"/>\n</shape>\n</scene>",
    );
    // Unknown parameters are errors only where read; this one names a property the cube ignores.
    assert!(load(&p).is_ok());
    let p = write(
        "param2.xml",
        "<scene>\n<shape type=\"ply\">\n<string name=\"filename\" value=\"$mesh\"/>\n</shape>\n</scene>",
    );
    let e = load(&p).unwrap_err();
    assert_eq!(
        e.to_string(),
        format!("{}:3: unknown parameter $mesh", p.display())
    );
    let p = write(
        "missing.xml",
        "<scene>\n<shape type=\"ply\">\n<string name=\"filename\" value=\"nope.ply\"/>\n</shape>\n</scene>",
    );
    assert!(matches!(load(&p).unwrap_err(), SceneError::Io { .. }));
    assert!(matches!(
        load(Path::new("/no/such/scene.xml")).unwrap_err(),
        SceneError::Io { .. }
    ));
    assert!(matches!(
        resolve("no-such-scene").unwrap_err(),
        SceneError::UnknownScene { .. }
    ));
}

#[test]
fn parameters_defaults_and_overrides() {
    let text = "<scene>\n<default name=\"s\" value=\"2\"/>\n<shape type=\"cube\">\n<transform name=\"to_world\">\n<scale value=\"$s\"/>\n</transform>\n</shape>\n</scene>";
    let p = write("params.xml", text);
    let max = |s: &pbgi::scene::Scene| {
        s.meshes[0]
            .positions
            .iter()
            .map(|v| v.max_element())
            .fold(f32::MIN, f32::max)
    };
    assert_eq!(max(&load(&p).unwrap()), 2.0);
    let over = HashMap::from([("s".to_string(), "3".to_string())]);
    assert_eq!(max(&load_with(&p, &over).unwrap()), 3.0);
}

#[test]
fn primitives_and_transforms() {
    let text = r#"<scene>
<shape type="rectangle"><transform name="to_world"><rotate x="1" angle="-90"/><translate y="-1"/></transform></shape>
<shape type="sphere"><point name="center" x="0" y="2" z="0"/><float name="radius" value="0.5"/></shape>
<emitter type="point"><point name="position" value="0 3 0"/><rgb name="intensity" value="5"/></emitter>
<unknown-thing/>
</scene>"#;
    let s = load(&write("prims.xml", text)).unwrap();
    // The rectangle, rotated to face up and moved to y = −1.
    let quad = &s.meshes[0];
    assert!(quad.positions.iter().all(|p| (p.y + 1.0).abs() < 1e-5));
    let t = quad.triangles[0].map(|i| quad.positions[i as usize]);
    assert!(
        (t[1] - t[0])
            .cross(t[2] - t[0])
            .normalize()
            .abs_diff_eq(glam::Vec3::Y, 1e-5)
    );
    let sphere = &s.meshes[1];
    assert!(
        sphere
            .positions
            .iter()
            .all(|p| ((*p - glam::Vec3::new(0.0, 2.0, 0.0)).length() - 0.5).abs() < 1e-4)
    );
    assert_eq!(s.lights.len(), 1);
    assert!(
        s.warnings.iter().any(|w| w.contains("unknown-thing")),
        "{:?}",
        s.warnings
    );
}

#[test]
fn ply_errors() {
    let header = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
    assert!(
        load(&write(
            "ok.ply",
            &format!("{header}0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n")
        ))
        .is_ok()
    );
    let e = load(&write("trunc.ply", &format!("{header}0 0 0\n1 0 0\n"))).unwrap_err();
    assert!(e.to_string().contains("ends early"), "{e}");
    let e = load(&write(
        "range.ply",
        &format!("{header}0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n"),
    ))
    .unwrap_err();
    assert!(e.to_string().contains("beyond"), "{e}");
    let e = load(&write(
        "nan.ply",
        &format!("{header}0 0 0\n1 zero 0\n0 1 0\n3 0 1 2\n"),
    ))
    .unwrap_err();
    assert_eq!(parse_line(e), 11);
    let huge =
        "ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty float x\nend_header\n";
    assert_eq!(parse_line(load(&write("huge.ply", huge)).unwrap_err()), 3);
}

#[test]
fn obj_errors_and_materials() {
    let ok = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl lamp\nf 1 2 3\n";
    write("m.mtl", "newmtl lamp\nKd 1 1 1\nKa 20 20 20\n");
    let s = load(&write("ok.obj", ok)).unwrap();
    assert_eq!(s.meshes[0].emission, Some(glam::Vec3::splat(20.0)));
    assert!(s.materials[0].albedo.max_element() < 1.0);
    assert!(s.warnings.iter().any(|w| w.contains("Ka")) && s.warnings.iter().any(|w| w.contains("clamped")));
    let e = load(&write("bad.obj", "v 0 0 0\nv 1 0 0\nf 1 2 9\n")).unwrap_err();
    assert_eq!(parse_line(e), 3);
    let e = load(&write("badv.obj", "v 0 0 0\nv 1 nope 0\n")).unwrap_err();
    assert_eq!(parse_line(e), 2);
    // Faces of one or two vertices (lines, points: real exports have them)
    // are left out with a warning naming the first; the rest loads.
    let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2\nf 1 2 3\nf 4\nf 2 4 3\n";
    let s = load(&write("lines.obj", text)).unwrap();
    assert_eq!(s.triangle_count(), 2);
    assert!(
        s.warnings
            .iter()
            .any(|w| w.contains("2 face(s) with fewer than three vertices") && w.contains("line 5")),
        "{:?}",
        s.warnings
    );
}

/// OFF meshes load as bare meshes (default material and camera); polygons
/// are fan-triangulated, faces of fewer than three vertices left out with a
/// warning; malformed files name the line.
#[test]
fn off_meshes_and_their_errors() {
    let text = "OFF\n# a unit square and a stray edge\n5 3 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n0 0 1\n4 0 1 2 3\n2 0 4\n3 0 1 4 255 0 0\n";
    let s = load(&write("square.off", text)).unwrap();
    assert_eq!(s.triangle_count(), 3);
    assert_eq!(s.meshes[0].triangles[..2], [[0, 1, 2], [0, 2, 3]]);
    assert!(
        s.warnings.iter().any(|w| w.contains("a bare mesh")),
        "{:?}",
        s.warnings
    );
    assert!(
        s.warnings
            .iter()
            .any(|w| w.contains("1 face(s) with fewer than three vertices") && w.contains("line 10")),
        "{:?}",
        s.warnings
    );
    // Counts on the keyword's line, as some writers put them.
    assert_eq!(
        load(&write("inline.off", "OFF 3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"))
            .unwrap()
            .triangle_count(),
        1
    );
    for (name, text, line) in [
        ("magic.off", "PLY\n", 1),
        ("counts.off", "OFF\nthree 1 0\n", 2),
        ("vertex.off", "OFF\n3 1 0\n0 0 0\n1 nope 0\n0 1 0\n3 0 1 2\n", 4),
        ("index.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n", 6),
        ("short.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1\n", 6),
        ("huge.off", "OFF\n4000000000 1 0\n0 0 0\n", 2),
    ] {
        let e = load(&write(name, text)).unwrap_err();
        assert_eq!(parse_line(e), line, "{name}");
    }
}

/// Mitsuba's `constant` and `envmap` emitters become the scene's
/// environment; a file with no light at all gets the default sky and sun,
/// with a warning, and renders lit.
#[test]
fn environment_emitters_and_unlit_files() {
    use pbgi::environment::Environment;
    use pbgi::scene::{DEFAULT_SKY, Light};
    let rect = r#"<shape type="rectangle"/>"#;
    let xml = format!(
        r#"<scene version="3.0.0"><emitter type="constant"><rgb name="radiance" value="0.5 0.6 0.7"/></emitter>{rect}</scene>"#
    );
    let s = load(&write("sky.xml", &xml)).unwrap();
    assert_eq!(
        s.environment,
        Some(Environment::Uniform(glam::Vec3::new(0.5, 0.6, 0.7)))
    );
    assert!(s.lights.is_empty(), "a sky is a light: no default sun");
    // An equirectangular map: 4 × 2, the top row brighter.
    let exr = write("sky.exr", "");
    exr::prelude::write_rgb_file(&exr, 4, 2, |_, y| {
        if y == 0 {
            (4.0f32, 4.0f32, 4.0f32)
        } else {
            (1.0, 1.0, 1.0)
        }
    })
    .unwrap();
    let xml = format!(
        r#"<scene version="3.0.0"><emitter type="envmap"><string name="filename" value="sky.exr"/><float name="scale" value="0.5"/></emitter>{rect}</scene>"#
    );
    let s = load(&write("map.xml", &xml)).unwrap();
    let env = s.environment.expect("an environment");
    assert_eq!(env.radiance(glam::Vec3::Y), glam::Vec3::splat(2.0));
    assert_eq!(env.radiance(-glam::Vec3::Y), glam::Vec3::splat(0.5));
    let missing = format!(
        r#"<scene version="3.0.0"><emitter type="envmap"><string name="filename" value="nowhere.exr"/></emitter>{rect}</scene>"#
    );
    let e = load(&write("nomap.xml", &missing)).unwrap_err();
    assert!(e.to_string().contains("nowhere.exr"), "{e}");
    // No light at all: a default sky and sun, said so.
    let text = "OFF\n4 2 0\n-1 0 -1\n1 0 -1\n1 0 1\n-1 0 1\n3 0 2 1\n3 0 3 2\n";
    let s = load(&write("unlit.off", text)).unwrap();
    assert_eq!(s.environment, Some(Environment::Uniform(DEFAULT_SKY)));
    assert!(s.lights.iter().any(|l| matches!(l, Light::Directional { .. })));
    assert!(
        s.warnings.iter().any(|w| w.contains("default sky")),
        "{:?}",
        s.warnings
    );
    let mut small = s.clone();
    small.camera.width = 16;
    small.camera.height = 16;
    let out = pbgi::render::render(&small, &pbgi::render::RenderOptions::default(), &|_, _| {}).unwrap();
    let mean = out.image.pixels.iter().map(|p| p.element_sum()).sum::<f32>() / out.image.pixels.len() as f32;
    assert!(mean > 0.1, "mean {mean}: not lit");
}

#[test]
fn mutated_files_never_panic() {
    let path = cbox();
    let text = std::fs::read_to_string(&path).unwrap();
    let dir = path.parent().unwrap();
    let mut seed = 0x1234_5678u64;
    let mut parsed = 0;
    for i in 0..200 {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        let mut bytes = text.clone().into_bytes();
        let at = (seed as usize) % bytes.len();
        match i % 3 {
            0 => bytes.truncate(at),
            1 => bytes[at] = (seed >> 32) as u8,
            _ => {
                bytes.insert(at, b'$');
            }
        }
        let p = write(&format!("mut{i}.xml"), &String::from_utf8_lossy(&bytes));
        // Mesh paths are relative to the scene file: give the copies the real meshes.
        let meshes = p.parent().unwrap().join("meshes");
        if !meshes.exists() {
            std::fs::create_dir_all(&meshes).unwrap();
            for e in std::fs::read_dir(dir.join("meshes")).unwrap() {
                let e = e.unwrap();
                std::fs::copy(e.path(), meshes.join(e.file_name())).unwrap();
            }
        }
        let r = std::panic::catch_unwind(|| load(&p));
        assert!(r.is_ok(), "mutation {i} panicked");
        parsed += r.unwrap().is_ok() as usize;
    }
    eprintln!("{parsed} of 200 mutated files still loaded; the rest were typed errors");
}

#[test]
fn mitsuba_s_own_vector_and_point_forms_and_substituted_warnings() {
    use pbgi::scene::Light;
    let xml = r#"<scene version="3.0.0">
<default name="spp" value="64"/>
<integrator type="path"><integer name="max_depth" value="$spp"/><integer name="rr_depth" value="$spp"/></integrator>
<emitter type="directional"><vector name="direction" x="0" y="-1" z="1"/><rgb name="irradiance" value="2"/></emitter>
<emitter type="point"><point name="position" x="1" z="3"/></emitter>
<shape type="rectangle"/>
</scene>"#;
    let s = load(&write("xyz.xml", xml)).unwrap();
    let sun = std::f32::consts::FRAC_1_SQRT_2;
    assert!(
        s.lights
            .iter()
            .any(|l| matches!(l, Light::Directional { direction, .. }
            if (*direction - glam::Vec3::new(0.0, -sun, sun)).length() < 1e-6)),
        "{:?}",
        s.lights
    );
    assert!(
        s.lights.iter().any(
            |l| matches!(l, Light::Point { position, .. } if *position == glam::Vec3::new(1.0, 0.0, 3.0))
        ),
        "{:?}",
        s.lights
    );
    // The integrator's `$`-substituted max_depth is read, for the command line.
    assert_eq!(s.file_settings.max_depth, Some(64), "{:?}", s.warnings);
    let ignored = s
        .warnings
        .iter()
        .find(|w| w.contains("ignored"))
        .expect("the rest of the integrator is reported");
    assert!(
        ignored.contains("rr_depth=64") && !ignored.contains("max_depth") && !ignored.contains('$'),
        "{ignored}"
    );
    let bad = r#"<scene version="3.0.0"><emitter type="point"><point name="position" x="one"/></emitter><shape type="rectangle"/></scene>"#;
    let e = load(&write("xyz-bad.xml", bad)).unwrap_err().to_string();
    assert!(e.contains("x=\"one\"") && e.contains(":1"), "{e}");
}

#[test]
fn a_bare_mesh_is_the_same_two_sided_grey_in_every_format() {
    // A unit cube seen by its default camera from +z, the face towards
    // the camera wound inward: only a two-sided material shows it lit.
    let v = [
        [0, 0, 0],
        [1, 0, 0],
        [1, 1, 0],
        [0, 1, 0],
        [0, 0, 1],
        [1, 0, 1],
        [1, 1, 1],
        [0, 1, 1],
    ];
    // The +z face (towards the default camera) wound to face −z.
    let faces = [
        [4, 6, 5],
        [4, 7, 6],
        [0, 2, 1],
        [0, 3, 2],
        [0, 1, 5],
        [0, 5, 4],
        [3, 7, 6],
        [3, 6, 2],
    ];
    let mut obj = String::new();
    let mut off = format!("OFF\n8 {} 0\n", faces.len());
    for p in v {
        obj += &format!("v {} {} {}\n", p[0], p[1], p[2]);
        off += &format!("{} {} {}\n", p[0], p[1], p[2]);
    }
    for f in faces {
        obj += &format!("f {} {} {}\n", f[0] + 1, f[1] + 1, f[2] + 1);
        off += &format!("3 {} {} {}\n", f[0], f[1], f[2]);
    }
    let render = |path: PathBuf| {
        let mut s = load(&path).unwrap();
        assert!(
            s.materials.iter().all(|m| m.two_sided),
            "{}: {:?}",
            path.display(),
            s.materials
        );
        (s.camera.width, s.camera.height) = (16, 16);
        let opts = pbgi::render::RenderOptions {
            spp: 1,
            ..Default::default()
        };
        pbgi::render::render(&s, &opts, &|_, _| {}).unwrap().image
    };
    let (a, b) = (render(write("cube.obj", &obj)), render(write("cube.off", &off)));
    let centre = a.pixels[8 * 16 + 8];
    assert!(
        centre.min_element() > 0.05,
        "the inward-wound face is lit: {centre}"
    );
    assert_eq!(a.digest(), b.digest(), "the same cube, the same image");
}

#[test]
fn mitsuba_smooths_a_mesh_file_without_normals_unless_asked_for_face_normals() {
    // Two triangles folded 90° along the shared edge x = 0: a vertex on
    // the fold takes the mean of both faces' normals, as Mitsuba's does.
    write(
        "fold.obj",
        "v 0 0 0\nv 0 0 1\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 4 2\n",
    );
    let shape = |extra: &str| {
        format!(
            r#"<scene version="3.0.0"><shape type="obj"><string name="filename" value="fold.obj"/>{extra}</shape></scene>"#
        )
    };
    let smooth = load(&write("fold.xml", &shape(""))).unwrap();
    let n = smooth.meshes[0].normals.as_ref().expect("vertex normals made");
    let fold = std::f32::consts::FRAC_1_SQRT_2;
    let on_fold = n[0];
    assert!(
        (on_fold.abs() - glam::Vec3::new(fold, fold, 0.0)).length() < 1e-6,
        "{on_fold}"
    );
    // Off the fold, a vertex of one face keeps that face's normal.
    assert!((n[2].abs() - glam::Vec3::Y).length() < 1e-6, "{}", n[2]);
    let flat = load(&write(
        "fold-flat.xml",
        &shape(r#"<boolean name="face_normals" value="true"/>"#),
    ))
    .unwrap();
    assert!(flat.meshes[0].normals.is_none());
}
