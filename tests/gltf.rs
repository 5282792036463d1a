//! glTF 2.0 files written by the test (a `.gltf` with a base64 data URI, the
//! same as `.glb`, one with a `.bin` beside it): a small Cornell-like box
//! with a camera and a point light renders as the same scene built in code;
//! node transforms compose; materials, emission and lights map; malformed
//! files are typed errors naming the item; mutated files never panic.

use std::path::PathBuf;

use glam::Vec3;
use pbgi::render::{RenderOptions, render};
use pbgi::scene::{Camera, FovAxis, Glossy, Light, Material, Mesh, Scene, SceneError, load};

fn dir() -> PathBuf {
    let d = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("pbgi-gltf-tests-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn write(name: &str, bytes: &[u8]) -> PathBuf {
    let p = dir().join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

fn base64(bytes: &[u8]) -> String {
    const A: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut s = String::new();
    for c in bytes.chunks(3) {
        let n = (c[0] as u32) << 16 | (*c.get(1).unwrap_or(&0) as u32) << 8 | *c.get(2).unwrap_or(&0) as u32;
        for k in 0..4 {
            s.push(if k <= c.len() {
                A[(n >> (18 - 6 * k) & 63) as usize] as char
            } else {
                '='
            });
        }
    }
    s
}

/// Where a document's one buffer lives.
enum Buffer<'a> {
    DataUri,
    Glb,
    File(&'a str),
}

/// A glTF document under construction: the binary data, its views and accessors.
#[derive(Default)]
struct Doc {
    bin: Vec<u8>,
    views: Vec<String>,
    accessors: Vec<String>,
}

impl Doc {
    fn view(&mut self, bytes: &[u8]) -> usize {
        self.views.push(format!(
            r#"{{"buffer":0,"byteOffset":{},"byteLength":{}}}"#,
            self.bin.len(),
            bytes.len()
        ));
        self.bin.extend_from_slice(bytes);
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        self.views.len() - 1
    }

    /// A VEC3 float accessor (with the min and max a POSITION needs).
    fn vec3(&mut self, v: &[Vec3]) -> usize {
        let bytes: Vec<u8> = v
            .iter()
            .flat_map(|p| p.to_array())
            .flat_map(f32::to_le_bytes)
            .collect();
        let view = self.view(&bytes);
        let (lo, hi) = v.iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(l, h), p| {
            (l.min(*p), h.max(*p))
        });
        self.accessors.push(format!(
            r#"{{"bufferView":{view},"componentType":5126,"count":{},"type":"VEC3","min":{:?},"max":{:?}}}"#,
            v.len(),
            lo.to_array(),
            hi.to_array()
        ));
        self.accessors.len() - 1
    }

    fn indices(&mut self, idx: &[u16]) -> usize {
        let bytes: Vec<u8> = idx.iter().flat_map(|i| i.to_le_bytes()).collect();
        let view = self.view(&bytes);
        self.accessors.push(format!(
            r#"{{"bufferView":{view},"componentType":5123,"count":{},"type":"SCALAR"}}"#,
            idx.len()
        ));
        self.accessors.len() - 1
    }

    /// The JSON with `rest` (the scene's own members) and the buffer where asked.
    fn json(&self, buffer: &Buffer, rest: &str) -> String {
        let uri = match buffer {
            Buffer::DataUri => format!(
                r#","uri":"data:application/octet-stream;base64,{}""#,
                base64(&self.bin)
            ),
            Buffer::Glb => String::new(),
            Buffer::File(f) => format!(r#","uri":"{f}""#),
        };
        format!(
            r#"{{"asset":{{"version":"2.0"}},"buffers":[{{"byteLength":{}{uri}}}],"bufferViews":[{}],"accessors":[{}],{rest}}}"#,
            self.bin.len(),
            self.views.join(","),
            self.accessors.join(",")
        )
    }

    /// The GLB container: header, JSON chunk (space-padded), BIN chunk.
    fn glb(&self, rest: &str) -> Vec<u8> {
        let mut json = self.json(&Buffer::Glb, rest).into_bytes();
        while !json.len().is_multiple_of(4) {
            json.push(b' ');
        }
        let total = 12 + 8 + json.len() + 8 + self.bin.len();
        let mut out = Vec::new();
        out.extend_from_slice(b"glTF");
        out.extend_from_slice(&2u32.to_le_bytes());
        out.extend_from_slice(&(total as u32).to_le_bytes());
        out.extend_from_slice(&(json.len() as u32).to_le_bytes());
        out.extend_from_slice(b"JSON");
        out.extend_from_slice(&json);
        out.extend_from_slice(&(self.bin.len() as u32).to_le_bytes());
        out.extend_from_slice(b"BIN\0");
        out.extend_from_slice(&self.bin);
        out
    }
}

/// A quad of half-sizes `u`, `v` around `c`, facing `u × v` (counter-clockwise).
fn quad(c: Vec3, u: Vec3, v: Vec3) -> Vec<Vec3> {
    vec![c - u - v, c + u - v, c + u + v, c - u + v]
}

const QUAD: [u16; 6] = [0, 1, 2, 0, 2, 3];

/// The box's walls: floor, ceiling, back, left (red), right (green), each facing in.
fn walls() -> Vec<(Vec<Vec3>, usize)> {
    let (x, y, z) = (Vec3::X, Vec3::Y, Vec3::Z);
    vec![
        (quad(Vec3::ZERO, z, x), 0),
        (quad(2.0 * y, x, z), 0),
        (quad(y - z, x, y), 0),
        (quad(y - x, y, z), 1),
        (quad(y + x, z, y), 2),
    ]
}

const COLOURS: [Vec3; 3] = [
    Vec3::splat(0.7),
    Vec3::new(0.7, 0.1, 0.1),
    Vec3::new(0.1, 0.7, 0.1),
];
const YFOV: f32 = 0.8;
const LIGHT_AT: Vec3 = Vec3::new(0.0, 1.8, 0.0);
const CANDELA: f32 = 3.0;

/// The box as glTF: one mesh per wall, a camera node at (0, 1, 2.4) looking
/// down −Z, a point light node under the ceiling.
fn cornell() -> (Doc, String) {
    let mut doc = Doc::default();
    let mut meshes = Vec::new();
    for (p, m) in walls() {
        let (a, i) = (doc.vec3(&p), doc.indices(&QUAD));
        meshes.push(format!(
            r#"{{"primitives":[{{"attributes":{{"POSITION":{a}}},"indices":{i},"material":{m}}}]}}"#
        ));
    }
    let materials: Vec<String> = COLOURS
        .iter()
        .map(|c| {
            format!(
                r#"{{"pbrMetallicRoughness":{{"baseColorFactor":[{},{},{},1],"metallicFactor":0,"roughnessFactor":1}}}}"#,
                c.x, c.y, c.z
            )
        })
        .collect();
    let rest = format!(
        r#""scene":0,"scenes":[{{"nodes":[0,1,2,3,4,5,6]}}],
        "nodes":[{{"mesh":0}},{{"mesh":1}},{{"mesh":2}},{{"mesh":3}},{{"mesh":4}},
          {{"camera":0,"translation":[0,1,2.4]}},
          {{"translation":[{},{},{}],"extensions":{{"KHR_lights_punctual":{{"light":0}}}}}}],
        "meshes":[{}],"materials":[{}],
        "cameras":[{{"type":"perspective","perspective":{{"yfov":{YFOV},"aspectRatio":1.0,"znear":0.1}}}}],
        "extensionsUsed":["KHR_lights_punctual"],
        "extensions":{{"KHR_lights_punctual":{{"lights":[{{"type":"point","color":[1,1,1],"intensity":{CANDELA}}}]}}}}"#,
        LIGHT_AT.x,
        LIGHT_AT.y,
        LIGHT_AT.z,
        meshes.join(","),
        materials.join(",")
    );
    (doc, rest)
}

/// The same box built in code, with the mapping the loader documents:
/// metallic 0 → albedo the base colour, a 4 % lobe of α = roughness².
fn cornell_in_code() -> Scene {
    Scene {
        name: "code".into(),
        meshes: walls()
            .into_iter()
            .enumerate()
            .map(|(i, (positions, material))| Mesh {
                name: format!("mesh {i}/0"),
                positions,
                triangles: vec![[0, 1, 2], [0, 2, 3]],
                normals: None,
                uvs: Vec::new(),
                material,
                emission: None,
            })
            .collect(),
        materials: COLOURS
            .iter()
            .enumerate()
            .map(|(i, c)| Material {
                glossy: Some(Glossy {
                    specular: Vec3::splat(0.04),
                    roughness: 1.0,
                }),
                ..Material::diffuse(format!("material {i}"), *c)
            })
            .collect(),
        lights: vec![Light::Point {
            position: LIGHT_AT,
            intensity: Vec3::splat(CANDELA),
        }],
        environment: None,
        camera: Camera {
            origin: Vec3::new(0.0, 1.0, 2.4),
            target: Vec3::new(0.0, 1.0, 1.4),
            up: Vec3::Y,
            fov_degrees: YFOV.to_degrees(),
            fov_axis: FovAxis::Y,
            width: 256,
            height: 256,
        },
        warnings: Vec::new(),
        file_settings: Default::default(),
    }
}

/// The mean of the floor's pixels (the bottom eighth of a 32×32 image, its middle half).
fn floor_mean(scene: &Scene) -> Vec3 {
    let mut s = scene.clone();
    s.camera.width = 32;
    s.camera.height = 32;
    let opts = RenderOptions {
        spp: 1,
        density: 200.0,
        ..RenderOptions::default()
    };
    let img = render(&s, &opts, &|_, _| {}).unwrap().image;
    let mut sum = Vec3::ZERO;
    for y in 28..32 {
        for x in 8..24 {
            sum += img.pixels[y * 32 + x];
        }
    }
    sum / 64.0
}

#[test]
fn box_with_camera_and_point_light_renders_as_built_in_code() {
    let (doc, rest) = cornell();
    let s = load(&write("box.gltf", doc.json(&Buffer::DataUri, &rest).as_bytes())).unwrap();
    let code = cornell_in_code();
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    assert_eq!(s.camera.width, 256);
    assert!(s.camera.origin.abs_diff_eq(code.camera.origin, 1e-6));
    assert!(s.camera.frame().0.abs_diff_eq(-Vec3::Z, 1e-6), "looks down −Z");
    assert!(s.camera.frame().1.abs_diff_eq(Vec3::X, 1e-6), "image right is +X");
    assert!((s.camera.fov_degrees - code.camera.fov_degrees).abs() < 1e-4);
    assert_eq!(s.lights, code.lights);
    assert_eq!(s.materials, code.materials);
    assert_eq!(s.meshes, code.meshes);
    let (file, built) = (floor_mean(&s), floor_mean(&code));
    assert!(
        file.is_finite() && file.min_element() > 0.01,
        "floor {file}: not lit"
    );
    assert!(
        file.abs_diff_eq(built, 1e-3 * built.max_element()),
        "file {file} code {built}"
    );
}

#[test]
fn glb_and_external_bin_load_as_the_data_uri() {
    let (doc, rest) = cornell();
    let uri = load(&write("same.gltf", doc.json(&Buffer::DataUri, &rest).as_bytes())).unwrap();
    let glb = load(&write("same.glb", &doc.glb(&rest))).unwrap();
    write("box data.bin", &doc.bin);
    let bin = load(&write(
        "bin.gltf",
        doc.json(&Buffer::File("box%20data.bin"), &rest).as_bytes(),
    ))
    .unwrap();
    for s in [&glb, &bin] {
        assert_eq!(s.meshes, uri.meshes);
        assert_eq!(s.materials, uri.materials);
        assert_eq!(s.lights, uri.lights);
        assert_eq!(s.camera, uri.camera);
    }
}

/// A unit triangle mesh (mesh 0) and `rest` around it.
fn triangle_doc(buffer: &Buffer, rest: &str) -> String {
    let mut doc = Doc::default();
    let a = doc.vec3(&[Vec3::ZERO, Vec3::X, Vec3::Y]);
    let i = doc.indices(&[0, 1, 2]);
    doc.json(
        buffer,
        &format!(r#""meshes":[{{"primitives":[{{"attributes":{{"POSITION":{a}}},"indices":{i},"material":0}}]}}],{rest}"#),
    )
}

fn bounds(s: &Scene) -> (Vec3, Vec3) {
    s.meshes
        .iter()
        .flat_map(|m| &m.positions)
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(l, h), p| {
            (l.min(*p), h.max(*p))
        })
}

#[test]
fn node_transforms_compose_down_the_tree() {
    let material = r#""materials":[{"pbrMetallicRoughness":{"metallicFactor":0}}]"#;
    // Parent: translate (10, 0, 0) and scale 2; child: rotate 90° about +Z
    // (x → y) and translate (0, 5, 0) in the parent's frame.
    let s2 = std::f32::consts::FRAC_1_SQRT_2;
    let trs = format!(
        r#""scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[
        {{"translation":[10,0,0],"scale":[2,2,2],"children":[1]}},
        {{"translation":[0,5,0],"rotation":[0,0,{s2},{s2}],"mesh":0}}],{material}"#
    );
    let s = load(&write(
        "trs.gltf",
        triangle_doc(&Buffer::DataUri, &trs).as_bytes(),
    ))
    .unwrap();
    // The triangle (0,0,0), (1,0,0), (0,1,0) → rotated (0,0,0), (0,1,0), (−1,0,0)
    // → + (0,5,0) → × 2 → + (10,0,0).
    let (lo, hi) = bounds(&s);
    assert!(lo.abs_diff_eq(Vec3::new(8.0, 10.0, 0.0), 1e-5), "{lo}");
    assert!(hi.abs_diff_eq(Vec3::new(10.0, 12.0, 0.0), 1e-5), "{hi}");
    // The same as a column-major matrix on one node.
    let matrix = format!(
        r#""scenes":[{{"nodes":[0]}}],"nodes":[{{"matrix":[0,2,0,0, -2,0,0,0, 0,0,2,0, 10,10,0,1],"mesh":0}}],{material}"#
    );
    let m = load(&write(
        "matrix.gltf",
        triangle_doc(&Buffer::DataUri, &matrix).as_bytes(),
    ))
    .unwrap();
    assert_eq!(bounds(&m), (lo, hi));
    // A mirror flips the winding: the face still faces the same side of the mesh.
    let mirror = format!(r#""scenes":[{{"nodes":[0]}}],"nodes":[{{"scale":[-1,1,1],"mesh":0}}],{material}"#);
    let f = load(&write(
        "mirror.gltf",
        triangle_doc(&Buffer::DataUri, &mirror).as_bytes(),
    ))
    .unwrap();
    assert_eq!(f.meshes[0].triangles, vec![[0, 2, 1]]);
    // A cycle (node 0 its own grandchild) is walked once, with a warning.
    let cycle = format!(
        r#""scenes":[{{"nodes":[0]}}],"nodes":[{{"children":[1]}},{{"children":[0],"mesh":0}}],{material}"#
    );
    match load(&write(
        "cycle.gltf",
        triangle_doc(&Buffer::DataUri, &cycle).as_bytes(),
    )) {
        Ok(c) => {
            assert_eq!(c.meshes.len(), 1);
            assert!(c.warnings.iter().any(|w| w.contains("twice")), "{:?}", c.warnings);
        }
        Err(e) => assert!(e.to_string().contains("nodes"), "{e}"),
    }
}

#[test]
fn materials_emission_and_lights_map() {
    let rest = r#""scenes":[{"nodes":[0,1,2,3,4]}],"nodes":[{"mesh":0},{"mesh":1},{"mesh":2},
        {"rotation":[0.7071068,0,0,0.7071068],"extensions":{"KHR_lights_punctual":{"light":0}}},
        {"translation":[1,2,3],"extensions":{"KHR_lights_punctual":{"light":1}}}],
      "materials":[
        {"name":"gold","pbrMetallicRoughness":{"baseColorFactor":[0.9,0.6,0.3,1],"metallicFactor":1,"roughnessFactor":0.5}},
        {"name":"lamp","emissiveFactor":[1,0.5,0.25],"extensions":{"KHR_materials_emissive_strength":{"emissiveStrength":4}},
         "pbrMetallicRoughness":{"baseColorTexture":{"index":0},"metallicFactor":0}}],
      "textures":[{"source":0}],"images":[{"uri":"none.png"}],
      "extensionsUsed":["KHR_lights_punctual","KHR_materials_emissive_strength"],
      "extensions":{"KHR_lights_punctual":{"lights":[
        {"type":"directional","color":[1,1,1],"intensity":2},
        {"type":"spot","intensity":5,"spot":{"outerConeAngle":0.5}}]}}"#;
    let mut doc = Doc::default();
    let a = doc.vec3(&[Vec3::ZERO, Vec3::X, Vec3::Y]);
    // Mesh 0: gold; mesh 1: the lamp, without indices; mesh 2: lines and no material.
    let meshes = format!(
        r#""meshes":[{{"primitives":[{{"attributes":{{"POSITION":{a}}},"material":0}}]}},
        {{"primitives":[{{"attributes":{{"POSITION":{a}}},"material":1}}]}},
        {{"primitives":[{{"attributes":{{"POSITION":{a}}},"mode":1}},{{"attributes":{{"POSITION":{a}}}}}]}}],{rest}"#
    );
    let s = load(&write(
        "materials.gltf",
        doc.json(&Buffer::DataUri, &meshes).as_bytes(),
    ))
    .unwrap();
    let gold = &s.materials[s.meshes[0].material];
    assert_eq!(gold.albedo, Vec3::ZERO, "metallic 1: no diffuse");
    let g = gold.glossy.expect("metallic 1: glossy");
    assert!(
        g.specular.abs_diff_eq(Vec3::new(0.9, 0.6, 0.3), 1e-6) && g.roughness == 0.25,
        "{g:?}"
    );
    let lamp = &s.meshes[1];
    assert_eq!(lamp.triangles, vec![[0, 1, 2]], "no indices: corners in order");
    assert_eq!(
        lamp.emission,
        Some(Vec3::new(4.0, 2.0, 1.0)),
        "emissive × strength"
    );
    let lamp_m = &s.materials[lamp.material];
    assert_eq!(
        lamp_m.albedo,
        Vec3::splat(0.99),
        "base colour 1 (default) clamped below 1"
    );
    assert_eq!(lamp_m.glossy.unwrap().specular, Vec3::splat(0.04));
    assert_eq!(s.meshes.len(), 3, "the lines primitive is skipped");
    let grey = &s.materials[s.meshes[2].material];
    assert!(grey.two_sided && grey.albedo == Vec3::splat(0.5), "{grey:?}");
    // Directional: the node's −Z turned 90° about +X points up, +Y.
    match s.lights[0] {
        Light::Directional {
            direction,
            irradiance,
        } => {
            assert!(direction.abs_diff_eq(Vec3::Y, 1e-6), "{direction}");
            assert_eq!(irradiance, Vec3::splat(2.0));
        }
        l => panic!("{l:?}"),
    }
    assert_eq!(
        s.lights[1],
        Light::Point {
            position: Vec3::new(1.0, 2.0, 3.0),
            intensity: Vec3::splat(5.0)
        }
    );
    for w in [
        "none.png", // a missing texture: the material keeps its factors
        "spot light",
        "Lines",
        "without a material",
        "clamped",
    ] {
        assert!(
            s.warnings.iter().any(|x| x.contains(w)),
            "no warning {w:?}: {:?}",
            s.warnings
        );
    }
}

fn error(name: &str, bytes: &[u8]) -> String {
    match load(&write(name, bytes)) {
        Ok(_) => panic!("{name} loaded"),
        Err(e) => {
            assert!(e.to_string().contains(name), "{name}: {e}");
            assert!(
                matches!(
                    e,
                    SceneError::Parse { .. } | SceneError::Io { .. } | SceneError::Unsupported { .. }
                ),
                "{e:?}"
            );
            e.to_string()
        }
    }
}

#[test]
fn bad_files_are_typed_errors_naming_the_item() {
    let material = r#""materials":[{}],"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}]"#;
    let ok = triangle_doc(&Buffer::DataUri, material);
    load(&write("ok.gltf", ok.as_bytes())).unwrap();
    // Bad JSON: the line.
    let e = error(
        "syntax.gltf",
        b"{\"asset\":\n{\"version\":\"2.0\"},\n\"nodes\": [}\n",
    );
    assert!(e.contains("syntax.gltf:3:"), "{e}");
    // An accessor index beyond the accessors: the JSON path and the value.
    let e = error(
        "index.gltf",
        ok.replace(r#""indices":1"#, r#""indices":7"#).as_bytes(),
    );
    assert!(
        e.contains("meshes[0].primitives[0].indices") && e.contains('7'),
        "{e}"
    );
    // A vertex index beyond the vertices.
    let mut doc = Doc::default();
    let a = doc.vec3(&[Vec3::ZERO, Vec3::X, Vec3::Y]);
    let i = doc.indices(&[0, 1, 9]);
    let prim = format!(r#""meshes":[{{"primitives":[{{"attributes":{{"POSITION":{a}}},"indices":{i}}}]}}],"#);
    let e = error(
        "vertex.gltf",
        doc.json(&Buffer::DataUri, &format!("{prim}{material}"))
            .as_bytes(),
    );
    assert!(e.contains("mesh 0 primitive 0") && e.contains("vertex 9"), "{e}");
    // Indices that are a VEC3 float accessor.
    let wrong = ok.replace(r#""indices":1"#, r#""indices":0"#);
    let e = error("type.gltf", wrong.as_bytes());
    assert!(
        e.contains("mesh 0 primitive 0 indices: accessor 0") && e.contains("SCALAR"),
        "{e}"
    );
    // An accessor longer than its view.
    let long = ok.replace(r#""count":3,"type":"VEC3""#, r#""count":300,"type":"VEC3""#);
    let e = error("long.gltf", long.as_bytes());
    assert!(e.contains("POSITION: accessor 0 of 300 elements"), "{e}");
    // A missing .bin: the file it looked for and the scene that named it.
    let e = error(
        "missing-bin.gltf",
        triangle_doc(&Buffer::File("nowhere.bin"), material).as_bytes(),
    );
    assert!(e.contains("nowhere.bin") && e.contains("buffer 0"), "{e}");
    // Bad base64.
    let e = error("base64.gltf", ok.replacen("base64,", "base64,*", 1).as_bytes());
    assert!(e.contains("base64") && e.contains("buffer 0"), "{e}");
    // A truncated GLB: the byte offset; every truncation is a typed error.
    let mut d = Doc::default();
    let a = d.vec3(&[Vec3::ZERO, Vec3::X, Vec3::Y]);
    let i = d.indices(&[0, 1, 2]);
    let glb = d.glb(&format!(
        r#""meshes":[{{"primitives":[{{"attributes":{{"POSITION":{a}}},"indices":{i}}}]}}],{material}"#
    ));
    load(&write("whole.glb", &glb)).unwrap();
    let e = error("half.glb", &glb[..glb.len() / 2]);
    assert!(e.contains("GLB byte 8"), "{e}");
    for cut in 0..glb.len() {
        error(&format!("cut{cut}.glb"), &glb[..cut]);
    }
    // A GLB whose buffer has no binary chunk.
    let json_only = {
        let json_len = u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
        let mut b = glb[..20 + json_len].to_vec();
        b[8..12].copy_from_slice(&((20 + json_len) as u32).to_le_bytes());
        b
    };
    let e = error("no-bin.glb", &json_only);
    assert!(e.contains("binary chunk"), "{e}");
}

#[test]
fn mutated_files_never_panic() {
    let (doc, rest) = cornell();
    let glb = doc.glb(&rest);
    let text = doc.json(&Buffer::DataUri, &rest).into_bytes();
    let mut seed = 0x9E37_79B9u64;
    let mut loaded = 0;
    for i in 0..400 {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        let (mut bytes, ext) = if i % 2 == 0 {
            (glb.clone(), "glb")
        } else {
            (text.clone(), "gltf")
        };
        let at = (seed as usize) % bytes.len();
        match i % 3 {
            0 => bytes.truncate(at),
            1 => bytes[at] = (seed >> 32) as u8,
            _ => bytes[at] = b"0123456789"[(seed >> 40) as usize % 10],
        }
        let p = write(&format!("mut{i}.{ext}"), &bytes);
        let r = std::panic::catch_unwind(|| load(&p));
        assert!(r.is_ok(), "mutation {i} panicked");
        loaded += r.unwrap().is_ok() as usize;
    }
    eprintln!("{loaded} of 400 mutated files still loaded; the rest were typed errors");
}

/// Textures of a GLB: an embedded PNG (a buffer view), the sampler's wrap
/// modes, `KHR_texture_transform` (its `texCoord` over the reference's),
/// a second coordinate set, alpha `MASK` at its cutoff.
#[test]
fn textures_samplers_transforms_and_coordinate_sets_map() {
    use glam::Vec2;
    use pbgi::scene::texture::Wrap;
    let mut png = Vec::new();
    let texels: Vec<u8> = [
        [255, 0, 0, 255],
        [0, 255, 0, 0],
        [0, 0, 255, 255],
        [255, 255, 255, 128],
    ]
    .into_iter()
    .flatten()
    .collect();
    image::RgbaImage::from_raw(2, 2, texels)
        .unwrap()
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .unwrap();
    let mut doc = Doc::default();
    let p = doc.vec3(&[Vec3::ZERO, Vec3::X, Vec3::Y]);
    let mut vec2 = |v: [[f32; 2]; 3]| {
        let bytes: Vec<u8> = v.iter().flatten().flat_map(|x| x.to_le_bytes()).collect();
        let view = doc.view(&bytes);
        doc.accessors.push(format!(
            r#"{{"bufferView":{view},"componentType":5126,"count":3,"type":"VEC2"}}"#
        ));
        doc.accessors.len() - 1
    };
    let (uv0, uv1) = (vec2([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]), vec2([[0.5; 2]; 3]));
    let image = doc.view(&png);
    let rest = format!(
        r#""scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],
        "meshes":[{{"primitives":[{{"attributes":{{"POSITION":{p},"TEXCOORD_0":{uv0},"TEXCOORD_1":{uv1}}},"material":0}}]}}],
        "materials":[{{"name":"leaf","alphaMode":"MASK","alphaCutoff":0.3,"pbrMetallicRoughness":{{"metallicFactor":0,
          "baseColorTexture":{{"index":0,"texCoord":1,"extensions":{{"KHR_texture_transform":{{"offset":[0.5,0],"scale":[2,3],"texCoord":0}}}}}}}}}}],
        "textures":[{{"source":0,"sampler":0}}],"samplers":[{{"wrapS":33071,"wrapT":33648}}],
        "images":[{{"bufferView":{image},"mimeType":"image/png"}}],
        "extensionsUsed":["KHR_texture_transform"]"#
    );
    let s = load(&write("textured.glb", &doc.glb(&rest))).unwrap();
    assert_eq!(s.meshes[0].uvs.len(), 2, "both coordinate sets");
    assert_eq!(s.meshes[0].uvs[1][2], Vec2::splat(0.5));
    let m = &s.materials[s.meshes[0].material];
    let map = m.albedo_map.as_ref().expect("the base colour texture");
    assert_eq!(map.texture.size(), (2, 2));
    assert_eq!(map.uv_set, 0, "the transform's texCoord wins");
    assert_eq!(map.wrap, [Wrap::Clamp, Wrap::Mirror]);
    assert_eq!(map.transform.apply(Vec2::ZERO), Vec2::new(0.5, 0.0));
    assert_eq!(map.transform.apply(Vec2::ONE), Vec2::new(2.5, 3.0));
    assert_eq!(m.albedo, Vec3::ONE, "a texture's factor is not clamped");
    let alpha = m.alpha.as_ref().expect("MASK with an alpha texture is a cut-out");
    assert_eq!((alpha.channel, alpha.cutoff), (3, 0.3));
    assert!(
        !s.warnings.iter().any(|w| w.contains("extensions ignored")),
        "{:?}",
        s.warnings
    );
}
