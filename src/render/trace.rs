//! Ray queries against the scene's triangles through a compressed wide BVH
//! (obvhs): closest hits for camera rays, occlusion for shadow rays. A
//! material's cut-out is tested at each candidate hit: every ray passes
//! through its holes.

use std::time::Duration;

use glam::{Vec2, Vec3};
use obvhs::BvhBuildParams;
use obvhs::cwbvh::CwBvh;
use obvhs::cwbvh::builder::build_cwbvh_from_tris;
use obvhs::ray::{Ray, RayHit};
use obvhs::triangle::Triangle;

use super::edged::edged;
use crate::microbuffer::Sight;
use crate::scene::{AlphaMap, Scene};

/// A ray's closest hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Distance along the (unit) direction.
    pub t: f32,
    /// Mesh index in the scene.
    pub mesh: u32,
    /// Triangle index in the mesh.
    pub triangle: u32,
    /// Barycentric coordinates of vertices 1 and 2.
    pub uv: Vec2,
    /// Unit geometric normal of the front face (counter-clockwise winding).
    pub geometric_normal: Vec3,
}

/// No cut-out.
const NONE: u32 = u32::MAX;

/// A triangle whose material cuts out: its vertices' texture coordinates
/// and which cut-out.
struct CutOut {
    uvs: [Vec2; 3],
    alpha: u32,
}

/// The scene's triangles in a BVH.
pub struct Tracer {
    bvh: Option<CwBvh>,
    /// Triangles in BVH primitive order.
    triangles: Vec<Triangle>,
    /// (mesh, triangle) of each entry of `triangles`.
    ids: Vec<(u32, u32)>,
    /// Per entry of `triangles`, its index in `cutouts` (`NONE`: opaque);
    /// empty when nothing is cut out.
    cutout_of: Vec<u32>,
    /// The triangles of cut-out materials: their texture coordinates and cut-out.
    cutouts: Vec<CutOut>,
    alphas: Vec<AlphaMap>,
    /// Per entry of `triangles`, whether an opening may lie beside it
    /// ([`edged`]): where it does not, a ray meeting it edge-on is
    /// [`Sight::Smooth`].
    edged: Vec<bool>,
    /// Offset that moves ray origins off their surface, relative to the scene size.
    epsilon: f32,
}

impl Tracer {
    /// Builds the BVH over every triangle of `scene`.
    pub fn new(scene: &Scene) -> Tracer {
        let mut triangles = Vec::with_capacity(scene.triangle_count());
        let mut ids = Vec::with_capacity(scene.triangle_count());
        let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
        let cut = scene.materials.iter().any(|m| m.alpha.is_some());
        let mut alphas: Vec<AlphaMap> = Vec::new();
        let mut alpha_of = vec![NONE; scene.materials.len()];
        let (mut cutout_of, mut cutouts) = (Vec::new(), Vec::new());
        for (mi, mesh) in scene.meshes.iter().enumerate() {
            let alpha = scene.materials[mesh.material].alpha.as_ref();
            let uvs = alpha.and_then(|a| mesh.uvs.get(a.map.uv_set));
            if let Some(a) = alpha
                && alpha_of[mesh.material] == NONE
            {
                alpha_of[mesh.material] = alphas.len() as u32;
                alphas.push(a.clone());
            }
            for (ti, t) in mesh.triangles.iter().enumerate() {
                if let Some(a) = alpha
                    && uvs.is_none()
                    && !a.opaque(mesh, ti as u32, Vec2::ZERO)
                {
                    continue; // without coordinates, the texture's mean cuts it out whole
                }
                if cut {
                    cutout_of.push(match uvs {
                        Some(uvs) => {
                            cutouts.push(CutOut {
                                uvs: t.map(|i| uvs[i as usize]),
                                alpha: alpha_of[mesh.material],
                            });
                            cutouts.len() as u32 - 1
                        }
                        None => NONE,
                    });
                }
                let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
                lo = lo.min(a).min(b).min(c);
                hi = hi.max(a).max(b).max(c);
                triangles.push(Triangle {
                    v0: a.into(),
                    v1: b.into(),
                    v2: c.into(),
                });
                ids.push((mi as u32, ti as u32));
            }
        }
        let extent = if triangles.is_empty() {
            1.0
        } else {
            (hi - lo).max_element().max(f32::MIN_POSITIVE)
        };
        if triangles.is_empty() {
            return Tracer {
                bvh: None,
                triangles,
                ids,
                cutout_of,
                cutouts,
                alphas,
                edged: Vec::new(),
                epsilon: 1e-4,
            };
        }
        let corners: Vec<[Vec3; 3]> = triangles
            .iter()
            .map(|t| [t.v0.into(), t.v1.into(), t.v2.into()])
            .collect();
        let marks = edged(&corners, |t| cutout_of.get(t).is_some_and(|&c| c != NONE));
        let bvh = build_cwbvh_from_tris(
            &triangles,
            BvhBuildParams::medium_build(),
            &mut Duration::default(),
        );
        // Reorder the triangles into BVH order so a hit's primitive id indexes them directly.
        let triangles: Vec<Triangle> = bvh
            .primitive_indices
            .iter()
            .map(|&i| triangles[i as usize])
            .collect();
        let ids = bvh.primitive_indices.iter().map(|&i| ids[i as usize]).collect();
        let cutout_of = if cut {
            bvh.primitive_indices
                .iter()
                .map(|&i| cutout_of[i as usize])
                .collect()
        } else {
            Vec::new()
        };
        let edged = bvh.primitive_indices.iter().map(|&i| marks[i as usize]).collect();
        Tracer {
            bvh: Some(bvh),
            triangles,
            ids,
            cutout_of,
            cutouts,
            alphas,
            edged,
            epsilon: 1e-5 * extent,
        }
    }

    /// The distance to entry `id` along `ray` (∞: a miss, or a cut-out there).
    #[inline(always)]
    fn distance(&self, id: usize, ray: &Ray) -> f32 {
        let (t, uv) = intersect(&self.triangles[id], ray);
        if t.is_finite()
            && let Some(&c) = self.cutout_of.get(id)
            && c != NONE
        {
            let c = &self.cutouts[c as usize];
            let at = c.uvs[0] * (1.0 - uv.x - uv.y) + c.uvs[1] * uv.x + c.uvs[2] * uv.y;
            if !self.alphas[c.alpha as usize].opaque_at_uv(at) {
                return f32::INFINITY;
            }
        }
        t
    }

    /// Distance by which secondary rays leave a surface.
    pub fn epsilon(&self) -> f32 {
        self.epsilon
    }

    /// The closest hit along `origin + t·dir`, `t ∈ (0, t_max)`; `dir` unit.
    pub fn closest(&self, origin: Vec3, dir: Vec3, t_max: f32) -> Option<Hit> {
        let bvh = self.bvh.as_ref()?;
        let ray = Ray::new(origin.into(), positive_zeros(dir).into(), 0.0, t_max);
        let mut hit = RayHit::none();
        if !bvh.ray_traverse(ray, &mut hit, |r, id| self.distance(id, r)) {
            return None;
        }
        let id = hit.primitive_id as usize;
        let tri = &self.triangles[id];
        // The traversal kept the distance; the barycentrics come from the
        // same test on the same ray.
        let (_, uv) = intersect(tri, &ray);
        let (mesh, triangle) = self.ids[id];
        Some(Hit {
            t: hit.t,
            mesh,
            triangle,
            uv,
            geometric_normal: geometric_normal(tri),
        })
    }

    /// Whether the ray along `origin + t·dir` (`dir` unit) meets a back
    /// face first, as a ray from inside a solid does. A face lying against
    /// another (a slab under a wall) puts a front and a back face at one
    /// distance, found in either order: a back face within [`epsilon`]
    /// of the nearest front face counts as first.
    ///
    /// [`epsilon`]: Self::epsilon
    pub fn meets_back_face(&self, origin: Vec3, dir: Vec3) -> bool {
        let Some(bvh) = self.bvh.as_ref() else {
            return false;
        };
        let ray = Ray::new(origin.into(), positive_zeros(dir).into(), 0.0, f32::INFINITY);
        let (mut front, mut back) = (f32::INFINITY, f32::INFINITY);
        let tie = self.epsilon;
        // Each hit shortens the ray to a tie beyond it, so that the faces
        // within a tie of the nearest are all met.
        bvh.ray_traverse(ray, &mut RayHit::none(), |r, id| {
            let t = self.distance(id, r);
            if !t.is_finite() {
                return t;
            }
            let nearest = if geometric_normal(&self.triangles[id]).dot(dir) > 0.0 {
                &mut back
            } else {
                &mut front
            };
            *nearest = nearest.min(t);
            t + tie
        });
        back.is_finite() && back <= front + tie
    }

    /// Whether the ray from a receiver at `origin` (unit `normal`) along
    /// `dir` leaves the scene: nothing at any distance (cut-outs' holes let
    /// it through), so that the environment shows there.
    pub fn escapes(&self, origin: Vec3, normal: Vec3, dir: Vec3) -> bool {
        !self.occluded(origin + normal * self.epsilon, dir, f32::INFINITY)
    }

    /// [`escapes`](Self::escapes) for each of `dirs` from one receiver, into
    /// `out`.
    pub fn escapes_each(&self, origin: Vec3, normal: Vec3, dirs: &[Vec3], out: &mut Vec<bool>) {
        out.clear();
        self.stops(origin, normal, dirs, |_, stop| out.push(stop.is_none()));
    }

    /// For each of `dirs` from one receiver, into `out`: the sky where the
    /// ray leaves the scene, else a triangle that stops it (the first one
    /// found, not always the nearest: a thick wall's far face is as
    /// edge-on as its near one) and the cosine there, or [`Sight::Smooth`]
    /// where no opening lies beside that triangle.
    pub fn sight_each(&self, origin: Vec3, normal: Vec3, dirs: &[Vec3], out: &mut Vec<Sight>) {
        out.clear();
        self.stops(origin, normal, dirs, |d, stop| {
            out.push(match stop {
                None => Sight::Sky,
                Some(id) if !self.edged[id] => Sight::Smooth,
                Some(id) => Sight::Surface {
                    cos: geometric_normal(&self.triangles[id]).dot(d).abs(),
                },
            })
        });
    }

    /// Calls `each(dir, stop)` for each of `dirs` from a receiver at
    /// `origin` (unit `normal`), in order: `stop` a triangle the ray meets,
    /// `None` where it leaves the scene. A receiver's rays mostly stop on a
    /// few large triangles (its room's walls), so the last [`BLOCKERS`]
    /// that stopped one are tried before the tree: a hit there is a hit
    /// whatever else the ray meets, so whether it escapes is as
    /// [`escapes`](Self::escapes) finds, with most traversals left out.
    fn stops(&self, origin: Vec3, normal: Vec3, dirs: &[Vec3], mut each: impl FnMut(Vec3, Option<usize>)) {
        let Some(bvh) = self.bvh.as_ref() else {
            dirs.iter().for_each(|&d| each(d, None));
            return;
        };
        let o = origin + normal * self.epsilon;
        // The latest first.
        let mut last = [usize::MAX; BLOCKERS];
        for &d in dirs {
            let ray = Ray::new(o.into(), positive_zeros(d).into(), 0.0, f32::INFINITY);
            if let Some(k) = last
                .iter()
                .position(|&id| id != usize::MAX && self.distance(id, &ray).is_finite())
            {
                last[..=k].rotate_right(1);
                each(d, Some(last[0]));
                continue;
            }
            let mut stop = None;
            bvh.ray_traverse_miss(ray, |r, id| {
                let t = self.distance(id, r);
                if t.is_finite() {
                    stop = Some(id);
                }
                t
            });
            if let Some(id) = stop {
                last.rotate_right(1);
                last[0] = id;
            }
            each(d, stop);
        }
    }

    /// Whether anything lies along `origin + t·dir`, `t ∈ (0, t_max)`.
    pub fn occluded(&self, origin: Vec3, dir: Vec3, t_max: f32) -> bool {
        let Some(bvh) = self.bvh.as_ref() else {
            return false;
        };
        let ray = Ray::new(origin.into(), positive_zeros(dir).into(), 0.0, t_max);
        !bvh.ray_traverse_miss(ray, |r, id| self.distance(id, r))
    }
}

/// How many of the triangles that last stopped a receiver's rays
/// [`Tracer::escapes_each`] tries before the tree.
const BLOCKERS: usize = 4;

/// `v` with each `-0.0` made `+0.0` (`x + 0.0` is `x` otherwise). obvhs's
/// wide BVH picks a node's slab planes by `dir < 0` (false for `-0.0`) but
/// divides by `safe_inverse(dir)`, negative for `-0.0`: a ray with a `-0.0`
/// component (an axis-aligned direction built from products with negative
/// zeros) met nothing at all.
#[inline(always)]
fn positive_zeros(v: Vec3) -> Vec3 {
    v + Vec3::ZERO
}

/// The unit normal of `tri` by its winding (zero for a degenerate one).
#[inline]
fn geometric_normal(tri: &Triangle) -> Vec3 {
    (Vec3::from(tri.v1) - Vec3::from(tri.v0))
        .cross(Vec3::from(tri.v2) - Vec3::from(tri.v0))
        .normalize_or_zero()
}

/// Möller–Trumbore, two-sided: `(t, barycentrics)`, `t = ∞` on a miss.
///
/// In `Vec3`, not obvhs's `Vec3A`: glam's NEON `Vec3A::cross` fuses a
/// multiply-subtract (`vfmsq_f32`) where SSE2 and scalar code round the
/// product first, so hits (and every pixel after them) differed in the last
/// bits between x86 and AArch64. `Vec3` is plain `*` and `-` on every target.
#[inline]
fn intersect(tri: &Triangle, ray: &Ray) -> (f32, Vec2) {
    let v0 = Vec3::from(tri.v0);
    let (dir, origin) = (Vec3::from(ray.direction), Vec3::from(ray.origin));
    let e1 = Vec3::from(tri.v1) - v0;
    let e2 = Vec3::from(tri.v2) - v0;
    let p = dir.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-20 {
        return (f32::INFINITY, Vec2::ZERO);
    }
    let inv = 1.0 / det;
    let s = origin - v0;
    let u = s.dot(p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return (f32::INFINITY, Vec2::ZERO);
    }
    let q = s.cross(e1);
    let v = dir.dot(q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return (f32::INFINITY, Vec2::ZERO);
    }
    let t = e2.dot(q) * inv;
    if t > ray.tmin && t < ray.tmax {
        (t, Vec2::new(u, v))
    } else {
        (f32::INFINITY, Vec2::ZERO)
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::Tracer;
    use crate::microbuffer::Sight;
    use crate::scene::builtin::cornell_box;

    /// A receiver's batch of rays, tried first against the triangles that
    /// stopped the last ones, escapes exactly where each ray alone does.
    #[test]
    fn a_batch_of_rays_escapes_where_each_ray_alone_does() {
        let tracer = Tracer::new(&cornell_box());
        let (origin, normal) = (Vec3::new(0.1, 0.5, 0.0), Vec3::Y);
        // Fibonacci directions over the sphere: the box's walls and blocks,
        // and its open front.
        let n = 4000;
        let dirs: Vec<Vec3> = (0..n)
            .map(|i| {
                let z = 1.0 - (2 * i + 1) as f32 / n as f32;
                let phi = i as f32 * 2.399_963;
                let r = (1.0 - z * z).sqrt();
                Vec3::new(r * phi.cos(), r * phi.sin(), z)
            })
            .collect();
        let alone: Vec<bool> = dirs.iter().map(|&d| tracer.escapes(origin, normal, d)).collect();
        let escaping = alone.iter().filter(|&&e| e).count();
        assert!(escaping > n / 20 && escaping < n / 2, "{escaping} of {n} escape");
        let mut batch = Vec::new();
        tracer.escapes_each(origin, normal, &dirs, &mut batch);
        assert_eq!(batch, alone);
        let mut sight = Vec::new();
        tracer.sight_each(origin, normal, &dirs, &mut sight);
        for (s, &e) in sight.iter().zip(&alone) {
            match *s {
                Sight::Sky => assert!(e),
                Sight::Surface { cos } => assert!(!e && (0.0..=1.0).contains(&cos), "{s:?}"),
                Sight::Smooth => panic!("the box's walls are edged"),
            }
        }
    }

    /// A ray along −z towards the Cornell box's back wall hits it whatever
    /// the signs of its zero components (obvhs's wide BVH missed
    /// everything with a `-0.0` in the direction).
    #[test]
    fn a_direction_with_negative_zeros_hits() {
        let tracer = Tracer::new(&cornell_box());
        let origin = Vec3::new(0.1, 0.5, 0.0);
        for dir in [
            Vec3::new(0.0, 0.0, -1.0),
            Vec3::new(-0.0, 0.0, -1.0),
            Vec3::new(0.0, -0.0, -1.0),
            -Vec3::Z,
        ] {
            let hit = tracer.closest(origin, dir, 10.0);
            assert_eq!(hit.map(|h| h.t), Some(1.0), "{dir:?}");
            assert!(tracer.occluded(origin, dir, 10.0), "{dir:?}");
        }
    }
}
