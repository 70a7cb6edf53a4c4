//! Keep clear of obstacles the range sensors see.

use crate::clearance::{free_distance, EchoPoints};
use serde::Deserialize;
use std::f64::consts::FRAC_PI_2;
use ubf_core::config::{non_negative, positive, Check};
use ubf_core::{wrap_angle, Action, Behavior, State};

/// Settings of [`AvoidCollision`], as written in a scenario file.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct AvoidCollisionConfig {
    /// An echo ahead nearer than this makes the robot slow and turn, m.
    #[serde(deserialize_with = "positive")]
    pub slow_distance: f64,
    /// With an echo ahead nearer than this the robot may not drive forward, m.
    #[serde(deserialize_with = "non_negative")]
    pub stop_distance: f64,
    /// Forward speed allowed per metre of clearance ahead beyond
    /// `stop_distance`, 1/s: the robot stays this many seconds from contact.
    #[serde(deserialize_with = "positive")]
    pub speed_per_metre: f64,
    /// Half the width of the strip ahead that the robot will sweep, m: echoes
    /// ahead within this distance of the centreline are in its way. The
    /// default is the Powerbot's half-width (0.34 m) and a 16 cm margin.
    #[serde(deserialize_with = "positive")]
    pub path_half_width: f64,
    /// Distance from the centre of rotation to the front of the robot, m
    /// (the Powerbot's 0.369 m by default).
    #[serde(deserialize_with = "non_negative")]
    pub body_front: f64,
    /// Turn rate per radian between the current and the chosen heading, 1/s.
    #[serde(deserialize_with = "positive")]
    pub turn_gain: f64,
    /// Largest turn rate it asks for, °/s.
    #[serde(deserialize_with = "ubf_core::config::rate_deg_s")]
    pub max_turn_deg: f64,
    /// Vote when an obstacle is at `stop_distance`; it falls to 0 at
    /// `slow_distance`.
    #[serde(deserialize_with = "non_negative")]
    pub vote: f64,
}

impl Default for AvoidCollisionConfig {
    fn default() -> Self {
        AvoidCollisionConfig {
            slow_distance: 1.2,
            stop_distance: 0.25,
            speed_per_metre: 0.5,
            path_half_width: 0.5,
            body_front: 0.369,
            turn_gain: 1.5,
            max_turn_deg: 45.0,
            vote: 1.0,
        }
    }
}

impl Check for AvoidCollisionConfig {
    fn check(&self) -> Result<(), String> {
        if self.stop_distance >= self.slow_distance {
            return Err(format!(
                "stop_distance {} must be less than slow_distance {}",
                self.stop_distance, self.slow_distance
            ));
        }
        Ok(())
    }
}

/// Keeps the robot off obstacles seen by its range sensors (sonar).
///
/// It looks along candidate headings every 5° from −90° to +90° of the
/// current one and measures how far the robot could drive along each before
/// its swept strip (`path_half_width` either side) meets an echo. While the
/// way straight ahead is clear for `slow_distance` it is silent, so walls
/// alongside never fight a go-to behaviour; once it has turned off, it
/// stays until the way towards the goal is clear too (up to the goal), so
/// that a go-to cannot turn straight back into the obstacle. Otherwise it:
///
/// - limits the forward speed in proportion to the clearance straight ahead,
///   down to zero at `stop_distance`, through the `max_velocity` limit
///   channel that every arbiter respects;
/// - turns towards the clear heading nearest the goal's bearing (or nearest
///   straight ahead without a goal), or when none is free that far towards
///   the freest; it keeps that heading (in the world) while it stays free,
///   so that sonar noise does not make it dither;
/// - votes more the nearer the obstacle ahead.
#[derive(Clone, Debug)]
pub struct AvoidCollision {
    config: AvoidCollisionConfig,
    /// The world heading it chose, kept while it stays free so that sonar
    /// noise does not make it dither.
    committed: Option<f64>,
    /// Echo points in the robot frame (reused every tick).
    points: EchoPoints,
}

/// Candidate headings, relative to the robot's, every 5° over ±90°.
const CANDIDATES: usize = 37;

fn candidate(i: usize) -> f64 {
    (i as f64 * 5.0 - 90.0).to_radians()
}

/// Where the robot would rather go, relative to its heading: the goal's
/// bearing, within ±90°, or straight ahead without a goal.
fn preferred_heading(state: &State) -> f64 {
    state.goal.map_or(0.0, |g| state.pose.bearing_to(g.x, g.y)).clamp(-FRAC_PI_2, FRAC_PI_2)
}

impl AvoidCollision {
    /// An avoider with these settings.
    pub fn new(config: AvoidCollisionConfig) -> Self {
        AvoidCollision { config, committed: None, points: EchoPoints::default() }
    }

    /// The free heading (robot frame) nearest the goal's bearing, or nearest
    /// straight ahead without a goal; if none is free for `needed` metres,
    /// the freest.
    fn choose(&self, state: &State, needed: f64) -> f64 {
        let preferred = preferred_heading(state);
        let free: [f64; CANDIDATES] = std::array::from_fn(|i| self.free_distance(candidate(i)));
        let freest = free.iter().copied().fold(0.0, f64::max);
        let needed = needed.min(freest);
        (0..CANDIDATES)
            .filter(|&i| free[i] >= needed)
            .map(candidate)
            .min_by(|a, b| (a - preferred).abs().total_cmp(&(b - preferred).abs()))
            .unwrap_or(0.0)
    }

    /// How far the robot's strip along `heading` (robot frame) is free.
    fn free_distance(&self, heading: f64) -> f64 {
        free_distance(self.points.points(), heading, self.config.path_half_width)
    }
}

impl Behavior for AvoidCollision {
    fn gen_action(&mut self, state: &State) -> Action {
        self.points.update(state);
        let c = &self.config;
        // Clearance ahead is measured from the robot's front, where the
        // forward sonars sit: the echo's distance along the heading less the
        // nearest echo-free offset of the ring.
        let ahead = self.free_distance(0.0) - c.body_front;
        // Having turned off, it holds on while the way to the goal is still
        // blocked: going silent the moment straight ahead is clear let a
        // go-to turn straight back into the obstacle, and the two took turns
        // every few ticks at its edge.
        // Measured only while it has a heading to hold: the tick of a robot
        // in the open stays one strip's work. An echo beyond the goal (the
        // wall it stands by) is not in its way.
        let to_goal = self.committed.map(|_| self.free_distance(preferred_heading(state)) - c.body_front);
        let beyond_goal = || state.distance_to_goal().map_or(f64::INFINITY, |d| d - c.body_front);
        let holding = to_goal.filter(|&clear| clear < c.slow_distance.min(beyond_goal()));
        if ahead >= c.slow_distance && holding.is_none() {
            self.committed = None;
            return Action::none();
        }
        let nearness_at =
            |clear: f64| ((c.slow_distance - clear) / (c.slow_distance - c.stop_distance)).clamp(0.0, 1.0);
        let nearness = holding.map_or(nearness_at(ahead), |clear| nearness_at(ahead).max(nearness_at(clear)));
        let needed = c.slow_distance + c.body_front;
        let kept = self
            .committed
            .map(|world| wrap_angle(world - state.pose.theta))
            .filter(|h| h.abs() <= FRAC_PI_2 && self.free_distance(*h) >= needed);
        let target = match kept {
            Some(heading) => heading,
            None => self.choose(state, needed),
        };
        self.committed = Some(wrap_angle(state.pose.theta + target));
        let max_turn = c.max_turn_deg.to_radians();
        let limit = (ahead - c.stop_distance).max(0.0) * c.speed_per_metre;
        let mut turn = (c.turn_gain * target).clamp(-max_turn, max_turn);
        if limit == 0.0 {
            // Blocked, it turns at least half its top rate: a gentle turn
            // towards a heading a few degrees off could be cancelled, in a
            // fusing arbiter, by a go-to's turn back, and the robot stood
            // still for good where no sonar noise tipped the balance.
            turn = target.signum() * turn.abs().max(max_turn / 2.0);
        }
        Action::with_vote(c.vote * nearness).rot_velocity(turn).max_velocity(limit)
    }

    fn name(&self) -> &str {
        "AvoidCollision"
    }

    fn reset(&mut self) {
        self.committed = None;
    }
}

impl ubf_core::Describe for AvoidCollisionConfig {
    fn fields() -> Vec<ubf_core::Field> {
        use ubf_core::Field;
        vec![
            Field::new("slow_distance", "number", "m", "1.2", "> 0", "clearance ahead below which it acts"),
            Field::new(
                "stop_distance",
                "number",
                "m",
                "0.25",
                "≥ 0, < `slow_distance`",
                "clearance ahead at which forward speed is 0",
            ),
            Field::new(
                "speed_per_metre",
                "number",
                "1/s",
                "0.5",
                "> 0",
                "speed allowed per metre of clearance beyond `stop_distance`",
            ),
            Field::new(
                "path_half_width",
                "number",
                "m",
                "0.5",
                "> 0",
                "half the swept strip: the Powerbot's 0.34 m and a margin",
            ),
            Field::new("body_front", "number", "m", "0.369", "≥ 0", "centre of rotation to the front of the robot"),
            Field::new("turn_gain", "number", "1/s", "1.5", "> 0", "turn rate per radian towards the chosen heading"),
            Field::new("max_turn_deg", "number", "°/s", "45", "> 0", "largest turn rate it asks for"),
            Field::new("vote", "number", "", "1.0", "≥ 0", "vote at `stop_distance`, falling to 0 at `slow_distance`"),
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ubf_core::{Pose2, RangeReading};

    fn reading(bearing_deg: f64, range: f64) -> RangeReading {
        RangeReading {
            pose_robot_sensor: Pose2::new(0.0, 0.0, bearing_deg.to_radians()),
            range: Some(range),
            max_range: 5.0,
        }
    }

    fn state(readings: &[(f64, f64)]) -> State {
        State { ranges: readings.iter().map(|&(b, r)| reading(b, r)).collect(), ..State::default() }
    }

    #[test]
    fn silent_unless_something_is_in_the_way() {
        let mut avoid = AvoidCollision::new(AvoidCollisionConfig::default());
        assert!(
            !avoid.gen_action(&state(&[(0.0, 3.0), (90.0, 0.6), (-90.0, 0.6)])).is_voting(),
            "walls alongside are left alone"
        );
        assert!(!avoid.gen_action(&state(&[(180.0, 0.3)])).is_voting(), "echoes behind are ignored");
    }

    #[test]
    fn slows_and_turns_to_a_free_heading() {
        let mut avoid = AvoidCollision::new(AvoidCollisionConfig::default());
        // A post 1 m ahead, slightly left, and a wall close on the left:
        // go right, slowly.
        let a = avoid.gen_action(&state(&[(5.0, 1.0), (60.0, 0.7), (80.0, 0.7)]));
        assert!(a.motion.rot_velocity.unwrap() < 0.0, "{a:?}");
        let ahead = 1.0 * 5f64.to_radians().cos() - 0.369;
        assert!((a.motion.max_velocity.unwrap() - (ahead - 0.25) * 0.5).abs() < 1e-9);
        // Nearer means a stronger vote.
        assert!(avoid.gen_action(&state(&[(5.0, 0.8)])).vote > a.vote);
        // At the stop distance, no forward speed at all.
        assert_eq!(avoid.gen_action(&state(&[(0.0, 0.5)])).motion.max_velocity, Some(0.0));
    }

    #[test]
    fn holds_on_while_the_way_to_the_goal_is_blocked() {
        let mut avoid = AvoidCollision::new(AvoidCollisionConfig::default());
        let goal_at = |bearing_deg: f64| {
            let b = f64::to_radians(bearing_deg);
            Some(ubf_core::Goal { x: 5.0 * b.cos(), y: 5.0 * b.sin(), tolerance: 0.2 })
        };
        let mut s = state(&[(0.0, 1.0)]);
        s.goal = goal_at(0.0);
        assert!(avoid.gen_action(&s).is_voting());
        // Turned off: straight ahead is clear, the box is on the goal's side.
        let mut s = state(&[(40.0, 1.0)]);
        s.goal = goal_at(40.0);
        assert!(avoid.gen_action(&s).is_voting(), "let go while the goal is still behind the box");
        // Past it: the way to the goal is clear, and it falls silent.
        let mut s = state(&[(100.0, 1.0)]);
        s.goal = goal_at(40.0);
        assert!(!avoid.gen_action(&s).is_voting());
        // A wall beyond the goal is not in the way.
        avoid.gen_action(&state(&[(0.0, 1.0)]));
        let mut s = state(&[(40.0, 1.0)]);
        s.goal = Some(ubf_core::Goal { x: 0.5, y: 0.3, tolerance: 0.2 });
        assert!(!avoid.gen_action(&s).is_voting());
    }

    #[test]
    fn blocked_it_turns_firmly_even_towards_a_heading_a_few_degrees_off() {
        let mut avoid = AvoidCollision::new(AvoidCollisionConfig::default());
        // An echo 0.55 m ahead, 0.45 m right: no forward speed, and the
        // nearest free heading is 10° left.
        let echo = (0.55f64, -0.45f64);
        let a = avoid.gen_action(&state(&[(echo.1.atan2(echo.0).to_degrees(), echo.0.hypot(echo.1))]));
        assert_eq!(a.motion.max_velocity, Some(0.0));
        let turn = a.motion.rot_velocity.unwrap();
        assert!(turn >= 45f64.to_radians() / 2.0 - 1e-12, "{turn} rad/s");
    }

    #[test]
    fn heads_for_the_side_of_the_goal() {
        let mut avoid = AvoidCollision::new(AvoidCollisionConfig::default());
        let mut s = state(&[(0.0, 1.0)]);
        s.goal = Some(ubf_core::Goal { x: 5.0, y: -2.0, tolerance: 0.2 });
        assert!(avoid.gen_action(&s).motion.rot_velocity.unwrap() < 0.0);
        // Once it has chosen right, a goal slightly left does not flip it.
        s.goal = Some(ubf_core::Goal { x: 5.0, y: 0.3, tolerance: 0.2 });
        assert!(avoid.gen_action(&s).motion.rot_velocity.unwrap() < 0.0);
    }
}
