//! The settings of [`ActionAiding`](super::ActionAiding) as a scenario
//! file gives them, and their description for `ubf behaviors --describe`.

use crate::decision::DecisionCosts;
use crate::tracking::TrackingConfig;
use serde::{Deserialize, Serialize};
use ubf_core::config::{non_negative, number_in, optional_non_negative, positive};
use ubf_perception::error_model::{ErrorModelKind, MODEL_STEP_M};

/// How the heading of each step is chosen (thesis §3.4).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Technique {
    /// No aiding: straight at the goal.
    None,
    /// Non-evaluative: ±`zigzag_angle_deg` off the path's centre line,
    /// alternating at turning points that ignore the landmarks.
    ZigZag,
    /// Evaluative with a physical scan: before every step the robot turns
    /// through the permitted angles, looks, and takes the best heading.
    Scan,
    /// Evaluative over the landmark tracking list: the same evaluation in
    /// software, over the landmarks seen so far and still recognisable.
    /// With the shipped costs, whose step term is fitted to zero (no step
    /// model measured predicts which views leave less error), it drives
    /// straight at the goal and turns only where the view along the goal's
    /// bearing would keep fewer than `min_landmarks` landmarks and a turn
    /// costs less than bridging by odometry: on the routes measured, in
    /// the last few metres of some runs. It does not seek landmarks out.
    Tracking,
}

impl Technique {
    /// The name used in experiment output.
    pub fn name(self) -> &'static str {
        match self {
            Technique::None => "none",
            Technique::ZigZag => "zigzag",
            Technique::Scan => "scan",
            Technique::Tracking => "tracking",
        }
    }
}

/// What the evaluative techniques minimise when they choose a heading.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum DecisionObjective {
    /// The predicted end-point variance: the step's translation variance
    /// plus the heading variance of the turn (now and back to the goal
    /// bearing) times the remaining distance squared. Driving straight at
    /// the goal is always a candidate, so it is chosen when nothing beats it.
    #[default]
    EndPoint,
    /// The thesis's objective (§3.5.2.2): the step's fused CV alone, turns
    /// free. For thesis-faithful runs.
    Cv,
}

/// What action aiding steers to put landmarks where egomotion is least
/// uncertain.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Steer {
    /// The robot, by its technique; the camera looks ahead.
    #[default]
    Robot,
    /// A camera on a pan-tilt unit, chosen at every frame by the evaluative
    /// decision over the tracking list, while the robot drives straight at
    /// the goal (the technique does not turn it). The unit's angle is read
    /// far more precisely than a turn of the robot is estimated (thesis
    /// §5.3.4). Where egomotion fuses odometry's sideways motion (its
    /// default, `Sideways`) the camera looks for the view of least step CV;
    /// otherwise (purely visual, or `Full` fusion) the objective decides,
    /// which with the shipped costs looks ahead unless too few landmarks
    /// are there.
    Camera,
    /// Both: the technique turns the robot, and the camera looks where the
    /// decision says from the heading the robot takes, by the same rule as
    /// `Camera` (with `Both` that rule is not measured).
    Both,
}

/// Settings of [`ActionAiding`](super::ActionAiding), as written in a scenario file.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ActionAidingConfig {
    /// The technique.
    pub technique: Technique,
    /// Length of each translation step between decisions, m. The default is
    /// the error model's step.
    #[serde(default = "ActionAidingConfig::default_step", deserialize_with = "step_m")]
    pub step_m: f64,
    /// Permitted headings: up to this far either side of the bearing to the
    /// goal, °.
    #[serde(default = "ActionAidingConfig::default_max_angle", deserialize_with = "half_turn_deg")]
    pub max_angle_deg: f64,
    /// Spacing of the candidate headings, °.
    #[serde(default = "ActionAidingConfig::default_angle_step", deserialize_with = "angle_step_deg")]
    pub angle_step_deg: f64,
    /// Zig-zag: angle off the centre line, ° (the thesis: 20°).
    #[serde(default = "ActionAidingConfig::default_zigzag_angle", deserialize_with = "positive")]
    pub zigzag_angle_deg: f64,
    /// Zig-zag: the largest distance from the centre line at which it turns
    /// back, m; each leg turns at a random share (50–100 %) of it.
    #[serde(default = "ActionAidingConfig::default_zigzag_offset", deserialize_with = "positive")]
    pub zigzag_max_offset_m: f64,
    /// A landmark nearer than this to the projected position rejects the
    /// heading, m (the thesis: 0.5 m).
    #[serde(default = "ActionAidingConfig::default_min_slant", deserialize_with = "non_negative")]
    pub min_slant_m: f64,
    /// Landmarks farther than this are not counted, m.
    #[serde(default = "ActionAidingConfig::default_max_range", deserialize_with = "max_range_m")]
    pub max_range_m: f64,
    /// Forward speed during a step, m/s.
    #[serde(default = "ActionAidingConfig::default_speed", deserialize_with = "positive")]
    pub speed: f64,
    /// Turn rate while scanning, °/s: slow enough for the camera to look.
    #[serde(default = "ActionAidingConfig::default_scan_rate", deserialize_with = "positive")]
    pub scan_rate_deg: f64,
    /// Scan: the most time the robot may spend turning on the spot (the
    /// scans' sweeps and every turn to a heading), as a share of the time
    /// spent driving since the start. A decision that finds the budget spent drives on at the goal
    /// without scanning, so a run takes about `1 + scan_budget` times as
    /// long as driving straight. `None` scans before every step, as the
    /// thesis did (about 5 times as long on its routes).
    #[serde(default, deserialize_with = "optional_non_negative")]
    pub scan_budget: Option<f64>,
    /// Heading error under which a turn counts as done, °.
    #[serde(default = "ActionAidingConfig::default_tolerance", deserialize_with = "positive")]
    pub heading_tolerance_deg: f64,
    /// Turn rate per radian of heading error, 1/s.
    #[serde(default = "ActionAidingConfig::default_turn_gain", deserialize_with = "positive")]
    pub turn_gain: f64,
    /// Largest turn rate asked for, °/s.
    #[serde(default = "ActionAidingConfig::default_max_turn", deserialize_with = "positive")]
    pub max_turn_deg: f64,
    /// A heading is permitted only if the range sensors show its swept strip
    /// clear for this far, m: the robot keeps off walls that carry no
    /// landmark (thesis §4.4.10.5). 0 turns the check off.
    #[serde(default = "ActionAidingConfig::default_clearance", deserialize_with = "non_negative")]
    pub clearance_m: f64,
    /// Half the width of that strip, m (the Powerbot's 0.34 m and a margin).
    #[serde(default = "ActionAidingConfig::default_half_width", deserialize_with = "positive")]
    pub path_half_width: f64,
    /// What a heading is chosen to minimise.
    #[serde(default)]
    pub objective: DecisionObjective,
    /// Egomotion's error coefficients, for the end-point objective.
    #[serde(default)]
    pub costs: DecisionCosts,
    /// Landmarks a heading must keep in view: the estimator's minimum and a
    /// margin (the rigid estimator needs three consistent ones, or two with
    /// odometry fused in).
    #[serde(default = "ActionAidingConfig::default_min_landmarks")]
    pub min_landmarks: usize,
    /// Largest angle between the two cameras' lines of sight at a landmark
    /// for stereo matching, ° (thesis §4.4.10.3); nearer landmarks are not
    /// counted.
    #[serde(default = "ActionAidingConfig::default_stereo_viewpoint", deserialize_with = "positive")]
    pub max_stereo_viewpoint_deg: f64,
    /// The error model used to evaluate headings.
    #[serde(default)]
    pub model: ErrorModelKind,
    /// The landmark tracking list.
    #[serde(default)]
    pub tracking: TrackingConfig,
    /// Vote with egomotion certain (step CV near 0).
    #[serde(default = "ActionAidingConfig::default_vote_min", deserialize_with = "non_negative")]
    pub vote_min: f64,
    /// Vote as the step CV grows without bound.
    #[serde(default = "ActionAidingConfig::default_vote_max", deserialize_with = "non_negative")]
    pub vote_max: f64,
    /// The step CV at which the vote is halfway between the two.
    #[serde(default = "ActionAidingConfig::default_vote_cv", deserialize_with = "positive")]
    pub vote_half_cv: f64,
    /// What is steered: the robot, a camera on a pan-tilt unit, or both.
    #[serde(default)]
    pub steer: Steer,
    /// Camera steering: the farthest the camera looks either side of the
    /// robot's heading, °.
    #[serde(default = "ActionAidingConfig::default_max_pan", deserialize_with = "half_turn_deg")]
    pub max_pan_deg: f64,
}

// Bounds that keep the work a decision does finite: the candidates it
// weighs (headings, views) and the error model's table it reads.

/// A step between decisions, m: 1 cm to 100 m.
fn step_m<'de, D: serde::Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    number_in(d, 0.01..=100.0, "from 0.01 to 100 m")
}

/// An angle either side of a direction, °: > 0 and at most 180.
fn half_turn_deg<'de, D: serde::Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    number_in(d, f64::MIN_POSITIVE..=180.0, "> 0 and at most 180°")
}

/// The spacing of candidate headings, °: 0.1 to 180.
fn angle_step_deg<'de, D: serde::Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    number_in(d, 0.1..=180.0, "from 0.1 to 180°")
}

/// The farthest landmark counted, m: > 0 and at most 1 km.
fn max_range_m<'de, D: serde::Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    number_in(d, f64::MIN_POSITIVE..=1000.0, "> 0 and at most 1000 m")
}

impl ActionAidingConfig {
    fn default_step() -> f64 {
        MODEL_STEP_M
    }
    fn default_max_angle() -> f64 {
        45.0
    }
    fn default_angle_step() -> f64 {
        2.5
    }
    fn default_zigzag_angle() -> f64 {
        20.0
    }
    fn default_zigzag_offset() -> f64 {
        2.0
    }
    fn default_min_slant() -> f64 {
        0.5
    }
    fn default_max_range() -> f64 {
        80.0
    }
    fn default_clearance() -> f64 {
        2.0
    }
    fn default_half_width() -> f64 {
        0.5
    }
    fn default_speed() -> f64 {
        0.6
    }
    fn default_scan_rate() -> f64 {
        30.0
    }
    fn default_tolerance() -> f64 {
        2.0
    }
    fn default_turn_gain() -> f64 {
        2.0
    }
    fn default_max_turn() -> f64 {
        // At the thesis's 2 Hz, 10° between frames keeps most of a 60° view
        // in both.
        20.0
    }
    fn default_min_landmarks() -> usize {
        4
    }
    fn default_stereo_viewpoint() -> f64 {
        30.0
    }
    fn default_vote_min() -> f64 {
        0.3
    }
    fn default_vote_max() -> f64 {
        1.0
    }
    fn default_vote_cv() -> f64 {
        0.5
    }
    fn default_max_pan() -> f64 {
        90.0
    }

    /// The defaults with this technique.
    pub fn with_technique(technique: Technique) -> Self {
        ActionAidingConfig {
            technique,
            step_m: Self::default_step(),
            max_angle_deg: Self::default_max_angle(),
            angle_step_deg: Self::default_angle_step(),
            zigzag_angle_deg: Self::default_zigzag_angle(),
            zigzag_max_offset_m: Self::default_zigzag_offset(),
            min_slant_m: Self::default_min_slant(),
            max_range_m: Self::default_max_range(),
            clearance_m: Self::default_clearance(),
            path_half_width: Self::default_half_width(),
            speed: Self::default_speed(),
            scan_rate_deg: Self::default_scan_rate(),
            scan_budget: None,
            heading_tolerance_deg: Self::default_tolerance(),
            turn_gain: Self::default_turn_gain(),
            max_turn_deg: Self::default_max_turn(),
            objective: DecisionObjective::default(),
            costs: DecisionCosts::default(),
            min_landmarks: Self::default_min_landmarks(),
            max_stereo_viewpoint_deg: Self::default_stereo_viewpoint(),
            model: ErrorModelKind::default(),
            tracking: TrackingConfig::default(),
            vote_min: Self::default_vote_min(),
            vote_max: Self::default_vote_max(),
            vote_half_cv: Self::default_vote_cv(),
            steer: Steer::default(),
            max_pan_deg: Self::default_max_pan(),
        }
    }
}

impl ubf_core::Describe for ActionAidingConfig {
    fn fields() -> Vec<ubf_core::Field> {
        use ubf_core::Field;
        vec![
            Field::new(
                "technique",
                "technique",
                "",
                "required",
                "",
                "`None` (straight at the goal), `ZigZag`, `Scan` (physical scan before every step, or within \
                 `scan_budget`), `Tracking` (evaluation over the landmark tracking list; with the shipped costs it \
                 drives straight unless the view ahead would keep fewer than `min_landmarks`, so it rarely turns)",
            ),
            Field::new("step_m", "number", "m", "1.0", "0.01 to 100", "step between decisions (the error model's step)"),
            Field::new(
                "max_angle_deg",
                "number",
                "°",
                "45",
                "> 0, ≤ 180",
                "permitted headings either side of the goal's bearing",
            ),
            Field::new("angle_step_deg", "number", "°", "2.5", "0.1 to 180", "spacing of the candidate headings"),
            Field::new(
                "zigzag_angle_deg",
                "number",
                "°",
                "20",
                "> 0",
                "zig-zag angle off the centre line (the thesis's)",
            ),
            Field::new(
                "zigzag_max_offset_m",
                "number",
                "m",
                "2.0",
                "> 0",
                "largest offset from the centre line; each leg turns at a random 50–100 % of it",
            ),
            Field::new(
                "min_slant_m",
                "number",
                "m",
                "0.5",
                "≥ 0",
                "a landmark nearer than this to the projected position rejects the heading (§3.5.2.2)",
            ),
            Field::new("max_range_m", "number", "m", "80", "> 0, ≤ 1000", "landmarks farther than this are not counted"),
            Field::new(
                "clearance_m",
                "number",
                "m",
                "2.0",
                "≥ 0",
                "a heading's swept strip must be clear of sonar echoes this far (§4.4.10.5); 0 turns the check off",
            ),
            Field::new("path_half_width", "number", "m", "0.5", "> 0", "half that strip"),
            Field::new("speed", "number", "m/s", "0.6", "> 0", "forward speed during a step"),
            Field::new("scan_rate_deg", "number", "°/s", "30", "> 0", "turn rate during a physical scan"),
            Field::new(
                "scan_budget",
                "number",
                "",
                "None",
                "≥ 0",
                "the most time the robot may spend turning on the spot (scans and turns to headings), as a share of \
                 the time driving; once spent, a decision drives on at the goal without scanning (`None`: scan \
                 before every step, the thesis's)",
            ),
            Field::new("heading_tolerance_deg", "number", "°", "2", "> 0", "a turn counts as done within this"),
            Field::new("turn_gain", "number", "1/s", "2.0", "> 0", "turn rate per radian of heading error"),
            Field::new("max_turn_deg", "number", "°/s", "20", "> 0", "largest turn rate: at 2 Hz, 10° between frames"),
            Field::new(
                "objective",
                "objective",
                "",
                "EndPoint",
                "",
                "what the evaluative techniques minimise: `EndPoint`, the predicted end-point variance (the step's \
                 translation variance plus the heading variance of the turn now and back to the goal bearing, times \
                 the remaining distance squared; the goal bearing is always a candidate, so the robot drives straight \
                 unless turning pays, and with too few landmarks predicted there it costs the odometry bridge's \
                 heading drift instead), or `Cv`, the thesis's step CV with turns free; a steered camera's look \
                 takes `Cv` with egomotion's `odometry_fusion: Sideways` (see `steer`)",
            ),
            Field::new(
                "costs",
                "costs",
                "",
                "(step_sigma_per_cv: 0.0, heading_var_per_rad: 1.44e-5, heading_var_per_turn: 0.0, \
                 bridge_heading_var_per_m: 1.15e-5)",
                "each ≥ 0",
                "the end-point objective's coefficients, measured: as `ubf model fit-costs --against` fits them from \
                 run logs, each run against a straight run of the same route and seed (`lab/scripts/fit-costs.sh`; on the \
                 thesis routes the steps' CVs did not tell which path ends nearer, so the step term is 0 and the \
                 robot turns only where the goal bearing would leave egomotion too few landmarks); a turn within `heading_tolerance_deg` is steered while driving and costs no \
                 turn; `bridge_heading_var_per_m` is the heading variance a metre on the odometry bridge adds",
            ),
            Field::new(
                "min_landmarks",
                "whole number",
                "",
                "4",
                "",
                "a heading must keep at least this many landmarks predicted in both images, within range and beyond \
                 the stereo-matching distance; fewer and egomotion's steps fail or lean on odometry (under `EndPoint` the goal bearing \
                 stays, at the odometry bridge's cost)",
            ),
            Field::new(
                "max_stereo_viewpoint_deg",
                "number",
                "°",
                "30",
                "> 0",
                "nearer than where the two cameras' lines of sight differ by this, a landmark is not counted \
                 (§4.4.10.3)",
            ),
            Field::new(
                "model",
                "error model",
                "",
                "Geometric",
                "",
                "error model for evaluating headings: `Geometric` (eq. 16–23), `Geometric3d` (the same in both image \
                 axes: landmarks above or below the cameras move in rows too, §5.3.1), `FittedExponential`, \
                 `FittedExponential3d` (eq. 24 fitted to those two) or `Exponential(alpha: .., beta: .., gamma: .., \
                 delta: ..)`",
            ),
            Field::new(
                "tracking",
                "tracking list",
                "",
                "(matching: (max_distance: 64, ratio: 0.8), gate_m: 0.5, gate_per_m: 0.05, drop_viewpoint_deg: 20)",
                "",
                "the landmark tracking list, below",
            ),
            Field::new("vote_min", "number", "", "0.3", "≥ 0", "vote with egomotion certain (step CV near 0)"),
            Field::new("vote_max", "number", "", "1.0", "≥ 0", "vote as the step CV grows without bound"),
            Field::new("vote_half_cv", "number", "", "0.5", "> 0", "the step CV at which the vote is halfway between"),
            Field::new(
                "steer",
                "steer",
                "",
                "Robot",
                "",
                "what is steered: `Robot` (by the technique), `Camera` (a camera on a pan-tilt unit, chosen every \
                 frame by the evaluative decision, while the robot drives straight at the goal: with egomotion's \
                 `odometry_fusion: Sideways`, the default (with the rigid estimator and the gate's `noise`, as \
                 fusion needs), towards the view of least step CV, whatever `objective` and `costs` say; \
                 otherwise by `objective`, which with the shipped costs looks ahead unless too few \
                 landmarks are there) or `Both` (the technique turns the robot, the camera looks by the same rule, not measured with `Both`)",
            ),
            Field::new(
                "max_pan_deg",
                "number",
                "°",
                "90",
                "> 0, ≤ 180",
                "camera steering: the farthest the camera looks either side of the heading",
            ),
        ]
    }
}
