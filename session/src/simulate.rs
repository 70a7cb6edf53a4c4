//! `ubf simulate SCENARIO --ros2`: the simulator served as a ROS 2 robot,
//! for another stack (Nav2, a teleop node) to drive. It takes
//! `geometry_msgs/msg/Twist` (or `TwistStamped`) on `/cmd_vel` and
//! publishes what a robot's driver does (`/odom`, `/tf`, `/scan`, camera
//! images), paced at real time.
//!
//! It is the session loop like every other command: the simulated robot,
//! a paced clock, a ROS 2 publisher as its sink, and for a tree one
//! behaviour, [`FollowCmdVel`], that obeys the latest `/cmd_vel`.

use crate::ros2_publish::background_publisher;
use crate::ros2_view::{Shown, ODOM_FRAME};
use crate::scenario::Scenario;
use std::ops::ControlFlow;
use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};
use ubf_core::{
    Action, Behavior, Controller, Ends, PacedClock, Pose2, RobotError, Session, SessionEnd, State, TracingSink,
};
use ubf_robots::ros2::msg::{ros_name, RosMessage, Twist, TwistStamped};
use ubf_robots::ros2::{domain_from_env, Node, Qos, Subscription};
use ubf_robots::sim::SimRobot;

/// A command older than this is no command: the robot stops, as ROS 2
/// base drivers do when their controller goes quiet.
const COMMAND_TIMEOUT: Duration = Duration::from_millis(500);

/// A behaviour that obeys the latest `/cmd_vel`: its linear x and angular z
/// as the robot's velocity and turn rate, or STOP once no command has come
/// for half a second.
pub struct FollowCmdVel {
    cmd_vel: Commands,
    latest: Option<(Twist, Instant)>,
    /// When discovery was last asked whether a commander sends another
    /// type, until one was found and said.
    asked_at: Option<Instant>,
    /// Last, so that it is dropped after its reader.
    node: Node,
}

/// How often discovery is asked whether a commander sends another type.
const ASKED_EVERY: Duration = Duration::from_secs(1);

/// The commands' reader, of the type they come as.
enum Commands {
    Twist(Subscription<Twist>),
    /// Their stamps are not read: a command's age is counted from when it
    /// came, whatever the commander's clock says.
    Stamped(Subscription<TwistStamped>),
}

impl Commands {
    fn take_latest(&mut self) -> Result<Option<Twist>, RobotError> {
        match self {
            Commands::Twist(reader) => reader.take_latest(),
            Commands::Stamped(reader) => Ok(reader.take_latest()?.map(|stamped| stamped.twist)),
        }
    }
}

impl FollowCmdVel {
    /// Subscribes `/cmd_vel` in `domain`, as `TwistStamped` if `stamped`.
    pub fn subscribe(domain: u16, stamped: bool) -> Result<FollowCmdVel, RobotError> {
        let node = Node::join(domain, "")?;
        let cmd_vel = match stamped {
            true => Commands::Stamped(node.reader("cmd_vel", Qos::Reliable)?),
            false => Commands::Twist(node.reader("cmd_vel", Qos::Reliable)?),
        };
        Ok(FollowCmdVel { cmd_vel, latest: None, asked_at: Some(Instant::now()), node })
    }

    /// Says, once, a commander that sends a type this reader does not
    /// read (`TwistStamped` to a simulator serving `Twist`): it would
    /// otherwise drive nothing and hear nothing of why.
    fn say_other_commanders(&mut self) {
        if self.asked_at.is_none_or(|at| at.elapsed() < ASKED_EVERY) {
            return;
        }
        self.asked_at = Some(Instant::now());
        let (read, other, flag) = match self.cmd_vel {
            Commands::Twist(_) => (Twist::NAME, TwistStamped::NAME, "with"),
            Commands::Stamped(_) => (TwistStamped::NAME, Twist::NAME, "without"),
        };
        if self.node.writer_types("cmd_vel").iter().any(|sent| ros_name(sent) == other) {
            tracing::warn!(
                "a commander sends {other} on /cmd_vel, which is read as {read} here: serve it {flag} \
                 `--cmd-vel-stamped`"
            );
            self.asked_at = None;
        }
    }
}

impl Behavior for FollowCmdVel {
    fn gen_action(&mut self, _: &State) -> Action {
        self.say_other_commanders();
        match self.cmd_vel.take_latest() {
            Ok(Some(twist)) => self.latest = Some((twist, Instant::now())),
            Ok(None) => {}
            Err(e) => tracing::warn!("{e}"),
        }
        match self.latest {
            Some((twist, at)) if at.elapsed() <= COMMAND_TIMEOUT => {
                Action::with_vote(1.0).velocity(twist.linear.x).rot_velocity(twist.angular.z)
            }
            _ => Action::stop(1.0),
        }
    }

    fn name(&self) -> &str {
        "FollowCmdVel"
    }
}

/// How a served simulation ended.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Served {
    /// Ticks simulated.
    pub ticks: u64,
    /// Where the robot really ended.
    pub true_pose: Pose2,
}

/// Why a simulation could not be served.
#[derive(Debug, thiserror::Error)]
pub enum SimulateError {
    /// ROS 2 could not be joined.
    #[error("ROS 2: {0}")]
    Ros2(RobotError),
    /// The simulation failed.
    #[error("{0}")]
    Failed(String),
}

/// How a simulation is served.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Serving {
    /// The seed of its random streams.
    pub seed: u64,
    /// Times real time.
    pub speed: f64,
    /// When to stop, in simulated seconds, if ever.
    pub max_time_s: Option<f64>,
    /// Whether the commands come as `TwistStamped` (Nav2 from Kilted on).
    pub cmd_vel_stamped: bool,
}

/// Serves `scenario` (its world, robot and start; not its tree) as a ROS 2
/// robot, as `serving` says, until `stop` is set or its time is up.
pub fn serve(scenario: &Scenario, serving: Serving, stop: &AtomicBool) -> Result<Served, SimulateError> {
    let Serving { seed, speed, max_time_s, cmd_vel_stamped } = serving;
    let domain = domain_from_env().map_err(SimulateError::Ros2)?;
    let follow = FollowCmdVel::subscribe(domain, cmd_vel_stamped).map_err(SimulateError::Ros2)?;
    let sim = SimRobot::new(&scenario.robot, &scenario.world, scenario.period_s, seed);
    let mut controller = Controller::new(sim, Box::new(follow), Box::new(PacedClock::new(scenario.period_s, speed)));
    controller.add_sink(Box::new(TracingSink));
    let shown = Shown { robot: true, images: true, tree: false };
    let publisher = background_publisher(shown, Some(domain), "", ODOM_FRAME).map_err(SimulateError::Ros2)?;
    controller.add_sink(Box::new(publisher));
    let mut session = Session::new(controller, Ends { max_time_s, ..Ends::default() });
    let ended = session.run(stop, |_| ControlFlow::Continue(()));
    let (controller, shutdown) = session.finish();
    match ended {
        SessionEnd::Failed(e) => return Err(SimulateError::Failed(e.to_string())),
        SessionEnd::Panicked(why) => return Err(SimulateError::Failed(format!("internal error: {why}"))),
        _ => shutdown.map_err(|e| SimulateError::Failed(e.to_string()))?,
    }
    let true_pose = controller.robot().true_pose();
    Ok(Served { ticks: controller.last_record().tick + 1, true_pose })
}
