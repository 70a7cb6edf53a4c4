//! A headless simulated robot: a differential-drive body in a world of
//! walls, boxes, landmarks and people, with a sonar ring, bumpers and a
//! stereo camera.
//!
//! Everything random (the landmark layout unless it has a seed of its own,
//! odometry slip, sonar noise, pixel noise) is drawn from `ChaCha8Rng`
//! streams seeded by the run's seed, one stream per source, so the same
//! scenario and seed always give the same run, and turning one noise source
//! off does not change the others' draws.

mod body;
mod camera;
mod descriptor;
pub mod geometry;
mod hash;
mod pan_tilt;
pub mod render;
mod sonar;
mod world;

pub(crate) use body::approach;
pub use body::{integrate, MotionProfile, OdometryErrors, StartPose};
pub use camera::SimCameraConfig;
pub use descriptor::descriptor_from;
pub use pan_tilt::{PanTiltConfig, SimPanTilt};
pub use sonar::{Sonar, SonarConfig};
pub use world::{
    Anchor, BoxConfig, CorridorConfig, FeaturelessConfig, LandmarkConfig, PersonConfig, RandomLandmarks, Side,
    WallConfig, World, WorldConfig, WorldLandmark, Xy, MOST_RANDOM_LANDMARKS,
};

use crate::model::{Footprint, RobotModel};
use crate::wall_compass::WallCompassConfig;
use body::{Body, BodyConfig};
use camera::SimCamera;
use geometry::Circle;
use rand_chacha::ChaCha8Rng;
use serde::Deserialize;
use ubf_core::config::{positive, Check};
use ubf_core::seeds::{rng, Stream};
use ubf_core::{Aim, Bumpers, Command, Limits, PanTilt, Pose2, Robot, RobotError, State};
use ubf_perception::egomotion::EgomotionConfig;

/// The simulated robot's settings, as written in a scenario file. The
/// geometry and the sonar ring default to the Powerbot's.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SimRobotConfig {
    /// Where the robot starts.
    #[serde(default)]
    pub start: StartPose,
    /// Largest forward speed, m/s. The default is the thesis robot's reduced
    /// top speed (§4.4.6).
    #[serde(deserialize_with = "positive")]
    pub max_velocity: f64,
    /// Largest turn rate, °/s.
    #[serde(deserialize_with = "positive")]
    pub max_rot_velocity_deg: f64,
    /// Largest change of forward speed, m/s².
    #[serde(deserialize_with = "positive")]
    pub max_acceleration: f64,
    /// Largest change of turn rate, °/s².
    #[serde(deserialize_with = "positive")]
    pub max_rot_acceleration_deg: f64,
    /// Turn rate per radian of error when a command gives a heading, 1/s.
    #[serde(deserialize_with = "positive")]
    pub heading_gain: f64,
    /// How drive commands are executed.
    #[serde(default)]
    pub motion: MotionProfile,
    /// How odometry errs; perfect by default.
    #[serde(default)]
    pub odometry: OdometryErrors,
    /// The outline; by default the Powerbot's.
    #[serde(default)]
    pub footprint: Option<Footprint>,
    /// The sonar ring.
    #[serde(default)]
    pub sonar: SonarConfig,
    /// The stereo camera; none by default.
    #[serde(default)]
    pub camera: Option<SimCameraConfig>,
    /// Visual egomotion on the camera's frames; none by default. Needs a
    /// camera.
    #[serde(default)]
    pub egomotion: Option<EgomotionConfig>,
    /// Odometry's heading held by the walls the side sonars run along
    /// ([`crate::wall_compass`]), for buildings whose long walls are
    /// square; none by default.
    #[serde(default)]
    pub wall_compass: Option<WallCompassConfig>,
}

impl Check for SimRobotConfig {
    fn check(&self) -> Result<(), String> {
        if self.egomotion.is_some() && self.camera.is_none() {
            return Err("egomotion needs a stereo camera: add `camera: ()` to the robot".into());
        }
        if let Some(camera) = &self.camera {
            camera.check()?;
        }
        Ok(())
    }
}

impl Default for SimRobotConfig {
    fn default() -> Self {
        SimRobotConfig {
            start: StartPose::default(),
            max_velocity: 0.6,
            max_rot_velocity_deg: 60.0,
            max_acceleration: 0.5,
            max_rot_acceleration_deg: 120.0,
            heading_gain: 2.0,
            motion: MotionProfile::default(),
            odometry: OdometryErrors::default(),
            footprint: None,
            sonar: SonarConfig::default(),
            camera: None,
            egomotion: None,
            wall_compass: None,
        }
    }
}

/// A simulated robot. Each [`Robot::act`] advances the simulation by one
/// period.
#[derive(Clone, Debug)]
pub struct SimRobot {
    body: Body,
    world: World,
    sonar: Sonar,
    camera: Option<SimCamera>,
    pan_tilt: Option<SimPanTilt>,
    period: f64,
    time: f64,
    reach: f64,
    motion_rng: ChaCha8Rng,
    sonar_rng: ChaCha8Rng,
    camera_rng: ChaCha8Rng,
    people: Vec<Circle>,
    bumpers: Bumpers,
    stalled: bool,
    collisions: u32,
    /// The true pose when the robot last sensed: what this tick's state,
    /// and any frame taken in it, describe.
    sensed: Pose2,
}

impl SimRobot {
    /// A robot at its configured start in the world, stepping `period`
    /// seconds per act, with every random draw seeded by `seed`.
    pub fn new(config: &SimRobotConfig, world: &WorldConfig, period: f64, seed: u64) -> Self {
        let model = RobotModel::powerbot();
        let footprint = config.footprint.unwrap_or(model.footprint);
        let body = Body::new(BodyConfig {
            start: config.start.pose(),
            limits: Limits::new(config.max_velocity, config.max_rot_velocity_deg.to_radians()),
            max_acceleration: config.max_acceleration,
            max_rot_acceleration: config.max_rot_acceleration_deg.to_radians(),
            heading_gain: config.heading_gain,
            motion: config.motion,
            odometry: config.odometry,
            track_width: model.track_width,
            footprint,
        });
        let units = config.sonar.units.clone().unwrap_or(model.sonar);
        let world = World::build(world, &mut rng(seed, Stream::World));
        SimRobot {
            body,
            world,
            sonar: Sonar::new(config.sonar.clone(), units),
            camera: config.camera.clone().map(SimCamera::new),
            pan_tilt: config
                .camera
                .as_ref()
                .and_then(|c| c.pan_tilt)
                .map(|unit| SimPanTilt::new(unit, rng(seed, Stream::PanTilt), rng(seed, Stream::PanTiltAnchor))),
            period,
            time: 0.0,
            reach: footprint.radius(),
            motion_rng: rng(seed, Stream::Motion),
            sonar_rng: rng(seed, Stream::Sonar),
            camera_rng: rng(seed, Stream::Camera),
            people: Vec::new(),
            bumpers: Bumpers::default(),
            stalled: false,
            collisions: 0,
            sensed: config.start.pose(),
        }
    }

    /// Where the robot really is.
    pub fn true_pose(&self) -> Pose2 {
        self.body.true_pose
    }

    /// Where the robot really was when it last sensed: the ground truth of
    /// the latest state and stereo frame ([`Robot::act`] has moved it on
    /// since by one period).
    pub fn sensed_true_pose(&self) -> Pose2 {
        self.sensed
    }

    /// Where its odometry says it is.
    pub fn odometry_pose(&self) -> Pose2 {
        self.body.odometry
    }

    /// Metres driven so far (true path length).
    pub fn distance_travelled(&self) -> f64 {
        self.body.distance
    }

    /// How many times the robot has come into contact with something.
    pub fn collisions(&self) -> u32 {
        self.collisions
    }

    /// The world it drives in.
    pub fn world(&self) -> &World {
        &self.world
    }

    /// The robot's outline at `pose`, in the world, counter-clockwise.
    pub fn footprint_at(&self, pose: &Pose2) -> [(f64, f64); 4] {
        self.body.footprint_at(pose).0
    }

    /// The camera's settings, if the robot has one.
    pub fn camera(&self) -> Option<&SimCameraConfig> {
        self.camera.as_ref().map(SimCamera::config)
    }

    /// Whether the robot's outline at its start overlaps a wall, a box or a
    /// person: a run from there could not move.
    pub fn starts_in_contact(&self) -> bool {
        self.touches(&self.body.true_pose)
    }

    fn touches(&self, pose: &Pose2) -> bool {
        let quad = self.body.footprint_at(pose);
        self.world.segments.iter().any(|s| quad.touches_segment(s))
            || self.people.iter().any(|c| quad.touches_circle(c))
    }
}

impl Robot for SimRobot {
    fn sense(&mut self, state: &mut State) -> Result<(), RobotError> {
        self.world.people_at(self.time, &mut self.people);
        let pose = self.body.true_pose;
        self.sensed = pose;
        state.pose = self.body.odometry;
        state.odometry = state.pose;
        state.velocity = self.body.velocity;
        state.rot_velocity = self.body.rot_velocity;
        self.sonar.sense(&pose, self.reach, &self.world.segments, &self.people, &mut self.sonar_rng, &mut state.ranges);
        state.bumpers = self.bumpers;
        state.stalled = self.stalled;
        state.motors_enabled = true;
        state.estop = false;
        state.sensor_age = 0.0;
        // A frame looks where the unit truly points; its calibration says
        // where the encoders read it pointing.
        let aim = self.pan_tilt.as_ref().map(SimPanTilt::true_aim);
        // The first frame anchors egomotion's map: its reading is averaged.
        let first_frame = self.camera.as_ref().is_some_and(|camera| camera.frames() == 0);
        state.camera_aim = match &mut self.pan_tilt {
            Some(unit) if first_frame => Some(unit.anchor_reading()?),
            Some(unit) => Some(unit.measured()?),
            None => None,
        };
        if let Some(camera) = &mut self.camera {
            let landmarks = &mut state.stereo.landmarks;
            if let Some(number) = camera.capture(self.time, &pose, aim, &self.world, &mut self.camera_rng, landmarks) {
                let mut calibration = camera.config().stereo;
                if let Some(measured) = state.camera_aim {
                    calibration.mount = calibration.mount.aimed(measured.pan, measured.tilt);
                }
                state.stereo.number = number;
                state.stereo.time = state.time;
                state.stereo.calibration = Some(calibration);
                state.stereo.images = camera.last_images().cloned();
            }
        }
        Ok(())
    }

    fn act(&mut self, command: &Command) -> Result<(), RobotError> {
        let intended = self.body.velocity;
        let planned = self.body.plan(command, self.period, &mut self.motion_rng);
        // A move into contact is refused: the wheels stall against the
        // obstacle. A robot already in contact (a person walked into it) may
        // move, so that it can get away.
        let blocked = self.touches(&planned.true_pose()) && !self.touches(&self.body.true_pose);
        if blocked {
            if !self.stalled {
                self.collisions += 1;
            }
            let forwards = self.body.velocity.max(intended) >= 0.0;
            self.bumpers = Bumpers { front: forwards, rear: !forwards };
            self.stalled = true;
            self.body.block();
        } else {
            self.body.commit(planned);
            self.bumpers = Bumpers::default();
            self.stalled = false;
        }
        if let Some(unit) = &mut self.pan_tilt {
            unit.advance(self.period);
        }
        self.time += self.period;
        Ok(())
    }

    fn aim_camera(&mut self, pan: f64) -> Result<(), RobotError> {
        match &mut self.pan_tilt {
            Some(unit) => {
                let tilt = unit.true_aim().tilt;
                unit.command(Aim { pan, tilt })
            }
            None => Ok(()),
        }
    }

    fn shutdown(&mut self) -> Result<(), RobotError> {
        self.body.block();
        Ok(())
    }

    fn limits(&self) -> Limits {
        self.body.limits()
    }

    fn ground_truth(&self) -> Option<ubf_core::GroundTruth> {
        Some(ubf_core::GroundTruth { pose: self.sensed, collisions: self.collisions })
    }
}
