//! Directions uniform in the solid angle a triangle subtends (Arvo 1995,
//! "Stratified sampling of spherical triangles", in the robust form of
//! pbrt-v4): for direct light from a triangle close to the receiver, where
//! sampling by area weighs points by 1/d².

use glam::Vec3;

/// Below this solid angle (sr) `f32` loses the triangle's spherical excess
/// to rounding, and area sampling is as good (1/d² hardly changes across
/// it); above it the triangle covers most of the hemisphere and the
/// construction loses precision. pbrt-v4's bounds.
const MIN_SOLID_ANGLE: f32 = 3e-4;
const MAX_SOLID_ANGLE: f32 = 6.22;
/// Below this angular width (rad; solid angle over the longest side) a
/// sliver's samples stray off it by a sizeable part of its width: the
/// angles the construction sums carry rounding of about 10⁻⁷ rad, an
/// absolute error in the area swept (a quarter of the width measured at
/// 2·10⁻⁴). Area sampling is as good across so thin a triangle.
const MIN_WIDTH: f32 = 1e-3;

// The sine, cosine and arcsine below are polynomials in IEEE additions
// and multiplications only (Rust fuses none), so a sample gives the same
// bits on x86-64 and AArch64; the C library's `sinf` and `asinf` differ
// between them (and between its FMA and plain x86 variants).

/// `(sin x, cos x)` for `|x|` up to a few hundred: Cody–Waite reduction by
/// π/2, then Taylor series to x⁹ and x⁸ on `[−π/4, π/4]` (truncation below
/// 3·10⁻⁸).
#[inline(always)]
fn sin_cos(x: f32) -> (f32, f32) {
    // π/2 in two parts: the first exact in f32 with zeros in its low bits.
    const HALF_PI_HI: f32 = 1.570_312_5;
    const HALF_PI_LO: f32 = 4.838_268e-4;
    let k = (x * std::f32::consts::FRAC_2_PI).round();
    let r = (x - k * HALF_PI_HI) - k * HALF_PI_LO;
    let r2 = r * r;
    let s = r + r * r2 * (-1.0 / 6.0 + r2 * (1.0 / 120.0 + r2 * (-1.0 / 5040.0 + r2 * (1.0 / 362_880.0))));
    let c = 1.0 + r2 * (-0.5 + r2 * (1.0 / 24.0 + r2 * (-1.0 / 720.0 + r2 * (1.0 / 40_320.0))));
    match (k as i32).rem_euclid(4) {
        0 => (s, c),
        1 => (c, -s),
        2 => (-s, -c),
        _ => (-c, s),
    }
}

/// `asin x` for `x ∈ [0, 1]`: its series to x²¹ up to ½ (truncation below
/// 10⁻⁸), and `π/2 − 2 asin √((1 − x)/2)` above.
#[inline(always)]
fn asin(x: f32) -> f32 {
    #[inline(always)]
    fn series(x: f32) -> f32 {
        const C: [f32; 10] = [
            0.166_666_67,
            0.075,
            0.044_642_86,
            0.030_381_944,
            0.022_372_159,
            0.017_352_764,
            0.013_964_844,
            0.011_551_801,
            0.009_761_61,
            0.008_390_336,
        ];
        let x2 = x * x;
        let p = C.iter().rev().fold(0.0, |acc, &c| acc * x2 + c);
        x + x * x2 * p
    }
    if x <= 0.5 {
        series(x)
    } else {
        std::f32::consts::FRAC_PI_2 - 2.0 * series(((1.0 - x) * 0.5).max(0.0).sqrt())
    }
}

/// Angle between unit vectors, accurate near 0 and π.
#[inline(always)]
fn angle_between(a: Vec3, b: Vec3) -> f32 {
    if a.dot(b) < 0.0 {
        std::f32::consts::PI - 2.0 * asin(((a + b).length() * 0.5).min(1.0))
    } else {
        2.0 * asin(((b - a).length() * 0.5).min(1.0))
    }
}

/// The component of unit `v` orthogonal to unit `w`, normalized.
#[inline(always)]
fn orthogonal(v: Vec3, w: Vec3) -> Option<Vec3> {
    (v - w * v.dot(w)).try_normalize()
}

/// A direction from `p` uniform in the solid angle of triangle `v`, for
/// `(u0, u1) ∈ [0, 1)²`, and that solid angle; `None` where the triangle
/// subtends too little or too much for `f32` (see [`MIN_SOLID_ANGLE`]):
/// the caller samples by area there. Stratified in `(u0, u1)`: `u0`
/// sweeps the triangle's area from edge `v0 v2` on, `u1` goes from `v1`.
pub(crate) fn sample(v: &[Vec3; 3], p: Vec3, u0: f32, u1: f32) -> Option<(Vec3, f32)> {
    let a = (v[0] - p).try_normalize()?;
    let b = (v[1] - p).try_normalize()?;
    let c = (v[2] - p).try_normalize()?;
    let n_ab = a.cross(b).try_normalize()?;
    let n_bc = b.cross(c).try_normalize()?;
    let n_ca = c.cross(a).try_normalize()?;
    let alpha = angle_between(n_ab, -n_ca);
    let beta = angle_between(n_bc, -n_ab);
    let gamma = angle_between(n_ca, -n_bc);
    let pi = std::f32::consts::PI;
    let omega = alpha + beta + gamma - pi;
    let longest = (a - b).length().max((b - c).length()).max((c - a).length());
    if !(MIN_SOLID_ANGLE..=MAX_SOLID_ANGLE).contains(&omega) || omega < MIN_WIDTH * longest {
        return None;
    }
    // The sub-triangle a b' c' of area u0·Ω: c' on arc a c.
    let area = pi + u0 * omega;
    let (sin_area, cos_area) = sin_cos(area);
    let (sin_alpha, cos_alpha) = sin_cos(alpha);
    let sin_phi = sin_area * cos_alpha - cos_area * sin_alpha;
    let cos_phi = cos_area * cos_alpha + sin_area * sin_alpha;
    let k1 = cos_phi + cos_alpha;
    let k2 = sin_phi - sin_alpha * a.dot(b);
    // Zero only where the angle at `a` is (a triangle edge-on from `p`,
    // which the solid-angle bound has already turned away in practice).
    let den = (k2 * sin_phi + k1 * cos_phi) * sin_alpha;
    if den == 0.0 {
        return None;
    }
    let cos_bp = ((k2 + (k2 * cos_phi - k1 * sin_phi) * cos_alpha) / den).clamp(-1.0, 1.0);
    let sin_bp = (1.0 - cos_bp * cos_bp).max(0.0).sqrt();
    let cp = a * cos_bp + orthogonal(c, a)? * sin_bp;
    // Along arc b c', uniform in the remaining area.
    let cos_t = 1.0 - u1 * (1.0 - cp.dot(b));
    let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
    let w = b * cos_t + orthogonal(cp, b)? * sin_t;
    debug_assert!(w.is_finite(), "solid-angle sample {w} of triangle {v:?} from {p}");
    Some((w, omega))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Möller–Trumbore: whether the ray from `p` along `w` hits the triangle.
    fn hits(v: &[Vec3; 3], p: Vec3, w: Vec3) -> bool {
        let (e1, e2) = (v[1] - v[0], v[2] - v[0]);
        let q = w.cross(e2);
        let det = e1.dot(q);
        let s = (p - v[0]) / det;
        let (b1, r) = (s.dot(q), s.cross(e1));
        let b2 = w.dot(r);
        b1 >= -1e-4 && b2 >= -1e-4 && b1 + b2 <= 1.0 + 1e-4 && e2.dot(r) > 0.0
    }

    /// Every sample lies in the triangle, the solid angle is the closed
    /// form's (Van Oosterom and Strackee), and the samples are uniform in
    /// it: a cosine's mean over them is its integral over the triangle
    /// (quadrature by area, `cos θ cos θ' / d²`) divided by Ω.
    #[test]
    fn uniform_in_the_triangle_solid_angle() {
        let v = [
            Vec3::new(-0.3, 0.2, 1.0),
            Vec3::new(0.9, -0.1, 0.6),
            Vec3::new(0.1, 0.8, 0.4),
        ];
        let p = Vec3::new(0.05, 0.1, 0.0);
        let (a, b, c) = (
            (v[0] - p).normalize(),
            (v[1] - p).normalize(),
            (v[2] - p).normalize(),
        );
        let exact = 2.0
            * a.dot(b.cross(c))
                .abs()
                .atan2(1.0 + a.dot(b) + b.dot(c) + c.dot(a));
        let n = 256;
        let mut mean = 0.0f64;
        let mut omega = 0.0;
        for i in 0..n {
            for j in 0..n {
                let (u0, u1) = ((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
                let (w, o) = sample(&v, p, u0, u1).expect("a triangle of moderate solid angle");
                assert!(hits(&v, p, w), "sample {w} at ({u0}, {u1}) misses the triangle");
                mean += f64::from(w.z);
                omega = o;
            }
        }
        mean /= (n * n) as f64;
        approx::assert_relative_eq!(omega, exact, max_relative = 1e-4);
        // ∫ cos θ dω over the triangle, by its area.
        let normal = (v[1] - v[0]).cross(v[2] - v[0]);
        let twice_area = normal.length();
        let normal = normal / twice_area;
        let m = 1024;
        let mut integral = 0.0f64;
        for i in 0..m {
            for j in 0..m - i {
                let (s, t) = (
                    (i as f32 + 1.0 / 3.0) / m as f32,
                    (j as f32 + 1.0 / 3.0) / m as f32,
                );
                let q = v[0] + (v[1] - v[0]) * s + (v[2] - v[0]) * t;
                let d = q - p;
                let w = d.normalize();
                integral += f64::from(w.z * normal.dot(w).abs() / d.length_squared());
            }
        }
        integral *= f64::from(twice_area) / 2.0 / (m * m / 2) as f64;
        approx::assert_relative_eq!(mean, integral / f64::from(exact), max_relative = 2e-3);
    }

    /// The polynomials against the C library, over their ranges here.
    #[test]
    fn sine_cosine_and_arcsine() {
        for i in 0..=20_000 {
            let x = -20.0 + 40.0 * i as f32 / 20_000.0;
            let (s, c) = sin_cos(x);
            let (x64, s64, c64) = (f64::from(x), f64::from(x).sin(), f64::from(x).cos());
            assert!(
                (f64::from(s) - s64).abs() < 4e-7 && (f64::from(c) - c64).abs() < 4e-7,
                "sin_cos({x64})"
            );
        }
        for i in 0..=20_000 {
            let x = i as f32 / 20_000.0;
            let a = f64::from(asin(x));
            assert!(
                (a - f64::from(x).asin()).abs() <= 3e-7 * f64::from(x).asin().max(1e-3),
                "asin({x})"
            );
        }
    }

    /// How far (relative to its distance) the ray from `p` along `w` passes
    /// outside the triangle, in its plane: 0 inside.
    fn miss(v: &[Vec3; 3], p: Vec3, w: Vec3) -> f32 {
        let n = (v[1] - v[0]).cross(v[2] - v[0]).normalize();
        let q = p + w * (n.dot(v[0] - p) / n.dot(w));
        let edge = |a: Vec3, b: Vec3| {
            let t = ((q - a).dot(b - a) / (b - a).length_squared()).clamp(0.0, 1.0);
            (q - (a + (b - a) * t)).length()
        };
        let inside = (0..3).all(|i| (v[(i + 1) % 3] - v[i]).cross(q - v[i]).dot(n) >= 0.0);
        let d = if inside {
            0.0
        } else {
            edge(v[0], v[1]).min(edge(v[1], v[2])).min(edge(v[2], v[0]))
        };
        d / (q - p).length()
    }

    /// The longest side of triangle `v` seen from `p` (radians).
    fn longest(v: &[Vec3; 3], p: Vec3) -> f32 {
        let d = v.map(|q| (q - p).normalize());
        (0..3)
            .map(|i| d[i].angle_between(d[(i + 1) % 3]))
            .fold(0.0, f32::max)
    }

    /// Slivers and needles, seen from close by at every orientation: each
    /// sample is finite and in the triangle, or the triangle is refused.
    /// "In" up to rounding: the construction goes through the triangle's
    /// angles, whose `f32` rounding is an absolute error in the area swept,
    /// so across a sliver (angular width Ω / longest side) a sample may
    /// stray by a fraction of that width; a quarter is allowed, and the
    /// light estimate, which takes the triangle's radiance and 1/Ω, does not
    /// see it.
    #[test]
    fn slivers_give_samples_in_the_triangle_or_none() {
        let (mut sampled, mut worst) = (0, 0.0f32);
        for k in 0..64 {
            let t = k as f32 * 0.1;
            let (s, c) = (t.sin(), t.cos());
            let thin = 10f32.powi(-(k % 6) - 1);
            let p = Vec3::new(0.01 * c, 0.02 * s, -0.05);
            // A needle from the origin, and a sliver whose apex almost
            // lies on its base.
            for v in [
                [Vec3::ZERO, Vec3::new(c, s, 0.3), Vec3::new(c, s + thin, 0.3)],
                [
                    Vec3::new(-1.0, 0.0, 0.2),
                    Vec3::new(1.0, 0.0, 0.2),
                    Vec3::new(0.1 * c, thin, 0.2),
                ],
            ] {
                for i in 0..16 {
                    for j in 0..16 {
                        let (u0, u1) = ((i as f32 + 0.5) / 16.0, (j as f32 + 0.5) / 16.0);
                        if let Some((w, omega)) = sample(&v, p, u0, u1) {
                            let m = miss(&v, p, w) / (omega / longest(&v, p));
                            worst = worst.max(m);
                            assert!(
                                w.is_finite() && m < 0.25,
                                "{w} for {v:?} from {p}: {m} of the width"
                            );
                            sampled += 1;
                        }
                    }
                }
            }
        }
        // Most are sampled: the test is not passed by refusing them.
        assert!(sampled > 2 * 64 * 256 / 3, "{sampled}");
        println!("{sampled} samples, the furthest {worst} of the width outside");
    }

    #[test]
    fn too_small_or_edge_on_falls_back_to_area() {
        let v = [
            Vec3::new(0.0, 0.0, 100.0),
            Vec3::new(0.1, 0.0, 100.0),
            Vec3::new(0.0, 0.1, 100.0),
        ];
        assert!(sample(&v, Vec3::ZERO, 0.5, 0.5).is_none());
        let v = [
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(2.0, 0.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
        ];
        assert!(sample(&v, Vec3::ZERO, 0.5, 0.5).is_none());
    }
}
