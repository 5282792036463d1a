//! A node's bounds and aggregates from its surfels: the bounding sphere,
//! the normal cone, the mean normal and radiance, and the facets (by
//! normal, each with its light and its plane), all in `f64`, rounded
//! outward where the node test reads them.

use glam::{DVec3, Vec3};

use super::quantize::Quantized;
use super::{Cluster, FACETS, SplatRecord};
use crate::points::Surfel;

/// A node as the builder makes it, before it is written into the arrays.
#[derive(Clone, Debug, Default)]
pub(super) struct BuildNode {
    pub center: [f32; 3],
    pub centroid: [f32; 3],
    pub light_centroid: [f32; 3],
    pub radius: f32,
    pub axis: [f32; 3],
    pub cos: f32,
    pub sin: f32,
    /// A leaf's `LEAF_BIT | surfel`, an inner node's left child.
    pub child: u32,
    pub area: f32,
    pub normal: Vec3,
    pub radiance: Vec3,
    pub facets: u32,
    /// The facets, where there are several.
    pub cluster: Option<Box<Cluster>>,
    pub depth: u32,
    /// The steps of a compact tree's node (the fields above are their
    /// decoded values), and the sphere they are steps of.
    pub steps: Quantized,
    pub base: [f32; 4],
}

/// The plane of a node's facet that could hide another of its facets from
/// a receiver: all of the other lies behind it, and it does not all lie
/// behind the other's (a wall's inside and the roof beyond the wall; not a
/// block's top and side, each behind the other's plane, nor a room's floor
/// and wall, each in front of the other's). Drawn as one splat, the node
/// would send the hidden facet's light where the other hides it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Hiding {
    pub normal: DVec3,
    pub point: DVec3,
    /// How far the facet's own disks leave its plane.
    pub reach: f64,
}

impl Hiding {
    /// Whether surfel `s` lies behind the plane, further than the hiding
    /// facet's own disks reach. By its centre: the first row of a jamb
    /// behind a wall pokes its disks out through the wall's plane.
    #[inline(always)]
    pub(super) fn behind(&self, s: &Surfel) -> bool {
        self.normal.dot(s.position.as_dvec3() - self.point) < -self.reach
    }
}

/// A surfel joins the facet whose first normal is nearest if within this
/// cosine (about 18°), else starts a facet while there are fewer than three.
const FACET_COS: f64 = 0.95;

/// Bounding sphere, normal cone and aggregates of the surfels in `order`;
/// with them, the planes of its facets that could hide others ([`Hiding`]).
pub(super) fn bound_node(surfels: &[Surfel], order: &[u32], lo: Vec3, hi: Vec3) -> (BuildNode, Vec<Hiding>) {
    // Centre of the position box: exact in f64, so homogeneous in the scale.
    let center = (lo.as_dvec3() + hi.as_dvec3()) * 0.5;
    let center32 = center.as_vec3();
    let c = center32.as_dvec3();
    let mut radius = 0.0f64;
    let mut area = 0.0f64;
    let mut normal = DVec3::ZERO;
    let mut radiance = DVec3::ZERO;
    // Σ A·p and Σ (A·|L|₁)·p, with their weights: the light centroid.
    let (mut by_area, mut by_light, mut light) = (DVec3::ZERO, DVec3::ZERO, 0.0f64);
    // Facets: first normal, Σ A·n, Σ A·L, Σ A, Σ A·p, Σ (A·|L|₁)·p, Σ A·|L|₁;
    // and each surfel's.
    #[allow(clippy::type_complexity)]
    let mut facets: Vec<(DVec3, DVec3, DVec3, f64, DVec3, DVec3, f64)> = Vec::with_capacity(FACETS);
    let mut facet_of: Vec<u8> = Vec::with_capacity(order.len());
    for &i in order {
        let s = &surfels[i as usize];
        radius = radius.max(s.position.as_dvec3().distance(c) + s.radius as f64);
        let a = (s.radius as f64) * (s.radius as f64);
        area += a;
        let (n, l) = (s.normal.as_dvec3(), s.radiance.as_dvec3());
        normal += n * a;
        radiance += l * a;
        let p = s.position.as_dvec3();
        let w = a * (l.x + l.y + l.z);
        by_area += p * a;
        by_light += p * w;
        light += w;
        let nearest = (0..facets.len()).max_by(|&x, &y| facets[x].0.dot(n).total_cmp(&facets[y].0.dot(n)));
        let k = match nearest {
            Some(k) if facets[k].0.dot(n) >= FACET_COS || facets.len() == FACETS => k,
            _ => {
                facets.push((n, DVec3::ZERO, DVec3::ZERO, 0.0, DVec3::ZERO, DVec3::ZERO, 0.0));
                facets.len() - 1
            }
        };
        facets[k].1 += n * a;
        facets[k].2 += l * a;
        facets[k].3 += a;
        facets[k].4 += p * a;
        facets[k].5 += p * w;
        facets[k].6 += w;
        facet_of.push(k as u8);
    }
    // Each facet's plane: its centroid, mean normal and how far its disks
    // leave that plane (a disk tilted by θ from it by `r·sinθ` at its rim).
    let mut planes = [(DVec3::ZERO, DVec3::ZERO, 0.0f64); FACETS];
    for (plane, f) in planes.iter_mut().zip(&facets) {
        *plane = (f.4 / f.3, f.1.normalize_or_zero(), 0.0);
    }
    // And per pair of facets `(k, j)`, how far in front of `j`'s plane
    // any surfel of `k` lies: its centre (as `Hiding::behind` reads it),
    // and its centre less its radius (a side's disks along a block's edge
    // lie on the top's plane, and do not rise in front of it).
    let mut lies = [[f64::NEG_INFINITY; FACETS]; FACETS];
    let mut rises = [[f64::NEG_INFINITY; FACETS]; FACETS];
    for (&i, &k) in order.iter().zip(&facet_of) {
        let s = &surfels[i as usize];
        let p = s.position.as_dvec3();
        if facets.len() > 1 {
            for (j, (c, m, _)) in planes[..facets.len()].iter().enumerate() {
                let ahead = m.dot(p - *c);
                lies[k as usize][j] = lies[k as usize][j].max(ahead);
                rises[k as usize][j] = rises[k as usize][j].max(ahead - s.radius as f64);
            }
        }
        let (c, m, reach) = &mut planes[k as usize];
        let n = s.normal.as_dvec3().normalize_or_zero();
        let tilt = (1.0 - m.dot(n).powi(2)).max(0.0).sqrt();
        *reach = reach.max(m.dot(p - *c).abs() + s.radius as f64 * tilt);
    }
    // Only where the facets are flat pieces (as the microbuffer draws them):
    // more orientations than facets (a block's six faces) merge into facets
    // whose planes are none of its faces', and each face lies behind the
    // others' planes.
    let shown: f64 = facets.iter().map(|f| f.1.length()).sum();
    let mut hiding = Vec::new();
    for a in (0..facets.len()).filter(|_| shown >= f64::from(FLAT) * area) {
        for b in (0..facets.len()).filter(|&b| b != a) {
            let ((ca, ma, ra), (_, _, rb)) = (planes[a], planes[b]);
            if lies[b][a] < -ra && rises[a][b] > rb {
                hiding.push(Hiding {
                    normal: ma,
                    point: ca,
                    reach: ra,
                });
            }
        }
    }
    // The cone's axis is the area-weighted normal direction; its half-angle the
    // widest normal from it. Both are scale-free.
    let axis = normal.normalize_or_zero();
    let mut cos_min = if axis == DVec3::ZERO { -1.0 } else { 1.0f64 };
    if cos_min > 0.0 {
        for &i in order {
            let n = surfels[i as usize].normal.as_dvec3();
            cos_min = cos_min.min(axis.dot(n / n.length()));
        }
    }
    // Slack for rounding in the node test; cones past a hemisphere never cull.
    let cos_min = cos_min - 1e-6;
    let (cos, sin) = if cos_min <= 0.0 {
        (0.0f32, 1.0f32)
    } else {
        let sin = (1.0 - cos_min * cos_min).max(0.0).sqrt();
        (round_down(cos_min), round_up(sin).min(1.0))
    };
    let radius32 = round_up(radius * (1.0 + 1e-6));
    // Where the node's surface is (its area centroid) and where its light
    // comes from (the centroid weighted by area times radiance; the area
    // centroid where it sends none): at each, the far-field estimate of its
    // coverage `Σ A·G(p)` and of its light `Σ A·L·G(p)` has no first-order
    // error. Both at the box's centre, a cluster holding a small bright
    // light and the dark ceiling around it put the light up to `R` away
    // (the light room's floor 7 % dark at Ω 0.2); the light centroid for
    // both moves the surface (the slab under it 3 % dark).
    let centroid = if area > 0.0 { by_area / area } else { c };
    let lit = if light > 0.0 { by_light / light } else { centroid };
    let node = BuildNode {
        center: center32.to_array(),
        centroid: centroid.as_vec3().to_array(),
        light_centroid: lit.as_vec3().to_array(),
        radius: radius32,
        axis: axis.as_vec3().to_array(),
        cos,
        sin,
        child: 0,
        // Saturates: radii up to `MAX_COORDINATE` can make `π Σ r²` overflow f32.
        area: disks_area(area),
        normal: (normal / area).as_vec3(),
        radiance: (radiance / area).as_vec3(),
        facets: facets.len() as u32,
        // Fractions of the node's area: `|A·n̄| ≤ A`, so a facet's weight
        // times `MAX_RADIANCE` stays finite however large the node.
        // Only a mixed node has one: inline, it was half of every node the
        // builder holds (4 GB of 10⁷ surfels' build).
        cluster: (facets.len() > 1).then(|| {
            let mut cluster = Box::new(Cluster::NONE);
            for (f, (_, an, p, a, ..)) in cluster.facet.iter_mut().zip(&facets) {
                let an = (*an / area).as_vec3();
                let l = (*p / *a).as_vec3();
                *f = [an.x, an.y, an.z, l.x, l.y, l.z];
            }
            // In units of `R` (scale-free, like the weights above); a facet
            // of one point has `R` 0 and nothing to place.
            let unit = if radius > 0.0 { 1.0 / radius32 as f64 } else { 0.0 };
            let from = centroid.as_vec3().as_dvec3();
            for (f, (p, _, reach)) in cluster.plane.iter_mut().zip(&planes[..facets.len()]) {
                let off = ((*p - from) * unit).as_vec3();
                *f = [off.x, off.y, off.z, round_up(reach * unit)];
            }
            // Each facet's light centroid (its area centroid where it sends
            // no light), from the same point.
            for (f, g) in cluster.light.iter_mut().zip(&facets) {
                let lit = if g.6 > 0.0 { g.5 / g.6 } else { g.4 / g.3 };
                *f = ((lit - from) * unit).as_vec3().to_array();
            }
            cluster
        }),
        depth: 0,
        steps: Default::default(),
        base: [0.0; 4],
    };
    (node, hiding)
}

/// Smallest f32 ≥ `x`.
pub(super) fn round_up(x: f64) -> f32 {
    let f = x as f32;
    if (f as f64) < x { f.next_up() } else { f }
}

/// Largest f32 ≤ `x`.
fn round_down(x: f64) -> f32 {
    let f = x as f32;
    if (f as f64) > x { f.next_down() } else { f }
}

/// How much of a mixed node's area its facets must show face-on
/// (`Σ|A·n̄| / A`) to be drawn as flat pieces: a box's corner shows all
/// of it; a column's or an arch's cluster, whose facets are curved (or
/// hold the normals a fourth facet would have had), shows less, and its
/// disks would leave gaps where its surface is.
const FLAT: f32 = 0.9;

/// The area a node stores of disks whose squared radii sum to `r2`.
pub(crate) fn disks_area(r2: f64) -> f32 {
    ((std::f64::consts::PI * r2) as f32).min(f32::MAX)
}

/// What the microbuffer reads of a mixed cluster's facets that depends on
/// the node alone, derived once per tree rather than for every receiver
/// that splats it (they were a tenth of the composition's time).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct FacetPlanes {
    /// Whether the facets are flat ([`FLAT`]): drawn as their disks, else
    /// the node is one round cone.
    pub flat: bool,
    /// Per facet: its unit normal (x, y, z), its plane's centroid in world
    /// space (x, y, z), its area `A·|A·n̄/A|` and how far its surfels leave
    /// its plane (both in world units).
    pub facet: [[f32; 8]; FACETS],
}

impl FacetPlanes {
    /// The facets of the mixed node `rec` with bounding radius `r` and
    /// facets `cluster`.
    #[inline(always)]
    pub(crate) fn of(rec: &SplatRecord, r: f32, cluster: &Cluster) -> FacetPlanes {
        let mut shown = 0.0;
        for f in &cluster.facet {
            shown += Vec3::new(f[0], f[1], f[2]).length();
        }
        let centre = Vec3::from_array(rec.centroid);
        let mut out = FacetPlanes {
            flat: shown >= FLAT,
            facet: [[0.0; 8]; FACETS],
        };
        for ((f, p), o) in cluster.facet.iter().zip(&cluster.plane).zip(&mut out.facet) {
            let an = Vec3::new(f[0], f[1], f[2]);
            let n = an.normalize_or_zero();
            let x = centre + Vec3::new(p[0], p[1], p[2]) * r;
            *o = [n.x, n.y, n.z, x.x, x.y, x.z, rec.area * an.length(), p[3] * r];
        }
        out
    }
}
