//! The robot's body: differential-drive kinematics under limits, the two
//! motion profiles, and odometry that drifts from the truth.

use super::geometry::Quad;
use crate::model::Footprint;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use serde::Deserialize;
use ubf_core::config::{finite, non_negative, positive};
use ubf_core::{wrap_angle, Command, Limits, Pose2, Turn};

/// Where the robot starts, as written in a scenario file.
#[derive(Clone, Copy, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StartPose {
    /// Metres.
    #[serde(default, deserialize_with = "ubf_core::config::coordinate_m")]
    pub x: f64,
    /// Metres.
    #[serde(default, deserialize_with = "ubf_core::config::coordinate_m")]
    pub y: f64,
    /// Degrees from the x axis, counter-clockwise.
    #[serde(default, deserialize_with = "ubf_core::config::angle_deg")]
    pub heading_deg: f64,
}

impl StartPose {
    /// The start as a pose in SI units.
    pub fn pose(&self) -> Pose2 {
        Pose2::new(self.x, self.y, wrap_angle(self.heading_deg.to_radians()))
    }
}

/// How the body executes drive commands.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum MotionProfile {
    /// Drive and turn at once, as commanded.
    #[default]
    Continuous,
    /// The thesis's decoupled motion (§4.4.5): a command that turns is
    /// executed as a turn on the spot, and the robot translates only when no
    /// turn is asked for (or, for a heading, once it is within tolerance).
    /// Accelerations bring it to rest in between.
    RotateThenTranslate {
        /// Heading error under which a heading command counts as reached, °.
        #[serde(default = "MotionProfile::default_tolerance_deg", deserialize_with = "positive")]
        heading_tolerance_deg: f64,
    },
}

impl MotionProfile {
    fn default_tolerance_deg() -> f64 {
        2.0
    }

    /// The thesis's decoupled motion with the default heading tolerance,
    /// as a scenario file's `RotateThenTranslate()` gives it.
    pub fn rotate_then_translate() -> Self {
        MotionProfile::RotateThenTranslate { heading_tolerance_deg: Self::default_tolerance_deg() }
    }
}

/// How odometry differs from the truth; a field left out keeps its
/// default (perfect odometry).
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct OdometryErrors {
    /// True distance per encoder distance of the left wheel (a soft tyre is
    /// below 1).
    #[serde(deserialize_with = "positive")]
    pub left_scale: f64,
    /// True distance per encoder distance of the right wheel.
    #[serde(deserialize_with = "positive")]
    pub right_scale: f64,
    /// A steady turn while driving that odometry does not see, °/m;
    /// negative veers right, like the thesis's robot (§4.4.1).
    #[serde(deserialize_with = "finite")]
    pub veer_deg_per_m: f64,
    /// Random heading slip, ° per √m driven.
    #[serde(deserialize_with = "non_negative")]
    pub slip_deg_per_sqrt_m: f64,
    /// Random distance slip, m per √m driven: both wheels over- or
    /// under-count together (a floor's give, wheels skidding on a start),
    /// an error of distance that no fixed scale describes.
    #[serde(deserialize_with = "non_negative")]
    pub distance_slip_m_per_sqrt_m: f64,
}

impl Default for OdometryErrors {
    fn default() -> Self {
        OdometryErrors {
            left_scale: 1.0,
            right_scale: 1.0,
            veer_deg_per_m: 0.0,
            slip_deg_per_sqrt_m: 0.0,
            distance_slip_m_per_sqrt_m: 0.0,
        }
    }
}

/// The body's settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BodyConfig {
    /// Where it starts.
    pub start: Pose2,
    /// Speed limits.
    pub limits: Limits,
    /// Largest change of forward speed, m/s².
    pub max_acceleration: f64,
    /// Largest change of turn rate, rad/s².
    pub max_rot_acceleration: f64,
    /// Turn rate per radian of error for heading commands, 1/s.
    pub heading_gain: f64,
    /// How commands are executed.
    pub motion: MotionProfile,
    /// How odometry errs.
    pub odometry: OdometryErrors,
    /// Wheel to wheel, m.
    pub track_width: f64,
    /// The outline.
    pub footprint: Footprint,
}

/// The body's state: where it is, where it thinks it is, how fast it goes.
#[derive(Clone, Debug)]
pub struct Body {
    config: BodyConfig,
    /// The true pose.
    pub true_pose: Pose2,
    /// The odometric pose.
    pub odometry: Pose2,
    /// Forward speed the encoders measure, m/s.
    pub velocity: f64,
    /// Turn rate the encoders measure, rad/s.
    pub rot_velocity: f64,
    /// True path length driven, m.
    pub distance: f64,
}

/// A move the body would make this step, not yet committed.
#[derive(Clone, Copy, Debug)]
pub struct Move {
    true_pose: Pose2,
    odometry: Pose2,
    distance: f64,
}

impl Move {
    /// Where the robot would truly be.
    pub fn true_pose(&self) -> Pose2 {
        self.true_pose
    }
}

pub(crate) fn approach(current: f64, target: f64, step: f64) -> f64 {
    current + (target - current).clamp(-step, step)
}

/// Advances `pose` along the arc of speeds `(v, w)` for `dt` seconds.
pub fn integrate(pose: Pose2, v: f64, w: f64, dt: f64) -> Pose2 {
    let dtheta = w * dt;
    let (dx, dy) = if dtheta.abs() < 1e-9 {
        (v * dt, 0.0)
    } else {
        let radius = v / w;
        (radius * dtheta.sin(), radius * (1.0 - dtheta.cos()))
    };
    pose.compose(&Pose2::new(dx, dy, dtheta))
}

impl Body {
    /// A body at rest at its start.
    pub fn new(config: BodyConfig) -> Self {
        Body {
            config,
            true_pose: config.start,
            odometry: config.start,
            velocity: 0.0,
            rot_velocity: 0.0,
            distance: 0.0,
        }
    }

    /// The body's speed limits.
    pub fn limits(&self) -> Limits {
        self.config.limits
    }

    /// The outline at `pose`, in the world.
    pub fn footprint_at(&self, pose: &Pose2) -> Quad {
        Quad(self.config.footprint.corners().map(|(x, y)| pose.transform_point(x, y)))
    }

    /// The speeds the command asks for, after the motion profile.
    fn targets(&self, command: &Command) -> (f64, f64) {
        let (velocity, turn) = match *command {
            Command::Stop => return (0.0, 0.0),
            Command::Drive { velocity, turn } => (velocity, turn),
        };
        let (rate, heading_error) = match turn {
            Turn::Rate(rate) => (rate, None),
            Turn::Heading { heading, max_rate } => {
                let error = wrap_angle(heading - self.odometry.theta);
                ((self.config.heading_gain * error).clamp(-max_rate, max_rate), Some(error))
            }
        };
        match self.config.motion {
            MotionProfile::Continuous => (velocity, rate),
            MotionProfile::RotateThenTranslate { heading_tolerance_deg } => {
                let turning = match heading_error {
                    Some(error) => error.abs() > heading_tolerance_deg.to_radians(),
                    // A requested rate under 0.5°/s is noise, not a turn.
                    None => rate.abs() > 0.5f64.to_radians(),
                };
                if turning {
                    // Come to rest before turning on the spot.
                    let at_rest = self.velocity.abs() < 1e-6;
                    (0.0, if at_rest { rate } else { 0.0 })
                } else if self.rot_velocity.abs() < 1e-6 {
                    (velocity, 0.0)
                } else {
                    (0.0, 0.0)
                }
            }
        }
    }

    /// Works out the move for one step of `dt` seconds under `command`;
    /// the speeds change now, the poses when the move is committed.
    pub fn plan(&mut self, command: &Command, dt: f64, rng: &mut ChaCha8Rng) -> Move {
        let (v_target, w_target) = self.targets(command);
        let limits = self.config.limits;
        self.velocity = approach(self.velocity, v_target, self.config.max_acceleration * dt)
            .clamp(-limits.max_velocity, limits.max_velocity);
        self.rot_velocity = approach(self.rot_velocity, w_target, self.config.max_rot_acceleration * dt)
            .clamp(-limits.max_rot_velocity, limits.max_rot_velocity);

        // The wheels turn as the encoders say; the ground moves them by their
        // true scale.
        let errors = &self.config.odometry;
        let half_track = self.config.track_width / 2.0;
        let left = (self.velocity - self.rot_velocity * half_track) * errors.left_scale;
        let right = (self.velocity + self.rot_velocity * half_track) * errors.right_scale;
        let mut v_true = (left + right) / 2.0;
        let mut w_true = (right - left) / self.config.track_width + errors.veer_deg_per_m.to_radians() * v_true;
        let mut ds = v_true.abs() * dt;
        if errors.slip_deg_per_sqrt_m > 0.0 && ds > 0.0 {
            let slip: f64 = StandardNormal.sample(rng);
            w_true += slip * errors.slip_deg_per_sqrt_m.to_radians() * ds.sqrt() / dt;
        }
        // Drawn after the heading's slip and only when asked for, so that
        // runs without it keep their random sequence.
        if errors.distance_slip_m_per_sqrt_m > 0.0 && ds > 0.0 {
            let slip: f64 = StandardNormal.sample(rng);
            let slipped = slip * errors.distance_slip_m_per_sqrt_m * ds.sqrt();
            // A slip never turns the wheels' motion round.
            let moved = (ds + slipped).max(0.0);
            v_true *= moved / ds;
            ds = moved;
        }
        Move {
            true_pose: integrate(self.true_pose, v_true, w_true, dt),
            odometry: integrate(self.odometry, self.velocity, self.rot_velocity, dt),
            distance: ds,
        }
    }

    /// Makes the planned move.
    pub fn commit(&mut self, m: Move) {
        self.true_pose = m.true_pose;
        self.odometry = m.odometry;
        self.distance += m.distance;
    }

    /// The planned move hit something: the wheels stall, nothing moves.
    pub fn block(&mut self) {
        self.velocity = 0.0;
        self.rot_velocity = 0.0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::RobotModel;
    use rand::SeedableRng;
    use std::f64::consts::PI;

    fn config(motion: MotionProfile, odometry: OdometryErrors) -> BodyConfig {
        let model = RobotModel::powerbot();
        BodyConfig {
            start: Pose2::default(),
            limits: Limits::new(0.6, 1.0),
            max_acceleration: 0.5,
            max_rot_acceleration: 2.0,
            heading_gain: 2.0,
            motion,
            odometry,
            track_width: model.track_width,
            footprint: model.footprint,
        }
    }

    fn drive(body: &mut Body, command: Command, steps: usize) {
        let mut rng = ChaCha8Rng::seed_from_u64(0);
        for _ in 0..steps {
            let m = body.plan(&command, 0.1, &mut rng);
            body.commit(m);
        }
    }

    #[test]
    fn a_full_circle_returns_home() {
        let pose = (0..1000).fold(Pose2::default(), |p, _| integrate(p, 1.0, 2.0 * PI / 10.0, 0.01));
        assert!(pose.x.abs() < 1e-9 && pose.y.abs() < 1e-9 && pose.theta.abs() < 1e-9, "{pose:?}");
    }

    #[test]
    fn acceleration_and_speed_are_limited() {
        let mut body = Body::new(config(MotionProfile::Continuous, OdometryErrors::default()));
        drive(&mut body, Command::Drive { velocity: 0.6, turn: Turn::Rate(0.0) }, 1);
        assert!((body.velocity - 0.05).abs() < 1e-12);
        drive(&mut body, Command::Drive { velocity: 5.0, turn: Turn::Rate(0.0) }, 100);
        assert_eq!(body.velocity, 0.6);
    }

    #[test]
    fn a_soft_right_tyre_veers_right_while_odometry_sees_straight() {
        let errors = OdometryErrors { right_scale: 0.99, ..OdometryErrors::default() };
        let mut body = Body::new(config(MotionProfile::Continuous, errors));
        drive(&mut body, Command::Drive { velocity: 0.5, turn: Turn::Rate(0.0) }, 200);
        assert_eq!(body.odometry.y, 0.0);
        assert!(body.true_pose.y < -0.05, "{:?}", body.true_pose);
    }

    #[test]
    fn veer_turns_the_truth_by_degrees_per_metre() {
        let errors = OdometryErrors { veer_deg_per_m: -1.0, ..OdometryErrors::default() };
        let mut body = Body::new(config(MotionProfile::Continuous, errors));
        drive(&mut body, Command::Drive { velocity: 0.5, turn: Turn::Rate(0.0) }, 400);
        let expected = -body.distance.to_radians();
        assert!((body.true_pose.theta - expected).abs() < 1e-9, "{} vs {expected}", body.true_pose.theta);
    }

    #[test]
    fn distance_slip_moves_the_truth_along_the_way_at_random_as_the_square_root_of_distance() {
        // 20 m at 0.5 m/s with 1 cm/√m: the truth ends ahead of or behind
        // odometry by about 4.5 cm (σ), on odometry's line and heading.
        let errors = OdometryErrors { distance_slip_m_per_sqrt_m: 0.01, ..OdometryErrors::default() };
        let along: Vec<f64> = (0..200)
            .map(|seed| {
                let mut body = Body::new(config(MotionProfile::Continuous, errors));
                let mut rng = ChaCha8Rng::seed_from_u64(seed);
                while body.odometry.x < 20.0 {
                    let m = body.plan(&Command::Drive { velocity: 0.5, turn: Turn::Rate(0.0) }, 0.1, &mut rng);
                    body.commit(m);
                }
                assert_eq!((body.true_pose.y, body.true_pose.theta), (0.0, 0.0));
                body.true_pose.x - body.odometry.x
            })
            .collect();
        let sigma = (along.iter().map(|d| d * d).sum::<f64>() / along.len() as f64).sqrt();
        assert!((0.035..0.055).contains(&sigma), "σ {sigma:.4} m over 20 m");
    }

    #[test]
    fn settings_written_without_fields_take_their_one_default() {
        use ubf_core::config::from_ron;
        let profile: MotionProfile = from_ron("RotateThenTranslate()").unwrap();
        assert_eq!(profile, MotionProfile::rotate_then_translate());
        assert_eq!(from_ron::<OdometryErrors>("()").unwrap(), OdometryErrors::default());
        let scaled: OdometryErrors = from_ron("(left_scale: 0.98)").unwrap();
        assert_eq!(scaled, OdometryErrors { left_scale: 0.98, ..OdometryErrors::default() });
        assert_eq!(from_ron::<crate::sim::sonar::SonarConfig>("()").unwrap(), Default::default());
    }

    #[test]
    fn rotate_then_translate_never_does_both() {
        let profile = MotionProfile::rotate_then_translate();
        let mut body = Body::new(config(profile, OdometryErrors::default()));
        let mut rng = ChaCha8Rng::seed_from_u64(0);
        let command = Command::Drive { velocity: 0.5, turn: Turn::Heading { heading: 1.0, max_rate: 1.0 } };
        let mut translated = false;
        for _ in 0..200 {
            let m = body.plan(&command, 0.1, &mut rng);
            body.commit(m);
            assert!(body.velocity.abs() < 1e-12 || body.rot_velocity.abs() < 1e-12, "both at once");
            translated |= body.velocity > 0.0;
        }
        assert!(translated);
        assert!((body.odometry.theta - 1.0).abs() < 2f64.to_radians());
    }
}
