//! Baking a scene into surfels: stratified area-uniform sampling of every
//! surface (triangles smaller than a surfel pooled, so the count follows the
//! density, not the triangles), none inside a solid where asked, and
//! direct light at each surfel through shadow rays.

use std::sync::atomic::{AtomicUsize, Ordering};

use glam::{Vec2, Vec3};
use rayon::prelude::*;

use super::light::{Brdf, LightSamples, Lights, triangle};
use super::trace::Tracer;
use crate::error::{Error, Invalid};
use crate::gather::morton_codes;
use crate::points::{MAX_RADIANCE, PointCloud, Surfel};
use crate::rng::{Rng, mix};
use crate::scene::{Scene, SurfacePoint};

/// Surfels between two progress reports.
const TICK: usize = 4096;

/// How a scene is turned into surfels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BakeOptions {
    /// Surfels per unit of surface area, counted over the whole surface
    /// (with `drop_buried`, the share of the surfaces that lie inside a
    /// solid goes to the surfaces in the open).
    pub density: f32,
    /// Area-light samples per surfel.
    pub light_samples: u32,
    /// Seed of every random choice (results do not depend on thread count).
    pub seed: u64,
    /// Leave out the surfels that lie inside a solid: a face against
    /// another, as a wall on its slab (on by default; see
    /// `docs/lab/compact-tree.md`, "Records inside solids"). No light
    /// reaches them, but their records gathered the room through the
    /// solid, and their dark disks diluted the clusters they joined.
    pub drop_buried: bool,
}

impl Default for BakeOptions {
    fn default() -> Self {
        Self {
            density: 4000.0,
            light_samples: 16,
            seed: 1,
            drop_buried: true,
        }
    }
}

/// Surfels with what shading them again needs.
#[derive(Clone, Debug)]
pub struct Baked {
    /// The surfels; their radiance is the reflected direct light (emission is
    /// left out: the renderer adds direct light with shadow rays).
    pub cloud: PointCloud,
    /// Diffuse albedo of each surfel, for extra bounces.
    pub albedo: Vec<Vec3>,
    /// Sites left out because they lay inside a solid (of the last
    /// placing; see [`BakeOptions::density`]).
    pub buried: usize,
}

/// Rays that must all leave through a back face for a surfel to be inside
/// a solid.
const BURIED_RAYS: u32 = 8;

/// Whether a surfel at `p` (unit normal `n`) lies inside a solid: every
/// one of [`BURIED_RAYS`] rays over its hemisphere, from just off its
/// face, meets a back face first. That is a face lying against another (a
/// slab under a wall, a box's footprint on a floor) or running into one.
/// No light reaches such a surfel and no camera sees it, but a cache
/// record placed there would gather the room through the solid (the
/// point-based gather tests no visibility of back faces) and serve that
/// to the visible surface beside it. A surfel in the open meets a front
/// face or the sky with its first ray, so the test costs one ray there.
fn buried(tracer: &Tracer, p: Vec3, n: Vec3, scramble: u32) -> bool {
    let o = p + n * tracer.epsilon();
    let (t, b) = n.any_orthonormal_pair();
    (0..BURIED_RAYS).all(|j| {
        // Cosine-distributed, stratified.
        let u = hammersley(j, BURIED_RAYS, scramble);
        let (r, phi) = (u.x.sqrt(), std::f32::consts::TAU * u.y);
        let d = (t * (r * phi.cos()) + b * (r * phi.sin()) + n * (1.0 - u.x).max(0.0).sqrt()).normalize();
        tracer.meets_back_face(o, d)
    })
}

/// A low-discrepancy point in the unit square (Hammersley with a scramble).
fn hammersley(i: u32, n: u32, scramble: u32) -> Vec2 {
    Vec2::new((i as f32 + 0.5) / n as f32, radical_inverse(i, scramble))
}

/// Van der Corput's radical inverse of `i` in base 2, digits XORed with
/// `scramble`: in `[0, 1)`.
fn radical_inverse(i: u32, scramble: u32) -> f32 {
    (i.reverse_bits() ^ scramble) as f32 * (1.0 / 4_294_967_296.0)
}

/// A triangle's place: its mesh and its index there.
type TriangleRef = (u32, u32);

/// The triangles of one material too small for a surfel of their own (less
/// than one surfel's area at the density), sampled together by area: the
/// budget holds however finely a surface is cut. Ordered by the axis they
/// face most (so a surfel never averages the two sides of a thin part)
/// and then along a Morton curve, surfel `k` of `count` stands for the
/// `k`-th equal share of their summed area: a compact patch of neighbours.
struct Pool {
    material: usize,
    triangles: Vec<TriangleRef>,
    /// Twice the area and the unit normal of each of `triangles`.
    shapes: Vec<(f32, Vec3)>,
    /// The summed area at each triangle's end.
    ends: Vec<f64>,
    count: u32,
    scramble: u32,
}

impl Pool {
    /// The area each surfel stands for.
    fn share(&self) -> f64 {
        self.ends.last().copied().unwrap_or(0.0) / self.count as f64
    }

    /// The summed area at triangle `t`'s start.
    fn start(&self, t: usize) -> f64 {
        if t == 0 { 0.0 } else { self.ends[t - 1] }
    }

    /// The point at summed area `x` (in `[0, area)`), `w` the second
    /// coordinate across its triangle, with that triangle's normal and
    /// where on it the point is.
    fn point(&self, scene: &Scene, x: f64, w: f32) -> (Vec3, Vec3, Place) {
        let t = self.ends.partition_point(|&e| e <= x).min(self.ends.len() - 1);
        let (m, i) = self.triangles[t];
        let mesh = &scene.meshes[m as usize];
        let v = mesh.triangles[i as usize].map(|i| mesh.positions[i as usize]);
        let (twice_area, normal) = self.shapes[t];
        // The fraction of the triangle's area swept from its first vertex
        // is the square of the first coordinate of the area-preserving map.
        let u = ((x - self.start(t)) / (0.5 * twice_area as f64)).clamp(0.0, 1.0) as f32;
        let (p, bary) = on_triangle(v, u, w);
        (p, normal, ((m, i), bary))
    }

    /// Surfel `k`: a point at the middle of its share, the area-weighted
    /// normal of the share, and the radius of a disk of the share's area.
    fn site(&self, scene: &Scene, k: u32) -> Own {
        let share = self.share();
        let (lo, hi) = (k as f64 * share, (k + 1) as f64 * share);
        let mut t = self.ends.partition_point(|&e| e <= lo);
        let mut sum = Vec3::ZERO;
        while t < self.ends.len() && self.start(t) < hi {
            let overlap = self.ends[t].min(hi) - self.start(t).max(lo);
            sum += self.shapes[t].1 * overlap as f32;
            t += 1;
        }
        let w = radical_inverse(k, self.scramble);
        let (position, own, place) = self.point(scene, (k as f64 + 0.5) * share, w);
        let normal = sum.try_normalize().unwrap_or(own);
        let radius = (share / std::f64::consts::PI).sqrt() as f32;
        (position, normal, radius, self.material, place)
    }
}

/// The point of triangle `v` at `(u, w)` of the unit square, mapped
/// area-preservingly, and its barycentric coordinates of vertices 1 and 2.
fn on_triangle(v: [Vec3; 3], u: f32, w: f32) -> (Vec3, Vec2) {
    let su = u.sqrt();
    let (b0, b1) = (1.0 - su, w * su);
    let b2 = 1.0 - b0 - b1;
    (v[0] * b0 + v[1] * b1 + v[2] * b2, Vec2::new(b1, b2))
}

/// Which of six directions (+x, +y, +z, −x, −y, −z: neighbours in this
/// order are never opposite) a normal faces most.
fn facing(n: Vec3) -> u8 {
    let a = n.abs();
    let axis = if a.x >= a.y && a.x >= a.z {
        0
    } else if a.y >= a.z {
        1
    } else {
        2
    };
    axis + if n[axis as usize] < 0.0 { 3 } else { 0 }
}

/// A triangle and barycentric coordinates on it (for texture lookups).
type Place = (TriangleRef, Vec2);

/// Position, normal, radius, material and place of a surfel.
type Own = (Vec3, Vec3, f32, usize, Place);

/// A surfel: a large triangle's, or the `k`-th of a pool.
#[derive(Clone, Copy)]
enum Site {
    Own(Own),
    Pooled { pool: usize, k: u32 },
}

/// Where the surfels go: one or more on each triangle of at least a
/// surfel's area, and the pools of the smaller ones.
struct Sites {
    own: Vec<Own>,
    pools: Vec<Pool>,
}

fn sites(scene: &Scene, opts: &BakeOptions, density: f32) -> Result<Sites, Error> {
    // Per triangle, twice its area and its normal (`None`: no area).
    let shapes: Vec<Vec<Option<(f32, Vec3)>>> = scene
        .meshes
        .iter()
        .map(|m| {
            m.triangles
                .par_iter()
                .map(|t| triangle(t.map(|i| m.positions[i as usize])))
                .collect()
        })
        .collect();
    let per_area = density as f64;
    let mut expected = scene.materials.len() as f64;
    for shape in shapes.iter().flatten().flatten() {
        expected += 0.5 * shape.0 as f64 * per_area;
    }
    if expected > PointCloud::MAX_SURFELS as f64 {
        return Err(Error::TooManySurfels {
            count: expected.min(usize::MAX as f64) as usize,
            max: PointCloud::MAX_SURFELS,
        });
    }
    // Per large triangle, a count from its area (stochastic rounding),
    // stratified with a scrambled Hammersley set mapped area-preservingly.
    let mut own = Vec::new();
    let mut small: Vec<Vec<(TriangleRef, (f32, Vec3))>> = vec![Vec::new(); scene.materials.len()];
    let mut tri_seed = Rng::new(opts.seed);
    for (m, (mesh, shape)) in scene.meshes.iter().zip(&shapes).enumerate() {
        for (t, (tri, shape)) in mesh.triangles.iter().zip(shape).enumerate() {
            let Some((twice_area, normal)) = *shape else {
                continue;
            };
            let area = 0.5 * twice_area;
            let want = area * density;
            if want < 1.0 {
                small[mesh.material].push(((m as u32, t as u32), (twice_area, normal)));
                continue;
            }
            let v = tri.map(|i| mesh.positions[i as usize]);
            let extra = if tri_seed.f32() < want.fract() { 1.0 } else { 0.0 };
            let n = (want.floor() + extra) as u32;
            // In f64: the radius of a tiny triangle's disk must not underflow.
            let radius = (area as f64 / (n as f64 * std::f64::consts::PI)).sqrt() as f32;
            let scramble = tri_seed.next_u64() as u32;
            for i in 0..n {
                let u = hammersley(i, n, scramble);
                let (p, bary) = on_triangle(v, u.x, u.y);
                own.push((p, normal, radius, mesh.material, ((m as u32, t as u32), bary)));
            }
        }
    }
    let pools = small
        .into_iter()
        .enumerate()
        .filter(|(_, triangles)| !triangles.is_empty())
        .map(|(material, triangles)| pool(scene, material, triangles, opts.seed, density))
        .collect();
    Ok(Sites { own, pools })
}

/// The pool of `material`'s small `triangles` (with twice their area and
/// their normal): ordered, summed, counted.
fn pool(
    scene: &Scene,
    material: usize,
    triangles: Vec<(TriangleRef, (f32, Vec3))>,
    seed: u64,
    density: f32,
) -> Pool {
    let centroid = |&((m, t), _): &(TriangleRef, (f32, Vec3))| {
        let mesh = &scene.meshes[m as usize];
        mesh.triangles[t as usize]
            .iter()
            .map(|&i| mesh.positions[i as usize])
            .sum::<Vec3>()
            / 3.0
    };
    let codes = morton_codes(triangles.iter().map(centroid));
    let mut keyed: Vec<(u8, u64, TriangleRef, (f32, Vec3))> = triangles
        .iter()
        .zip(codes)
        .map(|(&(r, shape), code)| (facing(shape.1), code, r, shape))
        .collect();
    // The key and the place decide the order; the shape follows the place.
    keyed.par_sort_unstable_by_key(|&(facing, code, r, _)| (facing, code, r));
    let mut sum = 0.0f64;
    let ends = keyed
        .iter()
        .map(|&(.., (twice_area, _))| {
            sum += 0.5 * twice_area as f64;
            sum
        })
        .collect();
    let mut rng = Rng::new(mix(seed ^ (material as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)));
    let want = sum * density as f64;
    let count = want.floor() as u32 + u32::from((rng.f32() as f64) < want.fract());
    Pool {
        material,
        triangles: keyed.iter().map(|&(_, _, r, _)| r).collect(),
        shapes: keyed.iter().map(|&(.., shape)| shape).collect(),
        ends,
        count,
        scramble: rng.next_u64() as u32,
    }
}

impl Site {
    /// Its position, normal, radius, material and place.
    fn resolve(self, scene: &Scene, pools: &[Pool]) -> Own {
        match self {
            Site::Own(s) => s,
            Site::Pooled { pool, k } => pools[pool].site(scene, k),
        }
    }
}

/// The two scrambles of surfel site `i`'s random choices.
fn scramble(seed: u64, i: usize) -> [u32; 2] {
    let h = mix(seed ^ (i as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15));
    [h as u32, (h >> 32) as u32]
}

/// The sites that make surfels, each with its index among all sites.
struct Open {
    sites: Vec<(u32, Site)>,
    pools: Vec<Pool>,
    /// Sites left out inside a solid.
    buried: usize,
}

/// The sites at `opts`' density that make surfels: on a cut-out's opaque
/// part and, with [`BakeOptions::drop_buried`], not inside a solid
/// ([`buried`]). Where some are buried, the
/// sites are placed again at a density raised by their share, so that the
/// surfels number what the density gives the scene's whole surface (a
/// budget holds) however much of it lies against other surfaces.
fn in_the_open(scene: &Scene, tracer: &Tracer, opts: &BakeOptions) -> Result<Open, Error> {
    let place = |density: f32| -> Result<Open, Error> {
        let Sites { own, pools } = sites(scene, opts, density)?;
        let pooled = pools
            .iter()
            .enumerate()
            .flat_map(|(pool, p)| (0..p.count).map(move |k| Site::Pooled { pool, k }));
        let all: Vec<Site> = own.iter().map(|&s| Site::Own(s)).chain(pooled).collect();
        // Per site: `None` on a hole, else whether it is buried.
        let open: Vec<Option<bool>> = all
            .par_iter()
            .enumerate()
            .map(|(i, site)| {
                let (position, normal, _, material, ((m, t), bary)) = site.resolve(scene, &pools);
                // No surfel on a cut-out's holes.
                let mesh = &scene.meshes[m as usize];
                if !scene.materials[material].opaque_at(mesh, t, bary) {
                    return None;
                }
                let [a, b] = scramble(opts.seed, i);
                Some(opts.drop_buried && buried(tracer, position, normal, a ^ b))
            })
            .collect();
        let buried = open.iter().filter(|&&o| o == Some(true)).count();
        let sites = all
            .into_iter()
            .zip(open)
            .enumerate()
            .filter(|(_, (_, o))| *o == Some(false))
            .map(|(i, (site, _))| (i as u32, site))
            .collect();
        Ok(Open { sites, pools, buried })
    };
    let first = place(opts.density)?;
    if first.buried == 0 || first.sites.is_empty() {
        return Ok(first);
    }
    let share = first.sites.len() as f64 / (first.sites.len() + first.buried) as f64;
    place((opts.density as f64 / share).min(f32::MAX as f64) as f32)
}

/// Samples the surfels of `scene` and lights them directly (`scene` valid,
/// see [`Scene::validate`]). A triangle of at least a surfel's area gets
/// surfels of its own; smaller ones share theirs, each surfel standing for
/// an equal share of their area (its normal their average over it, its
/// light the average of its light samples spread over it), so the count is
/// the density's whatever the number of triangles. Errors: a density that
/// is not a finite positive number, or one that asks for more than
/// [`PointCloud::MAX_SURFELS`] surfels (counted before anything is
/// allocated).
pub fn bake(scene: &Scene, tracer: &Tracer, lights: &Lights, opts: &BakeOptions) -> Result<Baked, Error> {
    bake_with_progress(scene, tracer, lights, opts, &|_, _| {})
}

/// [`bake`], calling `tick(done, total)` as the surfels' light is done.
pub(super) fn bake_with_progress(
    scene: &Scene,
    tracer: &Tracer,
    lights: &Lights,
    opts: &BakeOptions,
    tick: &(dyn Fn(usize, usize) + Sync),
) -> Result<Baked, Error> {
    if !(opts.density.is_finite() && opts.density > 0.0) {
        return Err(Error::InvalidParameter {
            name: "density",
            value: opts.density.to_string(),
            expected: "a finite number > 0 (surfels per unit area)",
        });
    }
    // The stage starts with the placing, before the surfels' count is known.
    tick(0, 0);
    let Open {
        sites: all,
        pools,
        buried,
    } = in_the_open(scene, tracer, opts)?;
    let done = AtomicUsize::new(0);
    tick(0, all.len());
    let baked: Vec<Option<(Surfel, Vec3)>> = all
        .par_iter()
        .map(|&(i, site)| {
            let i = i as usize;
            let (position, normal, radius, material, ((m, t), bary)) = site.resolve(scene, &pools);
            let (mesh, material) = (&scene.meshes[m as usize], &scene.materials[material]);
            let scramble = scramble(opts.seed, i);
            let at = SurfacePoint {
                triangle: t,
                uv: bary,
                width: 2.0 * radius,
            };
            let albedo = material.albedo_at(mesh, &at);
            let radiance = if albedo.max_element() <= 0.0 {
                Vec3::ZERO
            } else if let Site::Pooled { pool, k } = site {
                // One light sample at each of points spread over the share.
                let pool = &pools[pool];
                let spread = opts.light_samples.max(1);
                let share = pool.share();
                let mut sum = Vec3::ZERO;
                for j in 0..spread {
                    let x = (k as f64 + (j as f64 + 0.5) / spread as f64) * share;
                    let w = radical_inverse(j, scramble[1]);
                    let (at, n, _) = pool.point(scene, x, w);
                    let samples = LightSamples {
                        count: opts.light_samples.min(1),
                        first: j,
                        scramble,
                        ratio: false,
                    };
                    sum += lights.reflected(tracer, at, n, samples, Brdf::lambert(albedo));
                }
                sum / spread as f32
            } else {
                let samples = LightSamples {
                    count: opts.light_samples,
                    first: 0,
                    scramble,
                    ratio: false,
                };
                lights.reflected(tracer, position, normal, samples, Brdf::lambert(albedo))
            };
            if !radiance.is_finite() {
                return Err(Error::InvalidSurfel {
                    index: i,
                    reason: Invalid::NonFinite {
                        field: "radiance (direct light at the surfel)",
                    },
                });
            }
            // A finite estimate beyond the range a surfel accepts (a surfel
            // a hair from a light of the brightest emission) saturates.
            let surfel = Surfel {
                position,
                normal,
                radius,
                radiance: radiance.min(Vec3::splat(MAX_RADIANCE)),
            };
            let d = done.fetch_add(1, Ordering::Relaxed) + 1;
            if d.is_multiple_of(TICK) || d == all.len() {
                tick(d, all.len());
            }
            // Geometry beyond `MAX_COORDINATE` makes no surfel.
            Ok(surfel.validate(i).is_ok().then_some((surfel, albedo)))
        })
        .collect::<Result<_, Error>>()?;
    let (surfels, albedo): (Vec<Surfel>, Vec<Vec3>) = baked.into_iter().flatten().unzip();
    Ok(Baked {
        cloud: PointCloud::new(surfels).expect("baked surfels are validated one by one"),
        albedo,
        buried,
    })
}
