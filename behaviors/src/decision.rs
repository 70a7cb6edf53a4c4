//! The evaluative decision engine (thesis §3.5.2.2, eq. 38–48): which
//! heading puts the known landmarks where egomotion is least uncertain, and
//! whether turning to it is worth what the turn costs.

use serde::Deserialize;
use ubf_core::config::non_negative;
use ubf_core::{angle_difference, Pose2};
use ubf_perception::error_model::{CvTable, HeightFactor};

/// What the engine needs to know of the camera and the rules.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DecisionRules {
    /// Half the horizontal field of view, rad.
    pub half_fov: f64,
    /// The step the robot is projected ahead by, m (eq. 40–43).
    pub step_m: f64,
    /// A landmark nearer than this from the projected position means an
    /// obstacle: the heading is rejected, m.
    pub min_slant_m: f64,
    /// Landmarks farther than this are not seen, m.
    pub max_range_m: f64,
    /// The distance between the cameras: a landmark counts only if it is
    /// in both images, m.
    pub baseline_m: f64,
    /// Nearer than this, the two cameras see a landmark from too different
    /// directions for their descriptors to match (thesis §4.4.10.3), m.
    pub min_stereo_range_m: f64,
    /// Fewer landmarks in view than this and egomotion's steps fail or lean
    /// on odometry: the heading is infeasible.
    pub min_landmarks: usize,
    /// The cameras' height above the floor, m: landmarks' heights are
    /// measured from it.
    pub camera_height_m: f64,
    /// How far above and below the optical axis the images reach, rad: a
    /// landmark must fall in the images' rows too.
    pub up_fov: f64,
    /// As above, below the axis, rad.
    pub down_fov: f64,
}

/// The error coefficients of egomotion the end-point objective weighs,
/// measured from run logs by `ubf model fit-costs`. The defaults are what
/// choosing a path changes, fitted to each run's difference from a straight
/// run of the same route and seed; [`DecisionCosts::levels`] are what
/// predicts how large a run's error will be.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct DecisionCosts {
    /// Translation error σ of a step per unit of its fused CV and metre
    /// driven, m.
    #[serde(default = "DecisionCosts::default_step_sigma", deserialize_with = "non_negative")]
    pub step_sigma_per_cv: f64,
    /// Heading variance a turn leaves behind, per radian turned, rad².
    #[serde(default = "DecisionCosts::default_heading_var", deserialize_with = "non_negative")]
    pub heading_var_per_rad: f64,
    /// Heading variance any turn leaves behind, however small, rad².
    #[serde(default = "DecisionCosts::default_turn_var", deserialize_with = "non_negative")]
    pub heading_var_per_turn: f64,
    /// Heading variance a metre driven on the odometry bridge (egomotion
    /// failing) adds, rad²/m: what driving straight at the goal costs where
    /// too few landmarks are predicted in view.
    #[serde(default = "DecisionCosts::default_bridge_var", deserialize_with = "non_negative")]
    pub bridge_heading_var_per_m: f64,
}

// Each field's default is its own function, not `#[serde(default)]` on the
// struct: serde builds a struct's whole default before it reads a field, and
// this default comes from the built-in file being read, which would then
// wait on itself.
impl DecisionCosts {
    fn default_step_sigma() -> f64 {
        DecisionCosts::default().step_sigma_per_cv
    }
    fn default_heading_var() -> f64 {
        DecisionCosts::default().heading_var_per_rad
    }
    fn default_turn_var() -> f64 {
        DecisionCosts::default().heading_var_per_turn
    }
    fn default_bridge_var() -> f64 {
        DecisionCosts::default().bridge_heading_var_per_m
    }

    /// The predicted end-point variance of a step whose landmarks fuse to
    /// `cv`, taken after turning on the spot by `turns` (now, and back to
    /// the goal bearing later), with `remaining_m` still to go: the step's
    /// own translation variance, plus the heading variance the turns leave,
    /// carried over the remaining distance.
    pub fn end_point_variance(&self, cv: f64, step_m: f64, turns: [f64; 2], remaining_m: f64) -> f64 {
        let step = (self.step_sigma_per_cv * cv * step_m).powi(2);
        step + self.turns_variance(turns) * remaining_m * remaining_m
    }

    /// The heading variance a turn of `turned` rad leaves, rad².
    pub fn turn_variance(&self, turned: f64) -> f64 {
        self.heading_var_per_turn + self.heading_var_per_rad * turned
    }

    /// The predicted end-point variance of a step of `step_m` driven on the
    /// odometry bridge, taken after turning by `turns`, with `remaining_m`
    /// still to go: the heading variance the bridge and the turns leave,
    /// carried over the remaining distance (the bridge's own translation
    /// error over a step is far smaller and left out).
    pub fn bridged_variance(&self, step_m: f64, turns: [f64; 2], remaining_m: f64) -> f64 {
        (self.turns_variance(turns) + self.bridge_heading_var_per_m * step_m) * remaining_m * remaining_m
    }

    /// The heading variance `turns` (0 for none) leave, rad².
    fn turns_variance(&self, turns: [f64; 2]) -> f64 {
        turns.iter().filter(|t| **t > 0.0).map(|t| self.turn_variance(*t)).sum()
    }
}

/// The decision's coefficients as the lab's fit wrote them
/// (`decision_costs.ron`, beside this file): what choosing a path changes
/// (`against_straight`), and what predicts an error's size (`levels`).
#[derive(Clone, Debug, PartialEq, Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct FittedCosts {
    /// Fitted to each run's difference from a straight run of the same
    /// route and seed: the decision's defaults.
    pub against_straight: Fitted,
    /// Fitted to the end points as they are.
    pub levels: Fitted,
}

/// Coefficients, and how they were fitted.
#[derive(Clone, Debug, PartialEq, Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct Fitted {
    /// The command that fitted them, on which runs.
    pub by: String,
    /// The coefficients.
    pub costs: DecisionCosts,
}

/// The file the fit writes, built in.
const FITTED_COSTS: &str = include_str!("decision_costs.ron");

/// What a file of fitted coefficients says before its data.
const FITTED_COSTS_HEADER: &str = "// The end-point decision's egomotion error coefficients, as the lab fits\n\
// them: written by `ubf model fit-costs LOGS --write FILE` (with --against,\n\
// the `against_straight` part; without, `levels`), read by the decision\n\
// (behaviors/src/decision.rs); docs/results.md gives the runs. Edit by\n\
// re-running the fit, not by hand.\n";

impl FittedCosts {
    /// The coefficients built in (`decision_costs.ron`).
    pub fn built_in() -> &'static FittedCosts {
        static FITTED: std::sync::LazyLock<FittedCosts> = std::sync::LazyLock::new(|| {
            FittedCosts::parse(FITTED_COSTS).expect("decision_costs.ron is a FittedCosts (a test reads it)")
        });
        &FITTED
    }

    /// Reads a file the fit wrote.
    pub fn parse(text: &str) -> Result<FittedCosts, ubf_core::config::RonError> {
        ubf_core::config::from_ron(text)
    }

    /// The file for these coefficients.
    pub fn to_file(&self) -> String {
        let config = ron::ser::PrettyConfig::new().struct_names(true);
        let data = ron::ser::to_string_pretty(self, config).expect("coefficients always serialise");
        format!("{FITTED_COSTS_HEADER}{data}\n")
    }
}

impl Default for DecisionCosts {
    /// What choosing a path changes, as fitted ([`FittedCosts`]).
    fn default() -> Self {
        FittedCosts::built_in().against_straight.costs
    }
}

impl DecisionCosts {
    /// The coefficients fitted to the same runs' end points as they are
    /// (`ubf model fit-costs` without `--against`): across routes, the
    /// steps' CVs do go with the error (a route whose landmarks are far
    /// has both larger), so these predict how large a run's error will be,
    /// for reporting beside the actual error, though not which of two paths
    /// through the same place ends nearer.
    pub fn levels() -> Self {
        FittedCosts::built_in().levels.costs
    }
}

/// The end-point error the decision's model predicts for a path, from what
/// the robot knew while driving it (odometry and egomotion's step CVs, no
/// ground truth): each step's translation variance, plus the heading
/// variance of each turn and each step on the odometry bridge, carried over
/// the distance from there to the end. It is the sum the end-point
/// objective minimises one step at a time; given
/// [`DecisionCosts::levels`], a run's actual error over this σ says how
/// well the model is calibrated.
#[derive(Clone, Debug, Default)]
pub struct EndPointPredictor {
    costs: DecisionCosts,
    /// Summed translation variance of the steps, m².
    step_variance: f64,
    /// Where each turn or bridged step was made, and the heading variance
    /// it left.
    headings: Vec<((f64, f64), f64)>,
    last: Option<Pose2>,
    /// Where the turn under way began.
    turning_from: Option<Pose2>,
}

/// Between two frames, a heading change above this is a turn, rad (half a
/// degree).
const TURNING_RAD: f64 = 0.5 * std::f64::consts::PI / 180.0;
/// Between two frames, a move of at least this with no turn is a straight
/// step, m.
const MOVING_M: f64 = 0.05;

/// Whether `step`, the motion between two frames, is part of a turn as the
/// end-point model counts turns: the heading changed by more than half a
/// degree, whether or not the robot also moved. A turn of a few degrees on
/// the spot ends within one frame interval and the next step starts in the
/// same interval; counting only intervals without a move missed 29 of every
/// 30 of tracking's turns.
pub fn turned(step: &Pose2) -> bool {
    step.theta.abs() > TURNING_RAD
}

/// Whether `step` is a stretch of straight driving: a move with no turn.
pub fn drove_straight(step: &Pose2) -> bool {
    !turned(step) && step.x.hypot(step.y) >= MOVING_M
}

impl EndPointPredictor {
    /// A predictor with these coefficients.
    pub fn new(costs: DecisionCosts) -> Self {
        EndPointPredictor { costs, ..EndPointPredictor::default() }
    }

    /// Takes in a frame taken at `odometry`, whose egomotion step fused to
    /// `step_cv` (`None` when it failed).
    pub fn frame(&mut self, odometry: &Pose2, step_cv: Option<f64>) {
        let Some(last) = self.last.replace(*odometry) else { return };
        let step = odometry.relative_to(&last);
        if turned(&step) {
            self.turning_from.get_or_insert(last);
            return;
        }
        if let Some(from) = self.turning_from.take() {
            let turned = angle_difference(last.theta, from.theta).abs();
            self.headings.push(((last.x, last.y), self.costs.turn_variance(turned)));
        }
        let driven = step.x.hypot(step.y);
        match step_cv {
            Some(cv) => self.step_variance += (self.costs.step_sigma_per_cv * cv * driven).powi(2),
            None if driven > 0.0 => {
                self.headings.push(((odometry.x, odometry.y), self.costs.bridge_heading_var_per_m * driven));
            }
            None => {}
        }
    }

    /// The predicted end-point σ for a path ending at `end`, m.
    pub fn sigma(&self, end: (f64, f64)) -> f64 {
        let headings: f64 =
            self.headings.iter().map(|((x, y), v)| v * ((end.0 - x).powi(2) + (end.1 - y).powi(2))).sum();
        (self.step_variance + headings).sqrt()
    }
}

/// What the engine minimises.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Objective {
    /// The thesis's objective: the step's fused CV alone (eq. 6).
    Cv,
    /// The predicted end-point variance: the step's translation variance
    /// plus the heading variance of the turn it needs, now and back to the
    /// goal bearing, times the remaining distance squared. Driving at the
    /// goal stays a candidate where too few landmarks are predicted in view:
    /// it costs the odometry bridge's heading variance instead.
    EndPoint {
        /// The robot's heading now, rad.
        heading: f64,
        /// The bearing to the goal, rad.
        goal_bearing: f64,
        /// The distance still to go, m.
        remaining_m: f64,
        /// Heading changes up to this are steered while driving, not turned
        /// on the spot, and cost no turn, rad.
        turn_tolerance: f64,
        /// The error coefficients.
        costs: DecisionCosts,
    },
}

impl Objective {
    /// The cost of `heading` whose step's landmarks fuse to `cv`.
    fn cost(&self, heading: f64, cv: f64, step_m: f64) -> f64 {
        match *self {
            Objective::Cv => cv,
            Objective::EndPoint { remaining_m, costs, .. } => {
                costs.end_point_variance(cv, step_m, self.turns(heading), remaining_m)
            }
        }
    }

    /// The cost of driving `heading` on the odometry bridge, where it is
    /// the goal's bearing and the end-point objective is in use; `None`
    /// otherwise (the heading is then infeasible without landmarks).
    fn bridged_cost(&self, heading: f64, step_m: f64) -> Option<f64> {
        match *self {
            Objective::EndPoint { goal_bearing, remaining_m, costs, .. } if heading == goal_bearing => {
                Some(costs.bridged_variance(step_m, self.turns(heading), remaining_m))
            }
            _ => None,
        }
    }

    /// The turns on the spot `heading` needs, now and back to the goal's
    /// bearing, rad (0 for those within the turn tolerance, steered while
    /// driving).
    fn turns(&self, heading: f64) -> [f64; 2] {
        let Objective::EndPoint { heading: now, goal_bearing, turn_tolerance, .. } = *self else { return [0.0; 2] };
        [angle_difference(heading, now), angle_difference(goal_bearing, heading)].map(|t| {
            if t.abs() > turn_tolerance {
                t.abs()
            } else {
                0.0
            }
        })
    }
}

/// The engine's choice.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Decision {
    /// The heading, rad (world).
    pub heading: f64,
    /// Its fused CV over the landmarks predicted in view; infinite when
    /// too few are, and the step is to be driven on the odometry bridge.
    pub cv: f64,
    /// The objective's value.
    pub cost: f64,
    /// Landmarks predicted in view.
    pub landmarks: usize,
}

/// Bearing buckets over the full circle: one degree each.
const BUCKETS: usize = 360;
/// Landmarks nearer than this many steps are looked at by every candidate:
/// the step can swing their bearing too far.
const NEAR_STEPS: f64 = 4.0;
/// Farther landmarks fall into bands of distance, each twice as far out as
/// the one before, the last unbounded: the farther a landmark, the less one
/// step swings its bearing, so the narrower the window a candidate reads.
const BANDS: usize = 4;

/// The best heading among `candidates` (world angles) for a robot at
/// `position` among `landmarks` (world `[x, y, height above the floor]`,
/// m, each recognisable
/// from here: the tracking list drops those seen from too far round): the
/// one of least `objective` over the landmarks predicted in view after one
/// projected step. A heading with
/// fewer than `min_landmarks` in view (egomotion's steps fail or lean on odometry) or with one
/// nearer than the slant limit is rejected, except that under the
/// end-point objective the goal's bearing with too few in view stays, at
/// the odometry bridge's cost. Ties go to the candidate listed first.
/// `None` if every heading is rejected.
///
/// For speed, landmarks are sorted once by distance band and bearing, and
/// each candidate reads, in each band, only the bearings its field of view
/// can reach from the projected position (from `d` away, a step of `s`
/// moves a bearing by at most `asin(s/d)`).
pub fn best_heading(
    table: &CvTable,
    rules: &DecisionRules,
    landmarks: &[[f64; 3]],
    position: (f64, f64),
    candidates: impl IntoIterator<Item = f64>,
    objective: &Objective,
) -> Option<Decision> {
    best_view(table, rules, landmarks, position, None, candidates, objective)
}

/// The best direction for a steerable camera to look among `looks` (world
/// angles) while the robot steps along `driving`: as [`best_heading`], but
/// the step is projected along the robot's course and the view turned to
/// each candidate, so the landmarks are the camera's, not the heading's.
/// The decision's `heading` is the direction to look. Under the end-point
/// objective give the robot's heading and the goal's bearing as `driving`:
/// the robot does not turn, and the look costs no turn.
pub fn best_look(
    table: &CvTable,
    rules: &DecisionRules,
    landmarks: &[[f64; 3]],
    position: (f64, f64),
    driving: f64,
    looks: impl IntoIterator<Item = f64>,
    objective: &Objective,
) -> Option<Decision> {
    best_view(table, rules, landmarks, position, Some(driving), looks, objective)
}

/// [`best_heading`] and [`best_look`]: the step along `driving`, or along
/// each candidate when `None`.
fn best_view(
    table: &CvTable,
    rules: &DecisionRules,
    landmarks: &[[f64; 3]],
    position: (f64, f64),
    driving: Option<f64>,
    candidates: impl IntoIterator<Item = f64>,
    objective: &Objective,
) -> Option<Decision> {
    use std::f64::consts::TAU;
    let bucket_width = TAU / BUCKETS as f64;
    // For an angle in [0, 2π].
    let bucket_of = |angle: f64| ((angle / bucket_width) as usize).min(BUCKETS - 1);
    // Keys: band × BUCKETS + bucket for far landmarks, then one key for the
    // near ones. Offsets from the robot are computed once: from the
    // projected position a landmark's depth is `d·u − step` and its lateral
    // offset `d·n`.
    const NEAR: usize = BANDS * BUCKETS;
    let near2 = (NEAR_STEPS * rules.step_m).powi(2);
    let key_of = |dx: f64, dy: f64| {
        let distance2 = dx * dx + dy * dy;
        if distance2 < near2 {
            return NEAR;
        }
        let mut band = 0;
        while band + 1 < BANDS && distance2 >= near2 * f64::from(4u32 << (2 * band)) {
            band += 1;
        }
        // In [−π, π]: one add instead of `rem_euclid`'s division.
        let bearing = fast_atan2(dy, dx);
        band * BUCKETS + bucket_of(if bearing < 0.0 { bearing + TAU } else { bearing })
    };
    // A counting sort by key.
    let mut starts = vec![0usize; NEAR + 2];
    let mut keys = Vec::with_capacity(landmarks.len());
    for &[lx, ly, _] in landmarks {
        let key = key_of(lx - position.0, ly - position.1);
        starts[key + 1] += 1;
        keys.push(key);
    }
    for k in 0..=NEAR {
        starts[k + 1] += starts[k];
    }
    let mut fill = starts.clone();
    let mut sorted = vec![Offset::default(); landmarks.len()];
    for (offset, &key) in Offset::all(table, rules, position, landmarks).zip(&keys) {
        sorted[fill[key]] = offset;
        fill[key] += 1;
    }
    let nearby = &sorted[starts[NEAR]..starts[NEAR + 1]];
    // Each band's half-window in buckets; one more for the quantisation of
    // the heading's and the landmark's bearings, and one for the error of
    // the fast arctangent, which can put a bearing in the next bucket.
    let spans: [usize; BANDS] = std::array::from_fn(|band| {
        let reach = rules.half_fov + (1.0 / (NEAR_STEPS * f64::from(1u32 << band))).asin();
        (reach / bucket_width).ceil() as usize + 2
    });

    let mut best: Option<Decision> = None;
    for heading in candidates {
        // A heading whose turns alone cost more than the best so far cannot
        // win, whatever it sees.
        let turned_to = driving.unwrap_or(heading);
        if best.is_some_and(|b| objective.cost(turned_to, 0.0, rules.step_m) >= b.cost) {
            continue;
        }
        // Eq. 40–43: the robot projected one step ahead along the heading
        // (or its course, for a camera looking elsewhere).
        let view = View::new(rules, heading, turned_to);
        let centre = bucket_of(heading.rem_euclid(TAU));
        let mut seen = view.information(table, nearby);
        for (band, &span) in spans.iter().enumerate() {
            let Some(sum) = seen else { break };
            let within = |from: usize, to: usize| &sorted[starts[band * BUCKETS + from]..starts[band * BUCKETS + to]];
            // The window is one run of the band, or two where it wraps.
            let runs: [&[Offset]; 2] = if 2 * span + 1 >= BUCKETS {
                [within(0, BUCKETS), &[]]
            } else {
                let (lo, hi) = ((centre + BUCKETS - span) % BUCKETS, (centre + span) % BUCKETS);
                if lo <= hi {
                    [within(lo, hi + 1), &[]]
                } else {
                    [within(lo, BUCKETS), within(0, hi + 1)]
                }
            };
            seen = runs.iter().try_fold(sum, |sum, run| Some(sum.add(view.information(table, run)?)));
        }
        consider(&mut best, rules, objective, heading, turned_to, seen);
    }
    best
}

/// Keeps `heading` in `best` if it is cheaper and its view is feasible:
/// no landmark too near (`seen` is `None`) and enough in view, or, for the
/// goal's bearing under the end-point objective, too few in view and the
/// step driven on the odometry bridge.
///
/// `heading` is the candidate; `turned_to` the robot's heading it implies
/// (the candidate itself, or the course a steerable camera's robot keeps).
fn consider(
    best: &mut Option<Decision>,
    rules: &DecisionRules,
    objective: &Objective,
    heading: f64,
    turned_to: f64,
    seen: Option<Seen>,
) {
    let Some(seen) = seen else { return };
    let (cv, cost) = if seen.count >= rules.min_landmarks.max(1) && seen.information > 0.0 {
        let cv = 1.0 / seen.information;
        (cv, objective.cost(turned_to, cv, rules.step_m))
    } else {
        let Some(cost) = objective.bridged_cost(turned_to, rules.step_m) else { return };
        (f64::INFINITY, cost)
    };
    let landmarks = seen.count;
    if best.is_none_or(|b| cost < b.cost) {
        *best = Some(Decision { heading, cv, cost, landmarks });
    }
}

/// `atan2(y, x)` within 2e-5 rad, several times faster than the exact one:
/// the polynomial of Abramowitz and Stegun 4.4.49 on `[0, 1]`, extended by
/// symmetry. Good enough to pick a one-degree bucket give or take one.
fn fast_atan2(y: f64, x: f64) -> f64 {
    use std::f64::consts::{FRAC_PI_2, PI};
    let (ax, ay) = (x.abs(), y.abs());
    if ax == 0.0 && ay == 0.0 {
        return 0.0;
    }
    let z = ax.min(ay) / ax.max(ay);
    let z2 = z * z;
    let atan = z * (0.999_866_0 + z2 * (-0.330_299_5 + z2 * (0.180_141_0 + z2 * (-0.085_133_0 + z2 * 0.020_835_1))));
    let first_octant_folded = if ay > ax { FRAC_PI_2 - atan } else { atan };
    let half_plane = if x < 0.0 { PI - first_octant_folded } else { first_octant_folded };
    if y < 0.0 {
        -half_plane
    } else {
        half_plane
    }
}

/// What a view holds: summed information (Σ 1/CV) and landmarks counted.
#[derive(Clone, Copy, Debug, Default)]
struct Seen {
    information: f64,
    count: usize,
}

impl Seen {
    fn add(self, other: Seen) -> Seen {
        Seen { information: self.information + other.information, count: self.count + other.count }
    }
}

/// A landmark as every candidate reads it: what depends on its height is
/// worked out once, not once per heading.
#[derive(Clone, Copy, Debug, Default)]
struct Offset {
    /// From the robot's position, m.
    dx: f64,
    dy: f64,
    /// The least depth at which it falls in the images' rows, m.
    row_depth: f64,
    /// Its height's part in its information.
    height: HeightFactor,
}

impl Offset {
    /// Offsets of `landmarks` from `position` under `rules`.
    fn all<'a>(
        table: &'a CvTable,
        rules: &DecisionRules,
        position: (f64, f64),
        landmarks: &'a [[f64; 3]],
    ) -> impl Iterator<Item = Offset> + 'a {
        let (up, down, level) = (rules.up_fov.tan(), rules.down_fov.tan(), rules.camera_height_m);
        landmarks.iter().map(move |&[x, y, height]| {
            let z = height - level;
            Offset {
                dx: x - position.0,
                dy: y - position.1,
                row_depth: (z / up).max(-z / down),
                height: table.height_factor(z),
            }
        })
    }
}

/// One candidate heading's view from the projected position.
struct View {
    sin: f64,
    cos: f64,
    /// The projected step along the view and across it (to the right), m.
    step: f64,
    step_across: f64,
    tan_half: f64,
    half_baseline: f64,
    min_slant2: f64,
    min_stereo2: f64,
    max_range2: f64,
}

impl View {
    /// Looking along `heading` after a step along `course`.
    fn new(rules: &DecisionRules, heading: f64, course: f64) -> Self {
        let (sin, cos) = heading.sin_cos();
        let (across, along) = (heading - course).sin_cos();
        View {
            sin,
            cos,
            step: rules.step_m * along,
            step_across: rules.step_m * across,
            tan_half: rules.half_fov.tan(),
            half_baseline: rules.baseline_m / 2.0,
            min_slant2: rules.min_slant_m.powi(2),
            min_stereo2: rules.min_stereo_range_m.powi(2),
            max_range2: rules.max_range_m.powi(2),
        }
    }

    /// The information and count of the landmarks in view, given as offsets
    /// from the robot's current position and the cameras' height, or `None`
    /// if one is nearer than the slant limit (an obstacle). A landmark
    /// counts if it is in both images (columns and rows), within range, and
    /// far enough for stereo matching.
    #[inline]
    fn information(&self, table: &CvTable, offsets: &[Offset]) -> Option<Seen> {
        let mut seen = Seen::default();
        for &Offset { dx, dy, height, row_depth } in offsets {
            // Eq. 44–48 without trigonometry: depth along the heading from
            // the projected position, lateral offset to the right.
            let depth = dx * self.cos + dy * self.sin - self.step;
            let lateral = dx * self.sin - dy * self.cos - self.step_across;
            if depth <= 0.0 || lateral.abs() > depth * self.tan_half {
                continue;
            }
            let range2 = depth * depth + lateral * lateral;
            if range2 < self.min_slant2 {
                return None;
            }
            if range2 > self.max_range2
                || range2 < self.min_stereo2
                || lateral.abs() + self.half_baseline > depth * self.tan_half
                || depth < row_depth
            {
                continue;
            }
            seen.information += table.information_at(lateral, depth, height);
            seen.count += 1;
        }
        Some(seen)
    }
}

/// The same evaluation without bucketing, every landmark for every heading:
/// the reference the fast version is tested against.
pub fn best_heading_exhaustive(
    table: &CvTable,
    rules: &DecisionRules,
    landmarks: &[[f64; 3]],
    position: (f64, f64),
    candidates: impl IntoIterator<Item = f64>,
    objective: &Objective,
) -> Option<Decision> {
    let offsets: Vec<Offset> = Offset::all(table, rules, position, landmarks).collect();
    let mut best = None;
    for heading in candidates {
        let seen = View::new(rules, heading, heading).information(table, &offsets);
        consider(&mut best, rules, objective, heading, heading, seen);
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;
    use ubf_perception::error_model::ErrorModelKind;
    use ubf_perception::StereoCamera;

    fn rules() -> DecisionRules {
        DecisionRules {
            half_fov: 30f64.to_radians(),
            step_m: 0.25,
            min_slant_m: 0.5,
            max_range_m: 80.0,
            baseline_m: 0.6,
            min_stereo_range_m: 1.12,
            min_landmarks: 1,
            camera_height_m: 1.0,
            up_fov: 23.4f64.to_radians(),
            down_fov: 23.4f64.to_radians(),
        }
    }

    /// Landmarks at the cameras' height, where the planar and 3D models
    /// agree.
    fn level(points: impl IntoIterator<Item = (f64, f64)>) -> Vec<[f64; 3]> {
        points.into_iter().map(|(x, y)| [x, y, rules().camera_height_m]).collect()
    }

    fn table() -> CvTable {
        CvTable::for_camera(ErrorModelKind::Geometric, &StereoCamera::default(), 1.0, 80.0)
    }

    fn headings() -> impl Iterator<Item = f64> {
        (-9..=9).map(|i| f64::from(i) * 5f64.to_radians())
    }

    #[test]
    fn the_built_in_coefficients_are_the_fit_and_round_trip_through_their_file() {
        let fitted = FittedCosts::built_in();
        let costs = DecisionCosts::default();
        assert_eq!(costs, fitted.against_straight.costs);
        assert_eq!((costs.heading_var_per_rad, costs.bridge_heading_var_per_m), (1.44e-5, 1.15e-5));
        assert_eq!(DecisionCosts::levels().step_sigma_per_cv, 0.614);
        let text = fitted.to_file();
        assert!(text.starts_with("// The end-point decision's"), "{text}");
        assert_eq!(&FittedCosts::parse(&text).unwrap(), fitted);
    }

    #[test]
    fn prefers_putting_a_landmark_off_centre_and_near() {
        let t = table();
        // One landmark 10 m ahead, 2 m left: looking straight at it is the
        // worst choice; turning so it sits near the edge of the view is best.
        let landmarks = level([(10.0, 2.0)]);
        let d = best_heading(&t, &rules(), &landmarks, (0.0, 0.0), headings(), &Objective::Cv).unwrap();
        let straight_at = 2f64.atan2(10.0);
        assert!((d.heading - straight_at).abs() > 15f64.to_radians(), "{}", d.heading.to_degrees());
        assert!(d.cv < 1.0 / t.information(0.0, 10.0, 0.0));
        assert_eq!(d.landmarks, 1);
    }

    #[test]
    fn a_steerable_camera_looks_at_landmarks_the_heading_would_miss() {
        let t = table();
        // Landmarks only on a wall 3 m to the left, from 1 to 4 m ahead:
        // out of the view along the course (more than 30° off it); the
        // robot keeps driving along x.
        let landmarks = level((2..=8).map(|x| (f64::from(x) / 2.0, 3.0)));
        let ahead = best_heading(&t, &rules(), &landmarks, (0.0, 0.0), [0.0], &Objective::Cv);
        let looks = (-18..=18).map(|i| f64::from(i) * 5f64.to_radians());
        let look = best_look(&t, &rules(), &landmarks, (0.0, 0.0), 0.0, looks, &Objective::Cv).unwrap();
        assert!(look.heading > 20f64.to_radians(), "{}", look.heading.to_degrees());
        assert!(look.landmarks > ahead.map_or(0, |d| d.landmarks));
        // Looking along the course is the same view as heading along it.
        let along = best_look(&t, &rules(), &landmarks, (0.0, 0.0), 0.3, [0.3], &Objective::Cv).unwrap();
        assert_eq!(Some(along), best_heading(&t, &rules(), &landmarks, (0.0, 0.0), [0.3], &Objective::Cv));
        // Under the end-point objective a look costs no turn: the robot
        // keeps its course.
        let end_point = Objective::EndPoint {
            heading: 0.0,
            goal_bearing: 0.0,
            remaining_m: 30.0,
            turn_tolerance: 2f64.to_radians(),
            costs: DecisionCosts::default(),
        };
        let looks = (-18..=18).map(|i| f64::from(i) * 5f64.to_radians());
        let chosen = best_look(&t, &rules(), &landmarks, (0.0, 0.0), 0.0, looks, &end_point).unwrap();
        assert_eq!(chosen.cost, end_point.cost(0.0, chosen.cv, rules().step_m));
    }

    #[test]
    fn fast_arctangent_is_within_its_bound() {
        let mut worst: f64 = 0.0;
        for k in 0..100_000 {
            let angle = f64::from(k) * 1e-4 - 5.0;
            for r in [1e-3, 1.0, 70.0] {
                let (y, x) = (r * angle.sin(), r * angle.cos());
                worst = worst.max((fast_atan2(y, x) - y.atan2(x)).abs());
            }
        }
        assert!(worst < 2e-5, "{worst}");
        assert_eq!(fast_atan2(0.0, 0.0), 0.0);
        assert!((fast_atan2(0.0, -1.0) - std::f64::consts::PI).abs() < 1e-5);
    }

    #[test]
    fn indexing_changes_nothing() {
        // Every heading on its own, so a landmark missed by any window would
        // show: corridors of many landmarks, and sparse landmarks all round
        // at every distance band with headings all round the circle; random
        // both objectives, and one or four landmarks needed.
        use rand::{Rng, SeedableRng};
        // Heights from the floor to 3 m, so that some landmarks fall outside
        // the images' rows; half the rounds with the 3D model.
        let tables = [table(), CvTable::for_camera(ErrorModelKind::Geometric3d, &StereoCamera::default(), 1.0, 80.0)];
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(4);
        for round in 0..100 {
            let t = &tables[round % 2];
            let (count, radius) = if round % 2 == 0 { (300, 0.0) } else { (rng.random_range(1..12), 30.0) };
            let landmarks: Vec<[f64; 3]> = (0..count)
                .map(|_| {
                    let height = rng.random_range(0.0..3.0);
                    match radius {
                        0.0 => [rng.random_range(-20.0..60.0), rng.random_range(-8.0..8.0), height],
                        r => {
                            let (d, a) = (rng.random_range(0.3f64..r), rng.random_range(-4.0f64..4.0));
                            [d * a.cos(), d * a.sin(), height]
                        }
                    }
                })
                .collect();
            let at = (rng.random_range(-2.0..2.0), rng.random_range(-2.0..2.0));
            let rules = DecisionRules { min_landmarks: 1 + 3 * (round % 3 == 0) as usize, ..rules() };
            let objective = if round % 4 < 2 {
                Objective::Cv
            } else {
                Objective::EndPoint {
                    heading: 0.3,
                    goal_bearing: 0.0,
                    remaining_m: 20.0,
                    turn_tolerance: 0.03,
                    costs: DecisionCosts::default(),
                }
            };
            for k in -80..=80 {
                let heading = [f64::from(k) * 2.5f64.to_radians() + rng.random_range(-0.02..0.02)];
                let fast = best_heading(t, &rules, &landmarks, at, heading, &objective);
                let slow = best_heading_exhaustive(t, &rules, &landmarks, at, heading, &objective);
                match (fast, slow) {
                    (Some(a), Some(b)) => {
                        assert!((a.cv / b.cv - 1.0).abs() < 1e-9, "{round} {k}");
                        assert_eq!(a.landmarks, b.landmarks, "{round} {k}");
                    }
                    (a, b) => assert_eq!(a, b, "{round} {k}"),
                }
            }
        }
    }

    #[test]
    fn rejects_headings_without_landmarks_or_with_one_too_near() {
        let t = table();
        // Only landmark far to the left, out of view for right headings.
        let left = level([(5.0, 4.0)]);
        let d = best_heading(&t, &rules(), &left, (0.0, 0.0), headings(), &Objective::Cv).unwrap();
        assert!(d.heading > 0.0);
        // A landmark right in front is an obstacle: straight ahead is out;
        // 34° left puts it out of view and a far landmark in.
        let landmarks = level([(0.6, 0.0), (20.0, -5.0), (20.0, 5.0)]);
        let d = best_heading(&t, &rules(), &landmarks, (0.0, 0.0), [0.0, 0.6], &Objective::Cv).unwrap();
        assert_eq!(d.heading, 0.6);
        assert!(best_heading(&t, &rules(), &[], (0.0, 0.0), headings(), &Objective::Cv).is_none());
    }

    #[test]
    fn a_heading_needs_enough_landmarks_in_both_images() {
        let t = table();
        // Three landmarks ahead and one at the edge of the left camera's
        // view only: with four needed, no heading that sees just those is
        // feasible.
        let three = [(10.0, 0.0), (12.0, 1.0), (14.0, -1.0)];
        let edge = (10.0, -(10.0 - 0.25) * 30f64.to_radians().tan() + 0.1);
        let landmarks = level(three.into_iter().chain([edge]));
        let four = DecisionRules { min_landmarks: 4, ..rules() };
        assert!(best_heading(&t, &four, &landmarks, (0.0, 0.0), [0.0], &Objective::Cv).is_none());
        let three_needed = DecisionRules { min_landmarks: 3, ..rules() };
        let d = best_heading(&t, &three_needed, &landmarks, (0.0, 0.0), [0.0], &Objective::Cv).unwrap();
        assert_eq!(d.landmarks, 3);
    }

    #[test]
    fn the_3d_model_prefers_landmarks_off_the_cameras_level_the_planar_one_cannot_tell() {
        // Two mirror-image clusters 30° either side: one at the cameras'
        // height, one 0.8 m below it. The planar model scores both alike
        // (the tie goes to the first candidate); the 3D one turns to the
        // landmarks whose rows move too.
        let mut landmarks = level((0..4).map(|i| (8.0 + f64::from(i), 5.0)));
        landmarks.extend((0..4).map(|i| [8.0 + f64::from(i), -5.0, rules().camera_height_m - 0.8]));
        let turns = [30f64.to_radians(), -30f64.to_radians()];
        let planar = best_heading(&table(), &rules(), &landmarks, (0.0, 0.0), turns, &Objective::Cv).unwrap();
        let t3 = CvTable::for_camera(ErrorModelKind::Geometric3d, &StereoCamera::default(), 1.0, 80.0);
        let with_height = best_heading(&t3, &rules(), &landmarks, (0.0, 0.0), turns, &Objective::Cv).unwrap();
        assert_eq!(planar.heading, turns[0]);
        assert_eq!(with_height.heading, turns[1]);
        assert!(with_height.cv < planar.cv);
    }

    #[test]
    fn a_landmark_above_the_images_rows_is_not_in_view() {
        // 3 m ahead and 1.5 m above the cameras: 27° up, beyond the 23.4°
        // the rows reach; farther on, the same height is in view.
        let t = table();
        let near = [[3.0 + rules().step_m, 0.0, rules().camera_height_m + 1.5]];
        assert!(best_heading(&t, &rules(), &near, (0.0, 0.0), [0.0], &Objective::Cv).is_none());
        let far = [[8.0, 0.0, rules().camera_height_m + 1.5]];
        assert_eq!(best_heading(&t, &rules(), &far, (0.0, 0.0), [0.0], &Objective::Cv).unwrap().landmarks, 1);
    }

    #[test]
    fn the_predictor_carries_a_turn_over_the_rest_of_the_path() {
        let costs = DecisionCosts {
            step_sigma_per_cv: 2.0,
            heading_var_per_rad: 0.0,
            heading_var_per_turn: 1e-4,
            bridge_heading_var_per_m: 1e-3,
        };
        let mut p = EndPointPredictor::new(costs);
        // 2 m straight in 0.5 m steps at CV 0.1, a 30° turn on the spot in
        // three frames, then 10 m on, of which one step (the sixth) on the
        // odometry bridge.
        let mut pose = Pose2::default();
        p.frame(&pose, None);
        for _ in 0..4 {
            pose = pose.compose(&Pose2::new(0.5, 0.0, 0.0));
            p.frame(&pose, Some(0.1));
        }
        for _ in 0..3 {
            pose = pose.compose(&Pose2::new(0.0, 0.0, 10f64.to_radians()));
            p.frame(&pose, Some(0.1));
        }
        let turned_at = pose;
        let mut bridged_at = pose;
        for k in 0..20 {
            pose = pose.compose(&Pose2::new(0.5, 0.0, 0.0));
            let bridged = k == 5;
            if bridged {
                bridged_at = pose;
            }
            p.frame(&pose, (!bridged).then_some(0.1));
        }
        let steps = 23.0 * (2.0 * 0.1 * 0.5f64).powi(2);
        let lever2 = |at: Pose2| (pose.x - at.x).powi(2) + (pose.y - at.y).powi(2);
        let expected = (steps + 1e-4 * lever2(turned_at) + 1e-3 * 0.5 * lever2(bridged_at)).sqrt();
        assert!((p.sigma((pose.x, pose.y)) - expected).abs() < 1e-12, "{} vs {expected}", p.sigma((pose.x, pose.y)));
    }

    #[test]
    fn a_turn_that_ends_while_the_robot_drives_on_is_a_turn() {
        // Tracking's turns of a few degrees end within one frame interval,
        // and the next step starts in the same interval.
        let turn_and_go = Pose2::new(0.2, 0.0, 5f64.to_radians());
        assert!(turned(&turn_and_go) && !drove_straight(&turn_and_go));
        assert!(drove_straight(&Pose2::new(0.2, 0.0, 0.2f64.to_radians())));
        let costs = DecisionCosts {
            step_sigma_per_cv: 0.0,
            heading_var_per_rad: 0.0,
            heading_var_per_turn: 1e-4,
            bridge_heading_var_per_m: 0.0,
        };
        let mut p = EndPointPredictor::new(costs);
        let mut pose = Pose2::default();
        p.frame(&pose, None);
        pose = pose.compose(&Pose2::new(0.5, 0.0, 0.0));
        p.frame(&pose, Some(0.1));
        pose = pose.compose(&turn_and_go);
        p.frame(&pose, Some(0.1));
        let turned_at = pose;
        for _ in 0..10 {
            pose = pose.compose(&Pose2::new(0.5, 0.0, 0.0));
            p.frame(&pose, Some(0.1));
        }
        let lever2 = (pose.x - turned_at.x).powi(2) + (pose.y - turned_at.y).powi(2);
        assert!((p.sigma((pose.x, pose.y)) - (1e-4 * lever2).sqrt()).abs() < 1e-12);
    }

    #[test]
    fn the_end_point_objective_turns_only_when_it_pays() {
        let t = table();
        // A far wall across the whole view, and a near cluster 40° left: the
        // CV objective turns to the cluster; with 40 m still to go, the
        // end-point objective stays on the goal bearing, and with half a
        // metre to go it turns.
        let wall = (0..11).map(|i| (50.0, -25.0 + 5.0 * f64::from(i)));
        let landmarks = level(wall.chain((0..6).map(|i| (3.0 + 0.3 * f64::from(i), 3.5 + 0.2 * f64::from(i)))));
        let candidates = || (-18..=18).map(|k| f64::from(k) * 2.5f64.to_radians());
        let cv = best_heading(&t, &rules(), &landmarks, (0.0, 0.0), candidates(), &Objective::Cv).unwrap();
        assert!(cv.heading > 20f64.to_radians(), "{}", cv.heading.to_degrees());
        let costs = DecisionCosts {
            step_sigma_per_cv: 1.0,
            heading_var_per_rad: 1e-5,
            heading_var_per_turn: 0.0,
            bridge_heading_var_per_m: 1e-5,
        };
        let end_point = |remaining_m| Objective::EndPoint {
            heading: 0.0,
            goal_bearing: 0.0,
            remaining_m,
            turn_tolerance: 2f64.to_radians(),
            costs,
        };
        let far = best_heading(&t, &rules(), &landmarks, (0.0, 0.0), candidates(), &end_point(40.0)).unwrap();
        assert_eq!(far.heading, 0.0);
        let near = best_heading(&t, &rules(), &landmarks, (0.0, 0.0), candidates(), &end_point(0.5)).unwrap();
        assert!(near.heading > 20f64.to_radians(), "{}", near.heading.to_degrees());
    }

    #[test]
    fn driving_at_the_goal_stays_a_candidate_at_the_bridges_cost() {
        let t = table();
        // Nothing ahead; a cluster 40° left. The CV objective must turn: no
        // landmark, no egomotion. The end-point objective weighs the turn
        // there and back against driving the step on the odometry bridge.
        let landmarks = level((0..6).map(|i| (6.0 + 0.5 * f64::from(i), 5.0 + 0.3 * f64::from(i))));
        let candidates = || (-18..=18).map(|k| f64::from(k) * 2.5f64.to_radians());
        let cv = best_heading(&t, &rules(), &landmarks, (0.0, 0.0), candidates(), &Objective::Cv).unwrap();
        assert!(cv.heading > 10f64.to_radians(), "{}", cv.heading.to_degrees());
        let end_point = |bridge_heading_var_per_m| Objective::EndPoint {
            heading: 0.0,
            goal_bearing: 0.0,
            remaining_m: 5.0,
            turn_tolerance: 2f64.to_radians(),
            costs: DecisionCosts {
                step_sigma_per_cv: 1.0,
                heading_var_per_rad: 0.0,
                heading_var_per_turn: 1e-4,
                bridge_heading_var_per_m,
            },
        };
        let cheap = best_heading(&t, &rules(), &landmarks, (0.0, 0.0), candidates(), &end_point(1e-5)).unwrap();
        assert_eq!((cheap.heading, cheap.landmarks), (0.0, 0));
        assert!(cheap.cv.is_infinite());
        assert!((cheap.cost - 1e-5 * rules().step_m * 25.0).abs() < 1e-15, "{}", cheap.cost);
        let dear = best_heading(&t, &rules(), &landmarks, (0.0, 0.0), candidates(), &end_point(1e-2)).unwrap();
        assert!(dear.heading > 0.0 && dear.landmarks > 0, "{dear:?}");
        // A landmark too near ahead is an obstacle, not a view: the bridge
        // does not drive into it.
        let mut blocked = landmarks.clone();
        blocked.extend(level([(rules().step_m + 0.3, 0.0)]));
        let d = best_heading(&t, &rules(), &blocked, (0.0, 0.0), candidates(), &end_point(1e-5)).unwrap();
        assert_ne!(d.heading, 0.0);
    }
}
