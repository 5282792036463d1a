//! Where a node falls in a receiver's microbuffer: its direction, distance,
//! solid angle and map coordinates, written once over lanes like the node
//! test, so one receiver (`f32`) and sixteen (`F32s`) get the same bits.

use glam::Vec3;

use crate::simd::{F32s, Real};
use crate::tree::{ClusterRef, MIXED, NodeId, PLANAR, SplatRecord, Tree};

/// What splatting reads of a node, for one node or one per lane.
#[derive(Clone, Copy)]
pub(crate) struct NodeSplat<V> {
    pub cx: V,
    pub cy: V,
    pub cz: V,
    pub area: V,
    pub nx: V,
    pub ny: V,
    pub nz: V,
    /// The light centroid.
    pub lx: V,
    pub ly: V,
    pub lz: V,
}

impl NodeSplat<f32> {
    #[inline(always)]
    pub(super) fn of(r: &SplatRecord) -> Self {
        NodeSplat {
            cx: r.centroid[0],
            cy: r.centroid[1],
            cz: r.centroid[2],
            area: r.area,
            nx: r.normal[0],
            ny: r.normal[1],
            nz: r.normal[2],
            lx: r.light_centroid[0],
            ly: r.light_centroid[1],
            lz: r.light_centroid[2],
        }
    }

    /// The same node in every lane.
    #[inline(always)]
    pub(super) fn splat(&self) -> NodeSplat<F32s> {
        NodeSplat {
            cx: F32s::splat(self.cx),
            cy: F32s::splat(self.cy),
            cz: F32s::splat(self.cz),
            area: F32s::splat(self.area),
            nx: F32s::splat(self.nx),
            ny: F32s::splat(self.ny),
            nz: F32s::splat(self.nz),
            lx: F32s::splat(self.lx),
            ly: F32s::splat(self.ly),
            lz: F32s::splat(self.lz),
        }
    }
}

/// What a node shows besides its geometry: its kind, its mean radiance and
/// its light by direction (read for a [`MIXED`] node only).
#[derive(Clone, Copy)]
pub(crate) struct NodeLight<'a> {
    pub kind: u32,
    pub radiance: Vec3,
    pub cluster: ClusterRef<'a>,
    /// Its [`SplatRecord`]'s bounds: `rise·s + lift`, `R`, and whether
    /// its light centroid is not its area centroid.
    pub rise: f32,
    pub lift: f32,
    pub radius: f32,
    pub shifted: bool,
}

impl NodeLight<'static> {
    /// A node of one mean normal showing `radiance` (`kind`: planar or leaf).
    #[cfg(test)]
    pub(crate) fn flat(kind: u32, radiance: Vec3) -> Self {
        NodeLight {
            kind,
            radiance,
            cluster: ClusterRef::NONE,
            rise: 0.0,
            lift: f32::INFINITY,
            radius: 0.0,
            shifted: false,
        }
    }
}

impl<'a> NodeLight<'a> {
    /// Node `node` of `tree` (`None` if it is not one).
    #[inline(always)]
    pub(crate) fn of(tree: &'a Tree, node: NodeId) -> Option<(SplatRecord, Self)> {
        let rec = tree.splat_record(node)?;
        let cluster = tree.cluster_of(node).unwrap_or(ClusterRef::NONE);
        Some((
            rec,
            NodeLight {
                kind: rec.kind,
                radiance: tree.radiance(node),
                cluster,
                rise: rec.rise,
                lift: rec.lift,
                radius: rec.radius,
                shifted: rec.shifted,
            },
        ))
    }
}

/// A receiver's position and tangent frame (`t`, `b`, `n`), for one
/// receiver or one per lane.
#[derive(Clone, Copy)]
pub(crate) struct FrameLanes<V> {
    pub px: V,
    pub py: V,
    pub pz: V,
    pub tx: V,
    pub ty: V,
    pub tz: V,
    pub bx: V,
    pub by: V,
    pub bz: V,
    pub nx: V,
    pub ny: V,
    pub nz: V,
}

/// A splat placed in a receiver's microbuffer: distance and direction
/// (local) of its centre, projected solid angle, the radiance it shows,
/// continuous pixel coordinates; `valid` is false where it cannot show.
pub(crate) struct Located<V: Real> {
    pub valid: V::Mask,
    pub d: V,
    pub omega: V,
    /// What it covers of the convolution, `∫cosθ dω`: `Ω·cosθ` at its
    /// centre, a mixed node's `Σ A·G` over its facets at their centroids.
    pub projected: V,
    pub radiance: [V; 3],
    pub wx: V,
    pub wy: V,
    pub wz: V,
    pub x: V,
    pub y: V,
}

/// The most a node's radiance is scaled for its light centroid (`locate`).
const SHIFT: f32 = 4.0;

/// `G = max(0, −m·ω)·max(0, n·ω)/|u|²`, `ω = u/|u|`: what a piece of
/// surface of normal `m` (times its area fraction) at `u` from a receiver
/// of normal `n` sends it per unit area and radiance (0 at `u = 0`, and
/// where `G` is not finite: a point closer than `10⁻¹⁹`, for which no
/// ratio of `G`s means anything).
#[inline(always)]
pub(super) fn transfer<V: Real>(m: [V; 3], u: [V; 3], n: [V; 3]) -> V {
    let (w, l2) = towards(u);
    transfer_towards(m, w, l2, n)
}

/// The unit direction of `u` and `|u|²`.
#[inline(always)]
fn towards<V: Real>(u: [V; 3]) -> ([V; 3], V) {
    let l2 = u[0] * u[0] + u[1] * u[1] + u[2] * u[2];
    let l = l2.sqrt();
    ([u[0] / l, u[1] / l, u[2] / l], l2)
}

/// [`transfer`] towards unit direction `w` at squared distance `l2`.
#[inline(always)]
fn transfer_towards<V: Real>(m: [V; 3], w: [V; 3], l2: V, n: [V; 3]) -> V {
    let zero = V::splat(0.0);
    let facing = (-(m[0] * w[0] + m[1] * w[1] + m[2] * w[2])).max_of(zero);
    let cos = (n[0] * w[0] + n[1] * w[1] + n[2] * w[2]).max_of(zero);
    let g = facing * cos / l2;
    // Inputs are checked finite where they enter (surfels, receivers), so
    // `g` is non-finite only where `l2` is 0 or underflows (a node centred
    // on the receiver, which sends it nothing): geometry, not a defect
    // that a NaN check downstream should see.
    V::select(zero.lt(l2) & zero.le(g) & g.lt(V::splat(f32::INFINITY)), g, zero)
}

/// A planar cluster's (or a facet's) projected solid angle `∫ cosθ_r dω`
/// over its far-field `A·f·c/d²` (`f = −m·ω` its facing, `c = n·ω` the
/// receiver's cosine, `ω` towards its centroid `u`), to second order in
/// `r/d` for a disk of its area (`x = r²/d² = A/(πd²)`):
/// `1 + x·(1 − 3f² − f·(n·m)/c)`.
/// On the axis of a disk facing the receiver it is `1 − x`, as
/// `πr²/(d² + r²)` is. The far field alone drew a coarse cut's planar
/// clusters 2–5 % larger than their cells (`examples/sky_coverage`): in a
/// room they covered about 1 % of the hemisphere too much, and a window's
/// sky, what the walls leave open, came out 30–45 % short at the
/// defaults. Within `[½, 3/2]`; 1 where `c` is near 0 (the cluster at the
/// horizon, which the cone's part below it already cuts) or the term is
/// not finite (a distance so small that `x` overflows). `w` is the unit
/// direction towards the centroid, `l2` its squared distance.
#[inline(always)]
fn near_field<V: Real>(area: V, m: [V; 3], w: [V; 3], l2: V, n: [V; 3]) -> V {
    let zero = V::splat(0.0);
    // `m` may be shorter than 1 (a facet's `A·n̄/A_node`): its length
    // scales the area, its direction gives the facing.
    let len = (m[0] * m[0] + m[1] * m[1] + m[2] * m[2]).sqrt();
    let unit = zero.lt(len);
    let len1 = V::select(unit, len, V::splat(1.0));
    let facing = -(m[0] * w[0] + m[1] * w[1] + m[2] * w[2]) / len1;
    let nm = (m[0] * n[0] + m[1] * n[1] + m[2] * n[2]) / len1;
    let c = n[0] * w[0] + n[1] * w[1] + n[2] * w[2];
    let x = area * len * V::splat(std::f32::consts::FRAC_1_PI) / l2;
    let lit = V::splat(1e-3).lt(c);
    let c = V::select(lit, c, V::splat(1.0));
    let k = V::splat(1.0) + x * (V::splat(1.0) - V::splat(3.0) * facing * facing - facing * nm / c);
    // Finite first: the clamp would turn a NaN into ½.
    let inf = V::splat(f32::INFINITY);
    let finite = (-inf).lt(k) & k.lt(inf);
    let k = k.max_of(V::splat(0.5)).min_of(V::splat(1.5));
    V::select(lit & unit & finite & zero.lt(l2) & l2.lt(inf), k, V::splat(1.0))
}

/// Places node `s` (showing `light`) in the microbuffer of receiver `f`
/// (`half` = `N/2`).
///
/// `Ω = A·max(0, −n̄·ω)/d²` and the mean radiance; for a [`MIXED`] node the
/// projected area of its [`Cluster`]'s facets toward `−ω`, and their mean
/// radiances weighted by it. The centre's local direction `w` goes through the
/// octahedral map (a centre below the horizon to the horizon point above
/// it); `Ω` is capped at 2π. Invalid: the centre at the receiver, a
/// non-finite distance or `Ω`, a node facing away, a centre straight below.
#[inline(always)]
pub(crate) fn locate<V: Real>(
    s: &NodeSplat<V>,
    light: &NodeLight<'_>,
    f: &FrameLanes<V>,
    half: V,
) -> Located<V> {
    let vx = s.cx - f.px;
    let vy = s.cy - f.py;
    let vz = s.cz - f.pz;
    let d2 = vx * vx + vy * vy + vz * vz;
    let d = d2.sqrt();
    let (dx, dy, dz) = (vx / d, vy / d, vz / d);
    let zero = V::splat(0.0);
    let mean = light.radiance;
    let n = [f.nx, f.ny, f.nz];
    // A mixed node's facets' `max(0, −n̄·ω)` toward its centroid, and each
    // facet's `G` at its own area centroid (times its share of the area).
    let mut facing = [zero; 3];
    let mut at_facet = [zero; 3];
    let cluster = (light.kind == MIXED).then(|| light.cluster.get());
    let (raw, radiance, sent_at_facets) = if let Some(cluster) = &cluster {
        // Each facet's `A·max(0, −n̄·ω)` as a fraction of the node's area (at
        // most 1, so `L·w` cannot overflow), and its radiance weighted by its
        // share `w / Σw` of what the facets send (a share, not `w`: `L·w`
        // underflowed into subnormals for a dim facet a small part of a
        // huge node, and the mean came out 0.05 % above the brightest).
        //
        // What the node sends is `Σ A·G` over its facets, each at its own
        // area centroid: `G` at the node's centroid made a facet rising from
        // the receiver's own plane (a room's corner, a wall's foot) look as
        // low as that centroid, halfway down into the receiver's own wall,
        // and its coverage 1.5 % of the mid-wall occlusion short at Ω 0.15
        // (its light was made good by the light centroid's scale, below).
        let r = V::splat(light.radius);
        let (mut area, mut total) = (zero, zero);
        for ((w, g), (f, c)) in facing
            .iter_mut()
            .zip(at_facet.iter_mut())
            .zip(cluster.facet.iter().zip(&cluster.plane))
        {
            let m = [V::splat(f[0]), V::splat(f[1]), V::splat(f[2])];
            let facing = -(m[0] * dx + m[1] * dy + m[2] * dz);
            *w = facing.max_of(zero);
            area = area + *w;
            let u = [
                vx + V::splat(c[0]) * r,
                vy + V::splat(c[1]) * r,
                vz + V::splat(c[2]) * r,
            ];
            let (w, l2) = towards(u);
            *g = transfer_towards(m, w, l2, n) * near_field(s.area, m, w, l2, n);
            total = total + *g;
        }
        // Shares of what the facets send; of their projected area where
        // they send nothing (the node then adds nothing but its depth).
        let sends = zero.lt(total);
        // A division per facet: `1/Σw` overflows for a subnormal `Σw`,
        // and `0·∞` is NaN.
        let sum = V::select(sends, total, V::select(zero.lt(area), area, V::splat(1.0)));
        let mut power = [zero; 3];
        for ((w, g), f) in facing.iter().zip(&at_facet).zip(&cluster.facet) {
            let share = V::select(sends, *g, *w) / sum;
            power = [
                power[0] + V::splat(f[3]) * share,
                power[1] + V::splat(f[4]) * share,
                power[2] + V::splat(f[5]) * share,
            ];
        }
        let some = zero.lt(area);
        let ratio = |ch: usize, m: f32| V::select(some, power[ch], V::splat(m));
        (
            s.area * area / d2,
            [ratio(0, mean.x), ratio(1, mean.y), ratio(2, mean.z)],
            s.area * total,
        )
    } else {
        let facing = -(s.nx * dx + s.ny * dy + s.nz * dz);
        (
            s.area * facing.max_of(zero) / d2,
            [V::splat(mean.x), V::splat(mean.y), V::splat(mean.z)],
            zero,
        )
    };
    let wx = dx * f.tx + dy * f.ty + dz * f.tz;
    let wy = dx * f.bx + dy * f.by + dz * f.bz;
    let wz = dx * f.nx + dy * f.ny + dz * f.nz;
    let raw = if light.kind == PLANAR {
        raw * near_field(s.area, [s.nx, s.ny, s.nz], [dx, dy, dz], d2, n)
    } else {
        raw
    };
    // A huge node right in front of the receiver overflows the far-field
    // estimate; it covers at most the hemisphere.
    let omega = raw.min_of(V::splat(std::f32::consts::TAU));
    let radiance = if light.shifted {
        // A cluster is drawn at its area centroid `c` (its coverage); its
        // light comes from its light centroid `l` (a mixed one's facets,
        // each from its own: one point for all would blend facets facing
        // ways the receiver does not see). Scale the radiance by
        // `Σ|L|₁·G(l) / Σ|L|₁·G(c)`, `G = max(0, −n̄·ω)·cosθ/d²` per facet
        // (a mixed node's `c` each facet's area centroid, where its
        // coverage was taken), so that it sends `A·L̄·G(l)`: no first-order
        // error in where the light lies. At most `SHIFT` (where `G(c)`
        // nears 0 at the horizon).
        let (mut at_l, mut at_c) = (zero, zero);
        if let Some(cluster) = &cluster {
            let r = V::splat(light.radius);
            for ((g, off), at) in cluster.facet.iter().zip(&cluster.light).zip(at_facet) {
                let (m, bright) = (
                    [V::splat(g[0]), V::splat(g[1]), V::splat(g[2])],
                    V::splat(g[3] + g[4] + g[5]),
                );
                let u = [
                    s.cx + V::splat(off[0]) * r - f.px,
                    s.cy + V::splat(off[1]) * r - f.py,
                    s.cz + V::splat(off[2]) * r - f.pz,
                ];
                at_l = at_l + bright * transfer(m, u, n);
                at_c = at_c + bright * at;
            }
        } else {
            let m = [s.nx, s.ny, s.nz];
            at_l = transfer(m, [s.lx - f.px, s.ly - f.py, s.lz - f.pz], n);
            at_c = transfer(m, [vx, vy, vz], n);
        }
        // Both `G`s are finite (`transfer`), so the ratio is a number or
        // `+∞`. Where `G(c)` is 0 (the centroid below the horizon or its
        // facets facing away) there is no ratio: unscaled.
        let g = V::select(
            zero.lt(at_c),
            (at_l / at_c).min_of(V::splat(SHIFT)),
            V::splat(1.0),
        );
        radiance.map(|c| c * g)
    } else {
        radiance
    };
    let sum = wx.abs() + wy.abs() + wz.max_of(zero);
    let (px, py) = (wx / sum, wy / sum);
    let one = V::splat(1.0);
    let x = (px + py + one) * half;
    let y = (px - py + one) * half;
    let inf = V::splat(f32::INFINITY);
    // A node whose surface lies wholly on or below the receiver's tangent
    // plane shows nothing: the receiver's own wall, which rounding puts a
    // hair below it and facing it (half a cut's nodes, which would leave
    // a cone of a pixel's width on the horizon).
    let (kx, ky, kz) = (
        s.ny * f.nz - s.nz * f.ny,
        s.nz * f.nx - s.nx * f.nz,
        s.nx * f.ny - s.ny * f.nx,
    );
    let sine = (kx * kx + ky * ky + kz * kz).sqrt();
    let top = vx * f.nx + vy * f.ny + vz * f.nz + V::splat(light.rise) * sine + V::splat(light.lift);
    let valid = zero.lt(d2) & d2.lt(inf) & zero.lt(raw) & zero.lt(sum) & zero.lt(top);
    // A mixed node's `Σ A·G` is far-field like `Ω` and capped alike.
    let projected = if light.kind == MIXED {
        sent_at_facets.min_of(V::splat(std::f32::consts::TAU))
    } else {
        omega * wz.max_of(zero)
    };
    Located {
        valid,
        d,
        omega,
        projected,
        radiance,
        wx,
        wy,
        wz,
        x,
        y,
    }
}
