//! A straight line through sonar echoes, and how well it fits.

/// The line of least squared perpendicular distance through a set of
/// points (a total least squares fit, from the points' second moments).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LineFit {
    /// The line's direction, radians, in (−π/2, π/2].
    pub direction: f64,
    /// RMS of the points' perpendicular distances from the line, m.
    pub rms_m: f64,
    /// RMS of the points' positions along the line about their mean, m:
    /// how much of the line they cover.
    pub spread_m: f64,
    /// How many points it was fitted to.
    pub points: usize,
}

impl LineFit {
    /// The variance of [`LineFit::direction`], rad², for points scattered
    /// about the line by at least `noise_m` (σ): the scatter over the
    /// points' spread along it, shared among them. The larger of the
    /// residual and `noise_m` stands for the scatter, so that a few points
    /// lying on the line by chance do not claim a perfect direction.
    pub fn direction_variance(&self, noise_m: f64) -> f64 {
        let dof = (self.points as f64 - 2.0).max(1.0);
        let scatter = (self.rms_m.powi(2) * self.points as f64 / dof).max(noise_m.powi(2));
        scatter / (self.points as f64 * self.spread_m.powi(2).max(f64::MIN_POSITIVE))
    }
}

/// The sums a [`LineFit`] needs, taken point by point: as many points as
/// come, in constant memory. Sums are about the first point, so that points
/// metres from the origin lose no precision.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Moments {
    origin: Option<(f64, f64)>,
    count: usize,
    sx: f64,
    sy: f64,
    sxx: f64,
    syy: f64,
    sxy: f64,
}

impl Moments {
    /// Takes in the point `(x, y)`.
    pub fn add(&mut self, x: f64, y: f64) {
        let (ox, oy) = *self.origin.get_or_insert((x, y));
        let (dx, dy) = (x - ox, y - oy);
        self.count += 1;
        self.sx += dx;
        self.sy += dy;
        self.sxx += dx * dx;
        self.syy += dy * dy;
        self.sxy += dx * dy;
    }

    /// The line through the points so far; `None` for fewer than three,
    /// which leave no residual to judge it by.
    pub fn fit(&self) -> Option<LineFit> {
        if self.count < 3 {
            return None;
        }
        let n = self.count as f64;
        let (mx, my) = (self.sx / n, self.sy / n);
        let sxx = self.sxx / n - mx * mx;
        let syy = self.syy / n - my * my;
        let sxy = self.sxy / n - mx * my;
        // The moments' eigenvalues: the larger lies along the line, the
        // smaller across it.
        let half_sum = (sxx + syy) / 2.0;
        let half_gap = ((sxx - syy) / 2.0).hypot(sxy);
        Some(LineFit {
            direction: 0.5 * (2.0 * sxy).atan2(sxx - syy),
            rms_m: (half_sum - half_gap).max(0.0).sqrt(),
            spread_m: (half_sum + half_gap).max(0.0).sqrt(),
            points: self.count,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    impl LineFit {
        /// The fit to `points`, as the compass's traces sum them.
        fn of(points: &[(f64, f64)]) -> Option<LineFit> {
            let mut moments = Moments::default();
            for &(x, y) in points {
                moments.add(x, y);
            }
            moments.fit()
        }
    }

    #[test]
    fn points_on_a_line_give_its_direction_and_no_residual() {
        let angle = 0.3_f64;
        let points: Vec<_> = (0..20).map(|k| (1.0 + k as f64 * angle.cos(), -2.0 + k as f64 * angle.sin())).collect();
        let fit = LineFit::of(&points).unwrap();
        assert!((fit.direction - angle).abs() < 1e-12, "{fit:?}");
        assert!(fit.rms_m < 1e-9, "{fit:?}");
        assert_eq!(fit.points, 20);
    }

    #[test]
    fn the_direction_is_the_same_either_way_along_the_line() {
        let forward: Vec<_> = (0..10).map(|k| (k as f64, 0.1 * k as f64)).collect();
        let backward: Vec<_> = forward.iter().rev().copied().collect();
        let (a, b) = (LineFit::of(&forward).unwrap(), LineFit::of(&backward).unwrap());
        assert!((a.direction - b.direction).abs() < 1e-12);
        assert!((a.direction - 0.1_f64.atan()).abs() < 1e-12);
    }

    #[test]
    fn scatter_across_the_line_is_its_residual() {
        // Alternating ±5 cm about the x axis.
        let points: Vec<_> = (0..40).map(|k| (0.1 * k as f64, if k % 2 == 0 { 0.05 } else { -0.05 })).collect();
        let fit = LineFit::of(&points).unwrap();
        assert!((fit.rms_m - 0.05).abs() < 1e-3, "{fit:?}");
        assert!(fit.direction.abs() < 0.01, "{fit:?}");
    }

    #[test]
    fn the_direction_is_surer_the_longer_the_line_and_the_quieter_its_points() {
        let line = |length: f64| {
            let points: Vec<_> = (0..20).map(|k| (length * k as f64 / 19.0, 0.0)).collect();
            LineFit::of(&points).unwrap()
        };
        assert!(line(4.0).direction_variance(0.02) < line(1.0).direction_variance(0.02));
        assert!(line(2.0).direction_variance(0.01) < line(2.0).direction_variance(0.02));
    }

    #[test]
    fn moments_far_from_the_origin_fit_as_well_as_near_it() {
        let near: Vec<_> = (0..50).map(|k| (0.04 * k as f64, 0.002 * k as f64 + 0.01 * (k % 3) as f64)).collect();
        let far: Vec<_> = near.iter().map(|(x, y)| (x + 5000.0, y - 3000.0)).collect();
        let (a, b) = (LineFit::of(&near).unwrap(), LineFit::of(&far).unwrap());
        assert!((a.direction - b.direction).abs() < 1e-9 && (a.rms_m - b.rms_m).abs() < 1e-9, "{a:?} {b:?}");
    }

    #[test]
    fn too_few_points_are_no_line() {
        assert!(LineFit::of(&[(0.0, 0.0), (1.0, 0.0)]).is_none());
    }
}
