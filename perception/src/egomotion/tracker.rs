//! The keyframe tracker: integrates egomotion over a run, frame by frame,
//! against a bank of keyframes, and bridges failed frames by odometry.

use super::config::{DisparityOffsetEstimate, EgomotionConfig, EstimatorKind};
use super::matching::match_frames;
use super::odometry::Stretch;
use super::offset::{self, OffsetReading};
use super::one_landmark;
use super::step::{MotionPhase, Mounts, Pair, PlanarMotion, StepInput, StepMotion};
use super::wheel_calibration::{
    scale_given_prior, DistanceLedger, OdometryPath, ProportionalFit, Travel, Veer, WheelScale, TURN_SHARE,
};
use super::OdometryFusion;
use crate::error_model::{CvTable, MODEL_STEP_M};
use crate::fusion::fuse_cv;
use crate::stereo::StereoCamera;
use nalgebra::{Matrix3, Vector2, Vector3};
use rand_chacha::ChaCha8Rng;
use ubf_core::{
    angle_difference, wrap_angle, CameraMount, Command, EgomotionState, HeadingFix, LandmarkObservation, Pose2,
    StereoFrame,
};

/// A reference frame new frames are matched against.
#[derive(Clone, Debug)]
struct Keyframe {
    landmarks: Vec<LandmarkObservation>,
    /// The frame's number.
    number: u64,
    time: f64,
    /// Egomotion's pose of the robot when it was taken.
    pose: Pose2,
    /// The odometric pose then: how far the robot has since driven and
    /// turned, to keep keyframes apart and retire them.
    odometry: Pose2,
    /// Odometry bridges chained into its pose since the start: an anchor
    /// with fewer rests on more vision.
    bridges: u32,
    /// The covariance of its pose (x, y, heading) from the visual estimates
    /// chained into it.
    covariance: Matrix3<f64>,
    /// What its pose's covariance lacks: the odometry bridges and the
    /// steps on too few landmarks chained into it.
    extra: Matrix3<f64>,
    /// The odometry bridges' part of `extra`.
    bridges_covariance: Matrix3<f64>,
    /// Where the camera looked on the robot (a pan-tilt unit's measured
    /// angles), to lift its landmarks into the robot frame.
    mount: CameraMount,
    /// Odometry's path up to then: how far it had driven and turned, and
    /// the sums a stretch from here is read against.
    path: OdometryPath,
    /// Odometry's distance chained into its pose, and the scale it was
    /// taken in.
    ledger: DistanceLedger,
}

/// Where the camera looked in the world by the robot's `odometry`: its
/// heading turned by the mount's pan.
fn view_heading(odometry: &Pose2, mount: &CameraMount) -> f64 {
    odometry.theta + mount.pan_deg.to_radians()
}

/// The covariance of `pose ∘ motion`, to first order, from the covariances
/// of the two (independent) parts.
fn composed_covariance(
    pose: &Pose2,
    pose_cov: &Matrix3<f64>,
    motion: &PlanarMotion,
    motion_cov: &Matrix3<f64>,
) -> Matrix3<f64> {
    let (s, c) = pose.theta.sin_cos();
    let (f, l) = (motion.forward, motion.left);
    let j_pose = Matrix3::new(1.0, 0.0, -s * f - c * l, 0.0, 1.0, c * f - s * l, 0.0, 0.0, 1.0);
    let j_motion = Matrix3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0);
    j_pose * pose_cov * j_pose.transpose() + j_motion * motion_cov * j_motion.transpose()
}

/// Integrates egomotion over a run: each new stereo frame is matched against
/// a bank of keyframes taken from distinct viewpoints.
///
/// With the rigid estimator, the keyframe tried first is the one whose pose
/// is the most certain (the fewest chained estimates, then the oldest):
/// driving straight, a frame is matched to a keyframe metres back instead of
/// to the frame before it, so a far landmark's depth error does not enter
/// step after step; after a physical scan, the frame at the chosen heading is
/// matched to the keyframe taken before the sweep, so the sweep costs one
/// rotation estimate. The newest keyframe's match is taken instead when it
/// predicts a smaller error (see `best_estimate`). A keyframe is
/// retired once the robot has driven `keyframe_range_m` from it (or, with
/// the bank full, the farthest one makes room), never for elapsed time: a
/// person standing in front of the camera for a minute loses nothing.
///
/// When no keyframe matches, the pose is carried across by odometry and the
/// stretch is counted as an outage (its duration and distance are in the
/// state). A later frame that matches a keyframe from before the outage
/// replaces the odometry bridge with a visual estimate.
pub struct Tracker {
    config: EgomotionConfig,
    camera: StereoCamera,
    table: CvTable,
    rng: ChaCha8Rng,
    keyframes: Vec<Keyframe>,
    /// The newest frame taken in: its number, and the odometric pose then.
    newest: (u64, Pose2),
    /// The newest frame's time, s.
    newest_time: f64,
    /// The covariance of the visual pose (x, y, heading), as the
    /// estimator's information puts it; keyframes are chosen by it.
    covariance: Matrix3<f64>,
    /// The uncertainty of the pose that `covariance` leaves out: failed
    /// steps bridged by odometry (or, with none, by standing still), and
    /// steps on fewer than `trusted_landmarks` landmarks taken at more than
    /// their estimator's word (but for steps on one landmark, whose
    /// translation is odometry's).
    extra: Matrix3<f64>,
    /// The bridges' part of `extra` alone: what the pose owes to
    /// odometry, without the margin starving steps are given.
    bridges_covariance: Matrix3<f64>,
    /// The consistent landmarks the latest step rested on; `None` when it
    /// failed or there was none.
    step_landmarks: Option<usize>,
    /// When the latest frame matched (or the first was taken), s.
    last_match: f64,
    /// Metres odometry has driven from the start to the newest frame: what
    /// the uncertainty of its own pose grows with.
    odometry_driven_m: f64,
    /// Where the tracker started, and odometry's pose at the first
    /// keyframe, where egomotion's pose starts: odometry's frame may be its
    /// own, and its pose is carried into the tracker's from these.
    start: Pose2,
    odometry_origin: Option<Pose2>,
    /// When the current outage began, if one is under way.
    outage_since: Option<f64>,
    /// What the robot was commanded to do since the newest frame.
    phase: MotionPhase,
    /// The same, up to the newest frame: what the next step is told.
    commanded: MotionPhase,
    state: EgomotionState,
    matches: Vec<(usize, usize)>,
    pairs: Vec<Pair>,
    /// The latest steps' readings of the disparity offset, each the whole
    /// offset beyond the calibration's (the correction the landmarks had
    /// plus what the step read on top), oldest first; at most
    /// `OFFSET_READINGS_KEPT`.
    offset_readings: std::collections::VecDeque<OffsetReading>,
    /// The disparity offset the landmarks are corrected by, beyond the
    /// calibration's, px: 0 until the estimate is applied.
    offset_applied: f64,
    /// The wheels' scale as the trusted visual steps measure it, for the
    /// `Sideways` fusion of odometry's distance.
    wheel_scale: ProportionalFit,
    /// The wheels' veer as the same steps measure it, and odometry's path
    /// since its origin, which the veer corrects.
    veer: ProportionalFit,
    odometry_path: OdometryPath,
    /// Odometry's distance chained into the latest pose, and the scale it
    /// was taken in: the pose is reported in the scale measured now.
    ledger: DistanceLedger,
    /// The latest heading measured by another sensor, with odometry's pose
    /// when it was, waiting for the next frame.
    heading_fix: Option<(HeadingFix, Pose2)>,
    /// The turn other sensors have put into odometry's heading since the
    /// newest frame (each [`HeadingFix::correction`]), rad: no motion, so
    /// not for the next bridge to carry.
    uncounted_turn: f64,
}

/// The rig's disparity offset as the frames put it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OffsetEstimate {
    /// The pixels to add to every disparity beyond the calibration's
    /// offset: the rig's offset is the calibration's plus this, px.
    pub px: f64,
    /// How many steps' readings it rests on.
    pub readings: usize,
}

/// The readings of the disparity offset the estimate pools: the latest
/// 500 steps, minutes of a robot's frames and enough for the median to
/// settle, yet a rig whose offset drifts (with temperature) is followed.
const OFFSET_READINGS_KEPT: usize = 500;

/// Readings the estimate must rest on before the landmarks are corrected
/// by it: a median of ten readings is not moved by a few wild ones (one
/// step on a car, a wall of far landmarks).
const OFFSET_SETTLED_READINGS: usize = 10;

/// A reading less certain than this, px (σ), is not taken: a step that
/// moved too little (a robot standing, or turning on the spot) cannot
/// tell the offset from its landmarks' depths, and its reading is noise.
/// Ten times what a step over metres reads on real frames.
const OFFSET_READING_MAX_SIGMA_PX: f64 = 0.5;

/// The least scatter a reading is weighed with, px (σ), added to its own:
/// the fit's variance counts only pixel noise, while on real frames
/// single readings scatter by about 0.2 px (motion the planar model leaves
/// out, mismatches), so without it two sharp readings could hold half the
/// weight of a young estimate.
const OFFSET_READING_SCATTER_PX: f64 = 0.1;

/// The result of matching a frame against one keyframe.
struct Estimate {
    motion: PlanarMotion,
    landmarks: usize,
    step_cv: Option<f64>,
    /// The motion's covariance, where the estimator gives one.
    covariance: Option<Matrix3<f64>>,
    /// The visual motion before any odometry was combined with it, the
    /// landmarks consistent with it and the mounts of its two frames: the
    /// disparity offset is read from them, for the chosen match only. (A
    /// step on one landmark has no visual motion of its own: the fused one
    /// stands here, and no offset is read.)
    visual: PlanarMotion,
    /// The visual motion's own covariance, before odometry, where the
    /// estimator gives one: the wheels' scale and veer are measured
    /// against it.
    visual_covariance: Option<Matrix3<f64>>,
    /// The share of odometry's forward and sideways distance in `motion`.
    distance_gain: Vector2<f64>,
    inliers: Vec<Pair>,
    mounts: Mounts,
    /// Whether it is a step on one landmark, its translation odometry's
    /// (`one_landmark.rs`).
    on_one_landmark: bool,
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
            rng: ubf_core::seeds::rng(seed, ubf_core::seeds::Stream::Egomotion),
            keyframes: Vec::new(),
            newest: (0, Pose2::default()),
            newest_time: 0.0,
            covariance: Matrix3::zeros(),
            extra: Matrix3::zeros(),
            bridges_covariance: Matrix3::zeros(),
            step_landmarks: None,
            last_match: 0.0,
            odometry_driven_m: 0.0,
            start,
            odometry_origin: None,
            outage_since: None,
            phase: MotionPhase::Still,
            commanded: MotionPhase::Still,
            state: EgomotionState {
                pose: Some(start),
                sideways_fusion: config.fuses_sideways(),
                ..EgomotionState::default()
            },
            matches: Vec::new(),
            pairs: Vec::new(),
            offset_readings: std::collections::VecDeque::new(),
            offset_applied: 0.0,
            wheel_scale: ProportionalFit::default(),
            veer: ProportionalFit::default(),
            odometry_path: OdometryPath::default(),
            ledger: DistanceLedger::default(),
            heading_fix: None,
            uncounted_turn: 0.0,
        }
    }

    /// The rig's disparity offset as the steps so far read it (with the
    /// rigid estimator, unless `disparity_offset` is `Off`): the median of
    /// the latest steps' readings weighed by their precision, beyond the
    /// calibration's offset. `None` before a step has read one.
    ///
    /// The median is weighed because a step matched over metres to
    /// landmarks at many depths reads the offset far more precisely than one
    /// over a few centimetres; a weighted mean would let one wild reading
    /// pull it.
    pub fn disparity_offset(&self) -> Option<OffsetEstimate> {
        let readings = self.offset_readings.iter().map(|r| (r.px, r.variance + OFFSET_READING_SCATTER_PX.powi(2)));
        crate::fusion::weighted_median(readings).map(|px| OffsetEstimate { px, readings: self.offset_readings.len() })
    }

    /// The disparity offset the landmarks are corrected by now, beyond the
    /// calibration's, px: 0 unless `disparity_offset` is `Correct` and the
    /// estimate rests on enough steps.
    pub fn applied_disparity_offset(&self) -> f64 {
        self.offset_applied
    }

    /// Takes in a step's reading of the disparity offset and, when asked
    /// to correct, moves the correction to the estimate once it has
    /// settled.
    fn read_offset(&mut self, reading: OffsetReading) {
        if self.offset_readings.len() >= OFFSET_READINGS_KEPT {
            self.offset_readings.pop_front();
        }
        self.offset_readings.push_back(OffsetReading { px: self.offset_applied + reading.px, ..reading });
        if self.config.disparity_offset == DisparityOffsetEstimate::Correct
            && self.offset_readings.len() >= OFFSET_SETTLED_READINGS
        {
            self.offset_applied = self.disparity_offset().map_or(0.0, |e| e.px);
        }
        // How the estimate settles, for `-vv` (evaluated only then).
        tracing::debug!(
            frame = self.newest.0,
            reading = self.offset_readings.back().map(|r| r.px),
            sigma = reading.variance.sqrt(),
            estimate = ?self.disparity_offset().map(|e| e.px),
            applied = self.offset_applied,
            "disparity offset read"
        );
    }

    /// How far the robot goes for each metre odometry counts, as the
    /// visual steps so far measure it (with the rigid estimator,
    /// when odometry's distance is fused: `odometry_fusion: Sideways`);
    /// `None` until steps from five keyframes have.
    pub fn wheel_scale(&self) -> Option<WheelScale> {
        self.wheel_scale.scale()
    }

    /// How far the robot turns for each metre it drives beyond the turns
    /// odometry counts (with the rigid estimator, when `Sideways` fusion
    /// measures the wheels' scale too; `None` otherwise): 0 with the noise
    /// model's `veer_deg_per_m` for σ until steps from five keyframes have
    /// measured it, then their measure weighed against that.
    pub fn veer(&self) -> Option<Veer> {
        let noise = self.config.odometry_gate.and_then(|gate| gate.noise)?;
        self.config.fuses_sideways().then(|| Veer::given_prior(self.veer.veer(), noise.veer_deg_per_m.to_radians()))
    }

    /// Odometry's motion `odometric` over a bridged frame with its distance
    /// put in the wheels' scale, once `Sideways` fusion has measured it;
    /// its turn as counted. A scale measured on distance says little of
    /// the turns; and turning bridged frames by the measured veer too cost
    /// egomotion's end point on training layouts where only a few
    /// landmarks are in view at a time (scanning with a 20 m detection
    /// range: 0.276 → 0.321 m and 0.234 → 0.307 m on two sets of seeds),
    /// as the veer is then measured from those few landmarks' own turns.
    fn scaled(&self, odometric: Pose2) -> Pose2 {
        self.wheel_scale().map_or(odometric, |scale| scale.driven(odometric))
    }

    /// Takes in the chosen step's visual forward motion against
    /// odometry's, for the wheels' scale, and its visual turn less
    /// odometry's against odometry's distance, for their veer, if
    /// `Sideways` fusion will use them. Every visual step the odometry gate
    /// passed counts (not a step on one landmark, whose motion rests on
    /// odometry's), weighed by its own variance: a step on few landmarks
    /// says so in its covariance.
    fn measure_wheels(&mut self, anchor: u64, estimate: &Estimate, odometric: &Pose2, travel: &Travel) {
        let noise = self.config.odometry_gate.and_then(|gate| gate.noise);
        let (OdometryFusion::Sideways, Some(noise), Some(visual)) =
            (self.config.odometry_fusion, noise, estimate.visual_covariance)
        else {
            return;
        };
        let odometric_covariance = noise.covariance(odometric.x.hypot(odometric.y));
        self.wheel_scale.add(
            anchor,
            odometric.x,
            estimate.visual.forward,
            visual[(0, 0)] + odometric_covariance[(0, 0)],
        );
        // The turn odometry did not count, against the distance: the
        // visual turn is taken before odometry was combined with it, and
        // `Sideways` takes odometry's turn only as its path's shape anyway,
        // which a veer does not bend. It is not quite
        // free of odometry: the rigid estimator lays the later lines of
        // sight by odometry's turn, and on far landmarks its yaw follows
        // an error there by about a third (`rigid.rs`), so the veer is
        // read short by up to that much: a correction that errs small. The
        // distance is the one the correction turns odometry's path by, and
        // a stretch that turned is read as less certain by its turn. (The
        // slip's share is still reckoned on the chord, which understates
        // it where the stretch went back and forth.)
        self.veer.add(
            anchor,
            travel.forward_m,
            angle_difference(estimate.visual.yaw, odometric.theta),
            visual[(2, 2)] + odometric_covariance[(2, 2)] + (TURN_SHARE * travel.turned_rad).powi(2),
        );
    }

    /// The tracker's camera with the disparity offset the landmarks are
    /// corrected by now.
    fn corrected_camera(&self) -> StereoCamera {
        StereoCamera { disparity_offset_px: self.camera.disparity_offset_px + self.offset_applied, ..self.camera }
    }

    /// What egomotion has made of the frames so far.
    pub fn state(&self) -> EgomotionState {
        // Symmetric, so nalgebra's columns are its rows too.
        let covariance = self.state.pose.map(|_| self.pose_covariance().into());
        let wheel_scale = self.wheel_scale();
        EgomotionState { pose: self.pose_in_scale(wheel_scale), pose_covariance: covariance, wheel_scale, ..self.state }
    }

    /// The latest pose with odometry's distance chained into it put in the
    /// wheels' scale as measured now, `scale` (from [`Tracker::wheel_scale`],
    /// passed in by callers that need it too; see [`DistanceLedger`]). The
    /// chain itself, keyframes and all, keeps the distance as it was taken,
    /// so a newer measure of the scale moves every pose alike.
    fn pose_in_scale(&self, scale: Option<WheelScale>) -> Option<Pose2> {
        let pose = self.state.pose?;
        let correction = self.ledger.correction(scale.map_or(1.0, |scale| scale.factor));
        Some(Pose2::new(pose.x + correction.x, pose.y + correction.y, pose.theta))
    }

    /// The latest pose as chained, before [`Tracker::pose_in_scale`].
    #[cfg(test)]
    pub(super) fn chained_pose(&self) -> Option<Pose2> {
        self.state.pose
    }

    /// Odometry's metres per metre counted as measured now: 1 (as counted)
    /// until the steps have measured it.
    fn scale_factor(&self) -> f64 {
        self.wheel_scale().map_or(1.0, |scale| scale.factor)
    }

    /// The covariance of the latest pose (x, y, heading): the estimator's
    /// own information over the anchor keyframe's chained estimates and the
    /// latest match to it, plus what that leaves out: each failed step
    /// bridged (by odometry's noise, or with no odometry gate by the
    /// largest step the speed limits allow), and each step on fewer than
    /// `trusted_landmarks` landmarks taken as `trusted_landmarks / n` times
    /// as uncertain as its estimator says (a step on one landmark, whose
    /// translation is odometry's, as uncertain as its fit says).
    pub fn pose_covariance(&self) -> Matrix3<f64> {
        self.covariance + self.extra
    }

    /// The covariance of the latest pose as the estimator's own
    /// information puts it, without what [`Tracker::pose_covariance`] adds
    /// for failed and starving steps.
    pub fn estimator_covariance(&self) -> Matrix3<f64> {
        self.covariance
    }

    /// The consistent landmarks the latest step rested on; `None` when it
    /// failed (or no step has been taken yet).
    pub fn step_landmarks(&self) -> Option<usize> {
        self.step_landmarks
    }

    /// Whether the latest step is one not to trust: it failed, or rests on
    /// fewer than `trusted_landmarks` consistent landmarks.
    pub fn starving(&self) -> bool {
        self.state.steps > 0 && self.step_landmarks.is_none_or(|n| n < self.config.trusted_landmarks)
    }

    /// Where the robot is now by egomotion, if it navigates by it
    /// (`navigate`) and a frame has been taken in: the pose at the newest
    /// frame, carried on by what `odometry` (the odometric pose now) says
    /// the robot did since. Frames come a few times a second; a controller
    /// ticking faster steers by this rather than by a pose that stands
    /// still between frames.
    ///
    /// With the rigid estimator and an odometry gate's `noise`, that pose
    /// and odometry's own are taken for two estimates of the same pose and
    /// combined by their covariances (egomotion's [`Tracker::pose_covariance`], odometry's by
    /// its noise model over the distance driven since the start, with the
    /// [`Tracker::veer`]'s error and the wheels' scale's where odometry's
    /// pose is corrected by them): while
    /// egomotion holds, its pose leads; where it has starved or failed for
    /// long, its covariance grows past odometry's and the robot leans on
    /// odometry instead of steering by a pose gone astray. (The two are
    /// not independent, as egomotion bridges its failures by odometry, so
    /// the combination counts that part twice; and the weights are taken
    /// afresh at each call, so the pose steps when egomotion's covariance
    /// does, as a starving step raises it and the next good match lowers
    /// it.)
    pub fn navigation_pose(&self, odometry: &Pose2) -> Option<Pose2> {
        if !self.config.navigate || self.newest.0 == 0 {
            return None;
        }
        let measured = self.wheel_scale();
        let visual = self.pose_in_scale(measured)?.compose(&odometry.relative_to(&self.newest.1));
        // Only the rigid estimator gives a covariance to weigh its pose by.
        let rigid = matches!(self.config.estimator, EstimatorKind::Rigid(_));
        let (true, Some(noise), Some(origin)) =
            (rigid, self.config.odometry_gate.and_then(|gate| gate.noise), self.odometry_origin)
        else {
            return Some(visual);
        };
        // Odometry's own pose is put in the wheels' scale the visual steps
        // measured, weighed by precision against the noise model's
        // `scale_sigma` (the measure's σ has a floor of its own, half a
        // percent, so with the default prior at most half of it): the
        // scale is measured by the steps, so taken whole it would carry
        // vision's own distance error into odometry's pose rather than
        // check it (with 1 px of pixel noise, where that error is about a
        // percent, the pose steered by ended 0.44–0.51 m off against
        // 0.17–0.42 on training layouts), while the distance as counted
        // carries a wheel a percent small into the pose steered by, past
        // the goal's tolerance in most runs on wheels 1 % short. Its turns
        // take the veer, whose error is added to odometry's: a veer
        // odometry does not see walks its pose off sideways with the square
        // of the distance, which its noise model, a random slip, does not
        // cover. The veer is measured by vision too, so the same caution
        // holds; the prior it is weighed against keeps a veer read from a
        // few landmarks small. Turned by it, odometry's pose took the runs
        // a veer had pinned against a wall on training layouts off the
        // time limit (the cost is in `VEER_DEG_PER_M`'s note, `odometry.rs`).
        let driven = self.odometry_driven_m + odometry.distance_to(self.newest.1.x, self.newest.1.y);
        let mut odometric = noise.covariance(driven);
        let by_odometry = match self.veer() {
            Some(veer) => {
                let newest = self.odometry_path.corrected(&self.newest.1.relative_to(&origin), &veer);
                let scale = scale_given_prior(measured, noise.scale_sigma);
                odometric = noise.covariance_in_scale(driven, Some(scale))
                    + self.odometry_path.covariance(&veer, self.start.theta);
                self.start.compose(&scale.driven(newest.compose(&odometry.relative_to(&self.newest.1))))
            }
            None => self.start.compose(&odometry.relative_to(&origin)),
        };
        let Some(inverse) = (odometric + self.pose_covariance()).try_inverse() else { return Some(visual) };
        let apart = Vector3::new(
            visual.x - by_odometry.x,
            visual.y - by_odometry.y,
            angle_difference(visual.theta, by_odometry.theta),
        );
        let step = odometric * inverse * apart;
        Some(Pose2::new(by_odometry.x + step.x, by_odometry.y + step.y, wrap_angle(by_odometry.theta + step.z)))
    }

    /// The error model's look-up table the tracker weighs landmarks with.
    pub fn table(&self) -> &CvTable {
        &self.table
    }

    /// Takes note of a command sent to the robot: the simplified estimator
    /// reads the motion type from the commanded phase.
    pub fn commanded(&mut self, command: &Command) {
        self.commanded = self.commanded.and(command);
    }

    /// Keyframes in the bank now.
    pub fn keyframes(&self) -> usize {
        self.keyframes.len()
    }

    /// Whether [`Tracker::update`] would take `frame` in: numbered (0 is
    /// no frame yet) and not the newest taken. A caller need not work out
    /// the odometry of when a frame was taken until there is a new one.
    pub fn is_new(&self, frame: &StereoFrame) -> bool {
        frame.number != 0 && frame.number != self.newest.0
    }

    /// Takes in `frame` if it is new: matches it against the keyframes,
    /// best anchored first, and sets the pose from the best match. A
    /// frame no keyframe matches is a failure: the pose is carried on by
    /// odometry and an outage is counted.
    ///
    /// `odometry` is the robot's odometric pose when the frame was taken. It
    /// measures how far each step drove (to weigh the step's CV in the
    /// journey CV, eq. 7 per metre), keeps keyframes apart, and bridges
    /// outages; it never enters a visual estimate.
    ///
    /// A heading given by [`Tracker::fix_heading`] since the last frame is
    /// taken in after this one.
    pub fn update(&mut self, frame: &StereoFrame, odometry: &Pose2) {
        if !self.is_new(frame) {
            return;
        }
        self.take_frame(frame, odometry);
        if let Some((fix, at)) = self.heading_fix.take() {
            self.take_heading(fix, &at, odometry);
        }
    }

    /// A heading measured by a sensor other than the wheels (the wall
    /// compass) when odometry read `odometry`, taken in at the next frame.
    /// Egomotion's heading drifts wherever it bridges frames on odometry
    /// and with every step's small turn error, and nothing visual pins it
    /// back; a heading measured against the building does.
    pub fn fix_heading(&mut self, fix: HeadingFix, odometry: &Pose2) {
        self.uncounted_turn += fix.correction;
        self.heading_fix = Some((fix, *odometry));
    }

    /// Turns egomotion's pose towards the heading `fix` measured when
    /// odometry read `at` (carried to `odometry`, the frame's, by
    /// odometry's turn between: backwards where the frame was taken before
    /// the fix and reached the robot after it), by how much of the pose's
    /// heading is odometry's against how sure the fix is: a Kalman update of the heading error the bridges
    /// laid down. A keyframe shares the part of that error laid down
    /// before it, and is turned (about the pose, so that the next match to
    /// it lands where the pose now is) by that share: one laid on vision
    /// alone keeps its heading, one laid after the same bridges turns with
    /// the pose. Each fix is taken as independent of the last, which a
    /// compass's are not (they share its error in the building's axes):
    /// fixes with no bridging between them shrink the bridges' variance
    /// below the compass's own, and each later one then moves the pose
    /// less. Bridging again restores their weight.
    fn take_heading(&mut self, fix: HeadingFix, at: &Pose2, odometry: &Pose2) {
        let (Some(pose), Some(origin)) = (self.state.pose, self.odometry_origin) else { return };
        // The fix is in odometry's frame; egomotion's pose starts at
        // `start` where odometry read `origin`.
        let heading = fix.heading + angle_difference(odometry.theta, at.theta) + (self.start.theta - origin.theta);
        let error = angle_difference(heading, pose.theta);
        // Only the bridges' share of the pose's heading variance is weighed
        // against the fix: a wall compass corrects odometry's drift, which
        // reached the pose through the bridges alone. Weighed by the whole
        // (the estimator's chain and the margin of starving steps, both far
        // above what vision errs by), a heading vision held to a tenth of a
        // degree was handed to the fix's half degree: straight driving
        // ended 1.8–2.9× further off on training layouts of the
        // feature-poor and ordinary-near families.
        let own = self.bridges_covariance[(2, 2)];
        // Written so that NaN fails it.
        if !(error.is_finite() && own > 0.0 && fix.variance > 0.0) {
            return;
        }
        let innovation = own + fix.variance;
        // Turned by `share`·error about the pose, with the bridges'
        // covariance (and `extra`, which holds it) reduced by what the fix
        // told: `share` is the part of the pose's bridged heading variance
        // `bridges` shares, which keeps the update's covariance positive.
        let update =
            |pose_of: &mut Pose2, bridges: &mut Matrix3<f64>, extra: &mut Matrix3<f64>, ledger: &mut DistanceLedger| {
                let share = bridges[(2, 2)].min(own);
                if share <= 0.0 {
                    return;
                }
                let turn = error * share / innovation;
                *pose_of = pose.compose(&Pose2::new(0.0, 0.0, turn)).compose(&pose_of.relative_to(&pose));
                *ledger = ledger.turned(turn);
                let told = bridges.column(2) * bridges.row(2) * (share / bridges[(2, 2)]).powi(2) / innovation;
                *bridges -= told;
                *extra -= told;
            };
        let mut now = pose;
        update(&mut now, &mut self.bridges_covariance, &mut self.extra, &mut self.ledger);
        self.state.pose = Some(now);
        for keyframe in &mut self.keyframes {
            update(&mut keyframe.pose, &mut keyframe.bridges_covariance, &mut keyframe.extra, &mut keyframe.ledger);
        }
    }

    /// Takes in a new `frame` (see [`Tracker::update`]).
    fn take_frame(&mut self, frame: &StereoFrame, odometry: &Pose2) {
        let (previous_frame, previous_odometry) = std::mem::replace(&mut self.newest, (frame.number, *odometry));
        let previous_time = std::mem::replace(&mut self.newest_time, frame.time);
        let uncounted_turn = std::mem::take(&mut self.uncounted_turn);
        // The commands between the last frame and this one.
        self.phase = std::mem::replace(&mut self.commanded, MotionPhase::Still);
        let Some(pose) = self.state.pose else { return };
        // Only the first frame starts the pose here. A later frame finding
        // every keyframe retired (a blind stretch longer than their reach)
        // is bridged like any frame nothing matches: starting afresh there
        // would drop the motion since the last frame.
        if previous_frame == 0 {
            self.last_match = frame.time;
            // Egomotion's pose starts here, so odometry's is carried into
            // the tracker's frame from here too.
            self.odometry_origin.get_or_insert(*odometry);
            // A first view with too few landmarks could never be matched,
            // and would keep frames near it from becoming keyframes.
            if frame.landmarks.len() >= self.keyframe_landmarks() {
                self.add_keyframe(frame, pose, *odometry, 0);
            }
            return;
        }
        self.keyframes.retain(|k| k.odometry.distance_to(odometry.x, odometry.y) <= self.config.keyframe_range_m);
        let driven = previous_odometry.distance_to(odometry.x, odometry.y);
        self.odometry_driven_m += driven;
        if let Some(origin) = self.odometry_origin {
            self.odometry_path.add(&previous_odometry.relative_to(&origin), &odometry.relative_to(&origin));
        }
        self.state.steps += 1;
        match self.best_estimate(frame, odometry) {
            Some((anchor, estimate)) => {
                let keyframe = &self.keyframes[anchor];
                let pose = keyframe.pose.compose(&estimate.motion.as_pose());
                let odometric = odometry.relative_to(&keyframe.odometry);
                let counted = Vector2::new(odometric.x, odometric.y).component_mul(&estimate.distance_gain);
                self.ledger = keyframe.ledger.plus(keyframe.pose.theta, counted, self.scale_factor());
                // What a replay needs to see why a frame landed where it did
                // (the fields are only evaluated with debug logging on).
                tracing::debug!(
                    frame = frame.number,
                    anchor_time = keyframe.time,
                    landmarks = estimate.landmarks,
                    visual = ?(estimate.motion.forward, estimate.motion.left, estimate.motion.yaw.to_degrees()),
                    odometric = ?{
                        let o = odometry.relative_to(&keyframe.odometry);
                        (o.x, o.y, o.theta.to_degrees())
                    },
                    sigma = ?estimate.covariance.map(|c| (c[(0, 0)].sqrt(), c[(1, 1)].sqrt(), c[(2, 2)].sqrt().to_degrees())),
                    veer_deg_per_m = ?self.veer().map(|v| (v.rad_per_m.to_degrees(), v.sigma.to_degrees())),
                    wheel_scale = ?self.wheel_scale().map(|s| (s.factor, s.sigma)),
                    "egomotion matched"
                );
                let bridges = keyframe.bridges;
                let trusted = self.config.trusted_landmarks;
                let mut step_extra = Matrix3::zeros();
                if let Some(motion_cov) = &estimate.covariance {
                    self.covariance =
                        composed_covariance(&keyframe.pose, &keyframe.covariance, &estimate.motion, motion_cov);
                    // A step on one landmark is odometry's translation and
                    // its turn as odometry's position across the line of
                    // sight allows, not a visual fit RANSAC chose for
                    // agreeing: widened as one, the pose steered by leaned
                    // on odometry's drifted heading (range-20 training
                    // layouts 2121–2828, seeds 100–109, straight: 0.363 m
                    // off widened, 0.287 m not, 0.372 m with no such steps).
                    if estimate.landmarks < trusted && !estimate.on_one_landmark {
                        step_extra = motion_cov * (trusted as f64 / estimate.landmarks.max(1) as f64 - 1.0);
                    }
                }
                self.extra = composed_covariance(&keyframe.pose, &keyframe.extra, &estimate.motion, &step_extra);
                self.bridges_covariance = composed_covariance(
                    &keyframe.pose,
                    &keyframe.bridges_covariance,
                    &estimate.motion,
                    &Matrix3::zeros(),
                );
                self.step_landmarks = Some(estimate.landmarks);
                self.state.pose = Some(pose);
                self.state.last_step_cv = estimate.step_cv;
                self.state.journey_cv += estimate.step_cv.unwrap_or(0.0) * driven / MODEL_STEP_M;
                self.state.bridging = false;
                self.state.anchor_frame = Some(keyframe.number);
                self.last_match = frame.time;
                let travel = self.odometry_path.travel().since(&keyframe.path.travel());
                self.measure_wheels(keyframe.number, &estimate, &odometric, &travel);
                if self.config.disparity_offset != DisparityOffsetEstimate::Off && !estimate.on_one_landmark {
                    let sigma = match self.config.estimator {
                        EstimatorKind::Rigid(rigid) => rigid.pixel_sigma,
                        EstimatorKind::Simple2d(simple) => simple.pixel_sigma,
                    };
                    let camera = self.corrected_camera();
                    if let Some(reading) =
                        offset::read(&camera, &estimate.mounts, &estimate.inliers, &estimate.visual, sigma)
                            .filter(|r| r.variance.sqrt() <= OFFSET_READING_MAX_SIGMA_PX)
                    {
                        self.read_offset(reading);
                    }
                }
                if let Some(since) = self.outage_since.take() {
                    self.state.outage_s += frame.time - since;
                }
                if self.frame_to_frame() || self.distinct(odometry, &self.mount_of(frame)) {
                    self.add_keyframe(frame, pose, *odometry, bridges);
                }
            }
            None => {
                // Carry the pose on by what odometry says the robot did
                // since the last frame, and say so; its distance in the
                // wheels' measured scale when fusion has measured it.
                let counted = odometry.relative_to(&previous_odometry);
                self.ledger = self.ledger.plus(pose.theta, Vector2::new(counted.x, counted.y), self.scale_factor());
                let bridged = self.scaled(counted);
                // A turn another sensor put into odometry's heading is taken
                // in by `take_heading`, by how sure each is, not here whole.
                let bridged = Pose2 { theta: wrap_angle(bridged.theta - uncounted_turn), ..bridged };
                // Why a frame was bridged: how much it saw, and against what.
                tracing::debug!(
                    frame = frame.number,
                    in_view = frame.landmarks.len(),
                    keyframes = self.keyframes.len(),
                    bridged = ?(bridged.x, bridged.y, bridged.theta.to_degrees()),
                    "egomotion bridged"
                );
                let step = PlanarMotion { forward: bridged.x, left: bridged.y, yaw: bridged.theta };
                let bridge = self.bridge_covariance(frame.time - previous_time, driven);
                self.extra = composed_covariance(&pose, &self.extra, &step, &bridge);
                self.bridges_covariance = composed_covariance(&pose, &self.bridges_covariance, &step, &bridge);
                self.step_landmarks = None;
                let pose = pose.compose(&bridged);
                self.state.pose = Some(pose);
                self.state.failures += 1;
                self.state.last_step_cv = None;
                self.state.bridging = true;
                self.state.anchor_frame = None;
                self.state.outage_m += driven;
                if self.outage_since.is_none() {
                    self.outage_since = Some(self.last_match);
                    self.state.outages += 1;
                }
                // A frame nothing matches, from a new viewpoint, anchors the
                // frames after it (through the odometry bridge) once the old
                // keyframes are out of sight.
                if frame.landmarks.len() >= self.keyframe_landmarks() && self.distinct(odometry, &self.mount_of(frame))
                {
                    let bridges = self.keyframes.iter().map(|k| k.bridges).min().unwrap_or_default();
                    self.add_keyframe(frame, pose, *odometry, bridges + 1);
                }
            }
        }
    }

    /// The uncertainty of a step bridged over `driven` metres in `dt`
    /// seconds: odometry's noise if the gate models it, else a step anywhere
    /// within the speed and turn limits (uniform, variance a third of the
    /// limit squared).
    fn bridge_covariance(&self, dt: f64, driven: f64) -> Matrix3<f64> {
        if let Some(noise) = self.config.odometry_gate.as_ref().and_then(|g| g.noise.as_ref()) {
            // Bridged in the wheels' measured scale, as uncertain as it.
            return noise.covariance_in_scale(driven, self.wheel_scale());
        }
        let dt = dt.max(0.0);
        let (step, turn) = (self.config.max_speed * dt, self.config.max_turn_rate_deg.to_radians() * dt);
        Matrix3::from_diagonal(&nalgebra::Vector3::new(step * step, step * step, turn * turn)) / 3.0
    }

    /// The fewest consistent landmarks a step may rest on. On its own a
    /// visual step needs three: two fit any rigid motion but one dimension
    /// (their distance apart), so a wrong match among them is hardly seen.
    /// With odometry fused in (the rigid estimator and the gate's noise
    /// model), two will do: the gate checks their motion against
    /// odometry's, and the fusion takes the sideways motion from the
    /// wheels (and the distance, once their scale is measured), which two
    /// landmarks alone fix poorly, leaving them the turn, which they fix
    /// well. Where only a couple of landmarks are in view at a time (a
    /// short detection range, walls seen only obliquely) that corrects
    /// the heading on frames that were bridged blind.
    fn min_landmarks(&self) -> usize {
        if self.config.fuses_odometry() {
            2
        } else {
            3
        }
    }

    /// The fewest landmarks a frame nothing matched must hold to become a
    /// keyframe: enough for a step against it, one with `Sideways` fusion
    /// (`one_landmark.rs`).
    fn keyframe_landmarks(&self) -> usize {
        if self.config.fuses_sideways() {
            1
        } else {
            self.min_landmarks()
        }
    }

    /// Whether the estimator must work frame to frame (the simplified one
    /// does): it is given the newest keyframe first and every matched frame
    /// becomes one.
    fn frame_to_frame(&self) -> bool {
        self.config.estimator.estimator().frame_to_frame()
    }

    /// Whether a frame taken at `odometry` is far enough from every
    /// keyframe, in position or heading, to be one.
    fn distinct(&self, odometry: &Pose2, mount: &CameraMount) -> bool {
        let (spacing, turn) = (self.config.keyframe_spacing_m, self.config.keyframe_spacing_deg.to_radians());
        let view = view_heading(odometry, mount);
        self.keyframes.iter().all(|k| {
            k.odometry.distance_to(odometry.x, odometry.y) >= spacing
                || angle_difference(view, view_heading(&k.odometry, &k.mount)).abs() >= turn
        })
    }

    fn add_keyframe(&mut self, frame: &StereoFrame, pose: Pose2, odometry: Pose2, bridges: u32) {
        if self.keyframes.len() >= self.config.keyframes {
            // Make room by retiring the keyframe farthest from here.
            let farthest = self
                .keyframes
                .iter()
                .enumerate()
                .max_by(|a, b| {
                    let d = |k: &Keyframe| k.odometry.distance_to(odometry.x, odometry.y);
                    d(a.1).total_cmp(&d(b.1))
                })
                .map(|(i, _)| i);
            if let Some(i) = farthest {
                self.keyframes.remove(i);
            }
        }
        self.keyframes.push(Keyframe {
            landmarks: frame.landmarks.clone(),
            number: frame.number,
            time: frame.time,
            pose,
            odometry,
            bridges,
            covariance: self.covariance,
            extra: self.extra,
            bridges_covariance: self.bridges_covariance,
            mount: self.mount_of(frame),
            path: self.odometry_path,
            ledger: self.ledger,
        });
    }

    /// The mount `frame` was taken with: its calibration's (on a pan-tilt
    /// unit, the measured angles then), else the tracker's camera's.
    fn mount_of(&self, frame: &StereoFrame) -> CameraMount {
        frame.calibration.map_or(self.camera.mount, |c| c.mount)
    }

    /// The anchor and the match to it: the first good match (at least
    /// `good_match_landmarks`) against the keyframes facing close enough to
    /// share the view, fewest odometry bridges first, then the smallest
    /// pose covariance (the fewest chained estimates); failing a good match,
    /// the match with the most landmarks. The simplified estimator, which
    /// works frame to frame, tries the newest first.
    ///
    /// A far anchor spares the chain of short steps, but it shares only the
    /// landmarks still in view, mostly distant ones whose depth is poor, and
    /// a wrong consensus among them can put the frame metres off (where no
    /// odometry gate catches it, as on a replayed recording). So the newest
    /// keyframe is matched too, and the anchor is the one predicting the
    /// smaller error: the keyframe's pose covariance carried through the
    /// match's (the estimator's inverse information), position variance plus
    /// heading variance over the keyframe reach, where a heading error
    /// becomes a position error.
    fn best_estimate(&mut self, frame: &StereoFrame, odometry: &Pose2) -> Option<(usize, Estimate)> {
        let fov = self.camera.horizontal_fov();
        let view = view_heading(odometry, &self.mount_of(frame));
        let mut order: Vec<usize> = (0..self.keyframes.len())
            .filter(|&i| {
                let k = &self.keyframes[i];
                angle_difference(view, view_heading(&k.odometry, &k.mount)).abs() < fov
            })
            .collect();
        let newest = order.iter().copied().max_by(|&a, &b| self.keyframes[a].time.total_cmp(&self.keyframes[b].time));
        if self.frame_to_frame() {
            order.sort_by(|&a, &b| self.keyframes[b].time.total_cmp(&self.keyframes[a].time));
        } else {
            let spread = |k: &Keyframe| self.predicted_error(&k.covariance);
            order.sort_by(|&a, &b| {
                let (ka, kb) = (&self.keyframes[a], &self.keyframes[b]);
                ka.bridges.cmp(&kb.bridges).then(spread(ka).total_cmp(&spread(kb))).then(ka.time.total_cmp(&kb.time))
            });
        }
        let mut best: Option<(usize, Estimate)> = None;
        for &i in &order {
            let Some(estimate) = self.estimate_from(i, frame, odometry) else { continue };
            if estimate.landmarks >= self.config.good_match_landmarks {
                best = Some((i, estimate));
                break;
            }
            if best.as_ref().is_none_or(|(_, b)| estimate.landmarks > b.landmarks) {
                best = Some((i, estimate));
            }
        }
        let (Some((anchor, far)), Some(newest)) = (&best, newest) else { return best };
        if *anchor == newest {
            return best;
        }
        let Some(near) = self.estimate_from(newest, frame, odometry) else { return best };
        if near.landmarks < self.config.good_match_landmarks {
            return best;
        }
        let (Some(far_cov), Some(near_cov)) = (far.covariance, near.covariance) else { return best };
        let (kf, kn) = (&self.keyframes[*anchor], &self.keyframes[newest]);
        let far_error = self.predicted_error(&composed_covariance(&kf.pose, &kf.covariance, &far.motion, &far_cov));
        let near_error = self.predicted_error(&composed_covariance(&kn.pose, &kn.covariance, &near.motion, &near_cov));
        if near_error < far_error {
            Some((newest, near))
        } else {
            best
        }
    }

    /// The error a pose with covariance `c` (x, y, heading) predicts: its
    /// position variance plus its heading variance over the keyframe reach,
    /// where a heading error becomes a position error, m².
    fn predicted_error(&self, c: &Matrix3<f64>) -> f64 {
        let reach = self.config.keyframe_range_m;
        c[(0, 0)] + c[(1, 1)] + reach * reach * c[(2, 2)]
    }

    /// The motion from keyframe `index` to `frame`, if the estimator finds
    /// one.
    fn estimate_from(&mut self, index: usize, frame: &StereoFrame, odometry: &Pose2) -> Option<Estimate> {
        let estimator = self.config.estimator.estimator();
        let keyframe = &self.keyframes[index];
        match_frames(&keyframe.landmarks, &frame.landmarks, &self.config.matching, &mut self.matches);
        // Each frame's landmarks are lifted by the mount it was taken with,
        // so a pan of the camera between them is not read as a turn of the
        // robot.
        let mounts = Mounts {
            before: keyframe.mount,
            after: self.mount_of(frame),
            ahead: CameraMount::ahead(self.camera.mount.forward, self.camera.mount.left, self.camera.mount.height),
        };
        self.pairs.clear();
        let reading = self.config.disparity_offset != DisparityOffsetEstimate::Off;
        let camera = self.corrected_camera();
        for &(i, j) in &self.matches {
            let (seen_before, seen_after) = (&keyframe.landmarks[i], &frame.landmarks[j]);
            let (mut before, mut after) = (seen_before.point_cam, seen_after.point_cam);
            // Uncorrected, the points are kept to the bit: reporting the
            // offset must not move the path.
            if self.offset_applied != 0.0 {
                let (Some(b), Some(a)) =
                    (camera.triangulate(&seen_before.pixels), camera.triangulate(&seen_after.pixels))
                else {
                    continue;
                };
                (before, after) = (b, a);
            }
            let cv = self.table.cv(after[0], after[1], after[2]);
            let mut pair = estimator.pair(before, after, &mounts, cv);
            if reading {
                pair.pixels = Some([seen_before.pixels, seen_after.pixels]);
            }
            self.pairs.push(pair);
        }
        let dt = (frame.time - keyframe.time).max(1e-6);
        // (The simplified estimator makes steps of one landmark its own way.)
        if self.pairs.len() == 1 && self.config.fuses_sideways() {
            return self.one_landmark_estimate(index, odometry, dt, mounts);
        }
        let input = StepInput {
            camera: &self.camera,
            max_step_m: self.config.max_speed * dt * 1.5 + 0.02,
            phase: self.phase,
            turned_rad: odometry.relative_to(&keyframe.odometry).theta,
            min_landmarks: self.min_landmarks(),
            rng: &mut self.rng,
        };
        let StepMotion { mut motion, landmarks, mut covariance, inliers } = estimator.estimate(&self.pairs, input)?;
        let (visual, visual_covariance) = (motion, covariance);
        let mut distance_gain = Vector2::zeros();
        // Frames that share landmarks cannot have looked further apart than
        // the view is wide, nor can the robot have turned faster than it
        // turns (§4.4.6).
        let max_turn = self.max_turn(dt);
        let looked = motion.yaw + (mounts.after.pan_deg - mounts.before.pan_deg).to_radians();
        if motion.yaw.abs() > max_turn || looked.abs() > self.camera.horizontal_fov() {
            return None;
        }
        if let Some(gate) = &self.config.odometry_gate {
            let stretch = self.stretch_since(keyframe, odometry);
            let scale = self.wheel_scale();
            (motion, covariance, distance_gain) =
                gate.pass(self.config.odometry_fusion, motion, covariance, &stretch, scale)?;
        }
        Some(Estimate {
            motion,
            landmarks,
            step_cv: fuse_cv(self.pairs.iter().map(|p| p.cv)),
            covariance,
            visual,
            visual_covariance,
            distance_gain,
            inliers,
            mounts,
            on_one_landmark: false,
        })
    }

    /// Odometry over the stretch from `keyframe` to now, when it read
    /// `odometry`.
    fn stretch_since(&self, keyframe: &Keyframe, odometry: &Pose2) -> Stretch {
        Stretch {
            motion: odometry.relative_to(&keyframe.odometry),
            drift_lever: self.odometry_path.drift_lever_since(&keyframe.path),
        }
    }

    /// The widest turn a step between frames `dt` s apart may make: the
    /// robot's top turn rate, with a margin (§4.4.6).
    fn max_turn(&self, dt: f64) -> f64 {
        self.config.max_turn_rate_deg.to_radians() * dt * 1.5 + 2f64.to_radians()
    }

    /// With `Sideways` fusion (on the rigid estimator), the step the one
    /// landmark matched to keyframe `index` (in `self.pairs`) makes with
    /// odometry's position (see `one_landmark.rs`), if it fits. Its motion
    /// is not measured by vision alone, so it neither measures the wheels
    /// nor reads the disparity offset. Elsewhere it counts as a step on
    /// one landmark: no outage, and its landmark's CV is the step's, which
    /// the journey CV, the end-point predictor and action aiding's vote
    /// read.
    fn one_landmark_estimate(&self, index: usize, odometry: &Pose2, dt: f64, mounts: Mounts) -> Option<Estimate> {
        let (true, EstimatorKind::Rigid(rigid), Some(gate), [pair]) =
            (self.config.fuses_sideways(), self.config.estimator, self.config.odometry_gate, self.pairs.as_slice())
        else {
            return None;
        };
        let stretch = self.stretch_since(&self.keyframes[index], odometry);
        let (motion, covariance, distance_gain) =
            one_landmark::step(&self.camera, rigid.pixel_sigma, pair, &gate, &stretch, self.wheel_scale())?;
        // The bound a step on more landmarks is held to (`estimate_from`).
        if motion.yaw.abs() > self.max_turn(dt) {
            return None;
        }
        Some(Estimate {
            motion,
            landmarks: 1,
            step_cv: Some(pair.cv),
            covariance: Some(covariance),
            visual: motion,
            visual_covariance: None,
            distance_gain,
            inliers: Vec::new(),
            mounts,
            on_one_landmark: true,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::egomotion::testing::{at, disturbed, frame, landmarks};
    use crate::egomotion::OdometryFusion;

    #[test]
    fn the_state_says_sideways_fusion_only_where_it_is_combined() {
        let flag = |config: EgomotionConfig| {
            Tracker::new(config, StereoCamera::default(), Pose2::default(), 0).state().sideways_fusion
        };
        let default = EgomotionConfig::default();
        assert!(flag(default));
        let simple = EstimatorKind::Simple2d(super::super::config::Simple2dConfig::default());
        for (name, config) in [
            ("Full", EgomotionConfig { odometry_fusion: OdometryFusion::Full, ..default }),
            ("Off", EgomotionConfig { odometry_fusion: OdometryFusion::Off, ..default }),
            ("Simple2d", EgomotionConfig { estimator: simple, ..default }),
            ("no gate", EgomotionConfig { odometry_gate: None, ..default }),
        ] {
            assert!(!flag(config), "{name}");
        }
    }

    #[test]
    fn a_camera_panning_on_a_robot_driving_straight_is_not_read_as_a_turn() {
        // The robot drives 6 m straight down the corridor while a pan-tilt
        // unit sweeps the pair between 60° left and right; each frame's
        // calibration carries the unit's angle at the frame.
        let corridor: Vec<[f64; 3]> = (0..40)
            .map(|i| [-4.0 + 1.1 * i as f64, if i % 2 == 0 { 2.0 } else { -2.0 }, 0.4 + 0.04 * i as f64])
            .collect();
        let sweep = |k: usize| 60f64.to_radians() * (k as f64 * std::f64::consts::TAU / 16.0).sin();
        let run = |told: &dyn Fn(usize) -> f64| {
            let fixed = StereoCamera::default();
            let mut tracker = Tracker::new(EgomotionConfig::default(), fixed, Pose2::default(), 1);
            for k in 0..25 {
                let pose = Pose2::new(0.25 * k as f64, 0.0, 0.0);
                let looking = StereoCamera { mount: fixed.mount.aimed(sweep(k), 0.0), ..fixed };
                let calibration = StereoCamera { mount: fixed.mount.aimed(told(k), 0.0), ..fixed };
                let f = StereoFrame {
                    number: k as u64 + 1,
                    time: k as f64 * 0.5,
                    landmarks: frame(&corridor, pose, &looking),
                    calibration: Some(calibration),
                    images: None,
                };
                tracker.update(&f, &pose);
            }
            tracker.state()
        };
        let measured = run(&sweep);
        let end = measured.pose.unwrap();
        assert!(end.distance_to(6.0, 0.0) < 1e-6 && end.theta.abs() < 1e-6, "{measured:?}");
        assert_eq!(measured.failures, 0, "{measured:?}");
        // Told the camera looked ahead throughout, the tracker takes the
        // sweep for turns of the robot, and rejects them or ends far off.
        let blind = run(&|_| 0.0);
        let off = blind.pose.unwrap();
        assert!(blind.failures > 5 || off.theta.abs() > 0.2 || off.distance_to(6.0, 0.0) > 0.5, "{blind:?}");
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
                    images: None,
                },
                pose,
            );
        }
        // Odometry says the robot stood still since: the failed frame is
        // bridged by no motion.
        let odometry = poses[1];
        tracker.update(
            &StereoFrame { number: 3, time: 1.0, landmarks: Vec::new(), calibration: None, images: None },
            &odometry,
        );
        let s = tracker.state();
        assert_eq!((s.steps, s.failures), (2, 1));
        assert!((s.pose.unwrap().x - 0.25).abs() < 1e-6, "a failure moves nothing: {:?}", s.pose);
        // The same frame twice is not a new step.
        tracker.update(
            &StereoFrame { number: 3, time: 1.0, landmarks: Vec::new(), calibration: None, images: None },
            &odometry,
        );
        assert_eq!(tracker.state().steps, 2);
        // The next good frame, 0.5 m on from the reference, recovers it all
        // (odometry, 5 cm short, weighs in by millimetres: its distance is
        // taken as counted, as uncertain as the noise model says).
        let seen = frame(&landmarks(), Pose2::new(0.75, 0.0, 0.0), &camera);
        let odometry = Pose2::new(0.7, 0.0, 0.0);
        tracker
            .update(&StereoFrame { number: 4, time: 1.5, landmarks: seen, calibration: None, images: None }, &odometry);
        assert!((tracker.state().pose.unwrap().x - 0.75).abs() < 0.01, "{:?}", tracker.state().pose);
    }

    #[test]
    fn two_landmarks_correct_a_turn_odometry_invents_when_odometry_is_fused() {
        // Two landmarks ahead and the robot driving straight 0.3 m a frame,
        // while odometry counts 0.3° of turn a frame that never happened.
        // Fused with odometry, two landmarks make a step, and the pose's
        // heading stays true; purely visual, two are too few, every frame
        // is bridged, and the pose turns with odometry. (The fused heading
        // is not exact: odometry's sideways motion, bent by the turn it
        // invents, is fused in, and a two-landmark fit couples its sideways
        // motion with its turn.)
        let two = [[8.0, 1.5, 0.8], [9.0, -1.5, 1.0]];
        for (fusion, failures, heading_deg, within_deg) in
            [(OdometryFusion::Sideways, 0, 0.0, 0.3), (OdometryFusion::Off, 8, 2.4, 1e-9)]
        {
            driving_past(&two, 0.3, fusion, failures, heading_deg, within_deg);
        }
    }

    /// Drives 9 frames 0.3 m apart straight past `points` while odometry
    /// counts `invented_deg` of turn a frame that never happened, and
    /// checks the failed steps and the heading at the end.
    fn driving_past(
        points: &[[f64; 3]],
        invented_deg: f64,
        fusion: OdometryFusion,
        failures: u32,
        heading_deg: f64,
        within_deg: f64,
    ) {
        let camera = StereoCamera::default();
        let config = EgomotionConfig { odometry_fusion: fusion, ..EgomotionConfig::default() };
        let mut tracker = Tracker::new(config, camera, Pose2::default(), 0);
        let mut odometry = Pose2::default();
        for k in 0..9u32 {
            let truth = Pose2::new(0.3 * f64::from(k), 0.0, 0.0);
            tracker.update(&at(u64::from(k) + 1, 0.5 * f64::from(k), frame(points, truth, &camera)), &odometry);
            odometry = odometry.compose(&Pose2::new(0.3, 0.0, invented_deg.to_radians()));
        }
        let s = tracker.state();
        assert_eq!((s.steps, s.failures), (8, failures), "{fusion:?}: {s:?}");
        let heading = s.pose.unwrap().theta.to_degrees();
        assert!((heading - heading_deg).abs() < within_deg, "{fusion:?}: {heading}° against {heading_deg}°");
    }

    #[test]
    fn one_landmark_corrects_a_turn_odometry_invents_when_odometry_is_fused() {
        // One landmark ahead and the robot driving straight 0.3 m a frame,
        // while odometry counts 0.1° of turn a frame that never happened.
        // Fused sideways, the landmark alone makes a step, and the pose's
        // heading stays true; with no fusion, or with `Full` (which takes
        // odometry's turn whole), every frame is bridged, and the pose
        // turns with odometry.
        let one = [[8.0, 1.5, 0.8]];
        for (fusion, failures, heading_deg, within_deg) in [
            (OdometryFusion::Sideways, 0, 0.0, 0.05),
            (OdometryFusion::Off, 8, 0.8, 1e-9),
            (OdometryFusion::Full, 8, 0.8, 1e-9),
        ] {
            driving_past(&one, 0.1, fusion, failures, heading_deg, within_deg);
        }
    }

    #[test]
    fn the_simplified_estimator_still_steps_on_one_landmark_its_own_way() {
        // Three landmarks in the first frame, then only the first of them:
        // the simplified estimator reads its change of range as a step, as
        // it did before the rigid estimator's steps on one landmark.
        let camera = StereoCamera::default();
        let three = [[8.0, 1.5, 0.8], [9.0, -1.5, 1.0], [10.0, 0.5, 1.2]];
        let simple = EstimatorKind::Simple2d(super::super::config::Simple2dConfig::default());
        let mut tracker = Tracker::new(
            EgomotionConfig { estimator: simple, ..EgomotionConfig::default() },
            camera,
            Pose2::default(),
            0,
        );
        for k in 0..5u32 {
            let truth = Pose2::new(0.3 * f64::from(k), 0.0, 0.0);
            let seen = if k == 0 { &three[..] } else { &three[..1] };
            tracker.update(&at(u64::from(k) + 1, 0.5 * f64::from(k), frame(seen, truth, &camera)), &truth);
        }
        let s = tracker.state();
        assert_eq!((s.steps, s.failures), (4, 0), "{s:?}");
        assert!((s.pose.unwrap().x - 1.2).abs() < 0.01, "{s:?}");
    }

    #[test]
    fn a_blind_stretch_beyond_every_keyframe_loses_no_motion() {
        // 30 frames with nothing in view, 0.3 m and 1° apart: 9 m, 3 m
        // beyond the keyframes' reach, so every keyframe is retired on the
        // way. Each frame is bridged by odometry; none starts the pose
        // afresh (which would drop that frame's 0.3 m and 1°).
        let camera = StereoCamera::default();
        let config = EgomotionConfig { keyframe_range_m: 6.0, ..EgomotionConfig::default() };
        let mut tracker = Tracker::new(config, camera, Pose2::default(), 0);
        tracker.update(&at(1, 0.0, frame(&landmarks(), Pose2::default(), &camera)), &Pose2::default());
        let mut odometry = Pose2::default();
        for k in 0..30u32 {
            odometry = odometry.compose(&Pose2::new(0.3, 0.0, 1f64.to_radians()));
            tracker.update(&at(u64::from(k) + 2, 0.5 * f64::from(k + 1), Vec::new()), &odometry);
        }
        let s = tracker.state();
        assert_eq!((s.steps, s.failures, s.outages), (30, 30, 1), "{s:?}");
        assert!((s.outage_m - 9.0).abs() < 1e-9, "{s:?}");
        let pose = s.pose.unwrap();
        assert!(pose.distance_to(odometry.x, odometry.y) < 1e-9, "{pose:?} against {odometry:?}");
        assert!((pose.theta - odometry.theta).abs() < 1e-12, "{pose:?} against {odometry:?}");
    }

    /// [`landmarks`] 3 m further on, under indices (and so descriptors) of
    /// their own: a keyframe of [`landmarks`] matches none of them.
    fn landmarks_further_on() -> Vec<[f64; 3]> {
        let unseen = landmarks().into_iter().map(|_| [-100.0, 0.0, 0.0]);
        unseen.chain(landmarks().into_iter().map(|p| [p[0] + 3.0, p[1], p[2]])).collect()
    }

    #[test]
    fn a_heading_fix_turns_what_odometry_bridged_and_the_keyframe_the_next_frames_match() {
        // The robot drives straight along x. Odometry turns 2° it did not
        // over the first 2 m, while the camera sees landmarks no keyframe
        // holds: egomotion bridges that frame on odometry and keeps it as a
        // keyframe, 2° off. Matched to it, every later frame inherits the
        // 2°, unless a heading measured by another sensor (the truth, 0°)
        // turns the pose and the keyframe.
        let camera = StereoCamera::default();
        let (far, later) = (landmarks(), landmarks_further_on());
        let odometry = |x: f64| Pose2::new(x, 0.035 + (x - 2.0) * 0.035, 2f64.to_radians());
        let heading_after = |fix: Option<HeadingFix>| {
            let mut tracker = Tracker::new(EgomotionConfig::default(), camera, Pose2::default(), 0);
            tracker.update(&at(1, 0.0, frame(&far, Pose2::default(), &camera)), &Pose2::default());
            tracker.update(&at(2, 4.0, frame(&later, Pose2::new(2.0, 0.0, 0.0), &camera)), &odometry(2.0));
            assert!(tracker.state().bridging, "the new landmarks match no keyframe");
            if let Some(fix) = fix {
                tracker.fix_heading(fix, &odometry(2.5));
            }
            for (n, x) in [(3, 3.0), (4, 4.0)] {
                tracker.update(&at(n, 2.0 * x, frame(&later, Pose2::new(x, 0.0, 0.0), &camera)), &odometry(x));
                assert!(!tracker.state().bridging, "frame {n} matches");
            }
            tracker.state().pose.unwrap().theta.to_degrees()
        };
        let unfixed = heading_after(None);
        assert!((unfixed - 2.0).abs() < 0.2, "{unfixed}°");
        let fixed =
            heading_after(Some(HeadingFix { heading: 0.0, variance: 0.1f64.to_radians().powi(2), correction: 0.0 }));
        assert!(fixed.abs() < 0.3, "{fixed}°");
        // A fix no surer than the bridge moves it part way.
        let vague =
            heading_after(Some(HeadingFix { heading: 0.0, variance: 0.4f64.to_radians().powi(2), correction: 0.0 }));
        assert!(vague > fixed + 0.5 && vague < unfixed - 0.5, "{vague}°");
    }

    #[test]
    fn a_compass_correction_bridged_into_the_pose_turns_what_odometry_laid_and_nothing_vision_did() {
        // As above, with 1° of odometry's error (a compass corrects less
        // than the odometry gate allows over a keyframe's reach), and the
        // fix from a compass that corrects the odometry it passes on: from
        // the fix on, odometry's heading jumps to the truth, and the next
        // frame sees nothing and is bridged. The bridge leaves the jump
        // out, and the fix turns the pose and, by its share, the keyframe
        // laid 1° off by the bridge; the first keyframe, laid by vision
        // alone, keeps its heading.
        let camera = StereoCamera::default();
        let (far, later) = (landmarks(), landmarks_further_on());
        let erring = Pose2::new(2.0, 0.0175, 1f64.to_radians());
        let corrected = |x: f64| Pose2::new(x, 0.0175, 0.0);
        let mut tracker = Tracker::new(EgomotionConfig::default(), camera, Pose2::default(), 0);
        tracker.update(&at(1, 0.0, frame(&far, Pose2::default(), &camera)), &Pose2::default());
        tracker.update(&at(2, 4.0, frame(&later, Pose2::new(2.0, 0.0, 0.0), &camera)), &erring);
        let fix = HeadingFix { heading: 0.0, variance: 0.05f64.to_radians().powi(2), correction: -1f64.to_radians() };
        tracker.fix_heading(fix, &corrected(2.5));
        tracker.update(&at(3, 6.0, Vec::new()), &corrected(3.0));
        assert!(tracker.state().bridging);
        let heading = |t: &Tracker| t.state().pose.unwrap().theta.to_degrees();
        assert!(heading(&tracker).abs() < 0.1, "the bridged pose: {}°", heading(&tracker));
        // Matched to the keyframe the bridge laid 1° off, which the fix
        // turned by the share of the pose's bridged error laid down before
        // it (the pose bridged 1 m more since): over half the way.
        tracker.update(&at(4, 8.0, frame(&later, Pose2::new(4.0, 0.0, 0.0), &camera)), &corrected(4.0));
        assert_eq!(tracker.state().anchor_frame, Some(2));
        assert!(heading(&tracker) > 0.0 && heading(&tracker) < 0.5, "{}°", heading(&tracker));
        // Matched to the first keyframe, which vision laid and the fix
        // left alone: the truth, to the estimator's precision.
        tracker.update(&at(5, 9.0, frame(&far, Pose2::new(4.5, 0.0, 0.0), &camera)), &corrected(4.5));
        assert_eq!(tracker.state().anchor_frame, Some(1));
        assert!(heading(&tracker).abs() < 0.05, "{}°", heading(&tracker));
    }

    #[test]
    fn a_heading_fix_leaves_a_heading_vision_measured_alone() {
        // Nothing was bridged, so none of the heading is odometry's, and a
        // heading fix 1° off (a wall a degree out of square) turns nothing.
        let camera = StereoCamera::default();
        let mut tracker = Tracker::new(EgomotionConfig::default(), camera, Pose2::default(), 0);
        tracker.update(&at(1, 0.0, frame(&landmarks(), Pose2::default(), &camera)), &Pose2::default());
        let truth = Pose2::new(1.0, 0.0, 0.0);
        tracker.fix_heading(HeadingFix { heading: 1f64.to_radians(), variance: 1e-6, correction: 0.0 }, &truth);
        tracker.update(&at(2, 2.0, frame(&landmarks(), truth, &camera)), &truth);
        assert!(!tracker.state().bridging);
        let pose = tracker.state().pose.unwrap();
        assert!(pose.theta.to_degrees().abs() < 0.01, "{pose:?}");
    }

    #[test]
    fn a_long_blackout_loses_no_motion_and_is_counted() {
        // Something covers the camera for 30 s while the robot drives 2 m
        // and turns; odometry, which bridges the gap, is 2 % short (within
        // what the odometry gate expects of it). The first frame after it
        // matches a keyframe from before it, so the visual estimate replaces
        // the bridge.
        let camera = StereoCamera::default();
        // Purely visual: a fused estimate would take some of odometry's
        // shortfall.
        let config = EgomotionConfig { odometry_fusion: OdometryFusion::Off, ..EgomotionConfig::default() };
        let mut tracker = Tracker::new(config, camera, Pose2::default(), 0);
        let start = Pose2::default();
        tracker.update(&at(1, 0.0, frame(&landmarks(), start, &camera)), &start);
        let end = Pose2::new(2.0, 0.1, 0.1);
        for k in 0..60u32 {
            let share = f64::from(k + 1) / 61.0;
            let odometry = Pose2::new(0.98 * end.x * share, 0.98 * end.y * share, end.theta * share);
            tracker.update(&at(u64::from(k) + 2, 0.5 * f64::from(k + 1), Vec::new()), &odometry);
            assert!(tracker.state().bridging);
        }
        let s = tracker.state();
        assert_eq!((s.outages, s.failures), (1, 60));
        assert!((s.outage_m - 0.98 * end.x.hypot(end.y) * 60.0 / 61.0).abs() < 1e-9, "{s:?}");
        // On odometry the pose is 2 % short…
        assert!((s.pose.unwrap().x - 0.98 * end.x * 60.0 / 61.0).abs() < 1e-9);
        // …until the camera sees again.
        tracker.update(&at(62, 30.5, frame(&landmarks(), end, &camera)), &Pose2::new(0.98 * end.x, 0.98 * end.y, 0.1));
        let s = tracker.state();
        let pose = s.pose.unwrap();
        assert!(pose.distance_to(end.x, end.y) < 1e-6 && (pose.theta - end.theta).abs() < 1e-6, "{pose:?}");
        assert!(!s.bridging);
        assert_eq!(s.outages, 1);
        assert!((s.outage_s - 30.5).abs() < 1e-9, "from the last match to the next: {}", s.outage_s);
    }

    #[test]
    fn a_scan_and_back_costs_one_estimate() {
        // The robot turns on the spot to +40°, to −40° and back to 0°,
        // 10° a frame; the noise is the same in every frame of a pose. The
        // last frame is matched against the keyframe from before the sweep,
        // so its pose is the one a direct match of the two gives, and the
        // sweep's own estimates leave no trace.
        let camera = StereoCamera::default();
        let wall: Vec<[f64; 3]> = (0..40)
            .map(|i| {
                let a = f64::from(i) * 9f64.to_radians();
                [2.0 + 8.0 * a.cos(), 8.0 * a.sin(), 1.0]
            })
            .collect();
        let seen = |pose: Pose2, k: u64| disturbed(frame(&wall, pose, &camera), k, 0.05);
        let mut headings: Vec<f64> = (0..=4).chain((-4..4).rev()).chain(-3..=0).map(|d| f64::from(d) * 10.0).collect();
        headings.dedup();
        let mut sweeping = Tracker::new(EgomotionConfig::default(), camera, Pose2::default(), 5);
        for (n, h) in headings.iter().enumerate() {
            let pose = Pose2::new(0.0, 0.0, h.to_radians());
            sweeping.update(&at(n as u64 + 1, 0.5 * n as f64, seen(pose, h.to_bits())), &pose);
        }
        let end = Pose2::default();
        let mut direct = Tracker::new(EgomotionConfig::default(), camera, end, 5);
        direct.update(&at(1, 0.0, seen(end, 0f64.to_bits())), &end);
        direct.update(&at(2, 0.5, seen(end, 0f64.to_bits())), &end);
        let (a, b) = (sweeping.state().pose.unwrap(), direct.state().pose.unwrap());
        assert!(a.distance_to(b.x, b.y) < 1e-9 && (a.theta - b.theta).abs() < 1e-9, "{a:?} vs {b:?}");
        assert_eq!(sweeping.state().failures, 0);
    }

    #[test]
    fn driving_straight_matches_keyframes_metres_back() {
        // Chaining frame to frame adds every step's depth error; matching
        // against the keyframe 8 m back gives the error of one estimate:
        // exactly what a direct match of the first and last frames gives.
        let camera = StereoCamera::default();
        let far: Vec<[f64; 3]> = (0..16).map(|i| [30.0, -3.0 + 0.4 * f64::from(i), 1.0]).collect();
        let seen = |k: u32| {
            let pose = Pose2::new(0.25 * f64::from(k), 0.0, 0.0);
            disturbed(frame(&far, pose, &camera), u64::from(k), 0.1)
        };
        let mut tracker = Tracker::new(EgomotionConfig::default(), camera, Pose2::default(), 2);
        for k in 0..=32u32 {
            let odometry = Pose2::new(0.25 * f64::from(k), 0.0, 0.0);
            tracker.update(&at(u64::from(k) + 1, 0.5 * f64::from(k), seen(k)), &odometry);
        }
        let mut direct = Tracker::new(EgomotionConfig::default(), camera, Pose2::default(), 2);
        direct.update(&at(1, 0.0, seen(0)), &Pose2::default());
        direct.update(&at(2, 16.0, seen(32)), &Pose2::new(8.0, 0.0, 0.0));
        let (a, b) = (tracker.state().pose.unwrap(), direct.state().pose.unwrap());
        assert!(a.distance_to(b.x, b.y) < 1e-9 && (a.theta - b.theta).abs() < 1e-9, "{a:?} vs {b:?}");
        assert!(tracker.keyframes() > 1, "new keyframes are still taken as the robot moves on");
    }

    #[test]
    fn a_navigating_tracker_leans_on_odometry_where_egomotion_is_not_to_be_trusted() {
        // The same frames and odometry (2 % short), egomotion trusted at its
        // estimator's word, and held to be starving on every step: its
        // covariance is then counted many times over, and the pose steered
        // by moves towards odometry's.
        let camera = StereoCamera::default();
        let navigated = |trusted_landmarks: usize| {
            let config = EgomotionConfig { trusted_landmarks, ..EgomotionConfig::default() };
            let mut tracker = Tracker::new(config, camera, Pose2::default(), 0);
            tracker.update(&at(1, 0.0, frame(&landmarks(), Pose2::default(), &camera)), &Pose2::default());
            let (truth, odometry) = (Pose2::new(1.0, 0.0, 0.0), Pose2::new(0.98, 0.0, 0.0));
            tracker.update(&at(2, 2.0, frame(&landmarks(), truth, &camera)), &odometry);
            tracker.navigation_pose(&odometry).unwrap()
        };
        let (trusted, starving) = (navigated(1), navigated(1_000_000));
        // Trusted, egomotion's σ of about a centimetre leads odometry's 3.
        assert!((trusted.x - 1.0).abs() < 5e-3, "{trusted:?}");
        assert!(starving.x < 0.99, "{starving:?}");
    }

    #[test]
    fn a_navigating_tracker_carries_its_pose_on_by_odometry_between_frames() {
        let camera = StereoCamera::default();
        let start = Pose2::new(1.0, 2.0, 0.0);
        let seen = |pose: Pose2| frame(&landmarks(), pose, &camera);
        for navigate in [false, true] {
            let config = EgomotionConfig { navigate, ..EgomotionConfig::default() };
            let mut tracker = Tracker::new(config, camera, start, 0);
            assert_eq!(tracker.navigation_pose(&start), None, "no frame yet");
            // Odometry starts elsewhere and reads 2 % short: egomotion's
            // pose at the frame is the truth, and the 0.3 m since the frame
            // comes from odometry.
            let odometry = Pose2::new(0.0, 0.0, 0.0);
            tracker.update(&at(1, 0.0, seen(start)), &odometry);
            let moved = Pose2::new(0.98 * 0.25, 0.0, 0.0);
            tracker.update(&at(2, 0.5, seen(Pose2::new(1.25, 2.0, 0.0))), &moved);
            assert_eq!(tracker.state().failures, 0);
            let now = tracker.navigation_pose(&Pose2::new(moved.x + 0.3, 0.0, 0.0));
            if navigate {
                // Odometry's own pose, 5 mm behind, counts for a little
                // beside egomotion's.
                let now = now.unwrap();
                assert!(now.distance_to(1.55, 2.0) < 2e-3 && now.theta.abs() < 1e-3, "{now:?}");
            } else {
                assert_eq!(now, None);
            }
        }
    }

    #[test]
    fn steps_on_too_few_landmarks_and_failed_steps_raise_the_pose_uncertainty() {
        // The same noisy frames, trusted at the estimator's word and with a
        // bar above every step's landmarks.
        let camera = StereoCamera::default();
        let points = landmarks();
        let drive = |trusted_landmarks: usize| {
            let config = EgomotionConfig { trusted_landmarks, odometry_gate: None, ..EgomotionConfig::default() };
            let mut tracker = Tracker::new(config, camera, Pose2::default(), 3);
            for k in 0..4u32 {
                let pose = Pose2::new(0.25 * f64::from(k), 0.0, 0.0);
                let seen = disturbed(frame(&points, pose, &camera), u64::from(k), 0.02);
                tracker.update(&at(u64::from(k) + 1, 0.5 * f64::from(k), seen), &pose);
            }
            tracker
        };
        let trusting = drive(1);
        assert!(!trusting.starving());
        assert_eq!(trusting.pose_covariance(), trusting.estimator_covariance());
        let wary = drive(points.len() * 4);
        let n = wary.step_landmarks().unwrap();
        assert!(wary.starving() && n < points.len() * 4);
        // The same estimate, its uncertainty counted more than once over,
        // and the state the behaviours read carries the larger one.
        assert_eq!(wary.state().pose, trusting.state().pose);
        assert_eq!(wary.state().pose_covariance, Some(wary.pose_covariance().into()));
        assert_eq!(wary.estimator_covariance(), trusting.estimator_covariance());
        assert!(
            wary.pose_covariance()[(0, 0)] > 2.0 * wary.estimator_covariance()[(0, 0)],
            "{}",
            wary.pose_covariance()
        );
        // A failed step with no odometry gate: a step anywhere within the
        // speed limit over its half second, σ = 0.6 · 0.5 / √3 m.
        let mut failing = drive(1);
        let before = failing.pose_covariance();
        failing.update(&at(5, 2.0, Vec::new()), &Pose2::new(0.75, 0.0, 0.0));
        assert!(failing.starving() && failing.step_landmarks().is_none());
        let added = failing.pose_covariance() - before;
        assert!((added[(0, 0)] - 0.09 / 3.0).abs() < 1e-9 && (added[(1, 1)] - 0.09 / 3.0).abs() < 1e-9, "{added}");
    }

    #[test]
    fn a_heading_error_becomes_a_position_error_along_the_motion() {
        // A pose known exactly but for its heading (σ 0.01 rad), facing +y,
        // then an exact 10 m step forward: the error lands across the step
        // (along x), 0.1 m σ, and the heading's variance carries over.
        let pose = Pose2::new(1.0, 2.0, std::f64::consts::FRAC_PI_2);
        let pose_cov = Matrix3::from_diagonal(&nalgebra::Vector3::new(0.0, 0.0, 1e-4));
        let motion = PlanarMotion { forward: 10.0, left: 0.0, yaw: 0.0 };
        let c = composed_covariance(&pose, &pose_cov, &motion, &Matrix3::zeros());
        assert!((c[(0, 0)] - 1e-2).abs() < 1e-12 && c[(1, 1)].abs() < 1e-12, "{c}");
        assert!((c[(2, 2)] - 1e-4).abs() < 1e-12);
        // The step's own covariance, given along the step, is turned into
        // the world frame.
        let motion_cov = Matrix3::from_diagonal(&nalgebra::Vector3::new(4e-2, 1e-2, 0.0));
        let c = composed_covariance(&pose, &Matrix3::zeros(), &motion, &motion_cov);
        assert!((c[(1, 1)] - 4e-2).abs() < 1e-12 && (c[(0, 0)] - 1e-2).abs() < 1e-12, "{c}");
    }

    /// A car-like drive where the truth is known: 60 frames 1 m apart down
    /// a road lined with 600 landmarks 2–190 m ahead and 3–12 m to either
    /// side, seen by a KITTI-like rig (707 px focal length, 0.54 m
    /// baseline, 1226 × 370) whose disparities are `offset_px` short of
    /// what its calibration assumes, through 0.2 px of pixel noise (about
    /// the sub-pixel matcher's error on Middlebury, docs/perception.md).
    /// Odometry is egomotion's own, as on a replay. Returns the tracker
    /// and how far its end point is from the truth, m.
    fn offset_drive(offset_px: f64, mode: DisparityOffsetEstimate, seed: u64, standing: u64) -> (Tracker, f64) {
        use crate::egomotion::testing::seen_with_offset;
        use rand::{Rng, SeedableRng};
        let camera = crate::egomotion::testing::kitti_rig();
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let road: Vec<[f64; 3]> = (0..600)
            .map(|_| {
                let side = if rng.random::<bool>() { 1.0 } else { -1.0 };
                [rng.random_range(2.0..190.0), side * rng.random_range(3.0..12.0), rng.random_range(0.2..4.0)]
            })
            .collect();
        let config = EgomotionConfig {
            max_speed: 40.0,
            max_turn_rate_deg: 90.0,
            odometry_gate: None,
            disparity_offset: mode,
            ..EgomotionConfig::default()
        };
        let mut tracker = Tracker::new(config, camera, Pose2::default(), seed);
        let mut truth = Pose2::default();
        for k in 0..standing + 60 {
            truth = Pose2::new(k.saturating_sub(standing) as f64, 0.0, 0.0);
            let seen = seen_with_offset(&road, truth, &camera, offset_px, 0.2, &mut rng);
            let odometry = tracker.state().pose.unwrap_or_default();
            tracker.update(&at(k + 1, k as f64 * 0.1, seen), &odometry);
        }
        let end = tracker.state().pose.unwrap();
        (tracker, end.distance_to(truth.x, truth.y))
    }

    #[test]
    fn the_disparity_offset_is_read_from_near_and_far_landmarks_disagreeing() {
        // Each step's reading scatters by about 0.05 px here; the pooled
        // estimate over ~60 of them (sharing landmarks, so not independent)
        // lands within a few hundredths. A fit to the triangulated points
        // instead read 0.4–0.9 px with no offset at all (see offset.rs).
        for (truth, seed) in [(0.3, 1), (-0.2, 2), (0.0, 3)] {
            let (tracker, _) = offset_drive(truth, DisparityOffsetEstimate::Report, seed, 0);
            let estimate = tracker.disparity_offset().unwrap();
            assert!(estimate.readings >= 50, "{estimate:?}");
            assert!((estimate.px - truth).abs() < 0.05, "truth {truth:+} px, estimated {estimate:?}");
            assert_eq!(tracker.applied_disparity_offset(), 0.0, "reported, not applied");
        }
    }

    #[test]
    fn a_robot_standing_still_before_it_drives_reads_nothing_from_it() {
        // Fifteen frames standing: each matches its keyframe with no motion,
        // which cannot tell the offset from the landmarks' depths. Taken,
        // such readings would set the correction to noise after ten steps.
        let (tracker, off) = offset_drive(0.3, DisparityOffsetEstimate::Correct, 6, 15);
        let estimate = tracker.disparity_offset().unwrap();
        assert!(estimate.readings < 60, "{estimate:?}");
        assert!((tracker.applied_disparity_offset() - 0.3).abs() < 0.05, "{estimate:?}");
        assert!(off < 0.3, "end point {off:.3} m off");
    }

    #[test]
    fn correcting_by_the_estimated_offset_shortens_the_drift() {
        let (_, reported) = offset_drive(0.3, DisparityOffsetEstimate::Report, 4, 0);
        let (corrected, off) = offset_drive(0.3, DisparityOffsetEstimate::Correct, 4, 0);
        assert!((corrected.applied_disparity_offset() - 0.3).abs() < 0.05, "{:?}", corrected.disparity_offset());
        assert!(off < 0.5 * reported, "end point {off:.3} m off corrected, {reported:.3} m uncorrected");
        // With no offset to find, correcting costs little.
        let (_, plain) = offset_drive(0.0, DisparityOffsetEstimate::Off, 5, 0);
        let (_, corrected) = offset_drive(0.0, DisparityOffsetEstimate::Correct, 5, 0);
        assert!(corrected < plain + 0.1, "end point {corrected:.3} m off corrected, {plain:.3} m not");
    }
}
