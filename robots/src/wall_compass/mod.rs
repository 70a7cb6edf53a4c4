//! A compass from the walls: odometry's heading held by the straight walls
//! the side sonars run along.
//!
//! Odometry's heading drifts without bound (random slip, a veer nobody
//! calibrated), and where a camera sees too few landmarks to measure the
//! turns, that drift is the pose's largest error: a degree off over 40 m
//! puts the robot most of a metre beside where it believes it is. Many
//! buildings give a reference odometry lacks: their walls are straight, and
//! parallel or square to one another. While the robot drives straight, each
//! side sonar's echoes trace the wall beside it; a line through them, where
//! they lie on one, gives the wall's direction in odometry's frame. Two
//! lines that agree fix the building's axes (their direction modulo 90°);
//! every later one within a few degrees of an axis measures how far
//! odometry's heading has drifted since, and a Kalman update on the heading
//! takes that out. This is the heading half of what indoor dead reckoning
//! calls heuristic drift elimination.
//!
//! It rests on that assumption: a long wall a few degrees off square, or a
//! corridor curving gently, is taken for drift and turns the heading by as
//! much. Walls further than `max_correction_deg` from an axis, clutter,
//! people, doorways and turns on the spot trace no line near an axis and
//! change nothing. So it is off unless asked for, for buildings whose long
//! walls are known to be square.
//!
//! [`WallCompassRobot`] puts it between any robot with side range sensors
//! and what reads its pose, so everything downstream (egomotion's odometry
//! bridge, the pose the robot steers by) sees the corrected odometry.

mod line;
mod robot;

use line::{LineFit, Moments};
pub use robot::WallCompassRobot;

use serde::Deserialize;
use std::f64::consts::FRAC_PI_4;
use ubf_core::config::{non_negative, number_in, positive};
use ubf_core::{angle_difference, wrap_angle, HeadingFix, Pose2, RangeReading};
use ubf_perception::egomotion::OdometryNoise;

/// The wall compass's settings, as written in a scenario file.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct WallCompassConfig {
    /// Metres of straight driving one wall's line spans: longer is surer,
    /// but corrects less often.
    #[serde(deserialize_with = "positive")]
    pub span_m: f64,
    /// A line's largest RMS residual, m: echoes further off a line than
    /// this are not one straight wall.
    #[serde(deserialize_with = "positive")]
    pub max_residual_m: f64,
    /// The sonar's range noise (σ), m: the least scatter a line's direction
    /// is taken to rest on.
    #[serde(deserialize_with = "positive")]
    pub range_noise_m: f64,
    /// The largest heading correction one wall may make, ° (below 45): a
    /// wall further than this from the building's axes is taken to be at
    /// another angle.
    #[serde(deserialize_with = "correction_deg")]
    pub max_correction_deg: f64,
    /// How far the robot may turn while a line is traced, °: the side
    /// sonars must sweep along the wall, not across it.
    #[serde(deserialize_with = "positive")]
    pub max_turn_deg: f64,
    /// How straight and square a wall is, ° (σ): the least uncertainty of
    /// a line's direction, whatever its echoes' scatter says (plaster,
    /// skirting and sonar errors that run along a wall are not noise that
    /// averages out).
    #[serde(deserialize_with = "positive")]
    pub wall_straightness_deg: f64,
    /// Odometry's turn error, a share of the angle turned (σ, per √radian):
    /// a wheel base a little off, which a turn on the spot between two
    /// walls brings in.
    #[serde(deserialize_with = "non_negative")]
    pub turn_share: f64,
    /// Odometry's heading noise, which sets how fast the heading's
    /// uncertainty grows between walls: its `heading_deg_per_sqrt_m` and
    /// `veer_deg_per_m` (the rest is egomotion's). A copy of its own:
    /// egomotion's `odometry_gate.noise` is set apart.
    pub odometry: OdometryNoise,
    /// The building's axes in odometry's frame, ° (a wall direction,
    /// modulo 90°), where they are known: a floor plan the start pose is
    /// given in. Without them the first walls fix the axes, as sure as the
    /// heading is by then.
    #[serde(deserialize_with = "ubf_core::config::optional_angle_deg")]
    pub axes_deg: Option<f64>,
}

impl Default for WallCompassConfig {
    fn default() -> Self {
        WallCompassConfig {
            span_m: 2.0,
            max_residual_m: 0.05,
            range_noise_m: 0.02,
            max_correction_deg: 5.0,
            max_turn_deg: 2.0,
            wall_straightness_deg: 0.3,
            turn_share: 0.02,
            odometry: OdometryNoise::default(),
            axes_deg: None,
        }
    }
}

/// A largest correction, °: above 0 and below 45, beyond which every
/// direction is within it of some axis.
fn correction_deg<'de, D: serde::Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    number_in(d, 0.01..=44.0, "from 0.01 to 44°")
}

/// Which side sonars look at: units pointing within this of square to
/// the robot's left or right.
const SIDE_TOLERANCE_DEG: f64 = 10.0;

/// How far the heading may have drifted (3σ, °) between two walls that
/// fix the axes together: a few spans' slip, where further the pair could
/// agree by the drift alone.
const CANDIDATE_DRIFT_DEG: f64 = 2.0;

/// The least number of echoes a line is fitted to.
const MIN_ECHOES: usize = 10;

/// One side's echoes since its line began.
#[derive(Clone, Debug, Default)]
struct Trace {
    /// The sums of the echoes' positions in the corrected odometry frame:
    /// as many echoes as a many-beamed scanner creeping along a wall gives,
    /// in constant memory.
    echoes: Moments,
    /// The corrected heading when the trace began.
    heading: Option<f64>,
    /// Metres driven since then.
    driven: f64,
}

impl Trace {
    fn restart(&mut self) {
        self.echoes = Moments::default();
        self.heading = None;
        self.driven = 0.0;
    }
}

/// A line traced along one side, with the heading the robot drove it at.
struct Traced {
    fit: LineFit,
    heading: f64,
}

/// Odometry with its heading corrected by the walls. Feed it every
/// odometry pose with the range readings taken with it.
///
/// A Kalman filter on two unknowns: the corrected heading's error `e`
/// (growing with the distance driven and the angle turned, as odometry's
/// noise model says) and the building's axes `a` (a wall direction modulo
/// 90°, in odometry's frame, fixed but unknown until two walls agree).
/// Each straight wall measures `a + e`. The start, where the heading is as
/// good as it gets, is what pins the axes: the first walls fix them, the
/// later ones measure the drift. Each update's estimate of `e` is taken out
/// of the pose at once, so the filter's `e` is always zero.
#[derive(Clone, Debug)]
pub struct WallCompass {
    config: WallCompassConfig,
    /// The last raw odometry pose, once one has been seen.
    last_odometry: Option<Pose2>,
    /// Odometry's motion since, laid from the corrected pose.
    pose: Pose2,
    /// The axes' estimate, rad, once two walls have agreed on them.
    axes: Option<f64>,
    /// A first wall waiting for a second to agree with it: its direction,
    /// that direction's variance and the heading's then, rad².
    candidate: Option<(f64, f64, f64)>,
    /// The covariance of the errors in (`e`, `a`), rad².
    covariance: [[f64; 2]; 2],
    /// The left and right sides' traces.
    traces: [Trace; 2],
    corrections: u64,
    /// The turn the latest update gave the heading, rad (0 where no wall
    /// corrected it).
    last_correction: f64,
}

impl WallCompass {
    /// A compass that has seen no wall yet.
    pub fn new(config: WallCompassConfig) -> Self {
        WallCompass {
            config,
            last_odometry: None,
            pose: Pose2::default(),
            axes: config.axes_deg.map(|a| to_axes(a.to_radians())),
            candidate: None,
            covariance: [[0.0; 2]; 2],
            traces: Default::default(),
            corrections: 0,
            last_correction: 0.0,
        }
    }

    /// The corrected pose at the last update: odometry's motion, its
    /// heading held by the walls.
    pub fn pose(&self) -> Pose2 {
        self.pose
    }

    /// The corrected pose for a raw `odometry` pose taken since the last
    /// update: its motion since laid from [`WallCompass::pose`], no wall
    /// taken in.
    pub fn corrected(&self, odometry: &Pose2) -> Pose2 {
        self.last_odometry.map_or(*odometry, |last| self.pose.compose(&odometry.relative_to(&last)))
    }

    /// The corrected heading with its error's variance, if the latest
    /// update corrected it by a wall: a measure of the heading for an
    /// estimator that has its own (egomotion), taken only when a wall was
    /// just seen, as between walls the heading drifts with the wheels.
    pub fn heading_fix(&self) -> Option<HeadingFix> {
        (self.last_correction != 0.0).then_some(HeadingFix {
            heading: self.pose.theta,
            variance: self.covariance[0][0],
            correction: self.last_correction,
        })
    }

    /// How many walls have corrected the heading.
    pub fn corrections(&self) -> u64 {
        self.corrections
    }

    /// The building's axes (a wall direction in the corrected frame,
    /// modulo 90°), once two walls have agreed on them.
    pub fn axes(&self) -> Option<f64> {
        self.axes
    }

    /// Takes the next raw odometry pose and the range readings taken with
    /// it, and gives the corrected pose. A pose that is not finite is
    /// passed on as it is and otherwise ignored: the next good one carries
    /// on from the last.
    pub fn update(&mut self, odometry: &Pose2, ranges: &[RangeReading]) -> Pose2 {
        self.last_correction = 0.0;
        if !(odometry.x.is_finite() && odometry.y.is_finite() && odometry.theta.is_finite()) {
            return *odometry;
        }
        let motion = match self.last_odometry {
            Some(last) => odometry.relative_to(&last),
            None => {
                self.pose = *odometry;
                Pose2::default()
            }
        };
        self.last_odometry = Some(*odometry);
        self.pose = self.pose.compose(&motion);
        let driven = motion.x.hypot(motion.y);
        let (noise, config) = (&self.config.odometry, &self.config);
        // Slip adds variance with distance; a veer of σ v°/m turns the
        // heading by v·span over one line, spread here over its metres; a
        // turn, by a share of the angle.
        self.covariance[0][0] += (noise.heading_deg_per_sqrt_m.powi(2) + noise.veer_deg_per_m.powi(2) * config.span_m)
            * driven
            * 1f64.to_radians().powi(2)
            + config.turn_share.powi(2) * motion.theta.abs();
        let traced = [0, 1].map(|side| self.trace(side, motion.x, driven, ranges));
        // Both sides' lines were traced with the heading as it was: the
        // second is turned by what the first corrected.
        let mut corrected = 0.0;
        for line in traced.iter().flatten() {
            corrected += self.take(line.fit.direction - corrected, line);
        }
        if corrected != 0.0 {
            self.last_correction = -corrected;
            // The traces under way were laid with the heading just
            // corrected: start them afresh, so no echo counts twice.
            for trace in &mut self.traces {
                trace.restart();
            }
        }
        self.pose
    }

    /// Adds `side`'s echoes to its trace (0: left, 1: right), and gives
    /// its line once the trace spans enough driving (starting it afresh).
    fn trace(&mut self, side: usize, forward: f64, driven: f64, ranges: &[RangeReading]) -> Option<Traced> {
        let facing = if side == 0 { 90f64 } else { -90.0 }.to_radians();
        let trace = &mut self.traces[side];
        let turned = trace
            .heading
            .is_some_and(|h| angle_difference(self.pose.theta, h).abs() > self.config.max_turn_deg.to_radians());
        if turned || forward < 0.0 {
            trace.restart();
        }
        let heading = *trace.heading.get_or_insert(self.pose.theta);
        trace.driven += driven;
        // Standing still adds nothing: the same echoes again would weigh
        // one spot of the wall over the rest.
        if driven > 0.0 {
            for reading in ranges {
                let mount = reading.pose_robot_sensor;
                let Some(range) = reading.range.filter(|r| *r > 0.0 && *r < reading.max_range) else { continue };
                let square = angle_difference(mount.theta, facing).abs() <= SIDE_TOLERANCE_DEG.to_radians();
                if !square {
                    continue;
                }
                let sensor = self.pose.compose(&mount);
                let (x, y) = sensor.transform_point(range, 0.0);
                trace.echoes.add(x, y);
            }
        }
        if trace.driven < self.config.span_m {
            return None;
        }
        let fit = trace.echoes.fit();
        trace.restart();
        fit.map(|fit| Traced { fit, heading })
    }

    /// Takes a traced line lying at `direction` in the frame as it is now:
    /// a straight wall along the way the robot drove, if it is one,
    /// measures the axes plus the heading's error. Gives the correction it
    /// made to the heading, rad.
    fn take(&mut self, direction: f64, line: &Traced) -> f64 {
        let (config, fit) = (&self.config, &line.fit);
        // Written so that NaN fails each test.
        let along = angle_difference(2.0 * fit.direction, 2.0 * line.heading).abs() / 2.0;
        let wall = fit.points >= MIN_ECHOES
            && fit.rms_m <= config.max_residual_m
            && fit.spread_m >= config.span_m / 4.0
            && along <= SIDE_TOLERANCE_DEG.to_radians()
            && direction.is_finite();
        if !wall {
            return 0.0;
        }
        let measured = fit.direction_variance(config.range_noise_m) + config.wall_straightness_deg.to_radians().powi(2);
        let Some(axes) = self.axes else {
            self.propose_axes(direction, measured);
            return 0.0;
        };
        // How far the wall lies from the nearest axis.
        let innovation = to_axes(direction - axes);
        let p = self.covariance;
        // The measurement is e + a: its variance, and each unknown's
        // covariance with it.
        let (pe, pa) = (p[0][0] + p[0][1], p[1][0] + p[1][1]);
        let total = pe + pa + measured;
        let near = innovation.abs() <= config.max_correction_deg.to_radians() && innovation * innovation <= 9.0 * total;
        if !near {
            return 0.0;
        }
        let (ke, ka) = (pe / total, pa / total);
        self.pose.theta = wrap_angle(self.pose.theta - ke * innovation);
        self.axes = Some(to_axes(axes + ka * innovation));
        self.covariance = [[p[0][0] - ke * pe, p[0][1] - ke * pa], [p[1][0] - ka * pe, p[1][1] - ka * pa]];
        self.corrections += 1;
        ke * innovation
    }

    /// A wall seen before the axes are fixed: with the one before, if the
    /// two agree, it fixes them; else it waits for the next. One line alone
    /// could be a step in the wall, a row of cabinets or a person walking
    /// alongside.
    fn propose_axes(&mut self, direction: f64, measured: f64) {
        let e = self.covariance[0][0];
        let Some((first, first_measured, e_then)) = self.candidate.take() else {
            self.candidate = Some((direction, measured, e));
            return;
        };
        // The first line measured the axes plus the heading's error then;
        // as a measure of the axes plus its error now, it is as much less
        // sure as the heading has drifted since. A first line from before a
        // drift that wide pins nothing: the next line starts afresh.
        let first_now = first_measured + (e - e_then);
        let gap = to_axes(direction - first);
        let agree = 9.0 * (e - e_then) <= CANDIDATE_DRIFT_DEG.to_radians().powi(2)
            && gap * gap <= 9.0 * (first_now + measured)
            && gap.abs() <= self.config.max_correction_deg.to_radians();
        if !agree {
            self.candidate = Some((direction, measured, e));
            return;
        }
        // The axes where the two lie, each weighed by the other's variance,
        // as sure as they and the heading are; their error goes with the
        // heading's.
        let weight = first_now / (first_now + measured);
        let pooled = first_now * measured / (first_now + measured);
        self.axes = Some(to_axes(first + weight * gap));
        self.covariance = [[e, -e], [-e, e + pooled]];
    }
}

/// An angle modulo 90°, in [−45°, 45°).
fn to_axes(angle: f64) -> f64 {
    (angle + FRAC_PI_4).rem_euclid(2.0 * FRAC_PI_4) - FRAC_PI_4
}

#[cfg(test)]
mod tests;
