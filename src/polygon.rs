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

/// The angle `atan2(s, c)` for `s ≥ 0`, in `[0, π]`, from IEEE-exact
/// operations alone: the C library's `atan2` may round its last bit
/// differently on another ISA, and the direct light (`render::light`)
/// takes it per camera sample, whose image must be the same bits there.
/// Two half-angle steps bring the tangent under tan(π/16), where ten terms
/// of its series are exact to about 1e-15.
pub(crate) fn angle(s: f64, c: f64) -> f64 {
    use std::f64::consts::{FRAC_PI_2, PI};
    // atan of t in [-1, 1].
    let atan = |t: f64| {
        let mut u = t;
        for _ in 0..2 {
            u /= 1.0 + (1.0 + u * u).sqrt();
        }
        let u2 = u * u;
        let mut p = 0.0;
        for k in (0..10).rev() {
            p = 1.0 / f64::from(2 * k + 1) - u2 * p;
        }
        4.0 * u * p
    };
    if s == 0.0 && c >= 0.0 {
        0.0
    } else if c >= s {
        atan(s / c)
    } else if -c >= s {
        PI - atan(s / -c)
    } else {
        FRAC_PI_2 - atan(c / s)
    }
}

/// [`projected_solid_angle`] of the triangle `v` (seen from the origin)
/// clipped to `n·q ≥ 0`, the half-space above a receiver's horizon, without
/// allocating: the direct light's closed form runs per camera sample.
pub(crate) fn triangle_projected_solid_angle(v: [DVec3; 3], n: DVec3) -> f64 {
    let side = v.map(|q| n.dot(q));
    let mut poly = [DVec3::ZERO; 4];
    let mut len = 0;
    for i in 0..3 {
        let (j, dp, dq) = ((i + 1) % 3, side[i], side[(i + 1) % 3]);
        if dp >= 0.0 {
            poly[len] = v[i];
            len += 1;
        }
        if (dp >= 0.0) != (dq >= 0.0) {
            poly[len] = v[i] + (v[j] - v[i]) * (dp / (dp - dq));
            len += 1;
        }
    }
    if len < 3 {
        return 0.0;
    }
    let mut sum = 0.0;
    for i in 0..len {
        let (a, b) = (poly[i], poly[(i + 1) % len]);
        let c = a.cross(b);
        let l = c.length();
        if l > 0.0 {
            sum += angle(l, a.dot(b)) * c.dot(n) / l;
        }
    }
    (0.5 * sum).abs()
}

#[cfg(test)]
mod tests {
    use glam::DVec3;

    use super::{angle, clip, projected_solid_angle, triangle_projected_solid_angle};
    use crate::rng::Rng;

    /// The series-based angle is `atan2` to rounding, in every octant.
    #[test]
    fn angle_is_atan2() {
        let mut rng = Rng::new(3);
        for i in 0..100_000 {
            let s = f64::from(rng.f32()) * if i % 7 == 0 { 1e-9 } else { 1.0 };
            let c = 2.0 * f64::from(rng.f32()) - 1.0;
            let (a, b) = (angle(s, c), s.atan2(c));
            assert!(
                (a - b).abs() <= 4.0 * f64::EPSILON * b.max(1e-300),
                "angle({s}, {c}) = {a}, atan2 {b}"
            );
        }
        assert_eq!(angle(0.0, 0.0), 0.0);
        assert_eq!(angle(0.0, -1.0), std::f64::consts::PI);
        assert_eq!(angle(1.0, 0.0), std::f64::consts::FRAC_PI_2);
    }

    /// The clipped triangle's closed form is the general polygon's, whichever
    /// of its corners lie below the horizon.
    #[test]
    fn triangle_matches_the_clipped_polygon() {
        let mut rng = Rng::new(5);
        for _ in 0..20_000 {
            let v = [(); 3].map(|_| rng.unit_vector().as_dvec3() * (0.1 + 2.0 * f64::from(rng.f32())));
            let n = rng.unit_vector().as_dvec3();
            let clipped = clip(&v, |q| n.dot(q));
            let (a, b) = (
                triangle_projected_solid_angle(v, n),
                projected_solid_angle(&clipped, n),
            );
            assert!((a - b).abs() <= 1e-12, "{v:?} {n}: {a} against {b}");
        }
        // Wholly below: nothing.
        let v = [
            DVec3::new(0.0, -1.0, 0.0),
            DVec3::new(1.0, -1.0, 0.0),
            DVec3::new(0.0, -1.0, 1.0),
        ];
        assert_eq!(triangle_projected_solid_angle(v, DVec3::Y), 0.0);
    }
}
