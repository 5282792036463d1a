//! The time a sweep has left. Each image's seconds are predicted from the
//! measured images of its curve: a line through the two dearest (cost =
//! fixed part + a part per sample), or from one point in proportion to the
//! samples (an upper bound when part of the cost is fixed). A curve with no
//! measured image borrows the first measured image of its renderer.

/// Measured and predicted seconds of a sweep's images.
pub(super) struct Eta {
    /// `(curve, spp)` of each image, in render order; `None` the path tracer.
    jobs: Vec<(Option<usize>, u32)>,
    /// Measured seconds of the images done.
    seconds: Vec<Option<f64>>,
}

impl Eta {
    pub(super) fn new(jobs: &[(Option<usize>, u32)]) -> Self {
        Self {
            jobs: jobs.to_vec(),
            seconds: vec![None; jobs.len()],
        }
    }

    /// Image `i` took `seconds`.
    pub(super) fn measured(&mut self, i: usize, seconds: f64) {
        if let Some(s) = self.seconds.get_mut(i) {
            *s = Some(seconds);
        }
    }

    /// Predicted seconds of image `j`.
    fn predict(&self, j: usize) -> Option<f64> {
        let (curve, spp) = self.jobs[j];
        let spp = f64::from(spp);
        let done = |keep: &dyn Fn(Option<usize>) -> bool| -> Vec<(f64, f64)> {
            let mut v: Vec<(f64, f64)> = self
                .jobs
                .iter()
                .zip(&self.seconds)
                .filter_map(|(&(c, s), t)| t.filter(|_| keep(c)).map(|t| (f64::from(s), t)))
                .collect();
            v.sort_by(|a, b| a.0.total_cmp(&b.0));
            v
        };
        let same = done(&|c| c == curve);
        match same[..] {
            [.., (s1, t1), (s2, t2)] if s2 > s1 => {
                let per_sample = ((t2 - t1) / (s2 - s1)).max(0.0);
                Some((t2 + per_sample * (spp - s2)).max(0.0))
            }
            [.., (s1, t1)] => Some(t1 * spp / s1.max(1.0)),
            [] => {
                let kin = done(&|c| c.is_some() == curve.is_some());
                kin.first().map(|&(s1, t1)| t1 * spp / s1.max(1.0))
            }
        }
    }

    /// Seconds left while image `current` is `fraction` done after
    /// `elapsed` seconds; `None` while an image left has no prediction.
    pub(super) fn remaining(&self, current: usize, fraction: f64, elapsed: f64) -> Option<f64> {
        // Past a tenth of an image its own pace predicts it better.
        let now = if fraction >= 0.1 {
            elapsed * (1.0 - fraction) / fraction
        } else {
            (self.predict(current)? - elapsed).max(0.0)
        };
        let rest: Option<f64> = (current + 1..self.jobs.len()).map(|j| self.predict(j)).sum();
        Some(now + rest?)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Costs of 1 + 0.5·spp seconds are predicted exactly once a curve has
    /// two points; the other curve borrows the first one's in proportion.
    #[test]
    fn two_points_predict_a_linear_cost() {
        let jobs = [(Some(0), 1), (Some(0), 2), (Some(0), 8), (Some(1), 4)];
        let mut eta = Eta::new(&jobs);
        assert_eq!(eta.remaining(0, 0.0, 0.0), None);
        eta.measured(0, 1.5);
        assert_eq!(eta.predict(1), Some(3.0));
        assert_eq!(eta.predict(3), Some(6.0));
        eta.measured(1, 2.0);
        assert_eq!(eta.predict(2), Some(5.0));
        assert_eq!(eta.remaining(2, 0.5, 2.0), Some(2.0 + 6.0));
    }
}
