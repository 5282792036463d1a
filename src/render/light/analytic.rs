//! The emitters' direct light in closed form, shadows aside (Lambert's
//! polygon formula per triangle, clipped to the receiver's horizon), and
//! one point on them above the horizon: what [`LightSamples::ratio`]
//! multiplies by the samples' shadow ratio.

use glam::{DVec3, Vec3};

#[cfg(doc)]
use super::LightSamples;
use super::groups::pick;
use super::{ANALYTIC_TRIANGLES, Lights};
use crate::polygon::projected_solid_angle;
use crate::render::trace::Tracer;

/// The triangle `v` (seen from the origin) clipped to `n·q ≥ 0`: at most
/// four corners, the first `len` of them.
fn above_horizon(v: [DVec3; 3], n: DVec3) -> ([DVec3; 4], usize) {
    let mut out = [DVec3::ZERO; 4];
    let mut len = 0;
    for i in 0..3 {
        let (p, q) = (v[i], v[(i + 1) % 3]);
        let (dp, dq) = (p.dot(n), q.dot(n));
        if dp >= 0.0 {
            out[len] = p;
            len += 1;
        }
        if (dp >= 0.0) != (dq >= 0.0) {
            out[len] = p + (q - p) * (dp / (dp - dq));
            len += 1;
        }
    }
    (out, len)
}

impl Lights {
    /// The groups a receiver works out in closed form, a bit each: those
    /// that give it light (`cdf` holds the cumulative sums of their
    /// estimates there), where the scene has at most
    /// [`ANALYTIC_TRIANGLES`] emissive triangles; else none. (Working out
    /// a subset, the groups of the largest estimates, cost more than the
    /// shadow rays in a nave of 208 window triangles, and took nothing
    /// from its error.)
    pub(super) fn closed_groups(&self, cdf: &[f32]) -> u64 {
        if self.triangles.len() > ANALYTIC_TRIANGLES {
            return 0;
        }
        (0..cdf.len())
            .filter(|&g| cdf[g] > if g == 0 { 0.0 } else { cdf[g - 1] })
            .fold(0, |bits, g| bits | 1 << g)
    }

    /// The triangles of the groups in `closed`, seen from the front.
    fn closed_triangles(&self, origin: Vec3, closed: u64) -> impl Iterator<Item = usize> + '_ {
        self.groups
            .iter()
            .enumerate()
            .filter(move |(g, _)| closed >> g & 1 == 1)
            .flat_map(|(_, group)| group.first..group.end)
            .filter(move |&k| {
                let (v, ln, _) = &self.triangles[k];
                ln.dot(origin - v[0]) > 0.0
            })
    }

    /// `∫ Le cosθ dω` over the fronts of the groups in `closed`, above
    /// `origin`'s horizon (normal `n`), shadows aside: each triangle
    /// clipped to the horizon, by Lambert's formula, in `f64`.
    pub(super) fn unshadowed(&self, origin: Vec3, n: Vec3, closed: u64) -> Vec3 {
        let (o, nd) = (origin.as_dvec3(), n.as_dvec3());
        let mut e = DVec3::ZERO;
        for k in self.closed_triangles(origin, closed) {
            let (v, _, radiance) = &self.triangles[k];
            let (poly, len) = above_horizon(v.map(|q| q.as_dvec3() - o), nd);
            e += radiance.as_dvec3() * projected_solid_angle(&poly[..len], nd);
        }
        e.as_vec3()
    }

    /// 1 if a point on the fronts of the groups in `closed` above
    /// `origin`'s horizon is lit, else 0: the triangle picked by `u` in
    /// proportion to its unshadowed light, and the point uniform by area
    /// over its part above the horizon (`u`'s remainder and `w`).
    pub(super) fn lit_above_horizon(
        &self,
        tracer: &Tracer,
        origin: Vec3,
        n: Vec3,
        closed: u64,
        u: f32,
        w: f32,
    ) -> f32 {
        let (o, nd) = (origin.as_dvec3(), n.as_dvec3());
        let mut parts = [([DVec3::ZERO; 4], 0usize); ANALYTIC_TRIANGLES];
        let mut cdf = [0.0f32; ANALYTIC_TRIANGLES];
        let (mut total, mut count) = (0.0f32, 0);
        for k in self.closed_triangles(origin, closed).take(ANALYTIC_TRIANGLES) {
            let (v, _, radiance) = &self.triangles[k];
            parts[count] = above_horizon(v.map(|q| q.as_dvec3() - o), nd);
            let (poly, len) = &parts[count];
            total += (radiance.x + radiance.y + radiance.z) * projected_solid_angle(&poly[..*len], nd) as f32;
            cdf[count] = total;
            count += 1;
        }
        if total <= 0.0 {
            return 0.0;
        }
        let (k, u) = pick(&cdf[..count], u * total);
        let (poly, len) = parts[k];
        if len < 3 {
            return 0.0;
        }
        // A fan of at most two triangles, one picked by area.
        let area = |i: usize| (poly[i] - poly[0]).cross(poly[i + 1] - poly[0]).length();
        let (a1, a2) = (area(1), if len == 4 { area(2) } else { 0.0 });
        let x = f64::from(u) * (a1 + a2);
        let (i, u) = if x < a1 || a2 <= 0.0 {
            (1, x / a1)
        } else {
            (2, (x - a1) / a2)
        };
        let su = u.clamp(0.0, 1.0).sqrt();
        let (a, b) = (su * (1.0 - f64::from(w)), su * f64::from(w));
        let q = poly[0] + (poly[i] - poly[0]) * a + (poly[i + 1] - poly[0]) * b;
        // Nudged a thousandth towards the centroid: a corner lies on the
        // horizon itself.
        let centroid = poly[..len].iter().sum::<DVec3>() / len as f64;
        let q = (q + (centroid - q) * 1e-3).as_vec3();
        let dist = q.length();
        if dist <= 0.0 || n.dot(q) <= 0.0 {
            return 0.0;
        }
        let eps = tracer.epsilon();
        if tracer.occluded(origin, q / dist, dist * (1.0 - 1e-4) - eps) {
            0.0
        } else {
            1.0
        }
    }
}
