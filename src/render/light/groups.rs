//! Emitters in groups: the consecutive coplanar triangles of a window or a
//! panel, which a receiver weighs as one before it picks a triangle.

use glam::Vec3;

use crate::scene::Scene;

/// A group spans at most this share of the scene's bounding-box diagonal.
const GROUP_EXTENT: f32 = 0.15;

/// Consecutive coplanar emissive triangles of one mesh, close together (a
/// window): a receiver weighs its light as one, then picks a triangle
/// within it by power.
pub(super) struct Group {
    /// Its triangles, `first..end` of [`Lights::triangles`].
    pub(super) first: usize,
    pub(super) end: usize,
    /// Area-weighted centroid, the plane's unit front normal, radius of a
    /// sphere about the centroid holding it.
    pub(super) centroid: Vec3,
    pub(super) normal: Vec3,
    pub(super) radius: f32,
    pub(super) area: f32,
    /// Σ area × radiance (summed over channels).
    pub(super) power: f32,
}

impl Group {
    /// The group's direct light at `origin` (normal `n`) as if it were a
    /// point at its centroid, its solid angle capped at a hemisphere's:
    /// zero only where it gives nothing (seen from its back, or wholly
    /// below the horizon), so that picking groups in proportion stays
    /// unbiased.
    #[inline(always)]
    pub(super) fn estimate(&self, origin: Vec3, n: Vec3) -> f32 {
        let d = self.centroid - origin;
        let cos_l = -self.normal.dot(d);
        if cos_l <= 0.0 || n.dot(d) <= -self.radius {
            return 0.0;
        }
        let dist2 = d.length_squared();
        let omega = (self.area * cos_l / (dist2 * dist2.sqrt())).min(std::f32::consts::TAU);
        // A floor, so a group seen edge-on from its centroid keeps a chance.
        self.power / self.area * omega.max(1e-6)
    }
}

/// The entry of cumulative sums `cdf` that `x` falls in, and where within
/// its share, in [0, 1].
#[inline(always)]
pub(super) fn pick(cdf: &[f32], x: f32) -> (usize, f32) {
    let k = cdf.partition_point(|&c| c <= x).min(cdf.len() - 1);
    let lo = if k == 0 { 0.0 } else { cdf[k - 1] };
    let share = cdf[k] - lo;
    (
        k,
        if share > 0.0 {
            ((x - lo) / share).clamp(0.0, 1.0)
        } else {
            0.0
        },
    )
}

/// Splits `triangles` (in mesh order) into [`Group`]s: a run of coplanar
/// triangles of one radiance within [`GROUP_EXTENT`] of the scene's
/// diagonal from its first vertex. Returns the groups and each triangle's
/// cumulative power within its group.
pub(super) fn groups(
    scene: &Scene,
    triangles: &[([Vec3; 3], Vec3, Vec3)],
    twice_areas: &[f32],
) -> (Vec<Group>, Vec<f32>) {
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for p in scene.meshes.iter().flat_map(|m| &m.positions) {
        (lo, hi) = (lo.min(*p), hi.max(*p));
    }
    let extent = GROUP_EXTENT * (hi - lo).length();
    let mut groups: Vec<Group> = Vec::new();
    let mut power_cdf = Vec::with_capacity(triangles.len());
    for (k, (v, normal, radiance)) in triangles.iter().enumerate() {
        let area = 0.5 * twice_areas[k];
        let power = area * (radiance.x + radiance.y + radiance.z);
        let joins = groups.last().is_some_and(|g| {
            let (w, gn, gr) = &triangles[g.first];
            gr == radiance
                && gn.dot(*normal) >= 0.9999
                && v.iter()
                    .all(|&q| (q - w[0]).length() <= extent && gn.dot(q - w[0]).abs() <= 1e-4 * extent)
        });
        if !joins {
            groups.push(Group {
                first: k,
                end: k,
                centroid: Vec3::ZERO,
                normal: *normal,
                radius: 0.0,
                area: 0.0,
                power: 0.0,
            });
        }
        let g = groups.last_mut().expect("a group was just pushed");
        g.end = k + 1;
        g.centroid += (v[0] + v[1] + v[2]) / 3.0 * area;
        g.area += area;
        g.power += power;
        power_cdf.push(g.power);
    }
    for g in &mut groups {
        g.centroid /= g.area;
        g.radius = triangles[g.first..g.end]
            .iter()
            .flat_map(|(v, _, _)| v.iter())
            .map(|&q| (q - g.centroid).length())
            .fold(0.0, f32::max);
    }
    (groups, power_cdf)
}
