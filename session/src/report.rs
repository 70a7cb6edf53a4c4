//! `report.json`: what a run did, and the summary `ubf run` prints.

use serde::Serialize;
use ubf_core::{Pose2, WheelScale};
// For the fields' links only: their docs are also the JSON log's schema
// descriptions, so a link's target is named here rather than in the text.
#[cfg(doc)]
use ubf_behaviors::decision::DecisionCosts;

/// Why a run ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum EndReason {
    /// The robot believed it was at the goal.
    GoalReached,
    /// `max_time_s` ran out first.
    TimeLimit,
    /// A behaviour panicked (the report's `failure` names it); the robot
    /// was stopped.
    BehaviorFailed,
    /// Ctrl-C or SIGTERM stopped the run; the report covers what ran.
    Interrupted,
    /// The robot stayed within the scenario's `progress` radius for its
    /// window: it was getting nowhere, and the run gave up.
    NoProgress,
}

/// What a run did: `report.json`.
#[derive(Clone, Debug, PartialEq, Serialize, schemars::JsonSchema)]
pub struct RunReport {
    /// The scenario's name.
    pub scenario: String,
    /// The seed the run used.
    pub seed: u64,
    /// Control ticks run.
    pub ticks: u64,
    /// Simulated seconds.
    pub sim_time_s: f64,
    /// True path length driven, m.
    pub distance_m: f64,
    /// Whether the robot's true position ended within the goal's tolerance.
    pub reached_goal: bool,
    /// Whether the scenario has a goal (the summary says so, not "no"; the
    /// JSON leaves it out, as its `reached_goal` always said `false`).
    #[serde(skip)]
    pub has_goal: bool,
    /// Times the robot came into contact with a wall, a box or a person.
    pub collisions: u32,
    /// Why the run ended.
    pub end: EndReason,
    /// What failed, when a behaviour did: its path in the tree and its
    /// message.
    pub failure: Option<String>,
    /// Where the robot really ended.
    #[schemars(with = "PoseSchema")]
    pub final_true_pose: Pose2,
    /// Where the robot believed it ended: the pose it steered by (with
    /// `navigate`, egomotion's, combined with odometry's where the rigid
    /// estimator and the gate's noise model weigh the two; else odometry's).
    #[schemars(with = "PoseSchema")]
    pub final_estimated_pose: Pose2,
    /// Distance between the two, m.
    pub estimate_error_m: f64,
    /// Egomotion's sum of step CVs (thesis eq. 7), when the robot runs it.
    pub journey_cv: Option<f64>,
    /// Egomotion steps (frame pairs) estimated.
    pub egomotion_steps: Option<u32>,
    /// Egomotion steps that failed for want of usable landmarks.
    pub egomotion_failures: Option<u32>,
    /// The end-point σ the decision's error model predicts for the path
    /// driven (from odometry and the step CVs, with the coefficients fitted
    /// to end points as they are, [`DecisionCosts::levels`]), m: compare
    /// with `endpoint_error_m`.
    pub predicted_endpoint_sigma_m: Option<f64>,
    /// The position σ of the last pose by egomotion's own covariance (the
    /// estimator's inverse information, chained through the keyframes),
    /// m: a second prediction to compare with `endpoint_error_m`.
    pub egomotion_sigma_m: Option<f64>,
    /// Egomotion outages: stretches of frames no keyframe matched, bridged
    /// by odometry.
    pub outages: Option<u32>,
    /// Seconds spent in outages.
    pub outage_s: Option<f64>,
    /// Metres driven across outages.
    pub outage_m: Option<f64>,
    /// Metres driven per metre the wheels counted, as egomotion's steps
    /// measured it by the end (with `Sideways` fusion): 0.99 is wheels
    /// that count 1 % long. Calibrate the robot's distance by it where
    /// drives agree: the pose steered by takes only part of it (weighed
    /// against the odometry noise model's `scale_sigma`).
    pub wheel_scale: Option<f64>,
    /// The standard error of `wheel_scale`.
    pub wheel_scale_sigma: Option<f64>,
    /// |true stop − egomotion stop|, m (thesis §4.4.3), both taken at the
    /// last stereo frame: the estimate is only as new as the frame.
    pub endpoint_error_m: Option<f64>,
    /// The end-point error as a share of the distance driven, %.
    pub endpoint_error_pct: Option<f64>,
    /// How much longer the path was than the straight line from start to
    /// goal, %.
    pub path_overhead_pct: Option<f64>,
    /// How much longer the run took than driving that straight line at top
    /// speed, %.
    pub time_overhead_pct: Option<f64>,
    /// Real seconds the run took: the only field that differs between two
    /// runs of the same scenario and seed.
    pub wall_time_s: f64,
}

/// A pose's JSON form, for the report's schema.
#[derive(schemars::JsonSchema)]
#[allow(dead_code)]
pub(crate) struct PoseSchema {
    /// m.
    x: f64,
    /// m.
    y: f64,
    /// Heading, rad, counter-clockwise from x.
    theta: f64,
}

/// The summary `ubf run` prints.
impl std::fmt::Display for RunReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let ending = match self.end {
            EndReason::GoalReached => "robot believes it reached the goal",
            EndReason::TimeLimit => "time limit",
            EndReason::BehaviorFailed => "a behaviour failed; the robot was stopped",
            EndReason::Interrupted => "interrupted",
            EndReason::NoProgress => "no progress: the robot stayed on one spot, and the run gave up",
        };
        let pose = |p: &Pose2| format!("({:.3}, {:.3}) m, {:.1}°", p.x, p.y, p.theta.to_degrees());
        writeln!(f, "scenario        {} (seed {})", self.scenario, self.seed)?;
        writeln!(f, "ended           {ending} after {:.1} s simulated, {} ticks", self.sim_time_s, self.ticks)?;
        if let Some(failure) = &self.failure {
            writeln!(f, "failure         {failure}")?;
        }
        let reached = match (self.has_goal, self.reached_goal) {
            (false, _) => "no goal set",
            (true, true) => "yes",
            (true, false) => "no",
        };
        writeln!(f, "goal reached    {reached}")?;
        writeln!(f, "distance        {:.2} m", self.distance_m)?;
        writeln!(f, "collisions      {}", self.collisions)?;
        writeln!(f, "true pose       {}", pose(&self.final_true_pose))?;
        writeln!(f, "estimated pose  {}", pose(&self.final_estimated_pose))?;
        if let (Some(error), Some(steps), Some(failures)) =
            (self.endpoint_error_m, self.egomotion_steps, self.egomotion_failures)
        {
            writeln!(f, "egomotion       end-point error {error:.2} m; {steps} steps, {failures} failed")?;
            if let Some(sigma) = self.predicted_endpoint_sigma_m {
                writeln!(f, "predicted       end-point σ {sigma:.2} m (the decision's error model)")?;
            }
            if let Some(sigma) = self.egomotion_sigma_m {
                writeln!(f, "                σ {sigma:.2} m (egomotion's own covariance)")?;
            }
            writeln!(
                f,
                "outages         {} ({:.1} s, {:.2} m driven on odometry)",
                self.outages.unwrap_or(0),
                self.outage_s.unwrap_or(0.0),
                self.outage_m.unwrap_or(0.0)
            )?;
            if let (Some(factor), Some(sigma)) = (self.wheel_scale, self.wheel_scale_sigma) {
                writeln!(f, "wheels          {}, measured by the camera", WheelScale { factor, sigma })?;
            }
        }
        writeln!(f, "wall time       {:.3} s", self.wall_time_s)
    }
}
