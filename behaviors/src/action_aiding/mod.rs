//! Action aiding (thesis chapter 3): steer so that landmarks fall where
//! stereo egomotion is least uncertain.
//!
//! The behaviour is a machine of phases (`Phase`: decide, scan, turn,
//! step, approach), each carrying what it needs; `ActionAiding::next` is
//! the one place a phase hands over to the next.

mod config;
mod phase;
mod prediction;
mod progress;
mod zigzag;

pub use config::{ActionAidingConfig, DecisionObjective, Steer, Technique};
pub use prediction::PredictionCheck;

use crate::clearance::{free_distance, EchoPoints};
use crate::decision::{best_heading, best_look, DecisionRules, Objective};
use crate::tracking::TrackingList;
use phase::Phase;
use prediction::Predictions;
use progress::ProgressWatch;
use ubf_core::{angle_difference, wrap_angle, Action, Behavior, BuildContext, Pose2, State};
use ubf_perception::error_model::{CvTable, MODEL_STEP_M};
use ubf_perception::StereoCamera;
use zigzag::ZigZag;

/// The action-aiding behaviour: drives to the goal in steps of `step_m`,
/// choosing each step's heading by its technique, and votes more when the
/// egomotion of the step just done was less certain (thesis §3.5.3).
///
/// It drives the robot itself (turn, then step), so it is the main driving
/// behaviour of its tree; a `Stop` and an `AvoidCollision` beside it keep it
/// safe.
pub struct ActionAiding {
    config: ActionAidingConfig,
    phase: Phase,
    camera: Option<(StereoCamera, CvTable)>,
    list: TrackingList,
    last_frame: u64,
    zigzag: ZigZag,
    positions: Vec<[f64; 3]>,
    echoes: EchoPoints,
    decisions: u64,
    predictions: Predictions,
    /// Camera steering: where the camera is to look (world), once chosen.
    look: Option<f64>,
    /// What the scan budget is measured by: time spent scanning and
    /// turning on the spot, and the state's time at the first tick and at
    /// the last, s.
    scanned_s: f64,
    started_s: Option<f64>,
    last_s: f64,
    /// Whether it has said that no camera frame came, which leaves it
    /// driving straight: said once a run, not every tick.
    said_blind: bool,
}

/// How long aiding waits for a camera frame before saying it has none: a
/// real camera takes a moment to start.
const BLIND_AFTER_S: f64 = 5.0;

/// What every phase reads of the tick.
struct Tick {
    /// The robot's pose.
    pose: Pose2,
    /// Where the goal is.
    goal: (f64, f64),
    /// The goal's bearing from the robot.
    to_goal: f64,
    /// The distance to the goal, m.
    distance: f64,
    /// The state's time, s.
    time: f64,
    /// The vote the behaviour's actions carry.
    vote: f64,
}

/// What a pass of the phase machine makes of the tick.
enum Pass {
    /// Send the action, staying in the phase (its watch updated).
    Act(Phase, Action),
    /// Hand over to the phase, within the tick.
    Hand(Phase),
}

/// Whether the strip along the world `heading` from `pose` is clear of
/// `echoes` as far as `config` asks.
fn strip_clear(config: &ActionAidingConfig, echoes: &[(f64, f64)], pose: &Pose2, heading: f64) -> bool {
    config.clearance_m <= 0.0
        || free_distance(echoes, angle_difference(heading, pose.theta), config.path_half_width) >= config.clearance_m
}

impl ActionAiding {
    /// A behaviour with these settings, drawing the zig-zag's turning points
    /// from `ctx`'s generator.
    pub fn new(config: ActionAidingConfig, ctx: &BuildContext) -> Self {
        let list = TrackingList::new(config.tracking);
        ActionAiding {
            config,
            zigzag: ZigZag::new(ctx.rng()),
            phase: Phase::Decide,
            camera: None,
            list,
            last_frame: 0,
            positions: Vec::new(),
            echoes: EchoPoints::default(),
            decisions: 0,
            predictions: Predictions::default(),
            look: None,
            scanned_s: 0.0,
            started_s: None,
            last_s: 0.0,
            said_blind: false,
        }
    }

    /// Decisions made so far.
    pub fn decisions(&self) -> u64 {
        self.decisions
    }

    /// How the evaluative decisions' predicted landmark counts compared
    /// with what the camera then saw.
    pub fn prediction_check(&self) -> PredictionCheck {
        self.predictions.check
    }

    fn rules(&self, camera: &StereoCamera) -> DecisionRules {
        let c = &self.config;
        let [up_fov, down_fov] = camera.vertical_reach();
        DecisionRules {
            half_fov: camera.horizontal_fov() / 2.0,
            step_m: c.step_m,
            min_slant_m: c.min_slant_m,
            max_range_m: c.max_range_m,
            baseline_m: camera.baseline_m,
            min_stereo_range_m: camera.baseline_m / 2.0 / (c.max_stereo_viewpoint_deg.to_radians() / 2.0).tan(),
            min_landmarks: c.min_landmarks,
            camera_height_m: camera.mount.height,
            up_fov,
            down_fov,
        }
    }

    /// Whether the strip along the world `heading` is clear far enough.
    fn clear(&self, pose: &Pose2, heading: f64) -> bool {
        strip_clear(&self.config, self.echoes.points(), pose, heading)
    }

    /// The permitted headings around `centre`, centre first so that ties
    /// keep to the path: within the angle limits and clear of walls. The
    /// centre (the goal's bearing) is always a candidate.
    fn candidates(&self, pose: &Pose2, centre: f64) -> Vec<f64> {
        let n = (self.config.max_angle_deg / self.config.angle_step_deg).floor() as i32;
        let step = self.config.angle_step_deg.to_radians();
        let mut out = vec![centre];
        for k in 1..=n {
            for h in [centre + f64::from(k) * step, centre - f64::from(k) * step] {
                if self.clear(pose, h) {
                    out.push(h);
                }
            }
        }
        out
    }

    /// What the decision minimises for a robot heading `facing` with the
    /// goal at `goal_bearing`, `remaining_m` away.
    fn objective(&self, facing: f64, goal_bearing: f64, remaining_m: f64) -> Objective {
        match self.config.objective {
            DecisionObjective::Cv => Objective::Cv,
            DecisionObjective::EndPoint => Objective::EndPoint {
                heading: facing,
                goal_bearing,
                remaining_m,
                turn_tolerance: self.config.heading_tolerance_deg.to_radians(),
                costs: self.config.costs,
            },
        }
    }

    /// Chooses the heading from the tracking list for a robot at `pose`
    /// whose heading egomotion last fixed was `facing`; without a feasible
    /// heading, the goal's bearing `centre`.
    fn evaluate(&mut self, pose: &Pose2, facing: f64, centre: f64, remaining_m: f64) -> f64 {
        self.refresh_positions();
        let Some((camera, table)) = &self.camera else { return centre };
        let rules = self.rules(camera);
        let objective = self.objective(facing, centre, remaining_m);
        let candidates = self.candidates(pose, centre);
        let decision = best_heading(table, &rules, &self.positions, (pose.x, pose.y), candidates, &objective);
        self.predictions.predict(decision.map(|d| d.landmarks));
        decision.map_or(centre, |d| d.heading)
    }

    /// The confirmed landmarks of the tracking list, which has dropped those
    /// seen from too far round to be recognised from here.
    fn refresh_positions(&mut self) {
        self.positions.clear();
        self.positions.extend(self.list.confirmed().map(|l| [l.position.0, l.position.1, l.height]));
    }

    /// How the robot itself is steered: by the technique, except that with
    /// only the camera steered it drives straight at the goal.
    fn robot_technique(&self) -> Technique {
        match self.config.steer {
            Steer::Camera => Technique::None,
            Steer::Robot | Steer::Both => self.config.technique,
        }
    }

    /// Camera steering: where the camera should look from `pose` while the
    /// robot keeps on along `course`, among directions within `max_pan_deg`
    /// of the course and half the field of view of where it looks now, so
    /// that consecutive frames share half their view. Without a feasible
    /// look, the one nearest the course among them, or, with none in
    /// reach, half the field of view towards the course.
    ///
    /// A look turns nothing, so the objective can only weigh its view.
    /// Where egomotion takes odometry's sideways motion (and distance) in and
    /// leaves vision the turn (`sideways_fusion`), the look is the view of
    /// least step CV, whatever the objective and costs.
    /// The shipped costs' step term, fitted to zero on the robot's own
    /// paths, ties every look that keeps enough landmarks in view, so the
    /// camera looked ahead wherever it could, and ended 0.91–1.03× straight
    /// driving's end-point error on the training layouts (2121–2828, seeds
    /// 100–129, each layout family of `lab/scripts/aiding-families.sh`,
    /// default estimate); the view of least CV ended 0.73–0.90× in seven
    /// families of eight (feature-poor 0.97). Purely visual, the same looks
    /// ended 0.91–1.30×, worse than looking ahead in four families and
    /// better in two; with `Full` fusion (the turn from odometry too)
    /// 0.91–1.30×, where looking ahead ended 0.93–1.17× (worse in three
    /// families, better in three). There the
    /// configured objective decides, as for the robot.
    fn choose_look(&self, pose: &Pose2, course: f64, remaining_m: f64, sideways_fusion: bool) -> f64 {
        let Some((camera, table)) = &self.camera else { return course };
        let rules = self.rules(camera);
        let objective = if sideways_fusion { Objective::Cv } else { self.objective(course, course, remaining_m) };
        let now = self.look.unwrap_or(course);
        let (max_pan, reach) = (self.config.max_pan_deg.to_radians(), rules.half_fov);
        let step = self.config.angle_step_deg.to_radians();
        let n = (max_pan / step).floor() as i32;
        // The course first, so that ties look ahead.
        let looks = std::iter::once(0.0)
            .chain((1..=n).flat_map(move |k| [f64::from(k) * step, -f64::from(k) * step]))
            .map(move |pan| course + pan)
            .filter(move |look| angle_difference(*look, now).abs() <= reach);
        // With nothing feasible the camera still moves by at most `reach`:
        // a jump back to the course would leave the next frame nothing in
        // common with the last. (The end-point objective prices such looks
        // as the odometry bridge, all alike, and so takes the same one,
        // unless a landmark nearer than the slant limit rules out every
        // look.) Where the course has swung beyond every look in reach (a
        // turn with `Both`), the camera turns towards it by `reach`.
        let fallback = looks.clone().next().unwrap_or_else(|| now + angle_difference(course, now).clamp(-reach, reach));
        best_look(table, &rules, &self.positions, (pose.x, pose.y), course, looks, &objective)
            .map_or(fallback, |d| d.heading)
    }

    /// Whether a scan from `facing` through `edges` (world headings, the
    /// first leg's end first) and the turn back to about the goal's bearing
    /// `centre` stays within the scan budget: the time scans and turns
    /// will have taken against the time spent driving so far. Judged with
    /// the scan's predicted length (at the scan rate and the top turn
    /// rate), so that a scan the budget cannot pay for is not begun; the
    /// slow end of each leg, a turn to a heading beyond the goal's bearing
    /// or a stalled turn can still overrun it a little.
    fn may_scan(&self, time: f64, facing: f64, edges: [f64; 2], centre: f64) -> bool {
        let Some(share) = self.config.scan_budget else { return true };
        let c = &self.config;
        let sweep = angle_difference(edges[0], facing).abs() + angle_difference(edges[1], edges[0]).abs();
        let scan_s = sweep / c.scan_rate_deg.to_radians()
            + angle_difference(centre, edges[1]).abs() / c.max_turn_deg.to_radians();
        let driving_s = time - self.started_s.unwrap_or(time) - self.scanned_s;
        self.scanned_s + scan_s <= share * driving_s
    }

    fn turn_towards(&self, pose: &Pose2, heading: f64) -> f64 {
        let max = self.config.max_turn_deg.to_radians();
        (self.config.turn_gain * angle_difference(heading, pose.theta)).clamp(-max, max)
    }

    fn vote(&self, state: &State) -> f64 {
        let c = &self.config;
        match state.egomotion.last_step_cv {
            Some(cv) => c.vote_min + (c.vote_max - c.vote_min) * cv / (cv + c.vote_half_cv),
            None => c.vote_max,
        }
    }
}

impl Behavior for ActionAiding {
    fn gen_action(&mut self, state: &State) -> Action {
        let action = self.drive(state);
        match self.look {
            Some(look) if action.is_voting() && self.config.steer != Steer::Robot => {
                action.camera_pan(wrap_angle(look - state.pose.theta))
            }
            _ => action,
        }
    }

    fn name(&self) -> &str {
        "ActionAiding"
    }

    fn reset(&mut self) {
        self.phase = Phase::Decide;
        self.list.clear();
        self.look = None;
        self.zigzag.restart();
        self.last_frame = 0;
        self.decisions = 0;
        self.scanned_s = 0.0;
        self.started_s = None;
    }
}

impl ActionAiding {
    /// The robot's action this tick (the camera's direction is added by
    /// [`Behavior::gen_action`]).
    fn drive(&mut self, state: &State) -> Action {
        let Some(goal) = state.goal else { return Action::none() };
        if state.goal_reached() {
            return Action::none();
        }
        let pose = state.pose;
        let to_goal = (goal.y - pose.y).atan2(goal.x - pose.x);
        let distance = pose.distance_to(goal.x, goal.y);
        self.started_s.get_or_insert(state.time);
        // A scan's cost is the sweep and the turn on the spot to the heading
        // it chose: the time the robot stands instead of driving.
        if matches!(self.phase, Phase::Scan { .. } | Phase::Turn { .. }) {
            self.scanned_s += state.time - self.last_s;
        }
        self.last_s = state.time;
        let frame = &state.stereo;
        if frame.number != self.last_frame {
            self.last_frame = frame.number;
            if let Some(calibration) = &frame.calibration {
                if self.camera.is_none() {
                    let camera = *calibration;
                    let table = CvTable::for_camera(self.config.model, &camera, MODEL_STEP_M, self.config.max_range_m);
                    self.camera = Some((camera, table));
                }
                let scanning = matches!(self.phase, Phase::Scan { .. });
                let steering_camera = self.config.steer != Steer::Robot;
                if self.config.technique == Technique::Tracking || scanning || steering_camera {
                    self.list.observe(&frame.landmarks, calibration, &pose);
                }
                if matches!(self.phase, Phase::Step { .. }) {
                    self.predictions.saw(frame.landmarks.len());
                }
                if steering_camera {
                    let course = self.phase.course(to_goal, pose.theta);
                    self.list.prune(&pose);
                    self.refresh_positions();
                    self.look = Some(self.choose_look(&pose, course, distance, state.egomotion.sideways_fusion));
                }
            }
        }
        self.say_if_blind(state.time);
        self.echoes.update(state);
        let tick = Tick { pose, goal: (goal.x, goal.y), to_goal, distance, time: state.time, vote: self.vote(state) };
        // Three passes at most: a finished phase hands over within the tick
        // (a step to the decision, the decision to a turn or a scan).
        for _ in 0..3 {
            let phase = std::mem::replace(&mut self.phase, Phase::Decide);
            match self.next(phase, &tick) {
                Pass::Act(phase, action) => {
                    self.phase = phase;
                    return action;
                }
                Pass::Hand(phase) => self.phase = phase,
            }
        }
        Action::with_vote(tick.vote).velocity(0.0).rot_velocity(0.0)
    }

    /// Says, once, that no camera frame has come: without one, every aid
    /// drives straight at the goal, which a scenario whose robot has no
    /// camera would otherwise do without a word.
    fn say_if_blind(&mut self, time: f64) {
        let aiding = self.config.technique != Technique::None || self.config.steer != Steer::Robot;
        let waited = time - self.started_s.unwrap_or(time) >= BLIND_AFTER_S;
        if aiding && waited && self.camera.is_none() && !self.said_blind {
            self.said_blind = true;
            tracing::warn!(
                "ActionAiding: no stereo frame with its calibration in {BLIND_AFTER_S} s (has the robot a camera?); \
                 without one it drives straight at the goal"
            );
        }
    }

    /// One pass of the phase machine, and the only place a phase changes:
    /// what `phase` does with this tick, or the phase it hands over to.
    fn next(&mut self, phase: Phase, tick: &Tick) -> Pass {
        let Tick { pose, goal, to_goal, distance, time, vote } = *tick;
        let tolerance = self.config.heading_tolerance_deg.to_radians();
        match phase {
            Phase::Decide => {
                self.decisions += 1;
                self.predictions.settle();
                if self.config.technique == Technique::Tracking {
                    self.list.prune(&pose);
                }
                let technique = self.robot_technique();
                // The last stretch is straight at the goal: a zig-zag leg
                // would pass it by a lateral offset.
                let final_approach = match technique {
                    Technique::ZigZag => 2.0 * self.config.zigzag_max_offset_m,
                    _ => self.config.step_m,
                };
                if distance <= final_approach {
                    return Pass::Hand(Phase::approach());
                }
                let heading = match technique {
                    Technique::None => to_goal,
                    Technique::ZigZag => {
                        let (config, echoes) = (&self.config, self.echoes.points());
                        let (angle, max_offset) = (config.zigzag_angle_deg.to_radians(), config.zigzag_max_offset_m);
                        self.zigzag
                            .heading(&pose, goal, angle, max_offset, |leg| strip_clear(config, echoes, &pose, leg))
                    }
                    Technique::Tracking => self.evaluate(&pose, pose.theta, to_goal, distance),
                    Technique::Scan => {
                        // Sweep the allowable headings: within the angle
                        // limits and clear of walls.
                        let offsets = self.candidates(&pose, to_goal).into_iter().map(|h| h - to_goal);
                        let (low, high) = offsets.fold((0.0_f64, 0.0_f64), |(l, h), o| (l.min(o), h.max(o)));
                        let edges = [to_goal + high, to_goal + low];
                        if self.may_scan(time, pose.theta, edges, to_goal) {
                            self.list.clear();
                            return Pass::Hand(Phase::scan(edges, to_goal, pose.theta));
                        }
                        to_goal
                    }
                };
                Pass::Hand(Phase::turn(heading))
            }
            Phase::Scan { edges, leg, centre, from, mut watch } => {
                let error = angle_difference(edges[leg], pose.theta).abs();
                // A leg that cannot be finished is cut short: the scan has
                // seen what it could.
                if error > tolerance && !watch.stuck(time, error) {
                    let rate = self.config.scan_rate_deg.to_radians();
                    let w = self.turn_towards(&pose, edges[leg]).clamp(-rate, rate);
                    let phase = Phase::Scan { edges, leg, centre, from, watch };
                    return Pass::Act(phase, Action::with_vote(vote).velocity(0.0).rot_velocity(w));
                }
                if leg == 0 {
                    Pass::Hand(Phase::Scan { edges, leg: 1, centre, from, watch: ProgressWatch::new() })
                } else {
                    Pass::Hand(Phase::turn(self.evaluate(&pose, from, centre, distance)))
                }
            }
            Phase::Turn { heading, mut watch } => {
                let error = angle_difference(heading, pose.theta);
                if error.abs() > tolerance {
                    // Stuck the short way round: less than a quarter turn
                    // from the heading, steer while driving, as a go-to
                    // beside collision avoidance does (a full revolution to
                    // close a few degrees would fail every frame on the
                    // way); further, try the long way, and stuck that way
                    // too, steer while driving.
                    if watch.stuck(time, watch.angle_left(error)) {
                        if watch.long_way.is_some() || error.abs() < std::f64::consts::FRAC_PI_2 {
                            return Pass::Hand(Phase::step(heading, (pose.x, pose.y)));
                        }
                        watch.long_way = Some(-error.signum());
                    }
                    let w = watch
                        .long_way_rate(error, self.config.max_turn_deg.to_radians())
                        .unwrap_or_else(|| self.turn_towards(&pose, heading));
                    let phase = Phase::Turn { heading, watch };
                    return Pass::Act(phase, Action::with_vote(vote).velocity(0.0).rot_velocity(w));
                }
                Pass::Hand(Phase::step(heading, (pose.x, pose.y)))
            }
            Phase::Step { heading, from, mut watch } => {
                let left = 1.0 - pose.distance_to(from.0, from.1) / self.config.step_m;
                // A step that gets nowhere is over: decide again from where
                // the robot is.
                if left <= 0.0 || watch.stuck(time, left) {
                    return Pass::Hand(Phase::Decide);
                }
                let action =
                    Action::with_vote(vote).velocity(self.config.speed).rot_velocity(self.turn_towards(&pose, heading));
                Pass::Act(Phase::Step { heading, from, watch }, action)
            }
            Phase::Approach { mut watch } => {
                let error = angle_difference(to_goal, pose.theta);
                // Progress is turning towards the goal or closing on it (a
                // step's length counting as a radian). Blocked (by
                // collision avoidance turning the other way at a wall,
                // say), go the long way round, which turns away from the
                // obstacle too; blocked that way, the short way.
                let remaining = watch.angle_left(error) + distance / self.config.step_m;
                if watch.stuck(time, remaining) {
                    watch.long_way = match watch.long_way {
                        None => Some(-error.signum()),
                        Some(_) => None,
                    };
                }
                let action = match watch.long_way_rate(error, self.config.max_turn_deg.to_radians()) {
                    Some(w) => Action::with_vote(vote).velocity(0.0).rot_velocity(w),
                    None => {
                        // Facing away from the goal, turn on the spot; near
                        // it, slow in proportion to the distance, so that
                        // the turn rate always outpaces the goal's bearing
                        // and the robot cannot orbit it.
                        let alignment = error.cos().max(0.0);
                        let ramp = (distance / self.config.step_m).min(1.0);
                        Action::with_vote(vote)
                            .velocity(self.config.speed * alignment * ramp)
                            .rot_velocity(self.turn_towards(&pose, to_goal))
                    }
                };
                Pass::Act(Phase::Approach { watch }, action)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::progress::STUCK_S;
    use super::*;
    use ubf_core::Goal;

    fn state(step_cv: Option<f64>) -> State {
        let mut s = State { goal: Some(Goal { x: 10.0, y: 0.0, tolerance: 0.2 }), ..State::default() };
        s.egomotion.last_step_cv = step_cv;
        s
    }

    #[test]
    fn the_vote_rises_with_the_last_step_cv() {
        let mut aa = ActionAiding::new(ActionAidingConfig::with_technique(Technique::None), &BuildContext::new(0));
        let low = aa.gen_action(&state(Some(0.05))).vote;
        let mid = aa.gen_action(&state(Some(0.5))).vote;
        let high = aa.gen_action(&state(Some(5.0))).vote;
        assert!(0.3 < low && low < mid && mid < high && high < 1.0, "{low} {mid} {high}");
        assert!((mid - 0.65).abs() < 1e-12, "halfway at vote_half_cv");
        // Without egomotion it bids its most.
        assert_eq!(aa.gen_action(&state(None)).vote, 1.0);
    }

    #[test]
    fn silent_without_a_goal_or_at_it() {
        let mut aa = ActionAiding::new(ActionAidingConfig::with_technique(Technique::Tracking), &BuildContext::new(0));
        assert!(!aa.gen_action(&State::default()).is_voting());
        let mut at_goal = state(None);
        at_goal.pose = Pose2::new(10.0, 0.1, 0.0);
        assert!(!aa.gen_action(&at_goal).is_voting());
    }

    #[test]
    fn no_aiding_turns_towards_the_goal_then_steps() {
        let mut aa = ActionAiding::new(ActionAidingConfig::with_technique(Technique::None), &BuildContext::new(0));
        let mut s = state(None);
        s.goal = Some(Goal { x: 0.0, y: 10.0, tolerance: 0.2 });
        let turning = aa.gen_action(&s);
        assert_eq!(turning.motion.velocity, Some(0.0));
        assert!(turning.motion.rot_velocity.unwrap() > 0.0);
        s.pose = Pose2::new(0.0, 0.0, std::f64::consts::FRAC_PI_2);
        let stepping = aa.gen_action(&s);
        assert_eq!(stepping.motion.velocity, Some(0.6));
        assert_eq!(aa.decisions(), 1);
    }

    /// Camera steering with a camera and a tracking list already set up,
    /// looking `look_deg` off a course along +x.
    fn steering_camera(landmarks: &[[f64; 3]], look_deg: f64) -> ActionAiding {
        let config =
            ActionAidingConfig { steer: Steer::Camera, ..ActionAidingConfig::with_technique(Technique::Tracking) };
        let mut aa = ActionAiding::new(config, &BuildContext::new(0));
        let camera = StereoCamera::default();
        let table = CvTable::for_camera(aa.config.model, &camera, MODEL_STEP_M, aa.config.max_range_m);
        aa.camera = Some((camera, table));
        aa.positions = landmarks.to_vec();
        aa.look = Some(look_deg.to_radians());
        aa
    }

    #[test]
    fn with_sideways_fusion_the_camera_looks_for_the_view_of_least_cv() {
        // A few far landmarks ahead, enough for a step, and a cluster of
        // near ones 40° to the left. The shipped costs weigh no view, so
        // alone they keep the camera ahead; with odometry's sideways motion
        // fused the look goes to the better view.
        let height = StereoCamera::default().mount.height;
        let mut landmarks: Vec<[f64; 3]> = (0..5).map(|i| [40.0, f64::from(i) - 2.0, height]).collect();
        landmarks.extend((0..8).map(|i| [6.0 + 0.5 * f64::from(i), 6.0 + 0.4 * f64::from(i), height]));
        let mut aa = steering_camera(&landmarks, 0.0);
        let pose = Pose2::new(0.0, 0.0, 0.0);
        assert_eq!(aa.choose_look(&pose, 0.0, 30.0, false), 0.0);
        let fused = aa.choose_look(&pose, 0.0, 30.0, true).to_degrees();
        assert!(fused > 10.0, "with sideways fusion the camera looked {fused:.1}° off");
        // Purely visual, costs that weigh the view decide as they say.
        aa.config.costs = crate::decision::DecisionCosts::levels();
        assert_eq!(aa.choose_look(&pose, 0.0, 30.0, false).to_degrees(), fused);
    }

    #[test]
    fn with_nothing_in_view_the_camera_turns_back_no_more_than_half_its_view() {
        // Looking 80° aside with no landmark anywhere: the camera turns
        // back towards the course by half its field of view (to the first
        // candidate angle within it), so consecutive frames still overlap,
        // under either objective. Looking 170° off, beyond every candidate
        // (`max_pan_deg` 90), it turns back by half its view all the same.
        let mut aa = steering_camera(&[], 80.0);
        let reach = StereoCamera::default().horizontal_fov().to_degrees() / 2.0;
        let step = aa.config.angle_step_deg;
        let pose = Pose2::new(0.0, 0.0, 0.0);
        for fused in [false, true] {
            let look = aa.choose_look(&pose, 0.0, 30.0, fused).to_degrees();
            assert!(
                (80.0 - reach - 1e-9..=80.0 - reach + step).contains(&look),
                "fused {fused}: looked {look:.1}° off"
            );
        }
        aa.look = Some(170f64.to_radians());
        let look = aa.choose_look(&pose, 0.0, 30.0, true).to_degrees();
        assert!((look - (170.0 - reach)).abs() < 1e-9, "from 170° it looked {look:.1}° off");
    }

    #[test]
    fn a_blocked_turn_goes_the_long_way_round_without_rocking_at_180_degrees() {
        let mut aa = ActionAiding::new(ActionAidingConfig::with_technique(Technique::None), &BuildContext::new(0));
        // The goal is behind and a little to the left: the short way is
        // counter-clockwise.
        let mut s = state(None);
        s.goal = Some(Goal { x: -10.0, y: 1.0, tolerance: 0.2 });
        let first = aa.gen_action(&s).motion.rot_velocity.unwrap();
        assert!(first > 0.0);
        // Held still for longer than a stuck turn is given: the long way,
        // clockwise.
        s.time = STUCK_S + 1.0;
        assert!(aa.gen_action(&s).motion.rot_velocity.unwrap() < 0.0);
        // Turning clockwise, the heading error grows past 180° and wraps;
        // the turn keeps its direction through it and on to the heading.
        let goal_bearing = (1.0_f64).atan2(-10.0);
        for (i, theta) in
            [-0.5_f64, -1.5, -2.5, -3.0, goal_bearing - std::f64::consts::TAU + 0.3].into_iter().enumerate()
        {
            s.time = STUCK_S + 1.5 + i as f64;
            s.pose = Pose2::new(0.0, 0.0, theta);
            let w = aa.gen_action(&s).motion.rot_velocity.unwrap();
            assert!(w < 0.0, "at {theta} rad the turn went {w} rad/s");
        }
    }
}
