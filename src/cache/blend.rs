//! A blend: the sums a point gathers from the records of one level around
//! it (their weighted light and the moments of where they lie), and the
//! light they give at the point, read off the plane they fit.

use glam::Vec3;

use super::grid::Key;

/// The records around the last cell a point was blended in: the next
/// point of the same cell and facing (most, since points come in tile
/// order) reads them without probing the 27 cells again.
#[derive(Clone, Copy, Default)]
pub(super) struct Around {
    pub(super) key: Option<Key>,
    pub(super) records: [u32; 27],
    pub(super) len: usize,
}

/// What the records of one level give a point.
pub(super) struct Blend {
    pub(super) sum: Vec3,
    pub(super) weight: f32,
    pub(super) lo: f32,
    pub(super) hi: f32,
    /// Weighted moments of the records' offsets (u, v) in the point's
    /// tangent plane, in cell sides, and of the light times them.
    pub(super) su: f32,
    pub(super) sv: f32,
    pub(super) suu: f32,
    pub(super) suv: f32,
    pub(super) svv: f32,
    pub(super) seu: Vec3,
    pub(super) sev: Vec3,
    pub(super) elo: Vec3,
    pub(super) ehi: Vec3,
}

/// The least determinant of the records' weighted covariance in the
/// tangent plane (in cell sides⁴) for which a blend fits a plane to their
/// light: below it they lie too nearly on a line, or at a point, for the
/// plane to be read off them, and the blend is their weighted mean.
const FIT_SPREAD: f32 = 1e-3;

impl Blend {
    /// No record yet.
    pub(super) fn empty() -> Self {
        Blend {
            sum: Vec3::ZERO,
            weight: 0.0,
            lo: f32::INFINITY,
            hi: 0.0,
            su: 0.0,
            sv: 0.0,
            suu: 0.0,
            suv: 0.0,
            svv: 0.0,
            seu: Vec3::ZERO,
            sev: Vec3::ZERO,
            elo: Vec3::INFINITY,
            ehi: Vec3::ZERO,
        }
    }

    /// The light at the point: the value there of the weighted
    /// least-squares plane through the records' light (exact where the
    /// light changes linearly along the surface, where their weighted mean
    /// leans to the nearest records), kept within the records' own range so
    /// that it never extrapolates their noise; their weighted mean where
    /// they cannot hold a plane up.
    pub(super) fn light(&self) -> Vec3 {
        let mean = self.sum / self.weight;
        let s = self.weight;
        let (mu, mv) = (self.su / s, self.sv / s);
        let (cuu, cuv, cvv) = (
            self.suu / s - mu * mu,
            self.suv / s - mu * mv,
            self.svv / s - mv * mv,
        );
        let spread = cuu * cvv - cuv * cuv;
        if spread.is_nan() || spread <= FIT_SPREAD {
            return mean;
        }
        // The first row of the inverse of the moments' matrix (symmetric:
        // cofactors), applied to the light's moments.
        let c00 = self.suu * self.svv - self.suv * self.suv;
        let c01 = self.suv * self.sv - self.su * self.svv;
        let c02 = self.su * self.suv - self.suu * self.sv;
        let det = s * c00 + self.su * c01 + self.sv * c02;
        let a = (self.sum * c00 + self.seu * c01 + self.sev * c02) / det;
        // A NaN stays NaN (glam's `clamp` would make it a bound): only a
        // defect upstream brings one, and the renderer reports it.
        if a.is_nan() {
            a
        } else {
            a.clamp(self.elo, self.ehi)
        }
    }
}
