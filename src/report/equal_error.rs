//! Time at equal error: where each curve reaches a given relative RMSE, and
//! how much sooner the point-based renderer gets there than the path tracer.

use super::sweep::{ErrorPoint, Method};

/// One curve of a sweep's points.
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    /// Which renderer.
    pub method: Method,
    /// The curve's label.
    pub label: String,
    /// `(spp, seconds, relative RMSE)`, by rising spp (the cost along it).
    pub points: Vec<(u32, f64, f64)>,
    /// Its error floor: what its last two points leave ([`fitted_floor`]),
    /// or its costliest point's mean offset ([`ErrorPoint::floor`]) with
    /// (point-based curves) the reference's noise, the path tracer's
    /// fitted floor, added in quadrature, the larger; no extrapolation
    /// along it goes below.
    pub floor: f64,
}

impl Series {
    /// `(seconds, error)` along the curve.
    pub fn time_error(&self) -> Vec<(f64, f64)> {
        self.points.iter().map(|&(_, t, e)| (t, e)).collect()
    }
}

/// The curves of `points`, in order of first appearance.
pub fn series(points: &[ErrorPoint]) -> Vec<Series> {
    let mut out: Vec<Series> = Vec::new();
    for p in points {
        let point = (p.spp, p.total_s, p.rel_rmse);
        match out
            .iter_mut()
            .find(|s| s.method == p.method && s.label == p.label)
        {
            Some(s) => s.points.push(point),
            None => out.push(Series {
                method: p.method,
                label: p.label.clone(),
                points: vec![point],
                floor: 0.0,
            }),
        }
    }
    for s in &mut out {
        s.points.sort_by_key(|p| p.0);
    }
    // The path tracer's floor is the reference's own noise (a path-traced
    // image too), which every curve measured against it keeps.
    let reference = out
        .iter()
        .find(|s| s.method == Method::PathTracer)
        .map_or(0.0, |s| fitted_floor(&s.points));
    for s in &mut out {
        let costliest = points
            .iter()
            .filter(|p| p.method == s.method && p.label == s.label)
            .max_by_key(|p| p.spp);
        let offset = costliest.map_or(0.0, |p| p.floor);
        s.floor = fitted_floor(&s.points).max(match s.method {
            Method::PathTracer => offset,
            Method::PointBased | Method::Denoised => offset.hypot(reference),
        });
    }
    out
}

/// The error its last two points leave at infinitely many samples, along
/// error² = floor² + c/spp (0 for fewer points, or where they fall faster
/// than that): the floor of an error that is no mean offset, which
/// [`ErrorPoint::floor`] misses. Sponza's coarse curve read 4.30 % at 8 spp
/// and 3.55 % at 16 (a 2.6 % floor) and measured 3.13 % at 64, where the
/// 0.75 % its mean offset made had it reach 2 % at 20 s: a few hundred
/// pixels where the gather misses light from a surface in contact hold
/// most of its squared error (docs/lab/BENCHMARKS.md, "Sponza's error floor").
///
/// ```
/// use pbgi::report::fitted_floor;
///
/// // Error² 0.0005 + 0.0032/spp: the floor √0.0005 comes back.
/// let e = |spp: f64| (0.0005 + 0.0032 / spp).sqrt();
/// let f = fitted_floor(&[(4, 1.0, e(4.0)), (8, 2.0, e(8.0)), (16, 4.0, e(16.0))]);
/// assert!((f - 0.0005f64.sqrt()).abs() < 1e-9);
/// // Noise alone (error ∝ 1/√spp): no floor.
/// assert!(fitted_floor(&[(4, 1.0, 0.04), (16, 4.0, 0.02)]) < 1e-9);
/// ```
pub fn fitted_floor(points: &[(u32, f64, f64)]) -> f64 {
    let [.., (s1, _, e1), (s2, _, e2)] = points else {
        return 0.0;
    };
    if s2 <= s1 {
        return 0.0; // two points at one spp say nothing of the floor
    }
    let (s1, s2) = (f64::from(*s1), f64::from(*s2));
    let f2 = (e2 * e2 * s2 - e1 * e1 * s1) / (s2 - s1);
    if f2 > 0.0 { f2.sqrt() } else { 0.0 }
}

/// When a curve reaches an error.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reach {
    /// Wall-clock seconds.
    pub seconds: f64,
    /// Whether it lies beyond the measured points (extrapolated along
    /// error² = floor² + c/t) rather than between two of them.
    pub extrapolated: bool,
}

/// The time at which a curve of `(seconds, error)` points, in order of rising
/// cost, first reaches `error`, for a curve with no error floor: see
/// [`time_above_floor`].
///
/// ```
/// use pbgi::report::time_for;
///
/// let curve = [(1.0, 0.08), (4.0, 0.04)];
/// let r = time_for(&curve, 0.04 * 2f64.sqrt()).unwrap(); // halfway in log-log
/// assert!((r.seconds - 2.0).abs() < 1e-9 && !r.extrapolated);
/// let r = time_for(&curve, 0.02).unwrap(); // 1/√t beyond the end
/// assert!((r.seconds - 16.0).abs() < 1e-9 && r.extrapolated);
/// assert!(time_for(&[(1.0, 0.03), (2.0, 0.03)], 0.02).is_none());
/// ```
pub fn time_for(curve: &[(f64, f64)], error: f64) -> Option<Reach> {
    time_above_floor(curve, 0.0, error)
}

/// The time at which a curve of `(seconds, error)` points, in order of rising
/// cost, first reaches `error`: between the two points that bracket it,
/// log(time) interpolated linearly in log(error); beyond its ends along
/// error² = floor² + c/t from the nearest point (the noise's share falling
/// as 1/t, the floor's staying: [`ErrorPoint::floor`]), marked
/// extrapolated. `None` if no point has positive time and error, if the
/// error lies below every point and at or below the floor (a bias that more
/// samples do not remove), or below every point of a curve that stopped
/// falling (its last point no lower than the one before).
///
/// ```
/// use pbgi::report::time_above_floor;
///
/// let curve = [(1.0, 0.05), (4.0, 0.03)];
/// // Error² 0.0009 = 0.0004 + 0.0005: a quarter of the noise's share left
/// // for 0.0004 + 0.000125 = 0.000525, four times the time.
/// let r = time_above_floor(&curve, 0.02, 0.000525f64.sqrt()).unwrap();
/// assert!((r.seconds - 16.0).abs() < 1e-9 && r.extrapolated);
/// assert!(time_above_floor(&curve, 0.02, 0.02).is_none()); // the floor itself
/// ```
pub fn time_above_floor(curve: &[(f64, f64)], floor: f64, error: f64) -> Option<Reach> {
    let ok = |x: f64| x > 0.0 && x.is_finite();
    let pts: Vec<(f64, f64)> = curve.iter().copied().filter(|&(t, e)| ok(t) && ok(e)).collect();
    // A floor that is no error (negative, NaN, infinite) says nothing of
    // where the curve goes: no answer, as for such an error.
    if !ok(error) || !(floor >= 0.0 && floor.is_finite()) {
        return None;
    }
    // Time along error² = floor² + c/t from the point (t, e).
    let along = |t: f64, e: f64| t * (e * e - floor * floor).max(0.0) / (error * error - floor * floor);
    let &(t0, e0) = pts.first()?;
    if e0 <= error {
        return (error > floor).then(|| Reach {
            seconds: along(t0, e0),
            extrapolated: e0 < error,
        });
    }
    // The first point at or below the error; the one before is above it.
    if let Some(k) = pts.iter().position(|&(_, e)| e <= error) {
        let ((ta, ea), (tb, eb)) = (pts[k - 1], pts[k]);
        let f = (error / ea).ln() / (eb / ea).ln();
        return Some(Reach {
            seconds: (ta.ln() + f * (tb / ta).ln()).exp(),
            extrapolated: false,
        });
    }
    let &(tn, en) = pts.last()?;
    let still_falling = pts.len() < 2 || en < pts[pts.len() - 2].1;
    (still_falling && error > floor).then(|| Reach {
        seconds: along(tn, en),
        extrapolated: true,
    })
}

/// One row of the equal-error table.
#[derive(Clone, Debug, PartialEq)]
pub struct EqualError {
    /// The relative RMSE.
    pub error: f64,
    /// When the path tracer reaches it.
    pub path_tracer: Option<Reach>,
    /// The point-based curve that reaches it soonest, and when; one that
    /// reaches it between measured points wins over any extrapolated one.
    pub point_based: Option<(String, Reach)>,
    /// The denoised path tracing that reaches it soonest, chosen alike.
    pub denoised: Option<(String, Reach)>,
}

impl EqualError {
    /// The path tracer's time over the point-based one (above 1: the
    /// point-based renderer is faster), extrapolated if either is.
    pub fn ratio(&self) -> Option<Reach> {
        Some(over(self.path_tracer?, self.point_based.as_ref()?.1))
    }

    /// The best denoised path tracing's time over the point-based one
    /// (above 1: the point-based renderer is faster).
    pub fn ratio_denoised(&self) -> Option<Reach> {
        Some(over(self.denoised.as_ref()?.1, self.point_based.as_ref()?.1))
    }
}

/// `a`'s time over `b`'s, extrapolated if either is.
fn over(a: Reach, b: Reach) -> Reach {
    Reach {
        seconds: a.seconds / b.seconds,
        extrapolated: a.extrapolated || b.extrapolated,
    }
}

/// Keeps the sooner of `best` and `(label, r)`: measured beats
/// extrapolated, as the model flatters a curve beyond its ends (fixed costs
/// below).
pub(super) fn keep_soonest(best: &mut Option<(String, Reach)>, label: &str, r: Reach) {
    let key = |r: &Reach| (r.extrapolated, r.seconds);
    if best.as_ref().is_none_or(|b| key(&r) < key(&b.1)) {
        *best = Some((label.to_string(), r));
    }
}

/// The equal-error table of `points` at each of `errors`.
pub fn equal_error(points: &[ErrorPoint], errors: &[f64]) -> Vec<EqualError> {
    let all = series(points);
    errors
        .iter()
        .map(|&error| {
            let mut path_tracer = None;
            let (mut point_based, mut denoised) = (None, None);
            for s in &all {
                let Some(r) = time_above_floor(&s.time_error(), s.floor, error) else {
                    continue;
                };
                match s.method {
                    Method::PathTracer => path_tracer = Some(r),
                    Method::PointBased => keep_soonest(&mut point_based, &s.label, r),
                    Method::Denoised => keep_soonest(&mut denoised, &s.label, r),
                }
            }
            EqualError {
                error,
                path_tracer,
                point_based,
                denoised,
            }
        })
        .collect()
}
