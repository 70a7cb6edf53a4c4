//! Egomotion: how the robot moved between two stereo frames, from the
//! landmarks seen in both (thesis §2.3.5, §4.4.6–4.4.9).
//!
//! Two estimators:
//! - [`Simple2d`], the thesis's simplified estimator (§4.4.7): each matched
//!   landmark says "translated by the change in its depth" if its range
//!   changed, else "rotated by the change in its bearing"; the category with
//!   the smallest fused CV wins and its CV-weighted mean is the motion. It
//!   assumes rotate-stop-translate motion.
//! - [`Rigid`], the full estimator the thesis recommends (§5.3.2): the rigid
//!   planar transform (x, y, yaw) that best aligns the two frames'
//!   triangulated landmarks, inside a seeded RANSAC of two-landmark samples
//!   that rejects wrong matches and moving landmarks. Weighted Kabsch
//!   (weights 1/CV, through nalgebra's SVD) gives the first solution;
//!   Gauss–Newton then weighs each landmark by its real, elongated stereo
//!   uncertainty (bearing precise, range not), without which a far wall's
//!   depth noise tilts the solution into metres of false sideways motion.
//!   It needs three consistent landmarks.

use crate::error_model::{CvTable, ErrorModelKind, MODEL_STEP_M};
use crate::fusion::{fuse_cv, weighted_mean};
use crate::stereo::StereoCamera;
use nalgebra::{Matrix2, Vector2};
use rand::seq::index::sample;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::Deserialize;
use ubf_core::config::{non_negative, positive, unit_interval};
use ubf_core::{Descriptor, EgomotionState, LandmarkObservation, Pose2, StereoFrame};

/// A planar motion of the robot between two frames, in the earlier frame's
/// robot frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PlanarMotion {
    /// Metres forward.
    pub forward: f64,
    /// Metres to the left.
    pub left: f64,
    /// Radians turned, counter-clockwise.
    pub yaw: f64,
}

impl PlanarMotion {
    fn as_pose(&self) -> Pose2 {
        Pose2::new(self.forward, self.left, self.yaw)
    }
}

/// Descriptor matching between frames (thesis eq. 8–11).
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MatchConfig {
    /// Largest Hamming distance of a match, bits of 256.
    #[serde(default = "MatchConfig::default_max_distance")]
    pub max_distance: u32,
    /// The best match must be nearer than this share of the second best.
    #[serde(default = "MatchConfig::default_ratio", deserialize_with = "unit_interval")]
    pub ratio: f64,
}

impl MatchConfig {
    fn default_max_distance() -> u32 {
        64
    }
    fn default_ratio() -> f64 {
        0.8
    }
}

impl Default for MatchConfig {
    fn default() -> Self {
        MatchConfig { max_distance: Self::default_max_distance(), ratio: Self::default_ratio() }
    }
}

impl MatchConfig {
    /// The index of the descriptor in `candidates` nearest `query`, if it is
    /// within `max_distance` and clearly nearer than the second nearest
    /// (thesis eq. 11). `Err(true)` when two candidates are too alike to
    /// tell apart, `Err(false)` when none is near enough.
    pub fn best_match<'a>(
        &self,
        query: &Descriptor,
        candidates: impl IntoIterator<Item = &'a Descriptor>,
    ) -> Result<usize, bool> {
        let (mut best, mut second) = ((u32::MAX, usize::MAX), u32::MAX);
        for (i, candidate) in candidates.into_iter().enumerate() {
            let d = query.hamming(candidate);
            if d < best.0 {
                second = best.0;
                best = (d, i);
            } else if d < second {
                second = d;
            }
        }
        if best.0 > self.max_distance {
            return Err(false);
        }
        if second != u32::MAX && f64::from(best.0) >= self.ratio * f64::from(second) {
            return Err(true);
        }
        Ok(best.1)
    }
}

/// Pairs `(previous, current)` of observations of the same landmark, by
/// descriptor: nearest within `max_distance`, clearly nearer than the second
/// nearest, and each previous observation used once (the nearer pair wins).
pub fn match_frames(
    previous: &[LandmarkObservation],
    current: &[LandmarkObservation],
    config: &MatchConfig,
    out: &mut Vec<(usize, usize)>,
) {
    out.clear();
    for (j, cur) in current.iter().enumerate() {
        if let Ok(i) = config.best_match(&cur.descriptor, previous.iter().map(|p| &p.descriptor)) {
            out.push((i, j));
        }
    }
    // One current observation per previous one: keep the closest.
    out.sort_by_key(|&(i, j)| (i, current[j].descriptor.hamming(&previous[i].descriptor)));
    out.dedup_by_key(|&mut (i, _)| i);
}

/// Settings of the thesis's simplified estimator.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Simple2dConfig {
    /// A range change above this means translation, m.
    #[serde(default = "Simple2dConfig::default_translation", deserialize_with = "non_negative")]
    pub translation_threshold_m: f64,
    /// A bearing change above this means rotation, °.
    #[serde(default = "Simple2dConfig::default_rotation", deserialize_with = "non_negative")]
    pub rotation_threshold_deg: f64,
    /// Rotation compensation RC (eq. 60); the thesis left it at 1.
    #[serde(default = "one", deserialize_with = "positive")]
    pub rc: f64,
    /// Translation compensation TC (eq. 61); the thesis left it at 1.
    #[serde(default = "one", deserialize_with = "positive")]
    pub tc: f64,
}

fn one() -> f64 {
    1.0
}

impl Simple2dConfig {
    fn default_translation() -> f64 {
        0.02
    }
    fn default_rotation() -> f64 {
        0.3
    }
}

impl Default for Simple2dConfig {
    fn default() -> Self {
        Simple2dConfig {
            translation_threshold_m: Self::default_translation(),
            rotation_threshold_deg: Self::default_rotation(),
            rc: 1.0,
            tc: 1.0,
        }
    }
}

/// Settings of the rigid estimator.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RigidConfig {
    /// RANSAC draws of two matches.
    #[serde(default = "RigidConfig::default_iterations")]
    pub iterations: u32,
    /// Pixel noise assumed when judging residuals, px.
    #[serde(default = "RigidConfig::default_pixel_sigma", deserialize_with = "positive")]
    pub pixel_sigma: f64,
}

impl RigidConfig {
    fn default_iterations() -> u32 {
        64
    }
    fn default_pixel_sigma() -> f64 {
        0.3
    }
}

impl Default for RigidConfig {
    fn default() -> Self {
        RigidConfig { iterations: Self::default_iterations(), pixel_sigma: Self::default_pixel_sigma() }
    }
}

/// Which estimator, as written in a scenario file.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum EstimatorKind {
    /// The thesis's simplified 2D estimator.
    Simple2d(#[serde(default)] Simple2dConfig),
    /// Weighted Kabsch inside RANSAC.
    Rigid(#[serde(default)] RigidConfig),
}

impl Default for EstimatorKind {
    fn default() -> Self {
        EstimatorKind::Rigid(RigidConfig::default())
    }
}

/// The egomotion settings, as written in a scenario file.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EgomotionConfig {
    /// The estimator.
    #[serde(default)]
    pub estimator: EstimatorKind,
    /// The error model weighting landmarks and giving step CVs.
    #[serde(default)]
    pub model: ErrorModelKind,
    /// Descriptor matching between frames.
    #[serde(default)]
    pub matching: MatchConfig,
    /// After a failed step the last good frame stays the reference, so the
    /// next good frame recovers the whole motion since; after this long
    /// without success the reference is given up and that motion is lost, s.
    #[serde(default = "EgomotionConfig::default_max_gap", deserialize_with = "positive")]
    pub max_gap_s: f64,
    /// The robot's top speed: motions faster than this are impossible and
    /// rejected (thesis §4.4.6), m/s.
    #[serde(default = "EgomotionConfig::default_max_speed", deserialize_with = "positive")]
    pub max_speed: f64,
}

impl EgomotionConfig {
    fn default_max_speed() -> f64 {
        0.6
    }
    fn default_max_gap() -> f64 {
        3.0
    }
}

impl Default for EgomotionConfig {
    fn default() -> Self {
        EgomotionConfig {
            estimator: EstimatorKind::default(),
            model: ErrorModelKind::default(),
            matching: MatchConfig::default(),
            max_gap_s: Self::default_max_gap(),
            max_speed: Self::default_max_speed(),
        }
    }
}

/// What the estimators know of one matched landmark.
#[derive(Clone, Copy, Debug)]
struct Pair {
    before: [f64; 3],
    after: [f64; 3],
    cv: f64,
}

/// The thesis's simplified 2D estimator (§4.4.7).
pub struct Simple2d;

impl Simple2d {
    /// The motion the pairs vote for, or `None` when no landmark gives a
    /// usable vote. `max_step` is the longest translation possible.
    fn estimate(config: &Simple2dConfig, pairs: &[Pair], max_step: f64) -> Option<PlanarMotion> {
        let mut translation: Vec<(f64, f64)> = Vec::new();
        let mut rotation: Vec<(f64, f64)> = Vec::new();
        let mut stationary: Vec<f64> = Vec::new();
        for p in pairs {
            let ([x0, y0, _], [x1, y1, _]) = (p.before, p.after);
            let range_change = (x0.hypot(y0) - x1.hypot(y1)).abs();
            if range_change > config.translation_threshold_m {
                // Eq. 51, signed: a landmark ahead comes nearer as the robot
                // advances; negative or impossibly fast speeds are noise or
                // moving landmarks (§4.4.6).
                let t = y0 - y1;
                if t >= 0.0 && t <= max_step {
                    translation.push((t, p.cv));
                }
            } else {
                // Eq. 52–54: bearings positive to the right.
                let turned = (x0 / y0).atan() - (x1 / y1).atan();
                if turned.abs() > config.rotation_threshold_deg.to_radians() {
                    rotation.push((turned, p.cv));
                } else {
                    stationary.push(p.cv);
                }
            }
        }
        let categories = [
            fuse_cv(translation.iter().map(|m| m.1)),
            fuse_cv(rotation.iter().map(|m| m.1)),
            fuse_cv(stationary.iter().copied()),
        ];
        let (winner, _) = categories
            .iter()
            .enumerate()
            .filter_map(|(i, cv)| cv.map(|cv| (i, cv)))
            .min_by(|a, b| a.1.total_cmp(&b.1))?;
        Some(match winner {
            0 => PlanarMotion { forward: config.tc * weighted_mean(translation)?, ..PlanarMotion::default() },
            // Eq. 59: the heading changes by minus the bearing change.
            1 => PlanarMotion { yaw: -config.rc * weighted_mean(rotation)?, ..PlanarMotion::default() },
            _ => PlanarMotion::default(),
        })
    }
}

/// The rigid estimator: weighted Kabsch inside RANSAC.
pub struct Rigid;

/// The planar rotation angle and translation with `before ≈ R(θ)·after + t`
/// on the floor plane, weighted (Kabsch in two dimensions). A ground robot
/// moves in x, y and yaw only; fitting pitch and roll as well lets the large
/// depth noise of distant landmarks tilt the solution, and a tilt across a
/// lever of tens of metres becomes metres of false translation.
fn kabsch(pairs: &[Pair], weights: &[f64]) -> Option<(f64, Vector2<f64>)> {
    let total: f64 = weights.iter().sum();
    if pairs.len() < 2 || total <= 0.0 {
        return None;
    }
    let v = |p: [f64; 3]| Vector2::new(p[0], p[1]);
    let centre_a = pairs.iter().zip(weights).map(|(p, w)| v(p.before) * *w).sum::<Vector2<f64>>() / total;
    let centre_b = pairs.iter().zip(weights).map(|(p, w)| v(p.after) * *w).sum::<Vector2<f64>>() / total;
    let h: Matrix2<f64> = pairs
        .iter()
        .zip(weights)
        .map(|(p, w)| (v(p.after) - centre_b) * (v(p.before) - centre_a).transpose() * *w)
        .sum();
    let svd = h.svd(true, true);
    let (u, v_t) = (svd.u?, svd.v_t?);
    let d = (v_t.transpose() * u.transpose()).determinant().signum();
    let r = v_t.transpose() * Matrix2::from_diagonal(&Vector2::new(1.0, d)) * u.transpose();
    let yaw = r[(1, 0)].atan2(r[(0, 0)]);
    Some((yaw, centre_a - r * centre_b))
}

fn rotation(yaw: f64) -> Matrix2<f64> {
    let (s, c) = yaw.sin_cos();
    Matrix2::new(c, -s, s, c)
}

/// The information matrix (inverse covariance) of the residual
/// `a − (R b + t)` of one landmark seen as `a` before and `b` after a move.
///
/// Stereo measures a point's bearing well and its range poorly, so each
/// observation's uncertainty is an ellipse stretched along its line of sight.
/// Once the frames are aligned, `R b` lies on `a`'s line of sight, so both
/// ellipses stretch along it: the variances add along and across that line.
/// (Adding `b`'s ellipse unrotated would tilt it by the turn between frames,
/// and a tilted depth error passes for a precise bearing.)
fn residual_information(camera: &StereoCamera, pixel_sigma: f64, a: [f64; 3], b: [f64; 3]) -> Matrix2<f64> {
    let range_a = a[0].hypot(a[1]).max(0.1);
    let range_b = b[0].hypot(b[1]).max(0.1);
    let along = Vector2::new(a[0], a[1]) / range_a;
    let across = Vector2::new(-along[1], along[0]);
    let var_along = camera.depth_sigma(range_a, pixel_sigma).powi(2) + camera.depth_sigma(range_b, pixel_sigma).powi(2);
    let var_across = ((range_a.powi(2) + range_b.powi(2)) * (pixel_sigma / camera.focal_px).powi(2)).max(1e-8);
    along * along.transpose() / var_along.max(1e-8) + across * across.transpose() / var_across
}

impl Rigid {
    /// Refines `(yaw, t)` by Gauss–Newton on the Mahalanobis residuals
    /// `Σ eᵢᵀ Λᵢ eᵢ`, `eᵢ = aᵢ − (R bᵢ + t)`.
    fn refine(pairs: &[Pair], info: &[Matrix2<f64>], mut yaw: f64, mut t: Vector2<f64>) -> (f64, Vector2<f64>) {
        for _ in 0..8 {
            let (mut h, mut g) = (nalgebra::Matrix3::<f64>::zeros(), nalgebra::Vector3::<f64>::zeros());
            for (p, l) in pairs.iter().zip(info) {
                let a = Vector2::new(p.before[0], p.before[1]);
                let b = Vector2::new(p.after[0], p.after[1]);
                let e = a - (rotation(yaw) * b + t);
                let (s, c) = yaw.sin_cos();
                let d_yaw = -Vector2::new(-s * b[0] - c * b[1], c * b[0] - s * b[1]);
                let j = nalgebra::Matrix2x3::new(-1.0, 0.0, d_yaw[0], 0.0, -1.0, d_yaw[1]);
                h += j.transpose() * l * j;
                g += j.transpose() * l * e;
            }
            let Some(step) = h.lu().solve(&(-g)) else { break };
            t += Vector2::new(step[0], step[1]);
            yaw += step[2];
            if step.norm() < 1e-9 {
                break;
            }
        }
        (yaw, t)
    }

    fn estimate(
        config: &RigidConfig,
        camera: &StereoCamera,
        pairs: &[Pair],
        max_step: f64,
        rng: &mut ChaCha8Rng,
    ) -> Option<PlanarMotion> {
        if pairs.len() < 3 {
            return None;
        }
        let info: Vec<Matrix2<f64>> =
            pairs.iter().map(|p| residual_information(camera, config.pixel_sigma, p.before, p.after)).collect();
        let mahalanobis = |yaw: f64, t: &Vector2<f64>, i: usize| {
            let p = &pairs[i];
            let e = Vector2::new(p.before[0], p.before[1]) - (rotation(yaw) * Vector2::new(p.after[0], p.after[1]) + t);
            (e.transpose() * info[i] * e)[0]
        };
        // χ² with 2 degrees of freedom at 99 %.
        const GATE: f64 = 9.21;
        let ones = [1.0; 2];
        let mut best: Option<Vec<usize>> = None;
        for _ in 0..config.iterations {
            let picked: Vec<usize> = sample(rng, pairs.len(), 2).into_vec();
            let two = [pairs[picked[0]], pairs[picked[1]]];
            let Some((yaw, t)) = kabsch(&two, &ones) else { continue };
            let (yaw, t) = Self::refine(&two, &[info[picked[0]], info[picked[1]]], yaw, t);
            let inliers: Vec<usize> = (0..pairs.len()).filter(|&i| mahalanobis(yaw, &t, i) < GATE).collect();
            if best.as_ref().is_none_or(|b| inliers.len() > b.len()) {
                best = Some(inliers);
            }
        }
        let inliers = best.filter(|b| b.len() >= 3)?;
        let chosen: Vec<Pair> = inliers.iter().map(|&i| pairs[i]).collect();
        let chosen_info: Vec<Matrix2<f64>> = inliers.iter().map(|&i| info[i]).collect();
        // Weighted Kabsch (weights 1/CV, thesis eq. 5) starts the refinement.
        let weights: Vec<f64> = chosen.iter().map(|p| 1.0 / p.cv).collect();
        let (yaw, t) = kabsch(&chosen, &weights)?;
        let (yaw, t) = Self::refine(&chosen, &chosen_info, yaw, t);
        let motion = PlanarMotion { forward: t[0], left: t[1], yaw };
        (motion.forward.hypot(motion.left) <= max_step && yaw.is_finite()).then_some(motion)
    }
}

/// Integrates egomotion over a run: one step per new stereo frame.
pub struct Tracker {
    config: EgomotionConfig,
    camera: StereoCamera,
    table: CvTable,
    rng: ChaCha8Rng,
    previous: Vec<LandmarkObservation>,
    /// The reference frame's number, time and odometric pose.
    previous_frame: Option<(u64, f64, Pose2)>,
    /// The number of the newest frame taken in.
    newest: u64,
    state: EgomotionState,
    matches: Vec<(usize, usize)>,
    pairs: Vec<Pair>,
}

impl Tracker {
    /// A tracker for `camera`, starting at `start`, drawing RANSAC samples
    /// from `seed`.
    pub fn new(config: EgomotionConfig, camera: StereoCamera, start: Pose2, seed: u64) -> Self {
        let table = CvTable::for_camera(config.model, &camera, MODEL_STEP_M, 100.0);
        Tracker {
            config,
            camera,
            table,
            rng: ChaCha8Rng::seed_from_u64(seed),
            previous: Vec::new(),
            previous_frame: None,
            newest: 0,
            state: EgomotionState { pose: Some(start), ..EgomotionState::default() },
            matches: Vec::new(),
            pairs: Vec::new(),
        }
    }

    /// What egomotion has made of the frames so far.
    pub fn state(&self) -> EgomotionState {
        self.state
    }

    /// The error model's look-up table the tracker weighs landmarks with.
    pub fn table(&self) -> &CvTable {
        &self.table
    }

    /// Takes in `frame` if it is new: matches it to the reference frame,
    /// estimates the motion and integrates it. A step without a usable
    /// estimate is a failure: the pose stays put and the reference frame is
    /// kept, so the next good frame recovers the motion across the gap; a
    /// reference older than `max_gap_s` is given up (pure egomotion takes no
    /// help from odometry, so that motion is lost).
    ///
    /// `odometry` is the robot's odometric pose when the frame was taken; it
    /// only measures how far each step drove, to weigh the step's CV in the
    /// journey CV (eq. 7 per metre), never the motion itself.
    pub fn update(&mut self, frame: &StereoFrame, odometry: &Pose2) {
        if frame.number == 0 || frame.number == self.newest {
            return;
        }
        self.newest = frame.number;
        let succeeded = match self.previous_frame {
            Some((_, before, from)) => {
                let driven = from.distance_to(odometry.x, odometry.y);
                self.step(&frame.landmarks, (frame.time - before).max(1e-6), driven)
            }
            None => true,
        };
        let stale = self.previous_frame.is_some_and(|(_, t, _)| frame.time - t > self.config.max_gap_s);
        if succeeded || stale {
            self.previous.clone_from(&frame.landmarks);
            self.previous_frame = Some((frame.number, frame.time, *odometry));
        }
    }

    /// One step from the reference frame to `current`, over which the robot
    /// drove `driven` metres; whether it succeeded.
    fn step(&mut self, current: &[LandmarkObservation], dt: f64, driven: f64) -> bool {
        match_frames(&self.previous, current, &self.config.matching, &mut self.matches);
        let mount = self.camera.mount;
        self.pairs.clear();
        for &(i, j) in &self.matches {
            let (before, after) = (self.previous[i].point_cam, current[j].point_cam);
            let cv = self.table.cv(after[0], after[1]);
            self.pairs.push(match self.config.estimator {
                EstimatorKind::Simple2d(_) => Pair { before, after, cv },
                // The rigid estimator works in the robot frame.
                EstimatorKind::Rigid(_) => {
                    Pair { before: mount.cam_to_robot(before), after: mount.cam_to_robot(after), cv }
                }
            });
        }
        let max_step = self.config.max_speed * dt * 1.5 + 0.02;
        let estimate = match &self.config.estimator {
            EstimatorKind::Simple2d(c) => Simple2d::estimate(c, &self.pairs, max_step),
            EstimatorKind::Rigid(c) => Rigid::estimate(c, &self.camera, &self.pairs, max_step, &mut self.rng),
        };
        self.state.steps += 1;
        match estimate {
            Some(motion) => {
                let step_cv = fuse_cv(self.pairs.iter().map(|p| p.cv));
                self.state.last_step_cv = step_cv;
                self.state.journey_cv += step_cv.unwrap_or(0.0) * driven / MODEL_STEP_M;
                self.state.pose = self.state.pose.map(|p| p.compose(&motion.as_pose()));
                true
            }
            None => {
                self.state.failures += 1;
                self.state.last_step_cv = None;
                false
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ubf_core::{Descriptor, StereoPixels};

    /// Observations of `points` (world frame, metres) from `pose`, exact.
    fn frame(points: &[[f64; 3]], pose: Pose2, camera: &StereoCamera) -> Vec<LandmarkObservation> {
        points
            .iter()
            .enumerate()
            .filter_map(|(i, p)| {
                let (dx, dy) = (p[0] - pose.x, p[1] - pose.y);
                let (s, c) = pose.theta.sin_cos();
                let robot = [c * dx + s * dy, -s * dx + c * dy, p[2]];
                let cam = camera.mount.robot_to_cam(robot);
                let px = camera.project(cam)?;
                let mut bits = [0u64; 4];
                bits[i % 4] = 0x9e37_79b9_7f4a_7c15u64.rotate_left(i as u32 * 7);
                bits[(i + 1) % 4] = (i as u64).wrapping_mul(0xff51_afd7_ed55_8ccd);
                Some(LandmarkObservation {
                    point_cam: cam,
                    pixels: px,
                    descriptor: Descriptor(bits),
                    source_id: Some(i as u32),
                })
            })
            .collect()
    }

    fn landmarks() -> Vec<[f64; 3]> {
        (0..12).map(|i| [6.0 + i as f64 * 1.5, if i % 2 == 0 { 2.5 } else { -2.5 }, 0.5 + 0.1 * i as f64]).collect()
    }

    fn run(estimator: EstimatorKind, poses: &[Pose2]) -> EgomotionState {
        let camera = StereoCamera::default();
        let config = EgomotionConfig { estimator, ..EgomotionConfig::default() };
        let mut tracker = Tracker::new(config, camera, poses[0], 1);
        for (n, pose) in poses.iter().enumerate() {
            let f = StereoFrame {
                number: n as u64 + 1,
                time: n as f64 * 0.5,
                landmarks: frame(&landmarks(), *pose, &camera),
                calibration: None,
            };
            tracker.update(&f, pose);
        }
        tracker.state()
    }

    #[test]
    fn frames_match_by_descriptor() {
        let camera = StereoCamera::default();
        let a = frame(&landmarks(), Pose2::default(), &camera);
        let b = frame(&landmarks(), Pose2::new(0.3, 0.0, 0.0), &camera);
        let mut m = Vec::new();
        match_frames(&a, &b, &MatchConfig::default(), &mut m);
        assert_eq!(m.len(), a.len().min(b.len()));
        assert!(m.iter().all(|&(i, j)| a[i].source_id == b[j].source_id));
    }

    #[test]
    fn exact_observations_give_exact_rigid_motion() {
        let poses: Vec<Pose2> =
            (0..20).map(|k| Pose2::new(0.25 * k as f64, 0.02 * k as f64, 0.01 * k as f64)).collect();
        let state = run(EstimatorKind::Rigid(RigidConfig::default()), &poses);
        let end = state.pose.unwrap();
        let truth = poses.last().unwrap();
        assert!(end.distance_to(truth.x, truth.y) < 1e-6, "{end:?} vs {truth:?}");
        assert!((end.theta - truth.theta).abs() < 1e-6);
        assert_eq!(state.failures, 0);
        assert!(state.journey_cv > 0.0);
    }

    #[test]
    fn turning_on_the_spot_before_a_far_wall() {
        // The thesis corridor's view: landmarks on an end wall 59 m away,
        // the robot turning 10° between frames.
        let camera = StereoCamera::default();
        let wall: Vec<[f64; 3]> = (0..12).map(|i| [60.0, -2.75 + 0.5 * i as f64, 1.0]).collect();
        let mut tracker = Tracker::new(EgomotionConfig::default(), camera, Pose2::new(1.0, 0.0, 0.0), 1);
        for k in 0..4 {
            let pose = Pose2::new(1.0, 0.0, -(k as f64) * 10f64.to_radians());
            let f = StereoFrame {
                number: k + 1,
                time: k as f64 * 0.5,
                landmarks: frame(&wall, pose, &camera),
                calibration: None,
            };
            tracker.update(&f, &pose);
        }
        let s = tracker.state();
        assert_eq!(s.failures, 0, "{s:?}");
        assert!((s.pose.unwrap().theta + 30f64.to_radians()).abs() < 1e-6, "{s:?}");
    }

    #[test]
    fn simple_estimator_follows_rotate_stop_translate_motion() {
        // Translate 0.25 m per frame, then turn 5° per frame, then translate.
        let mut poses = vec![Pose2::default()];
        for _ in 0..4 {
            let p = *poses.last().unwrap();
            poses.push(p.compose(&Pose2::new(0.25, 0.0, 0.0)));
        }
        for _ in 0..3 {
            let p = *poses.last().unwrap();
            poses.push(p.compose(&Pose2::new(0.0, 0.0, 5f64.to_radians())));
        }
        for _ in 0..4 {
            let p = *poses.last().unwrap();
            poses.push(p.compose(&Pose2::new(0.25, 0.0, 0.0)));
        }
        let state = run(EstimatorKind::Simple2d(Simple2dConfig::default()), &poses);
        let (end, truth) = (state.pose.unwrap(), *poses.last().unwrap());
        // The simplified estimator reads translation off depth changes, which
        // for a turned robot mix in the lateral offset: close, not exact.
        assert!(end.distance_to(truth.x, truth.y) < 0.1, "{end:?} vs {truth:?}");
        assert!((end.theta - truth.theta).abs() < 1f64.to_radians(), "{end:?} vs {truth:?}");
    }

    #[test]
    fn a_failed_step_is_recovered_from_the_kept_reference() {
        let camera = StereoCamera::default();
        let mut tracker = Tracker::new(EgomotionConfig::default(), camera, Pose2::default(), 0);
        let poses = [Pose2::default(), Pose2::new(0.25, 0.0, 0.0)];
        for (n, pose) in poses.iter().enumerate() {
            tracker.update(
                &StereoFrame {
                    number: n as u64 + 1,
                    time: n as f64 * 0.5,
                    landmarks: frame(&landmarks(), *pose, &camera),
                    calibration: None,
                },
                &Pose2::default(),
            );
        }
        tracker
            .update(&StereoFrame { number: 3, time: 1.0, landmarks: Vec::new(), calibration: None }, &Pose2::default());
        let s = tracker.state();
        assert_eq!((s.steps, s.failures), (2, 1));
        assert!((s.pose.unwrap().x - 0.25).abs() < 1e-6, "a failure moves nothing: {:?}", s.pose);
        // The same frame twice is not a new step.
        tracker
            .update(&StereoFrame { number: 3, time: 1.0, landmarks: Vec::new(), calibration: None }, &Pose2::default());
        assert_eq!(tracker.state().steps, 2);
        // The next good frame, 0.5 m on from the reference, recovers it all.
        let seen = frame(&landmarks(), Pose2::new(0.75, 0.0, 0.0), &camera);
        tracker.update(&StereoFrame { number: 4, time: 1.5, landmarks: seen, calibration: None }, &Pose2::default());
        assert!((tracker.state().pose.unwrap().x - 0.75).abs() < 1e-6, "{:?}", tracker.state().pose);
    }

    #[test]
    fn ransac_rejects_a_wrong_match() {
        let camera = StereoCamera::default();
        let poses = [Pose2::default(), Pose2::new(0.25, 0.0, 0.0)];
        let mut tracker = Tracker::new(EgomotionConfig::default(), camera, poses[0], 3);
        tracker.update(
            &StereoFrame { number: 1, time: 0.0, landmarks: frame(&landmarks(), poses[0], &camera), calibration: None },
            &Pose2::default(),
        );
        let mut second = frame(&landmarks(), poses[1], &camera);
        // One landmark appears 3 m off where it should be (a wrong match).
        second[2].point_cam[1] += 3.0;
        second[2].pixels = StereoPixels::default();
        tracker.update(&StereoFrame { number: 2, time: 0.5, landmarks: second, calibration: None }, &Pose2::default());
        let end = tracker.state().pose.unwrap();
        assert!((end.x - 0.25).abs() < 1e-6 && end.y.abs() < 1e-6, "{end:?}");
    }
}
