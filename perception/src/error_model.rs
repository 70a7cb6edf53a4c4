//! The landmark egomotion error model (thesis §3.3.3): how uncertain a step
//! of egomotion measured from one landmark is, given where the landmark sits
//! relative to the camera.
//!
//! Positions are in the camera frame: `x` to the right, `y` ahead (depth),
//! `z` up from the cameras' level, metres. The thesis's models are planar
//! and ignore `z`; the 3D forms (its §5.3.1 recommendation) count the image
//! motion in both image axes. CVs are relative measures, comparable with
//! each other, not absolute errors (thesis §3.3.3).

use crate::stereo::StereoCamera;
use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

/// The step the error model assumes: 1 m, as in the thesis (§3.3.3).
pub const MODEL_STEP_M: f64 = 1.0;

/// The geometric model (thesis eq. 16–23): the CV of a landmark is the
/// inverse of the image motion a forward step of `step` metres causes in the
/// two images, `P_s = |δP_L| + |δP_R|`.
///
/// With the cameras at `x = ∓T/2`, the equations reduce to
/// `P_s = f·s·(|x + T/2| + |T/2 − x|) / (y·(y − s))`, so
/// `CV = y·(y − s) / (f·s·max(T, 2|x|))`: it grows like `y²` and falls like
/// `1/|x|` once the landmark is wider than the baseline.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct GeometricModel {
    /// Focal length, pixels.
    pub focal_px: f64,
    /// Baseline, m.
    pub baseline_m: f64,
    /// The step the model assumes, m (the thesis: 1 m).
    pub step_m: f64,
}

impl GeometricModel {
    /// The model of `camera` for steps of `step_m`.
    pub fn new(camera: &StereoCamera, step_m: f64) -> Self {
        GeometricModel { focal_px: camera.focal_px, baseline_m: camera.baseline_m, step_m }
    }

    /// The nearest depth the model is evaluated at: a landmark nearer than
    /// one step would be passed during the step. Nearer depths are read at
    /// this one.
    pub fn min_depth(&self) -> f64 {
        1.05 * self.step_m
    }

    /// The CV of a landmark at `(x, y)`, straight from eq. 16–23.
    pub fn cv(&self, x: f64, y: f64) -> f64 {
        let y = y.max(self.min_depth());
        let (f, t, s) = (self.focal_px, self.baseline_m, self.step_m);
        let (x_left, x_right) = (-t / 2.0, t / 2.0);
        let p_l1 = f * (x - x_left) / y;
        let p_r1 = f * (x_right - x) / y;
        let p_l2 = f * (x - x_left) / (y - s);
        let p_r2 = f * (x_right - x) / (y - s);
        let signal = (p_l1 - p_l2).abs() + (p_r1 - p_r2).abs();
        1.0 / signal
    }

    /// The depth factor of the closed form, `y(y−s)/(f·s)`:
    /// `cv(x, y) = depth_factor(y) · lateral_factor(x)`.
    pub fn depth_factor(&self, y: f64) -> f64 {
        let y = y.max(self.min_depth());
        y * (y - self.step_m) / (self.focal_px * self.step_m)
    }

    /// The lateral factor of the closed form, `1/max(T, 2|x|)`.
    pub fn lateral_factor(&self, x: f64) -> f64 {
        1.0 / self.baseline_m.max(2.0 * x.abs())
    }

    /// The CV of a landmark at `(x, y, z)` with eq. 16–23 applied in both
    /// image axes (thesis §5.3.1): the step also moves the landmark's row,
    /// `δv = f·|z|·s/(y(y−s))` in each image (the cameras are level, so
    /// both rows move alike), and the signal is the summed motion of both
    /// axes in both images. In closed form
    /// `CV = y(y−s) / (f·s·(max(T, 2|x|) + 2|z|))`: the planar CV at the
    /// cameras' level, smaller the farther above or below it.
    pub fn cv_3d(&self, x: f64, y: f64, z: f64) -> f64 {
        let y = y.max(self.min_depth());
        let (f, s) = (self.focal_px, self.step_m);
        let row = |depth: f64| f * z / depth;
        let vertical = 2.0 * (row(y) - row(y - s)).abs();
        1.0 / (1.0 / self.cv(x, y) + vertical)
    }
}

/// The exponential model (thesis eq. 24): `CV = α·e^{βy}·e^{−γ|x|}`,
/// with a height term `e^{−δ|z|}` for the 3D form (δ = 0: the thesis's).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ExponentialModel {
    /// The CV of a landmark straight ahead at zero depth.
    #[serde(deserialize_with = "ubf_core::config::positive")]
    pub alpha: f64,
    /// Growth of the CV with depth, 1/m.
    #[serde(deserialize_with = "ubf_core::config::finite")]
    pub beta: f64,
    /// Decay of the CV with lateral offset, 1/m.
    #[serde(deserialize_with = "ubf_core::config::finite")]
    pub gamma: f64,
    /// Decay of the CV with height above or below the cameras, 1/m.
    #[serde(default, skip_serializing_if = "is_zero", deserialize_with = "ubf_core::config::finite")]
    pub delta: f64,
}

fn is_zero(v: &f64) -> bool {
    *v == 0.0
}

impl ExponentialModel {
    /// The CV of a landmark at `(x, y)` at the cameras' level.
    pub fn cv(&self, x: f64, y: f64) -> f64 {
        self.cv_3d(x, y, 0.0)
    }

    /// The CV of a landmark at `(x, y, z)`.
    pub fn cv_3d(&self, x: f64, y: f64, z: f64) -> f64 {
        self.alpha * (self.beta * y - self.gamma * x.abs() - self.delta * z.abs()).exp()
    }
}

/// How well an exponential model fits the geometric one.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct FitReport {
    /// The fitted model.
    pub model: ExponentialModel,
    /// Points of the field of view the fit used.
    pub samples: usize,
    /// Depth range fitted, m.
    pub depth_range_m: [f64; 2],
    /// Height range fitted, relative to the cameras, m; absent for the
    /// planar form (fitted at the cameras' level, δ = 0).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub height_range_m: Option<[f64; 2]>,
    /// Coefficient of determination of the fit of ln CV.
    pub r_squared_log: f64,
    /// Median of |fitted/geometric − 1|.
    pub median_relative_error: f64,
    /// 95th percentile of |fitted/geometric − 1|.
    pub p95_relative_error: f64,
    /// Spearman-like check: the share of sample pairs the two models order
    /// the same way (what the decision engine relies on).
    pub pair_order_agreement: f64,
}

/// The field of view's sample points between two depths: every `cell`
/// metres in depth and across, inside both cameras' views; at the cameras'
/// level, or every `cell` metres between `heights` (relative to the
/// cameras) inside the images' rows.
fn field_of_view_samples(
    camera: &StereoCamera,
    depths: [f64; 2],
    heights: Option<[f64; 2]>,
    cell: f64,
) -> Vec<[f64; 3]> {
    let half_fov = camera.horizontal_fov() / 2.0;
    let [up, down] = camera.vertical_reach().map(f64::tan);
    let levels: Vec<f64> = match heights {
        None => vec![0.0],
        Some([low, high]) => (0..).map(|k| low + f64::from(k) * cell).take_while(|z| *z <= high + 1e-9).collect(),
    };
    let mut points = Vec::new();
    let mut y = depths[0];
    while y <= depths[1] + 1e-9 {
        // Inside both images: |x| + T/2 ≤ y·tan(half FOV).
        let half_width = (y * half_fov.tan() - camera.baseline_m / 2.0).max(0.0);
        for &z in levels.iter().filter(|z| (-y * down..=y * up).contains(*z)) {
            let mut x = -half_width;
            while x <= half_width + 1e-9 {
                points.push([x, y, z]);
                x += cell;
            }
        }
        y += cell;
    }
    points
}

/// Fits α, β, γ (and δ, given `heights`) by least squares on ln CV to the
/// model `target(x, y, z)` (usually [`GeometricModel::cv_3d`]) over the
/// camera's field of view between `depths` (and `heights`, relative to the
/// cameras), sampling every `cell` metres.
pub fn fit_exponential(
    target: impl Fn(f64, f64, f64) -> f64,
    camera: &StereoCamera,
    depths: [f64; 2],
    heights: Option<[f64; 2]>,
    cell: f64,
) -> FitReport {
    let points = field_of_view_samples(camera, depths, heights, cell);
    // Normal equations of ln CV = a + β y − γ |x| (− δ |z|).
    let terms = if heights.is_some() { 4 } else { 3 };
    let row = |[x, y, z]: [f64; 3]| DVector::from_iterator(terms, [1.0, y, -x.abs(), -z.abs()].into_iter().take(terms));
    let mut ata = DMatrix::<f64>::zeros(terms, terms);
    let mut atb = DVector::<f64>::zeros(terms);
    for &point in &points {
        let r = row(point);
        ata += &r * r.transpose();
        atb += r * target(point[0], point[1], point[2]).ln();
    }
    let solution = ata.lu().solve(&atb).unwrap_or_else(|| DVector::zeros(terms));
    let model = ExponentialModel {
        alpha: solution[0].exp(),
        beta: solution[1],
        gamma: solution[2],
        delta: if terms == 4 { solution[3] } else { 0.0 },
    };

    let logs: Vec<(f64, f64)> =
        points.iter().map(|&[x, y, z]| (target(x, y, z).ln(), model.cv_3d(x, y, z).ln())).collect();
    let mean = logs.iter().map(|l| l.0).sum::<f64>() / logs.len() as f64;
    let total: f64 = logs.iter().map(|l| (l.0 - mean).powi(2)).sum();
    let residual: f64 = logs.iter().map(|l| (l.0 - l.1).powi(2)).sum();
    let mut relative: Vec<f64> = logs.iter().map(|l| ((l.1 - l.0).exp() - 1.0).abs()).collect();
    relative.sort_by(f64::total_cmp);
    let quantile = |q: f64| relative[((relative.len() - 1) as f64 * q).round() as usize];
    // Order agreement over a deterministic subsample of pairs.
    let stride = (logs.len() / 400).max(1);
    let subset: Vec<&(f64, f64)> = logs.iter().step_by(stride).collect();
    let (mut same, mut pairs) = (0usize, 0usize);
    for i in 0..subset.len() {
        for j in i + 1..subset.len() {
            let a = subset[i].0 - subset[j].0;
            let b = subset[i].1 - subset[j].1;
            if a != 0.0 {
                pairs += 1;
                same += usize::from(a * b > 0.0);
            }
        }
    }
    FitReport {
        model,
        samples: points.len(),
        depth_range_m: depths,
        height_range_m: heights,
        r_squared_log: 1.0 - residual / total,
        median_relative_error: quantile(0.5),
        p95_relative_error: quantile(0.95),
        pair_order_agreement: same as f64 / pairs.max(1) as f64,
    }
}

/// The heights a 3D fit covers for `camera`: from the floor to a 2.5 m
/// ceiling (a corridor's; the renderer's walls), relative to the cameras.
pub fn corridor_heights(camera: &StereoCamera) -> [f64; 2] {
    const CEILING_M: f64 = 2.5;
    let level = camera.mount.height;
    [-level, (CEILING_M - level).max(0.0)]
}

/// Which model a behaviour or an estimator uses, as written in a scenario
/// file.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum ErrorModelKind {
    /// The geometric model of the camera (eq. 16–23).
    #[default]
    Geometric,
    /// The geometric model in both image axes: landmarks above or below the
    /// cameras move in rows too, and are better ([`GeometricModel::cv_3d`]).
    Geometric3d,
    /// The exponential model with α, β, γ fitted to the geometric one.
    FittedExponential,
    /// The exponential model with α, β, γ, δ fitted to the 3D geometric one
    /// over the field of view from the floor to a 2.5 m ceiling.
    FittedExponential3d,
    /// The exponential model with given parameters (δ, the height term, is
    /// optional).
    Exponential(ExponentialModel),
}

/// How a landmark's height above or below the cameras enters a
/// [`CvTable`]'s information, `1/CV`.
#[derive(Clone, Debug, PartialEq)]
enum HeightTerm {
    /// Not at all: the thesis's planar models.
    Ignored,
    /// The 3D geometric model's row motion: `2|z|` joins the lateral
    /// factor's reciprocal, `max(T, 2|x|)`.
    RowMotion,
    /// The 3D exponential model's `e^{δ|z|}`, tabulated every cell from 0.
    Exponential { delta: f64, inverse: Vec<f64> },
}

/// A precomputed table of a model's CV (the thesis precomputes one for
/// speed), read by linear interpolation of ln CV.
///
/// Every model here factors into a depth term and a lateral term
/// (geometric: `y(y−s)/(f·s) · 1/max(T, 2|x|)`; exponential:
/// `α·e^{βy} · e^{−γ|x|}`), so the table is two short one-dimensional
/// tables rather than a grid: a few kilobytes that stay in the nearest
/// cache, where a 5 cm grid out to 80 m took 12 MB and missed it on nearly
/// every read. Interpolating ln CV bilinearly over a grid of such a product
/// gives exactly the sum of the two one-dimensional interpolations. The 3D
/// forms' height enters the lateral term: added to its reciprocal
/// (geometric) or as a third factor (exponential).
///
/// It is symmetric in `x` and `z`; outside its range positions are clamped
/// to the nearest edge.
#[derive(Clone, Debug, PartialEq)]
pub struct CvTable {
    x_max: f64,
    y_min: f64,
    y_max: f64,
    /// 1/cell, so lookups multiply instead of dividing.
    per_cell: f64,
    /// ln of the depth factor every cell from `y_min`.
    ln_depth: Vec<f64>,
    /// ln of the lateral factor every cell from 0.
    ln_lateral: Vec<f64>,
    /// The reciprocals of the two factors, for [`CvTable::information`].
    inverse_depth: Vec<f64>,
    inverse_lateral: Vec<f64>,
    height: HeightTerm,
}

/// A landmark height's part in its information (see
/// [`CvTable::height_factor`]): `1/CV = (lateral + add) · times · depth`,
/// where `lateral` and `depth` are the reciprocals of the table's factors.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct HeightFactor {
    add: f64,
    times: f64,
}

/// The highest `|z|` a table tabulates the exponential height factor to,
/// m: beyond any corridor's ceiling.
const HEIGHT_MAX_M: f64 = 10.0;

impl CvTable {
    /// Tabulates `CV(x, y) = depth_factor(y) · lateral_factor(|x|)` over
    /// `0 ≤ |x| ≤ x_max`, `y_min ≤ y ≤ y_max`, every `cell` metres; a
    /// landmark's height is ignored.
    pub fn new(
        depth_factor: impl Fn(f64) -> f64,
        lateral_factor: impl Fn(f64) -> f64,
        x_max: f64,
        [y_min, y_max]: [f64; 2],
        cell: f64,
    ) -> Self {
        let nodes =
            |from: f64, to: f64| (0..=((to - from) / cell).ceil() as usize).map(move |k| from + k as f64 * cell);
        let ln_depth: Vec<f64> = nodes(y_min, y_max).map(|y| depth_factor(y).ln()).collect();
        let ln_lateral: Vec<f64> = nodes(0.0, x_max).map(|x| lateral_factor(x).ln()).collect();
        let reciprocal = |logs: &[f64]| logs.iter().map(|l| (-l).exp()).collect();
        CvTable {
            x_max,
            y_min,
            y_max,
            per_cell: 1.0 / cell,
            inverse_depth: reciprocal(&ln_depth),
            inverse_lateral: reciprocal(&ln_lateral),
            ln_depth,
            ln_lateral,
            height: HeightTerm::Ignored,
        }
    }

    /// A table of the chosen model for `camera`, steps of `step_m`, out to
    /// `max_depth` metres.
    pub fn for_camera(kind: ErrorModelKind, camera: &StereoCamera, step_m: f64, max_depth: f64) -> Self {
        let geometric = GeometricModel::new(camera, step_m);
        let x_max = max_depth * (camera.horizontal_fov() / 2.0).tan();
        let (depths, cell) = ([geometric.min_depth(), max_depth], 0.05);
        let exponential = |m: ExponentialModel| {
            let mut table =
                CvTable::new(|y| m.alpha * (m.beta * y).exp(), |x| (-m.gamma * x).exp(), x_max, depths, cell);
            if m.delta != 0.0 {
                let nodes = (HEIGHT_MAX_M / cell).ceil() as usize;
                let inverse = (0..=nodes).map(|k| (m.delta * k as f64 * cell).exp()).collect();
                table.height = HeightTerm::Exponential { delta: m.delta, inverse };
            }
            table
        };
        let planar = |x: f64, y: f64, _| geometric.cv(x, y);
        let with_height = |x: f64, y: f64, z: f64| geometric.cv_3d(x, y, z);
        match kind {
            ErrorModelKind::Geometric | ErrorModelKind::Geometric3d => {
                let mut table =
                    CvTable::new(|y| geometric.depth_factor(y), |x| geometric.lateral_factor(x), x_max, depths, cell);
                if kind == ErrorModelKind::Geometric3d {
                    table.height = HeightTerm::RowMotion;
                }
                table
            }
            ErrorModelKind::Exponential(model) => exponential(model),
            ErrorModelKind::FittedExponential => exponential(fit_exponential(planar, camera, depths, None, 0.25).model),
            ErrorModelKind::FittedExponential3d => {
                let heights = Some(corridor_heights(camera));
                exponential(fit_exponential(with_height, camera, depths, heights, 0.25).model)
            }
        }
    }

    /// The nearest nodes' indices for `(x, y)`.
    #[inline]
    fn nearest(&self, x: f64, y: f64) -> (usize, usize) {
        // Non-negative after the clamps, so truncating v + 0.5 rounds.
        let i = ((x.abs().min(self.x_max) * self.per_cell + 0.5) as usize).min(self.ln_lateral.len() - 1);
        let j = (((y.clamp(self.y_min, self.y_max) - self.y_min) * self.per_cell + 0.5) as usize)
            .min(self.ln_depth.len() - 1);
        (i, j)
    }

    /// 1/CV at the node nearest `(x, y, z)`: the fast read for summing many
    /// landmarks' information (eq. 6: `1/CV_T = Σ 1/CV_i`), accurate to the
    /// table's 5 cm cells.
    #[inline]
    pub fn information(&self, x: f64, y: f64, z: f64) -> f64 {
        self.information_at(x, y, self.height_factor(z))
    }

    /// How a landmark `z` above (or below) the cameras has its information
    /// scaled: the part of [`CvTable::information`] that depends on the
    /// height alone, for a landmark read from many viewpoints.
    #[inline]
    pub fn height_factor(&self, z: f64) -> HeightFactor {
        match &self.height {
            HeightTerm::Ignored => HeightFactor { add: 0.0, times: 1.0 },
            HeightTerm::RowMotion => HeightFactor { add: 2.0 * z.abs(), times: 1.0 },
            HeightTerm::Exponential { inverse, .. } => {
                let k = ((z.abs() * self.per_cell + 0.5) as usize).min(inverse.len() - 1);
                HeightFactor { add: 0.0, times: inverse[k] }
            }
        }
    }

    /// [`CvTable::information`] with the height's factor given.
    #[inline]
    pub fn information_at(&self, x: f64, y: f64, height: HeightFactor) -> f64 {
        let (i, j) = self.nearest(x, y);
        (self.inverse_lateral[i] + height.add) * height.times * self.inverse_depth[j]
    }

    /// The CV at `(x, y, z)`.
    pub fn cv(&self, x: f64, y: f64, z: f64) -> f64 {
        let interpolate = |logs: &[f64], at: f64| {
            let at = at.min((logs.len() - 1) as f64);
            let k = at.floor() as usize;
            let t = at - k as f64;
            logs[k] * (1.0 - t) + logs[(k + 1).min(logs.len() - 1)] * t
        };
        let lateral = interpolate(&self.ln_lateral, x.abs().min(self.x_max) * self.per_cell);
        let depth = interpolate(&self.ln_depth, (y.clamp(self.y_min, self.y_max) - self.y_min) * self.per_cell);
        match &self.height {
            HeightTerm::Ignored => (lateral + depth).exp(),
            HeightTerm::RowMotion => depth.exp() / ((-lateral).exp() + 2.0 * z.abs()),
            HeightTerm::Exponential { delta, .. } => (lateral + depth - delta * z.abs().min(HEIGHT_MAX_M)).exp(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn model() -> GeometricModel {
        GeometricModel::new(&StereoCamera::default(), 1.0)
    }

    #[test]
    fn geometric_model_matches_its_closed_form() {
        let m = model();
        for (x, y) in [(0.0, 5.0), (0.2, 3.0), (-2.0, 10.0), (4.0, 20.0)] {
            let closed = y * (y - 1.0) / (m.focal_px * 1.0 * m.baseline_m.max(2.0 * f64::abs(x)));
            assert!((m.cv(x, y) / closed - 1.0).abs() < 1e-9, "({x}, {y})");
        }
    }

    #[test]
    fn both_models_factor_into_depth_and_lateral_terms() {
        // What lets the look-up table be two short tables.
        let m = model();
        let e = ExponentialModel { alpha: 0.02, beta: 0.1, gamma: 0.3, delta: 0.0 };
        let t = CvTable::for_camera(ErrorModelKind::Exponential(e), &StereoCamera::default(), 1.0, 60.0);
        for (x, y) in [(0.0, 1.5), (0.2, 3.0), (-2.0, 10.0), (4.0, 20.0), (-9.0, 45.0)] {
            assert!((m.depth_factor(y) * m.lateral_factor(x) / m.cv(x, y) - 1.0).abs() < 1e-9, "({x}, {y})");
            assert!((t.cv(x, y, 0.7) / e.cv(x, y) - 1.0).abs() < 1e-9, "({x}, {y})");
        }
    }

    #[test]
    fn near_and_wide_landmarks_are_better() {
        let m = model();
        assert!(m.cv(0.0, 5.0) < m.cv(0.0, 10.0));
        assert!(m.cv(3.0, 10.0) < m.cv(0.0, 10.0));
        assert_eq!(m.cv(0.1, 10.0), m.cv(-0.1, 10.0));
        assert_eq!(m.cv(0.0, 0.5), m.cv(0.0, m.min_depth()));
    }

    #[test]
    fn the_fit_recovers_an_exponential_exactly() {
        let truth = ExponentialModel { alpha: 0.02, beta: 0.1, gamma: 0.3, delta: 0.0 };
        let report = fit_exponential(|x, y, _| truth.cv(x, y), &StereoCamera::default(), [1.2, 40.0], None, 0.5);
        assert!((report.model.alpha / truth.alpha - 1.0).abs() < 1e-9, "{report:?}");
        assert!((report.model.beta - truth.beta).abs() < 1e-9 && (report.model.gamma - truth.gamma).abs() < 1e-9);
        assert!((report.r_squared_log - 1.0).abs() < 1e-9);
    }

    #[test]
    fn the_fit_to_the_geometric_model_keeps_its_shape() {
        // The geometric CV grows like y², not exponentially, so the fit is
        // only approximate (its quality is reported by `ubf model fit`);
        // what must hold is the shape: worse with depth, better off-centre,
        // and mostly the same ordering of landmarks.
        let m = model();
        let report = fit_exponential(|x, y, _| m.cv(x, y), &StereoCamera::default(), [1.2, 40.0], None, 0.25);
        assert!(report.model.beta > 0.0 && report.model.gamma > 0.0, "{report:?}");
        assert!(report.pair_order_agreement > 0.85, "{report:?}");
    }

    #[test]
    fn table_reproduces_the_model_between_its_nodes() {
        let m = model();
        let table = CvTable::for_camera(ErrorModelKind::Geometric, &StereoCamera::default(), 1.0, 60.0);
        for (x, y) in [(0.03, 4.02), (1.234, 7.77), (-5.5, 30.1)] {
            assert!((table.cv(x, y, 0.0) / m.cv(x, y) - 1.0).abs() < 0.01, "({x}, {y})");
        }
        // The fast read is the nearest node's value: within half a cell.
        for (x, y) in [(0.03, 4.02), (1.234, 7.77), (-5.5, 30.1), (0.0, 1.06)] {
            let nearest = |v: f64| (v / 0.05).round() * 0.05;
            let node = m.cv(nearest(x), nearest(y) + 1.05 - nearest(1.05));
            assert!((table.information(x, y, 0.5) * node - 1.0).abs() < 1e-9, "({x}, {y})");
        }
        // Beyond the table, clamped to its edge.
        assert_eq!(table.cv(0.0, 500.0, 0.0), table.cv(0.0, 60.0, 0.0));
        assert_eq!(table.information(99.0, 500.0, 0.0), table.information(46.0, 60.0, 0.0));
    }

    #[test]
    fn the_3d_geometric_model_is_eq_16_to_23_in_both_image_axes() {
        // Against the two images' pixels, projected before and after the
        // step: the summed |δu| + |δv| of both images.
        let camera = StereoCamera::default();
        let m = model();
        for [x, y, z] in [[0.0, 5.0, 0.0], [0.2, 3.0, -0.8], [-2.0, 10.0, 1.2], [4.0, 20.0, 0.3]] {
            let before = camera.project([x, y, z]).unwrap();
            let after = camera.project([x, y - 1.0, z]).unwrap();
            let signal = (before.u_left - after.u_left).abs()
                + (before.u_right - after.u_right).abs()
                + 2.0 * (before.v - after.v).abs();
            assert!((m.cv_3d(x, y, z) * signal - 1.0).abs() < 1e-9, "({x}, {y}, {z})");
        }
        // At the cameras' level it is the planar model; away from it,
        // better, alike above and below.
        assert_eq!(m.cv_3d(1.0, 8.0, 0.0), m.cv(1.0, 8.0));
        assert!(m.cv_3d(1.0, 8.0, 0.5) < m.cv(1.0, 8.0));
        assert!((m.cv_3d(1.0, 8.0, 0.5) / m.cv_3d(1.0, 8.0, -0.5) - 1.0).abs() < 1e-12);
    }

    #[test]
    fn the_3d_tables_reproduce_their_models() {
        let camera = StereoCamera::default();
        let m = model();
        let geometric = CvTable::for_camera(ErrorModelKind::Geometric3d, &camera, 1.0, 60.0);
        let e = ExponentialModel { alpha: 0.02, beta: 0.1, gamma: 0.3, delta: 0.4 };
        let exponential = CvTable::for_camera(ErrorModelKind::Exponential(e), &camera, 1.0, 60.0);
        for [x, y, z] in [[0.03, 4.02, 0.0], [1.234, 7.77, -0.6], [-5.5, 30.1, 1.3]] {
            assert!((geometric.cv(x, y, z) / m.cv_3d(x, y, z) - 1.0).abs() < 0.01, "({x}, {y}, {z})");
            assert!((geometric.information(x, y, z) * m.cv_3d(x, y, z) - 1.0).abs() < 0.03, "({x}, {y}, {z})");
            assert!((exponential.cv(x, y, z) / e.cv_3d(x, y, z) - 1.0).abs() < 1e-9, "({x}, {y}, {z})");
            assert!((exponential.information(x, y, z) * e.cv_3d(x, y, z) - 1.0).abs() < 0.05, "({x}, {y}, {z})");
        }
    }

    #[test]
    fn the_3d_fit_recovers_an_exponential_and_finds_height_helps() {
        let camera = StereoCamera::default();
        let truth = ExponentialModel { alpha: 0.02, beta: 0.1, gamma: 0.3, delta: 0.5 };
        let report = fit_exponential(|x, y, z| truth.cv_3d(x, y, z), &camera, [1.2, 40.0], Some([-1.0, 1.5]), 0.5);
        assert!((report.model.delta - truth.delta).abs() < 1e-9, "{report:?}");
        assert!((report.r_squared_log - 1.0).abs() < 1e-9);
        // Fitted to the geometric model, height lowers the CV as width does.
        let m = model();
        let heights = corridor_heights(&camera);
        let report = fit_exponential(|x, y, z| m.cv_3d(x, y, z), &camera, [1.2, 40.0], Some(heights), 0.5);
        assert!(report.model.delta > 0.0 && report.model.gamma > 0.0, "{report:?}");
        assert_eq!(report.height_range_m, Some([-1.0, 1.5]));
    }
}
