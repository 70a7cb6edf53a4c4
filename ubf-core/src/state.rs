//! What the robot senses this tick, as one read-only snapshot.

use crate::geometry::Pose2;
use crate::landmark::StereoFrame;
use serde::{Deserialize, Serialize};

/// Where the robot has been asked to go. A mission field: the controller sets
/// it, robots never touch it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Goal {
    /// Metres, world frame.
    #[serde(deserialize_with = "crate::config::coordinate_m")]
    pub x: f64,
    /// Metres, world frame.
    #[serde(deserialize_with = "crate::config::coordinate_m")]
    pub y: f64,
    /// Distance in metres within which the goal counts as reached.
    #[serde(default = "Goal::default_tolerance", deserialize_with = "crate::config::positive")]
    pub tolerance: f64,
}

impl Goal {
    fn default_tolerance() -> f64 {
        0.2
    }

    /// Whether `pose` is within the goal's tolerance.
    pub fn reached_by(&self, pose: &Pose2) -> bool {
        pose.distance_to(self.x, self.y) <= self.tolerance
    }
}

/// One range sensor's reading (a sonar transducer, an infrared ranger).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct RangeReading {
    /// The sensor's position and pointing direction in the robot frame.
    pub pose_robot_sensor: Pose2,
    /// Metres from the sensor to the nearest echo; `None` when nothing echoed
    /// within `max_range`.
    pub range: Option<f64>,
    /// The farthest range in metres the sensor reports.
    pub max_range: f64,
}

/// The bumper rings.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Bumpers {
    /// Any front bumper segment pressed.
    pub front: bool,
    /// Any rear bumper segment pressed.
    pub rear: bool,
}

impl Bumpers {
    /// Whether any segment is pressed.
    pub fn any(&self) -> bool {
        self.front || self.rear
    }
}

/// A heading measured by a sensor other than the wheels (the wall
/// compass), for an estimator to take in.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct HeadingFix {
    /// The robot's heading, rad, in the world frame of [`State::pose`].
    pub heading: f64,
    /// Its error's variance, rad².
    pub variance: f64,
    /// How far the sensor turned odometry's heading with this measurement,
    /// rad (the wall compass corrects the odometry it passes on; a sensor
    /// that leaves odometry alone gives 0). Egomotion leaves it out of the
    /// turn it carries a frame across on odometry, and takes the heading
    /// in by its own weighing instead.
    pub correction: f64,
}

/// The wheels' distance as a camera measured it while driving:
/// odometry's metres times `factor` are the metres driven, to within
/// `sigma` (a share of the distance).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct WheelScale {
    /// Metres driven per metre odometry counts.
    pub factor: f64,
    /// The factor's standard error.
    pub sigma: f64,
}

impl WheelScale {
    /// Where the robot went by a pose odometry `counted` from where it began
    /// counting: its distance in this scale, its heading as counted.
    pub fn driven(&self, counted: Pose2) -> Pose2 {
        Pose2::new(counted.x * self.factor, counted.y * self.factor, counted.theta)
    }
}

/// "0.9879 m driven per metre counted (σ 0.0062)".
impl std::fmt::Display for WheelScale {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{:.4} m driven per metre counted (σ {:.4})", self.factor, self.sigma)
    }
}

/// What visual egomotion has made of the stereo frames so far.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct EgomotionState {
    /// The pose integrated from egomotion alone, in the world frame of
    /// [`State::pose`]; `None` when the robot runs no estimator.
    pub pose: Option<Pose2>,
    /// The fused CV of the latest frame-to-frame step (thesis eq. 6), if it
    /// succeeded.
    pub last_step_cv: Option<f64>,
    /// The sum of the step CVs so far, each scaled by the distance of its
    /// step over the error model's step (thesis eq. 7).
    pub journey_cv: f64,
    /// Frame-to-frame steps estimated.
    pub steps: u32,
    /// Steps that failed: no keyframe matched the frame.
    pub failures: u32,
    /// Outages: stretches of failed frames, each bridged by odometry.
    pub outages: u32,
    /// Seconds spent in outages, from the last matched frame to the next.
    pub outage_s: f64,
    /// Metres driven across outages, as odometry counts them (not in the
    /// wheel scale fusion may have measured).
    pub outage_m: f64,
    /// The latest frame matched no keyframe: the pose is carried on by
    /// odometry until one does.
    pub bridging: bool,
    /// The number of the keyframe the latest frame was matched to (`None`
    /// while bridging): with each keyframe's own anchor, the chain of
    /// estimates a pose rests on.
    pub anchor_frame: Option<u64>,
    /// The covariance of [`EgomotionState::pose`] (x and y in m², heading
    /// in rad², row by row): what the estimator's own information says,
    /// plus each failed or starving step's share. `None` with no pose.
    pub pose_covariance: Option<[[f64; 3]; 3]>,
    /// The steps take odometry's sideways motion and distance in and leave
    /// vision the turn (egomotion's `odometry_fusion: Sideways`, the
    /// default, with the rigid estimator and the odometry gate's noise
    /// model), which changes which views serve vision best. `false` with
    /// `Off` or `Full` fusion, and where no estimator runs.
    pub sideways_fusion: bool,
    /// The wheels' scale as the visual steps have measured it (with
    /// `Sideways` fusion, once steps from five keyframes agree on it);
    /// `None` before, or where nothing measures it.
    pub wheel_scale: Option<WheelScale>,
}

/// Everything a behaviour may know this tick.
///
/// Robots fill the sensor fields in [`crate::Robot::sense`]; the controller
/// fills `time` and the mission fields. The buffers (`ranges`) are reused
/// from tick to tick so that sensing allocates nothing once warm.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct State {
    /// Seconds since the controller started, from its clock.
    pub time: f64,
    /// The robot's own estimate of its pose in the world frame (odometry,
    /// its heading held by the wall compass where there is one, fused with
    /// egomotion where that navigates): the pose behaviours steer by.
    /// Never ground truth.
    pub pose: Pose2,
    /// The wheels' own pose in the world frame, as the robot reported it
    /// (a ROS 2 robot's `/odom`, which its driver may already have fused),
    /// before anything here (the wall compass, egomotion) corrected it: kept
    /// beside `pose` so that a log can tell the wheels' error from the
    /// estimate's.
    pub odometry: Pose2,
    /// Measured forward velocity, m/s.
    pub velocity: f64,
    /// Measured rotational velocity, rad/s, counter-clockwise positive.
    pub rot_velocity: f64,
    /// Range sensors in a fixed order (the robot's sonar ring, say).
    pub ranges: Vec<RangeReading>,
    /// Bumper contacts.
    pub bumpers: Bumpers,
    /// A drive wheel is stalled (pushing against something).
    pub stalled: bool,
    /// The motors are powered and accept motion commands.
    pub motors_enabled: bool,
    /// The robot's emergency stop is engaged.
    pub estop: bool,
    /// Battery voltage, when the robot reports one.
    pub battery_volts: Option<f64>,
    /// The latest stereo frame from the camera, if the robot has one.
    pub stereo: StereoFrame,
    /// A heading measured this tick by something other than the wheels
    /// (the wall compass, when it has just corrected odometry's heading by
    /// a wall), for egomotion to take in; `None` on every other tick.
    pub heading_fix: Option<HeadingFix>,
    /// What egomotion has made of the stereo frames, if the robot runs an
    /// estimator.
    pub egomotion: EgomotionState,
    /// The camera's pan-tilt unit's measured angles this tick; `None` when
    /// the camera is fixed. A frame's own angles, those of when its pair
    /// was taken, are in its calibration's mount.
    pub camera_aim: Option<crate::Aim>,
    /// Seconds since the robot last delivered fresh sensor data; zero when the
    /// data is from this tick. Lets a behaviour notice a lost sensor stream.
    pub sensor_age: f64,
    /// Where the robot has been asked to go, if anywhere.
    pub goal: Option<Goal>,
}

impl State {
    /// Copies every sensor field of `other` (not `time`, not the goal),
    /// reusing this state's buffers.
    pub fn copy_sensors_from(&mut self, other: &State) {
        // Destructured, so that a field added to the state cannot be
        // forgotten here.
        let State {
            time: _,
            pose,
            odometry,
            velocity,
            rot_velocity,
            ranges,
            bumpers,
            stalled,
            motors_enabled,
            estop,
            battery_volts,
            stereo,
            heading_fix,
            egomotion,
            camera_aim,
            sensor_age,
            goal: _,
        } = other;
        self.pose = *pose;
        self.odometry = *odometry;
        self.velocity = *velocity;
        self.rot_velocity = *rot_velocity;
        self.ranges.clone_from(ranges);
        self.bumpers = *bumpers;
        self.stalled = *stalled;
        self.motors_enabled = *motors_enabled;
        self.estop = *estop;
        self.battery_volts = *battery_volts;
        self.stereo.copy_from(stereo);
        self.heading_fix = *heading_fix;
        self.egomotion = *egomotion;
        self.camera_aim = *camera_aim;
        self.sensor_age = *sensor_age;
    }

    /// Copies all of `other`, reusing this state's buffers.
    pub fn copy_from(&mut self, other: &State) {
        self.copy_sensors_from(other);
        self.time = other.time;
        self.goal = other.goal;
    }

    /// Distance to the goal from the estimated pose, if there is a goal.
    pub fn distance_to_goal(&self) -> Option<f64> {
        self.goal.map(|g| self.pose.distance_to(g.x, g.y))
    }

    /// Whether the estimated pose is within the goal's tolerance.
    pub fn goal_reached(&self) -> bool {
        self.goal.is_some_and(|g| g.reached_by(&self.pose))
    }

    /// The shortest range any range sensor reports, in metres.
    pub fn nearest_range(&self) -> Option<f64> {
        // Branch-free (no echo reads as infinitely far): behaviours ask every
        // tick, and a `filter_map` with `total_cmp` cost a tenth of a tick
        // over a 32-sonar ring.
        let nearest = self.ranges.iter().map(|r| r.range.unwrap_or(f64::INFINITY)).fold(f64::INFINITY, f64::min);
        (nearest < f64::INFINITY).then_some(nearest)
    }
}
