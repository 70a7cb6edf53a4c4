//! Drive to the goal.

use serde::Deserialize;
use ubf_core::config::{non_negative, positive};
use ubf_core::{Action, Behavior, Goal, State};

/// Settings of [`GoTo`], as written in a scenario file.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct GoToConfig {
    /// Forward speed far from the goal, m/s.
    #[serde(deserialize_with = "ubf_core::config::speed_m_s")]
    pub cruise_speed: f64,
    /// Turn rate per radian of heading error, 1/s.
    #[serde(deserialize_with = "positive")]
    pub turn_gain: f64,
    /// Largest turn rate it asks for, °/s. Bounded so that a large heading
    /// error does not swamp the other children of a fusing arbiter.
    #[serde(deserialize_with = "ubf_core::config::rate_deg_s")]
    pub max_turn_deg: f64,
    /// Within this distance of the goal the speed ramps down, m.
    #[serde(deserialize_with = "non_negative")]
    pub slow_radius: f64,
    /// The vote while driving.
    #[serde(deserialize_with = "non_negative")]
    pub vote: f64,
    /// A point to drive to instead of the goal (world frame). Once the
    /// robot is within its tolerance the behaviour falls silent for good (a
    /// waypoint is passed once), so that a lower-priority sibling takes
    /// over: "this, then that".
    pub waypoint: Option<Goal>,
}

impl Default for GoToConfig {
    fn default() -> Self {
        GoToConfig {
            cruise_speed: 0.5,
            turn_gain: 1.5,
            max_turn_deg: 45.0,
            slow_radius: 1.0,
            vote: 0.5,
            waypoint: None,
        }
    }
}

/// Drives towards the state's goal: turns in proportion to the heading error
/// and slows near the goal and while facing away from it. Silent when there
/// is no goal or it is reached (a `Stop` on `GoalReached` holds the robot
/// there).
///
/// With a waypoint it drives there instead, and stays silent from the first
/// tick it finds the robot within the waypoint's tolerance until
/// [`Behavior::reset`]. It is asked every tick whether or not it wins, so it
/// counts the waypoint passed whenever the robot comes that near, whichever
/// behaviour was driving.
#[derive(Clone, Debug)]
pub struct GoTo {
    config: GoToConfig,
    /// The waypoint has been reached.
    passed: bool,
}

impl GoTo {
    /// A go-to behaviour with these settings.
    pub fn new(config: GoToConfig) -> Self {
        GoTo { config, passed: false }
    }
}

impl Behavior for GoTo {
    fn gen_action(&mut self, state: &State) -> Action {
        let goal = match (self.config.waypoint, state.goal) {
            (Some(_), _) if self.passed => return Action::none(),
            (Some(waypoint), _) => waypoint,
            (None, Some(goal)) => goal,
            (None, None) => return Action::none(),
        };
        let distance = state.pose.distance_to(goal.x, goal.y);
        if distance <= goal.tolerance {
            self.passed = self.config.waypoint.is_some();
            return Action::none();
        }
        let error = state.pose.bearing_to(goal.x, goal.y);
        let max_turn = self.config.max_turn_deg.to_radians();
        // Facing away from the goal, turn on the spot rather than drive off.
        let alignment = error.cos().max(0.0);
        let ramp = if self.config.slow_radius > 0.0 { (distance / self.config.slow_radius).min(1.0) } else { 1.0 };
        Action::with_vote(self.config.vote)
            .velocity(self.config.cruise_speed * alignment * ramp)
            .rot_velocity((self.config.turn_gain * error).clamp(-max_turn, max_turn))
    }

    fn name(&self) -> &str {
        "GoTo"
    }

    fn reset(&mut self) {
        self.passed = false;
    }
}

impl ubf_core::Describe for GoToConfig {
    fn fields() -> Vec<ubf_core::Field> {
        use ubf_core::Field;
        vec![
            Field::new("cruise_speed", "number", "m/s", "0.5", "> 0", "speed far from the goal"),
            Field::new("turn_gain", "number", "1/s", "1.5", "> 0", "turn rate per radian of heading error"),
            Field::new("max_turn_deg", "number", "°/s", "45", "> 0", "largest turn rate it asks for"),
            Field::new("slow_radius", "number", "m", "1.0", "≥ 0", "within this distance the speed ramps down"),
            Field::new("vote", "number", "", "0.5", "≥ 0", "vote while driving"),
            Field::new(
                "waypoint",
                "point",
                "m",
                "None",
                "",
                "`(x: .., y: .., tolerance: 0.2)` in the world frame: drive there instead of the goal, and fall silent \
                 for good once within its tolerance (a waypoint is passed once; see \
                 [for-behaviortree-users.md](for-behaviortree-users.md#do-a-then-b))",
            ),
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;
    use ubf_core::Pose2;

    fn state_at(pose: Pose2, goal: Option<Goal>) -> State {
        State { pose, goal, ..State::default() }
    }

    #[test]
    fn silent_without_goal_or_at_goal() {
        let mut go = GoTo::new(GoToConfig::default());
        assert!(!go.gen_action(&state_at(Pose2::default(), None)).is_voting());
        let goal = Goal { x: 0.1, y: 0.0, tolerance: 0.2 };
        assert!(!go.gen_action(&state_at(Pose2::default(), Some(goal))).is_voting());
    }

    #[test]
    fn drives_straight_at_a_goal_ahead_and_turns_towards_one_behind() {
        let mut go = GoTo::new(GoToConfig::default());
        let ahead = go.gen_action(&state_at(Pose2::default(), Some(Goal { x: 5.0, y: 0.0, tolerance: 0.2 })));
        assert_eq!(ahead.motion.velocity, Some(0.5));
        assert_eq!(ahead.motion.rot_velocity, Some(0.0));
        let left_behind =
            go.gen_action(&state_at(Pose2::new(0.0, 0.0, 0.0), Some(Goal { x: -5.0, y: 1.0, tolerance: 0.2 })));
        assert_eq!(left_behind.motion.velocity, Some(0.0));
        assert!(left_behind.motion.rot_velocity.unwrap() > 0.0);
        let right =
            go.gen_action(&state_at(Pose2::new(0.0, 0.0, PI / 2.0), Some(Goal { x: 5.0, y: 0.0, tolerance: 0.2 })));
        assert!(right.motion.rot_velocity.unwrap() < 0.0);
    }

    #[test]
    fn a_waypoint_is_driven_to_then_left_to_others_for_good() {
        let waypoint = Goal { x: 2.0, y: 0.0, tolerance: 0.3 };
        let mut go = GoTo::new(GoToConfig { waypoint: Some(waypoint), ..GoToConfig::default() });
        // The goal lies behind: the waypoint, not the goal, is steered for.
        let goal = Some(Goal { x: -5.0, y: 0.0, tolerance: 0.2 });
        let toward = go.gen_action(&state_at(Pose2::default(), goal));
        assert!(toward.is_voting());
        assert_eq!(toward.motion.rot_velocity, Some(0.0));
        assert!(toward.motion.velocity.unwrap() > 0.0);
        // It needs no goal at all.
        assert!(go.gen_action(&state_at(Pose2::default(), None)).is_voting());
        // Within the tolerance: silent, and still silent once the robot has left.
        assert!(!go.gen_action(&state_at(Pose2::new(1.8, 0.0, 0.0), goal)).is_voting());
        assert!(!go.gen_action(&state_at(Pose2::default(), goal)).is_voting());
        go.reset();
        assert!(go.gen_action(&state_at(Pose2::default(), goal)).is_voting());
    }

    #[test]
    fn without_a_waypoint_it_drives_again_once_pushed_off_the_goal() {
        let mut go = GoTo::new(GoToConfig::default());
        let goal = Some(Goal { x: 2.0, y: 0.0, tolerance: 0.3 });
        assert!(!go.gen_action(&state_at(Pose2::new(1.8, 0.0, 0.0), goal)).is_voting());
        assert!(go.gen_action(&state_at(Pose2::default(), goal)).is_voting());
    }

    #[test]
    fn slows_near_the_goal() {
        let mut go = GoTo::new(GoToConfig::default());
        let near = go.gen_action(&state_at(Pose2::default(), Some(Goal { x: 0.5, y: 0.0, tolerance: 0.2 })));
        assert!((near.motion.velocity.unwrap() - 0.25).abs() < 1e-12);
    }
}
