//! Textures placed on surfaces: coordinate transforms, the albedo map's
//! lookup at a point of a mesh, cut-outs and normal (or height) maps.

use std::sync::Arc;

use glam::{Vec2, Vec3, Vec4};

use super::{Texture, Wrap};
use crate::scene::{MAX_ALBEDO, Material, Mesh};

/// An affine map of texture coordinates: `uv' = m · uv + offset`, `m`
/// by columns (glTF's `KHR_texture_transform`, Mitsuba's `to_uv`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UvTransform {
    /// The columns of the linear part.
    pub columns: [Vec2; 2],
    /// The translation.
    pub offset: Vec2,
}

impl Default for UvTransform {
    fn default() -> Self {
        Self::IDENTITY
    }
}

impl UvTransform {
    /// Coordinates unchanged.
    pub const IDENTITY: UvTransform = UvTransform {
        columns: [Vec2::X, Vec2::Y],
        offset: Vec2::ZERO,
    };

    /// `KHR_texture_transform`: scale, then rotate by `rotation` radians
    /// (counter-clockwise in the image, `v` down), then offset.
    pub fn offset_rotation_scale(offset: Vec2, rotation: f32, scale: Vec2) -> UvTransform {
        let (s, c) = rotation.sin_cos();
        UvTransform {
            columns: [Vec2::new(c, -s) * scale.x, Vec2::new(s, c) * scale.y],
            offset,
        }
    }

    /// `self` after `first`.
    pub fn after(&self, first: &UvTransform) -> UvTransform {
        UvTransform {
            columns: [self.linear(first.columns[0]), self.linear(first.columns[1])],
            offset: self.apply(first.offset),
        }
    }

    #[inline(always)]
    fn linear(&self, v: Vec2) -> Vec2 {
        self.columns[0] * v.x + self.columns[1] * v.y
    }

    /// Whether every entry is a finite number.
    pub fn is_finite(&self) -> bool {
        self.columns.iter().all(|c| c.is_finite()) && self.offset.is_finite()
    }

    /// The map at `uv`.
    #[inline(always)]
    pub fn apply(&self, uv: Vec2) -> Vec2 {
        self.linear(uv) + self.offset
    }

    /// How much the map scales lengths (the square root of its determinant's size).
    #[inline(always)]
    fn scale(&self) -> f32 {
        let [a, b] = self.columns;
        (a.x * b.y - a.y * b.x).abs().sqrt()
    }
}

/// A texture placed on a material.
#[derive(Clone, Debug, PartialEq)]
pub struct TextureMap {
    /// The image (shared by every material that uses the file).
    pub texture: Arc<Texture>,
    /// Which of a mesh's coordinate sets ([`Mesh::uvs`]) it reads.
    pub uv_set: usize,
    /// Applied to the coordinates before the lookup.
    pub transform: UvTransform,
    /// Wrap modes along `u` and `v`.
    pub wrap: [Wrap; 2],
}

/// Where on a mesh a lookup is: a triangle, barycentric coordinates of its
/// vertices 1 and 2, and the width in scene units it stands for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePoint {
    /// Triangle index in the mesh.
    pub triangle: u32,
    /// Barycentric coordinates of vertices 1 and 2.
    pub uv: Vec2,
    /// Width of the surface the lookup stands for (a pixel's footprint, a
    /// surfel's diameter); 0 for a point.
    pub width: f32,
}

impl TextureMap {
    /// A map of `texture` on coordinate set 0, untransformed.
    pub fn new(texture: Arc<Texture>) -> TextureMap {
        TextureMap {
            texture,
            uv_set: 0,
            transform: UvTransform::IDENTITY,
            wrap: [Wrap::Repeat; 2],
        }
    }

    /// The texture at `at` on `mesh`, averaged over the width it stands
    /// for; the image's mean where the mesh has no such coordinate set.
    pub fn sample(&self, mesh: &Mesh, at: &SurfacePoint) -> Vec4 {
        let Some(uvs) = mesh.uvs.get(self.uv_set) else {
            return self.texture.mean();
        };
        let t = mesh.triangles[at.triangle as usize];
        let [a, b, c] = t.map(|i| uvs[i as usize]);
        let uv = a * (1.0 - at.uv.x - at.uv.y) + b * at.uv.x + c * at.uv.y;
        let mut texels = 0.0;
        if at.width > 0.0 {
            let [p, q, r] = t.map(|i| mesh.positions[i as usize]);
            let area = (q - p).cross(r - p).length();
            let uv_area = ((b - a).perp_dot(c - a)).abs();
            if area > 0.0 {
                let (w, h) = self.texture.size();
                // Texels per scene unit: the square root of the ratio of areas.
                let density = (uv_area * w as f32 * h as f32 / area).sqrt() * self.transform.scale();
                texels = at.width * density;
            }
        }
        self.texture.sample(self.transform.apply(uv), texels, self.wrap)
    }
}

/// A cut-out: where the map's value (one channel, times `factor`) is below
/// `cutoff`, the surface is not there for any ray, and bears no surfel.
#[derive(Clone, Debug, PartialEq)]
pub struct AlphaMap {
    /// The map.
    pub map: TextureMap,
    /// The channel read: 3 for alpha, 0 for a grey image's value.
    pub channel: usize,
    /// Multiplies the texel (glTF's base colour factor's alpha).
    pub factor: f32,
    /// Below this the surface is cut out.
    pub cutoff: f32,
}

impl AlphaMap {
    /// Whether the surface is there at `at` (a point lookup: the image
    /// itself, bilinear).
    #[inline]
    pub fn opaque(&self, mesh: &Mesh, triangle: u32, uv: Vec2) -> bool {
        let at = SurfacePoint {
            triangle,
            uv,
            width: 0.0,
        };
        self.passes(self.map.sample(mesh, &at))
    }

    /// Whether the surface is there at texture coordinates `uv` (of the
    /// map's set, before its transform).
    #[inline]
    pub fn opaque_at_uv(&self, uv: Vec2) -> bool {
        let m = &self.map;
        self.passes(m.texture.sample(m.transform.apply(uv), 0.0, m.wrap))
    }

    #[inline(always)]
    fn passes(&self, texel: Vec4) -> bool {
        texel[self.channel] * self.factor >= self.cutoff
    }
}

/// What a [`NormalMap`]'s image holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Relief {
    /// Tangent-space normals, `n / 2 + 1/2` in red, green, blue: `x` along
    /// increasing `u`, `y` up the image (decreasing `v`), as glTF and most
    /// tools write them. `scale` multiplies `x` and `y`.
    Normals,
    /// Heights (red): the surface displaced along its normal by `scale × h`
    /// scene units (Mitsuba's `bumpmap`, OBJ's `bump`).
    Heights,
}

/// A map that tilts the shading normal.
#[derive(Clone, Debug, PartialEq)]
pub struct NormalMap {
    /// The map (linear data).
    pub map: TextureMap,
    /// What it holds.
    pub relief: Relief,
    /// Strength, see [`Relief`].
    pub scale: f32,
}

impl NormalMap {
    /// The shading normal `n` (unit, the interpolated one) tilted by the map
    /// at `at`; `n` itself where the triangle has no usable tangent frame.
    pub fn apply(&self, mesh: &Mesh, at: &SurfacePoint, n: Vec3) -> Vec3 {
        let Some(uvs) = mesh.uvs.get(self.map.uv_set) else {
            return n;
        };
        let t = mesh.triangles[at.triangle as usize];
        let [p, q, r] = t.map(|i| mesh.positions[i as usize]);
        let [a, b, c] = t.map(|i| self.map.transform.apply(uvs[i as usize]));
        let (e1, e2) = (q - p, r - p);
        let (d1, d2) = (b - a, c - a);
        let det = d1.perp_dot(d2);
        if det == 0.0 || !det.is_finite() {
            return n;
        }
        let dpdu = (e1 * d2.y - e2 * d1.y) / det;
        let dpdv = (e2 * d1.x - e1 * d2.x) / det;
        let tilted = match self.relief {
            Relief::Normals => {
                let Some(tangent) = (dpdu - n * n.dot(dpdu)).try_normalize() else {
                    return n;
                };
                // The map's y is up the image: along −∂p/∂v.
                let side = n.cross(tangent);
                let bitangent = if side.dot(dpdv) > 0.0 { -side } else { side };
                let m = self.map.sample(mesh, at);
                let x = (m.x * 2.0 - 1.0) * self.scale;
                let y = (m.y * 2.0 - 1.0) * self.scale;
                let z = m.z * 2.0 - 1.0;
                tangent * x + bitangent * y + n * z
            }
            Relief::Heights => {
                // Central differences a texel apart in the (transformed) coordinates.
                let uv = a * (1.0 - at.uv.x - at.uv.y) + b * at.uv.x + c * at.uv.y;
                let (w, h) = self.map.texture.size();
                let (du, dv) = (1.0 / w as f32, 1.0 / h as f32);
                let height = |o: Vec2| self.map.texture.sample(uv + o, 0.0, self.map.wrap).x;
                let hu = (height(Vec2::new(du, 0.0)) - height(Vec2::new(-du, 0.0))) / (2.0 * du);
                let hv = (height(Vec2::new(0.0, dv)) - height(Vec2::new(0.0, -dv))) / (2.0 * dv);
                // The displaced surface's tangents, their cross product on n's side.
                let tu = dpdu + n * (self.scale * hu);
                let tv = dpdv + n * (self.scale * hv);
                let m = tu.cross(tv);
                if m.dot(n) < 0.0 { -m } else { m }
            }
        };
        tilted.try_normalize().unwrap_or(n)
    }
}

/// A material's textures at a point.
impl Material {
    /// The albedo at `at` on `mesh`: `albedo` times the map's colour there
    /// (averaged over the width `at` stands for), at most [`MAX_ALBEDO`].
    #[inline]
    pub fn albedo_at(&self, mesh: &Mesh, at: &SurfacePoint) -> Vec3 {
        match &self.albedo_map {
            None => self.albedo,
            Some(map) => {
                let a = self.albedo * map.sample(mesh, at).truncate();
                // A non-finite lookup stays as it is, for the renderer's
                // checks to name (`min` would turn a NaN into the cap).
                if a.is_finite() {
                    a.min(Vec3::splat(MAX_ALBEDO))
                } else {
                    a
                }
            }
        }
    }

    /// Whether the surface is there at `at` (no cut-out, or its alpha high enough).
    #[inline]
    pub fn opaque_at(&self, mesh: &Mesh, triangle: u32, uv: Vec2) -> bool {
        self.alpha.as_ref().is_none_or(|a| a.opaque(mesh, triangle, uv))
    }

    /// Whether anything varies over the surface: a texture of any kind.
    pub fn is_textured(&self) -> bool {
        self.albedo_map.is_some() || self.alpha.is_some() || self.normal_map.is_some()
    }
}
