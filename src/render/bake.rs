//! The surfels and their tree as a render needs them: built (surfels with
//! direct light, the environment's light and extra bounces gathered at
//! them, the tree), or read from a tree file baked earlier ([`bake_tree`],
//! `pbgi bake`) after checking that it was baked from this scene with these
//! settings.

use std::sync::Arc;
use std::time::Instant;

use glam::Vec3;

use super::bounces::{SkyRays, gather_bounce, gather_sky};
use super::light::Lights;
use super::options::{Gathers, RenderOptions};
use super::output::{PreTimings, Progress, RenderError, Stage};
use super::surfel_groups::{Groups, group_size};
use super::surfels::{BakeOptions, bake_with_progress};
use super::trace::Tracer;
use crate::cut::SchemeChoice;
use crate::environment::Environment;
use crate::error::Error;
use crate::gather::{GatherOptions, ReceiverOrder};
use crate::points::{PointCloud, Surfel};
use crate::scene::{Light, Scene};
use crate::simd::LANES;
use crate::tree::file::Fnv1a;
use crate::tree::{BakeRecord, Tree, TreeFile};

/// The gather options of a render: its cut, microbuffer and environment,
/// over coherent packets (screen tiles; surfels in tree order).
pub(super) fn gather_options(
    opts: &RenderOptions,
    scheme: SchemeChoice,
    environment: &Option<Arc<Environment>>,
) -> GatherOptions {
    GatherOptions {
        cut: opts.cut,
        microbuffer: opts.microbuffer,
        scheme,
        order: ReceiverOrder::Coherent,
        environment: environment.clone(),
        // The renderer's pool.
        threads: None,
    }
}

/// What the open part of a receiver's hemisphere sees (none in AO mode).
pub(super) fn environment(scene: &Scene, opts: &RenderOptions) -> Option<Arc<Environment>> {
    if opts.ao {
        None
    } else {
        scene.environment.clone().map(Arc::new)
    }
}

/// Whether the render gathers at all: the environment's light arrives
/// through the gather, so it needs the surfels (as occluders) even without
/// bounces.
pub(super) fn needs_points(opts: &RenderOptions, environment: &Option<Arc<Environment>>) -> bool {
    opts.ao || opts.bounces > 0 || environment.is_some()
}

/// A gather threshold: finite, at least 0.
fn check_threshold(threshold: f32) -> Result<(), RenderError> {
    if !(threshold.is_finite() && threshold >= 0.0) {
        return Err(Error::InvalidParameter {
            name: "gather threshold",
            value: threshold.to_string(),
            expected: "a finite relative change of at least 0",
        }
        .into());
    }
    Ok(())
}

/// Checks the scene and the options a render and a bake share.
pub(super) fn check_options(scene: &Scene, opts: &RenderOptions) -> Result<(), RenderError> {
    scene.validate()?;
    if opts.spp == 0 {
        return Err(Error::InvalidParameter {
            name: "spp",
            value: "0".into(),
            expected: "at least 1",
        }
        .into());
    }
    if let Some(n @ (0 | 1)) = opts.first_samples {
        return Err(Error::InvalidParameter {
            name: "first samples",
            value: n.to_string(),
            expected: "at least 2 (a pixel's samples are compared)",
        }
        .into());
    }
    if let Gathers::Sparse { spacing, threshold } = opts.gathers {
        if !(spacing.is_power_of_two() && spacing <= 64) {
            return Err(Error::InvalidParameter {
                name: "gather spacing",
                value: spacing.to_string(),
                expected: "a power of two from 1 to 64 pixels",
            }
            .into());
        }
        check_threshold(threshold)?;
    }
    if let Gathers::Cache { threshold } = opts.gathers {
        check_threshold(threshold)?;
    }
    opts.surfel_density(scene)?;
    crate::microbuffer::MicroBuffer::new(opts.microbuffer)?;
    crate::microbuffer::MicroBuffer::new(opts.glossy_microbuffer)?;
    for (name, v) in [
        ("glossy_max_solid_angle", opts.glossy_max_solid_angle),
        ("glossy_light_offset", opts.glossy_light_offset),
        ("glossy_cache_roughness", opts.glossy_cache_roughness),
    ] {
        if !(v.is_finite() && v >= 0.0) {
            return Err(Error::InvalidParameter {
                name,
                value: v.to_string(),
                expected: "a finite number ≥ 0",
            }
            .into());
        }
    }
    if let Some(crop) = opts.crop {
        crop.within(scene.camera.width, scene.camera.height)?;
    }
    Ok(())
}

/// The stages [`build`] tells its [`Progress`] of.
const TRACER: &str = "ray-tracing BVH";
pub(super) const SURFELS: &str = "surfels + direct light";
pub(super) const SKY: &str = "environment at surfels";
pub(super) const BOUNCE: &str = "bounce at surfels";
pub(super) const TREE: &str = "tree";

/// The ray queries and the lights of `scene`, reported as one stage.
pub(super) fn tracer_and_lights(scene: &Scene, progress: &Progress) -> (Tracer, Lights) {
    progress(TRACER, 0, 1);
    let tracer = Tracer::new(scene);
    let lights = Lights::new(scene);
    progress(TRACER, 1, 1);
    (tracer, lights)
}

/// Surfels with direct light, the environment's light and extra bounces
/// gathered at them, and their tree (an empty cloud when the render needs
/// none); `stages` gets what ran and what was left out, `times` the seconds
/// of each part, `progress` where it is.
pub(super) fn build(
    scene: &Scene,
    opts: &RenderOptions,
    tracer: &Tracer,
    lights: &Lights,
    stages: &mut Vec<Stage>,
    times: &mut PreTimings,
    progress: &Progress,
) -> Result<(PointCloud, Tree), Error> {
    let environment = environment(scene, opts);
    if !needs_points(opts, &environment) {
        stages.push(Stage {
            name: "surfels, tree and cuts",
            skipped: Some("--bounces 0: direct light only".into()),
        });
        // Empty, at the asked precision, so that a file baked so says it.
        let none = PointCloud::default();
        let tree = Tree::build_with(&none, opts.tree_precision);
        return Ok((none, tree));
    }
    let bake_opts = BakeOptions {
        density: opts.surfel_density(scene)?,
        light_samples: if opts.ao { 0 } else { opts.surfel_light_samples },
        seed: opts.seed,
        drop_buried: opts.drop_buried,
    };
    let clock = Instant::now();
    let baked = bake_with_progress(scene, tracer, lights, &bake_opts, &|d, n| progress(SURFELS, d, n))?;
    times.surfels = clock.elapsed().as_secs_f64();
    stages.push(Stage {
        name: "surfels + direct light at surfels",
        skipped: opts.ao.then(|| "AO mode: surfels carry no radiance".to_string()),
    });
    let tree = |cloud: &PointCloud, times: &mut PreTimings| {
        let clock = Instant::now();
        progress(TREE, 0, 1);
        let tree = Tree::build_with(cloud, opts.tree_precision);
        progress(TREE, 1, 1);
        times.tree += clock.elapsed().as_secs_f64();
        tree
    };
    let scheme = opts.scheme.resolve(LANES);
    let gopts = gather_options(opts, SchemeChoice::Fixed(scheme), &environment);
    let direct: Vec<Vec3> = baked.cloud.surfels().iter().map(|s| s.radiance).collect();
    let group = group_size(direct.len(), opts.surfel_gathers);
    // The groups depend on the surfels' places and normals alone: the same
    // for the sky and every bounce, made once.
    let mut groups = None;
    let mut cloud = baked.cloud;
    if environment.is_some() {
        // The environment's light at the surfels, gathered with the
        // surfels as occluders only (no radiance of their own): with
        // no bounce, the receivers see only that occlusion.
        let dark = PointCloud::new(
            cloud
                .surfels()
                .iter()
                .map(|s| Surfel {
                    radiance: Vec3::ZERO,
                    ..*s
                })
                .collect(),
        )?;
        if opts.bounces == 0 {
            cloud = dark;
        } else {
            // Which directions see the sky, by rays (`microbuffer::open`):
            // the dark tree, where one is built, only groups the surfels.
            let dark_tree = Groups::need_tree(group).then(|| tree(&dark, times));
            let clock = Instant::now();
            // The stage starts with its groups, before their count is known.
            progress(SKY, 0, 0);
            let sky_groups = groups.insert(Groups::new(dark.surfels(), group, dark_tree.as_ref()));
            cloud = gather_sky(
                &dark,
                &direct,
                &baked.albedo,
                sky_groups,
                &gopts,
                &SkyRays(tracer),
                &|d, n| progress(SKY, d, n),
            )?;
            times.gathers += clock.elapsed().as_secs_f64();
            // `direct` stays the sun's and the lights' alone: each extra
            // bounce below gathers the sky again with the surfels' light
            // (taken as part of the direct light, the sky's first bounce
            // came in twice: the atrium at `--bounces 2` +8.1 %).
        }
    }
    let mut built = tree(&cloud, times);
    for _ in 1..opts.bounces.max(1) {
        let clock = Instant::now();
        let rays = SkyRays(tracer);
        let groups = groups.get_or_insert_with(|| Groups::new(cloud.surfels(), group, Some(&built)));
        cloud = gather_bounce(
            &cloud,
            &direct,
            &baked.albedo,
            &built,
            groups,
            &gopts,
            Some(&rays),
            &|d, n| progress(BOUNCE, d, n),
        )?;
        times.gathers += clock.elapsed().as_secs_f64();
        built = tree(&cloud, times);
    }
    stages.push(Stage {
        name: "extra bounces gathered at surfels",
        skipped: (opts.bounces <= 1).then(|| format!("--bounces {} needs none", opts.bounces)),
    });
    Ok((cloud, built))
}

/// The stages of a render whose surfels and tree were loaded.
pub(super) fn loaded_stages(opts: &RenderOptions, file: &TreeFile, stages: &mut Vec<Stage>) {
    if file.cloud().is_empty() {
        stages.push(Stage {
            name: "surfels, tree and cuts",
            skipped: Some("--bounces 0: direct light only".into()),
        });
        return;
    }
    stages.push(Stage {
        name: "surfels + direct light at surfels",
        skipped: Some("loaded with the tree".into()),
    });
    stages.push(Stage {
        name: "extra bounces gathered at surfels",
        skipped: Some(if opts.bounces <= 1 {
            format!("--bounces {} needs none", opts.bounces)
        } else {
            "baked into the loaded surfels".into()
        }),
    });
}

/// What the surfels' light of a render with `opts` depends on.
pub fn bake_record(scene: &Scene, opts: &RenderOptions) -> BakeRecord {
    let environment = environment(scene, opts);
    let points = needs_points(opts, &environment);
    let gathered = points && (opts.bounces >= 2 || (environment.is_some() && opts.bounces >= 1));
    BakeRecord {
        scene: scene_hash(scene),
        seed: opts.seed,
        // The density the surfels were made at (a budget's, over this scene;
        // an invalid budget is refused by `check_options` first).
        density: opts.surfel_density(scene).unwrap_or(opts.density),
        light_samples: if opts.ao { 0 } else { opts.surfel_light_samples },
        bounces: opts.bounces,
        ao: opts.ao,
        drop_buried: opts.drop_buried,
        gathered,
        max_solid_angle: if gathered { opts.cut.max_solid_angle } else { 0.0 },
        microbuffer: if gathered { opts.microbuffer as u32 } else { 0 },
    }
}

/// Refuses a tree whose record differs from the one this render would bake.
pub(super) fn check_record(baked: &BakeRecord, render: &BakeRecord) -> Result<(), RenderError> {
    let pairs: [(&'static str, String, String); 10] = [
        (
            "scene (hash of its geometry, materials, lights and environment)",
            format!("{:016x}", baked.scene),
            format!("{:016x}", render.scene),
        ),
        ("--bounces", baked.bounces.to_string(), render.bounces.to_string()),
        ("--ao", baked.ao.to_string(), render.ao.to_string()),
        (
            "--buried-surfels (dropped)",
            baked.drop_buried.to_string(),
            render.drop_buried.to_string(),
        ),
        ("--density", baked.density.to_string(), render.density.to_string()),
        ("seed", baked.seed.to_string(), render.seed.to_string()),
        (
            "light samples per surfel",
            baked.light_samples.to_string(),
            render.light_samples.to_string(),
        ),
        (
            "gathers at the surfels (extra bounces, environment)",
            baked.gathered.to_string(),
            render.gathered.to_string(),
        ),
        (
            "--max-solid-angle (of the gathers at the surfels)",
            baked.max_solid_angle.to_string(),
            render.max_solid_angle.to_string(),
        ),
        (
            "--microbuffer (of the gathers at the surfels)",
            baked.microbuffer.to_string(),
            render.microbuffer.to_string(),
        ),
    ];
    // Floats compare by their text, which round-trips: equal text, equal bits.
    match pairs.into_iter().find(|(_, b, r)| b != r) {
        Some((setting, baked, render)) => Err(RenderError::TreeMismatch {
            setting,
            baked,
            render,
        }),
        None => Ok(()),
    }
}

/// A hash of everything in `scene` the surfels' light depends on: meshes,
/// materials, lights, environment (not the names, the camera or the
/// warnings, so one baked tree serves any view).
pub fn scene_hash(scene: &Scene) -> u64 {
    let mut h = Fnv1a::default();
    let u32s = |h: &mut Fnv1a, v: &[u32]| v.iter().for_each(|x| h.write(&x.to_le_bytes()));
    let f32s = |h: &mut Fnv1a, v: &[f32]| v.iter().for_each(|x| h.write(&x.to_bits().to_le_bytes()));
    let vec3s = |h: &mut Fnv1a, v: &[Vec3]| v.iter().for_each(|p| f32s(h, &p.to_array()));
    u32s(&mut h, &[scene.meshes.len() as u32]);
    for m in &scene.meshes {
        u32s(
            &mut h,
            &[
                m.positions.len() as u32,
                m.triangles.len() as u32,
                m.material as u32,
            ],
        );
        vec3s(&mut h, &m.positions);
        m.triangles.iter().for_each(|t| u32s(&mut h, t));
        match &m.normals {
            Some(n) => {
                u32s(&mut h, &[1]);
                vec3s(&mut h, n);
            }
            None => u32s(&mut h, &[0]),
        }
        vec3s(&mut h, &[m.emission.unwrap_or(Vec3::splat(-1.0))]);
        // Only when present: an untextured scene hashes as it always did.
        for uvs in &m.uvs {
            uvs.iter().for_each(|uv| f32s(&mut h, &uv.to_array()));
        }
    }
    u32s(&mut h, &[scene.materials.len() as u32]);
    for m in &scene.materials {
        vec3s(&mut h, &[m.albedo]);
        let g = m.glossy.map_or([-1.0; 4], |g| {
            [g.specular.x, g.specular.y, g.specular.z, g.roughness]
        });
        let b = m.bump.map_or([-1.0; 2], |b| [b.amplitude, b.frequency]);
        f32s(&mut h, &g);
        f32s(&mut h, &b);
        u32s(&mut h, &[m.two_sided as u32]);
        let maps = [
            m.albedo_map.as_ref().map(|t| (t, 0, [0.0; 2])),
            m.alpha
                .as_ref()
                .map(|a| (&a.map, 1 + a.channel as u32, [a.factor, a.cutoff])),
            m.normal_map
                .as_ref()
                .map(|n| (&n.map, 5 + n.relief as u32, [n.scale, 0.0])),
        ];
        for (map, kind, values) in maps.into_iter().flatten() {
            let t = &map.transform;
            u32s(
                &mut h,
                &[kind, map.uv_set as u32, map.wrap[0] as u32, map.wrap[1] as u32],
            );
            f32s(
                &mut h,
                &[t.columns[0].x, t.columns[0].y, t.columns[1].x, t.columns[1].y],
            );
            f32s(&mut h, &[t.offset.x, t.offset.y, values[0], values[1]]);
            h.write(&map.texture.fingerprint().to_le_bytes());
        }
    }
    u32s(&mut h, &[scene.lights.len() as u32]);
    for l in &scene.lights {
        let (kind, a, b) = match *l {
            Light::Point { position, intensity } => (0, position, intensity),
            Light::Directional {
                direction,
                irradiance,
            } => (1, direction, irradiance),
        };
        u32s(&mut h, &[kind]);
        vec3s(&mut h, &[a, b]);
    }
    match &scene.environment {
        None => u32s(&mut h, &[0]),
        Some(env) => {
            let (w, ht, texels) = env.texels();
            u32s(&mut h, &[1, w as u32, ht as u32]);
            vec3s(&mut h, texels);
        }
    }
    h.0
}

/// Bakes the surfels and their tree as a render of `scene` with `opts`
/// would build them, with the record a render checks them against.
///
/// ```
/// use pbgi::render::{Frame, RenderOptions, bake_tree};
/// use pbgi::scene::builtin::cornell_box;
/// use pbgi::tree::TreeFile;
///
/// let mut scene = cornell_box();
/// (scene.camera.width, scene.camera.height) = (8, 8);
/// let opts = RenderOptions { spp: 1, density: 50.0, ..Default::default() };
/// let mut bytes = Vec::new();
/// bake_tree(&scene, &opts)?.save(&mut bytes)?;
///
/// let file = TreeFile::load(bytes.as_slice())?;
/// let loaded = Frame::with_tree(&scene, &opts, file)?.render(&|_, _| {})?;
/// let built = Frame::prepare(&scene, &opts)?.render(&|_, _| {})?;
/// assert_eq!(loaded.image, built.image); // bit for bit
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn bake_tree(scene: &Scene, opts: &RenderOptions) -> Result<TreeFile, RenderError> {
    bake_tree_with_progress(scene, opts, &|_, _, _| {})
}

/// [`bake_tree`], telling `progress` where it is (for a progress bar).
pub fn bake_tree_with_progress(
    scene: &Scene,
    opts: &RenderOptions,
    progress: &Progress,
) -> Result<TreeFile, RenderError> {
    check_options(scene, opts)?;
    let (tracer, lights) = tracer_and_lights(scene, progress);
    let (cloud, tree) = build(
        scene,
        opts,
        &tracer,
        &lights,
        &mut Vec::new(),
        &mut PreTimings::default(),
        progress,
    )?;
    TreeFile::new(cloud, tree, bake_record(scene, opts))
        .map_err(|e| RenderError::Check(format!("baked tree: {e}")))
}
