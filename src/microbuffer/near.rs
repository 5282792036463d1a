//! The near field: what a receiver sees within a few surfel radii, by rays.
//!
//! A disk stands for its surface well from afar, and badly from within its
//! own size: at a receiver a few millimetres above a sunlit ledge, disks of
//! the ledge buried under the wall (unlit, their centres in shadow) poke out
//! from under it, and lit disks overhang the ledge's edge. There 77–93 % of
//! the irradiance comes from within two surfel radii, and the gather was off
//! by −93 to +141 % at every Ω and N (docs/lab/BENCHMARKS.md, "Sponza's error
//! floor"). So where a receiver's cut holds a leaf of another surface within
//! [`NEAR_RADII`] of its own radius, the leaves that near are left out and
//! each pixel casts one ray through its centre, up to one radius further: a
//! hit makes the pixel opaque with the radiance the caller's
//! [`NearField`] finds there (the renderer: direct light at the hit, what
//! the surfels carry with one bounce). Pixels whose ray hits nothing
//! compose as before, so the far field is unchanged, and a receiver without
//! such a leaf keeps its bits.

use glam::Vec3;

use super::table::Table;
use crate::tree::{NodeId, Tree};

/// A leaf nearer to the receiver than this many of its radii is drawn by
/// rays.
pub const NEAR_RADII: f32 = 2.0;

/// What lies along short rays from a receiver: the scene itself, which the
/// surfels only stand for. Implemented by the renderer over its ray tracer
/// (`render::NearRays`).
///
/// ```
/// use glam::Vec3;
/// use pbgi::gather::{Gather, GatherOptions};
/// use pbgi::microbuffer::NearField;
/// use pbgi::{PointCloud, Surfel, Tree};
///
/// /// The floor z = 0, lit at radiance 1.
/// struct Floor;
/// impl NearField for Floor {
///     fn trace(&self, o: Vec3, _n: Vec3, d: Vec3, t_max: f32) -> Option<Vec3> {
///         (d.z < 0.0 && -o.z / d.z <= t_max).then_some(Vec3::ONE)
///     }
/// }
///
/// // Floor surfels, 2 cm apart, and a receiver on a wall 3 mm above them.
/// let mut surfels = Vec::new();
/// for i in 0..50 {
///     for j in 0..50 {
///         let position = Vec3::new(-0.5 + i as f32 * 0.02, -0.5 + j as f32 * 0.02, 0.0);
///         surfels.push(Surfel { position, normal: Vec3::Z, radius: 0.0113, radiance: Vec3::ONE });
///     }
/// }
/// let tree = Tree::build(&PointCloud::new(surfels)?);
/// let gather = Gather::new(&tree, &GatherOptions::default())?.with_near_field(&Floor);
/// let e = gather.irradiance(&[(Vec3::new(0.01, 0.0, 0.003), Vec3::X)])?;
/// assert!((e[0].x / (std::f32::consts::PI / 2.0) - 1.0).abs() < 0.05); // half the hemisphere
/// # Ok::<(), pbgi::Error>(())
/// ```
pub trait NearField: Sync {
    /// The radiance the first surface along unit `dir` from `origin` (a
    /// receiver with unit `normal`) sends back along `−dir`, if that surface
    /// is within `t_max`; `None` if nothing is.
    fn trace(&self, origin: Vec3, normal: Vec3, dir: Vec3, t_max: f32) -> Option<Vec3>;

    /// Whether leaves within [`NEAR_RADII`] give way to [`trace`](Self::trace)'s
    /// rays: `false` for a field that only answers [`escapes`](Self::escapes).
    fn near_leaves(&self) -> bool {
        true
    }

    /// Whether the ray along unit `dir` from `origin` (a receiver with unit
    /// `normal`) meets no surface at any distance, so that the environment
    /// shows there; `None` (the default) where the field cannot tell, and
    /// the microbuffer's open part `1 − coverage` stands for it. Asked only
    /// of receivers that see an environment (`microbuffer::open`).
    fn escapes(&self, origin: Vec3, normal: Vec3, dir: Vec3) -> Option<bool> {
        let _ = (origin, normal, dir);
        None
    }

    /// [`escapes`](Self::escapes) for each unit direction of `dirs` from
    /// one receiver, in order, into `out` (cleared first); `false` where the
    /// field cannot tell. One call for a receiver's rays lets a field reuse
    /// what one ray met for the next (the renderer first tries the triangle
    /// that stopped the previous ray); the answers must not depend on it.
    fn escapes_each(&self, origin: Vec3, normal: Vec3, dirs: &[Vec3], out: &mut Vec<bool>) -> bool {
        out.clear();
        for &d in dirs {
            match self.escapes(origin, normal, d) {
                Some(e) => out.push(e),
                None => return false,
            }
        }
        true
    }

    /// What each ray along `dirs` from one receiver meets, into `out`
    /// (cleared first): the sky, or a surface that stops it (the nearest,
    /// or any one as edge-on); `false` where the field cannot tell. The default
    /// asks [`escapes_each`](Self::escapes_each) and reports every surface
    /// face-on (`cos` 1), so that no pixel refines for meeting one edge-on.
    fn sight_each(&self, origin: Vec3, normal: Vec3, dirs: &[Vec3], out: &mut Vec<Sight>) -> bool {
        let mut escaped = Vec::with_capacity(dirs.len());
        if !self.escapes_each(origin, normal, dirs, &mut escaped) {
            return false;
        }
        out.clear();
        out.extend(escaped.iter().map(|&e| {
            if e {
                Sight::Sky
            } else {
                Sight::Surface { cos: 1.0 }
            }
        }));
        true
    }
}

/// What a ray from a receiver meets ([`NearField::sight_each`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Sight {
    /// Nothing at any distance: the environment shows.
    Sky,
    /// A surface, met at `cos = |its normal · the ray|` (0: edge-on). A
    /// pixel's footprint there stretches as `1 / cos`, so an opening in it
    /// that the pixel's centre ray misses may lie beside the hit.
    Surface {
        /// `|normal · dir|` at the hit.
        cos: f32,
    },
    /// A surface where no opening lies beside the hit, however edge-on
    /// the ray meets it: a smooth part of a closed mesh, away from any
    /// boundary or crease (the renderer's `edged` triangles are the others).
    Smooth,
}

/// One receiver's near field: the nodes its composition leaves out, and per
/// pixel what its ray hit.
#[derive(Clone, Debug, Default)]
pub struct Near {
    /// Leaves drawn by rays instead, sorted.
    pub(super) skip: Vec<NodeId>,
    /// Per pixel: the radiance its ray met (the pixel is then opaque).
    pub(super) pixels: Vec<Option<Vec3>>,
    /// How far the rays reached: no hit lies further.
    pub(super) reach: f32,
}

impl Near {
    /// Pixels whose ray met a surface.
    pub fn hits(&self) -> usize {
        self.pixels.iter().filter(|p| p.is_some()).count()
    }

    /// Whether the composition leaves node `node` out.
    #[inline(always)]
    pub(super) fn skips(&self, node: NodeId) -> bool {
        self.skip.binary_search(&node).is_ok()
    }
}

/// Whether leaf `node` lies on the receiver's own surface: about parallel
/// to it (within 30°) and within half its radius of the receiver's plane.
/// Such leaves lie at the horizon, where they show nothing; they alone never
/// call for rays (every receiver's cut holds a few).
#[inline(always)]
pub(super) fn coplanar(tree: &Tree, node: NodeId, position: Vec3, normal: Vec3) -> bool {
    let (c, r) = tree.sphere(node);
    tree.mean_normal(node).dot(normal) > 0.866 && (c - position).dot(normal).abs() < 0.5 * r
}

/// The near field of the receiver at `position` (local frame `frame`)
/// whose splatted nodes are `nodes` (in any order, repeats allowed), or
/// `None` where none of them is a leaf of another surface within
/// [`NEAR_RADII`] of its radius. Inlined into the shading clones, like
/// everything they run (scripts/check-asm.sh).
#[inline(always)]
pub(super) fn near(
    t: &Table,
    nodes: impl Iterator<Item = NodeId>,
    tree: &Tree,
    position: Vec3,
    frame: &[Vec3; 3],
    field: &dyn NearField,
) -> Option<Near> {
    let normal = frame[2];
    let mut skip = Vec::new();
    let (mut other, mut reach) = (false, 0.0f32);
    for node in nodes {
        if !tree.is_leaf(node) {
            continue;
        }
        let (c, r) = tree.sphere(node);
        if c.distance(position) < NEAR_RADII * r {
            skip.push(node);
            reach = reach.max((NEAR_RADII + 1.0) * r);
            other |= !coplanar(tree, node, position, normal);
        }
    }
    if !other {
        return None;
    }
    skip.sort_unstable();
    skip.dedup();
    // A loop, not `collect`: its `from_iter` would stay out of line.
    let mut pixels = Vec::with_capacity(t.dir.len());
    for l in &t.dir {
        let d = (frame[0] * l.x + frame[1] * l.y + frame[2] * l.z).normalize();
        pixels.push(field.trace(position, normal, d, reach));
    }
    Some(Near { skip, pixels, reach })
}

#[cfg(test)]
mod tests {
    use glam::DVec3;

    use super::*;
    use crate::cut::{CutOptions, Scheme, SchemeChoice};
    use crate::gather::{Gather, GatherOptions};
    use crate::points::{PointCloud, Surfel};
    use crate::polygon::projected_solid_angle;
    use crate::rng::Rng;

    /// Half the floor's side.
    const HALF: f32 = 0.5;

    /// The scene the surfels stand for: a floor `z = 0` of radiance one
    /// where `x > 0`, in front of a dark wall standing on `x = 0`.
    struct Floor;

    impl NearField for Floor {
        fn trace(&self, origin: Vec3, _normal: Vec3, dir: Vec3, t_max: f32) -> Option<Vec3> {
            if dir.z >= 0.0 {
                return None;
            }
            let t = -origin.z / dir.z;
            let q = origin + dir * t;
            (t <= t_max && q.x > 0.0 && q.x <= HALF && q.y.abs() <= HALF).then_some(Vec3::ONE)
        }
    }

    /// Jittered surfels of spacing `s`: the floor (lit where `x > 0`, unlit
    /// under the wall, where a surfel's centre in shadow leaves it dark
    /// although its disk pokes out) and the wall's dark face.
    fn cloud(s: f32) -> PointCloud {
        let mut rng = Rng::new(3);
        let r = s / std::f32::consts::PI.sqrt();
        let k = (2.0 * HALF / s) as usize;
        let mut surfels = Vec::new();
        for i in 0..k {
            for j in 0..k {
                let x = -HALF + (i as f32 + rng.f32()) * s;
                let y = -HALF + (j as f32 + rng.f32()) * s;
                surfels.push(Surfel {
                    position: Vec3::new(x, y, 0.0),
                    normal: Vec3::Z,
                    radius: r,
                    radiance: Vec3::splat(if x > 0.0 { 1.0 } else { 0.0 }),
                });
                if i < k / 2 {
                    let z = (i as f32 + rng.f32()) * s;
                    surfels.push(Surfel {
                        position: Vec3::new(0.0, y, z),
                        normal: Vec3::X,
                        radius: r,
                        radiance: Vec3::ZERO,
                    });
                }
            }
        }
        PointCloud::new(surfels).unwrap()
    }

    /// Receivers on the wall 2–4 mm above the floor (surfel radius 11 mm),
    /// and their exact irradiance: the lit floor's `∫cos dω`.
    fn receivers() -> Vec<((Vec3, Vec3), f64)> {
        (0..32)
            .map(|i| {
                let p = Vec3::new(
                    1e-4,
                    -0.2 + 0.013 * i as f32,
                    0.002 + 0.002 * (i % 3) as f32 / 2.0,
                );
                let q = p.as_dvec3();
                let h = f64::from(HALF);
                let poly = [
                    DVec3::new(0.0, -h - q.y, -q.z),
                    DVec3::new(h - q.x, -h - q.y, -q.z),
                    DVec3::new(h - q.x, h - q.y, -q.z),
                    DVec3::new(0.0, h - q.y, -q.z),
                ];
                ((p, Vec3::X), projected_solid_angle(&poly, DVec3::X))
            })
            .collect()
    }

    fn irradiance(g: &Gather, r: &[((Vec3, Vec3), f64)]) -> Vec<Vec3> {
        g.irradiance(&r.iter().map(|x| x.0).collect::<Vec<_>>()).unwrap()
    }

    /// Relative RMSE of `e` against the exact answers, in %.
    fn error(e: &[Vec3], r: &[((Vec3, Vec3), f64)]) -> f64 {
        let sum: f64 = e
            .iter()
            .zip(r)
            .map(|(e, r)| (f64::from(e.x) / r.1 - 1.0).powi(2))
            .sum();
        100.0 * (sum / r.len() as f64).sqrt()
    }

    #[test]
    fn rays_stand_for_a_lit_floor_just_below_a_receiver_where_its_disks_cannot() {
        let tree = crate::Tree::build(&cloud(0.02));
        let r = receivers();
        let opts = GatherOptions {
            cut: CutOptions {
                max_solid_angle: 0.05,
                ..CutOptions::default()
            },
            microbuffer: 24,
            ..GatherOptions::default()
        };
        let disks = error(&irradiance(&Gather::new(&tree, &opts).unwrap(), &r), &r);
        let near = irradiance(&Gather::new(&tree, &opts).unwrap().with_near_field(&Floor), &r);
        let rays = error(&near, &r);
        eprintln!("floor below the receivers: {disks:.2} % by disks, {rays:.2} % with the near field");
        // The exact answer is about π/2 (half the hemisphere at radiance
        // one); the buried disks darken it by a third.
        assert!(disks > 20.0, "disks alone {disks:.2} %");
        assert!(
            rays < 2.0,
            "with the near field {rays:.2} % (disks alone {disks:.2} %)"
        );
        // Both pipelines and every scheme give the same bits.
        for scheme in [Scheme::Scalar, Scheme::Single, Scheme::Packet, Scheme::Hybrid] {
            let o = GatherOptions {
                scheme: SchemeChoice::Fixed(scheme),
                ..opts.clone()
            };
            let e = irradiance(&Gather::new(&tree, &o).unwrap().with_near_field(&Floor), &r);
            let bits = |v: &[Vec3]| {
                v.iter()
                    .map(|e| e.to_array().map(f32::to_bits))
                    .collect::<Vec<_>>()
            };
            assert_eq!(bits(&e), bits(&near), "{scheme}");
        }
    }
}
