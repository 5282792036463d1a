//! Convex polygons seen from a point: clipping to a half-plane and Lambert's
//! formula for the projected solid angle. The microbuffer's exact per-pixel
//! integrals and the closed-form references (`exact`) both use them.

use std::ops::{Add, Mul, Sub};

use glam::DVec3;

/// Clips the convex polygon `poly` to `side(q) ≥ 0` (Sutherland–Hodgman),
/// `side` linear in `q`.
pub(crate) fn clip<P>(poly: &[P], side: impl Fn(P) -> f64) -> Vec<P>
where
    P: Copy + Add<Output = P> + Sub<Output = P> + Mul<f64, Output = P>,
{
    let mut out = Vec::with_capacity(poly.len() + 1);
    for i in 0..poly.len() {
        let (p, q) = (poly[i], poly[(i + 1) % poly.len()]);
        let (dp, dq) = (side(p), side(q));
        if dp >= 0.0 {
            out.push(p);
        }
        if (dp >= 0.0) != (dq >= 0.0) {
            out.push(p + (q - p) * (dp / (dp - dq)));
        }
    }
    out
}

/// `∫ cosθ dω` (θ from `n`) over the convex polygon `poly` seen from the
/// origin, by Lambert's formula `½ |Σ θᵢ γᵢ·n|`: θᵢ the angle edge `i`
/// subtends, γᵢ the unit normal of the plane through it and the origin.
pub(crate) fn projected_solid_angle(poly: &[DVec3], n: DVec3) -> f64 {
    if poly.len() < 3 {
        return 0.0;
    }
    let mut sum = 0.0;
    for i in 0..poly.len() {
        let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
        let c = a.cross(b);
        let len = c.length();
        if len > 0.0 {
            sum += len.atan2(a.dot(b)) * c.dot(n) / len;
        }
    }
    (0.5 * sum).abs()
}
