//! `ubf model fit-costs`: the egomotion error coefficients the end-point
//! decision weighs, measured from run logs (`trajectory.csv` files with
//! ground truth) instead of guessed.
//!
//! From each log the frames are taken (the rows where the stereo frame's
//! number changes) and the motion between consecutive frames compared with
//! the truth:
//!
//! Egomotion matches keyframes metres back, so the error of one
//! frame-to-frame step, or of the frames either side of a turn, is mostly
//! not what stays in the pose: the next frames re-anchor. What stays shows
//! at the end of each run, so the coefficients are fitted there, over all
//! runs at once, by non-negative least squares:
//! `e_end² ≈ σ_cv² · Σ (CV · d)² + Σ_turns (per_turn + per_rad · |turn|) · lever²`,
//! with `CV` each matched straight frame's fused step CV, `d` the metres it
//! drove, a turn a stretch of frames whose heading changes by more than
//! half a degree each, and `lever` the distance from the turn to the end.
//! (`ubf model fit-costs --check`, in `cost_forms`, compares this
//! form, on seeds kept apart, with others and with fitting at every tenth
//! frame instead of the end: none predicts the end points better.) The
//! heading error across each turn and the single steps' translation error
//! are reported beside the fit.
//!
//! Fitted that way, across runs of different routes, the step term is
//! credited with whatever separates the routes: one whose landmarks are far
//! has both larger CVs and larger errors. The decision chooses between
//! paths through the same place, so with `--against` each run is paired
//! with a straight run of the same scenario and seed, and the same form is
//! fitted to the differences: `Δe_end² ≈ σ_cv² · ΔΣ (CV · d)² + …`, what a
//! path's turns and views changed against driving straight.
//!
//! The odometry bridge's heading drift is measured directly: the heading
//! error each bridged step adds, per metre driven. Fitted at the end point
//! beside the others across routes it came out twelve times larger,
//! because runs that bridge more are runs whose visual steps are worse
//! too, so that fit leaves it out. In the differences from straight runs
//! (`--against`) it is fitted as a fourth term, `ΔΣ_bridged d · lever²`,
//! and printed beside the direct figure as a check on it.

use serde::Serialize;
use std::path::{Path, PathBuf};
use ubf_behaviors::decision::{drove_straight, turned, DecisionCosts, Fitted, FittedCosts};
use ubf_core::{angle_difference, Pose2};

/// Why logs could not be fitted.
#[derive(Debug, thiserror::Error)]
pub enum CostFitError {
    /// A log could not be read.
    #[error("reading {}: {source}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// A log is not a trajectory with ground truth and egomotion.
    #[error("{}:{line}: {message}", path.display())]
    Format {
        /// The file.
        path: PathBuf,
        /// The line, from 1.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// The logs come from too few seeds to keep some apart.
    #[error("need logs of at least three seeds (seed-N directories with trajectory.csv, as ubf sweep leaves them); found {seeds}")]
    TooFewSeeds {
        /// Seeds found.
        seeds: usize,
    },
    /// A log has no straight run to be paired with.
    #[error("{}: no straight run of scenario `{scenario}` and seed {seed} among the logs given to --against", path.display())]
    Unpaired {
        /// The log.
        path: PathBuf,
        /// Its scenario, as its report.json names it.
        scenario: String,
        /// Its seed.
        seed: u64,
    },
    /// A log's report, which names its scenario and seed, is missing or
    /// unreadable.
    #[error("{}: {message} (pairing runs needs the report.json `ubf run` and `ubf sweep` leave beside each trajectory.csv)", path.display())]
    Report {
        /// The report.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// The logs hold too few turns or steps to fit.
    #[error("too little to fit: {turns} turn(s), {steps} straight step(s) and {runs} run(s) to fit in {logs} log(s); need 3 turns, 3 steps and a run")]
    TooLittle {
        /// Logs read.
        logs: usize,
        /// Runs to fit (not counting the straight runs of `--against`).
        runs: usize,
        /// Turns found.
        turns: usize,
        /// Straight steps found.
        steps: usize,
    },
}

/// The fitted coefficients and what they rest on.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CostFit {
    /// Logs read.
    pub logs: usize,
    /// Turns fitted.
    pub turns: usize,
    /// Straight steps fitted.
    pub steps: usize,
    /// Runs fitted as differences against a straight run of the same
    /// scenario and seed; 0 when the runs were fitted as they are.
    pub paired: usize,
    /// Heading variance a turn leaves, per radian turned, rad².
    pub heading_var_per_rad: f64,
    /// Heading variance any turn leaves, rad².
    pub heading_var_per_turn: f64,
    /// Translation σ per unit of step CV and metre driven that stays in the
    /// end point.
    pub step_sigma_per_cv: f64,
    /// The same least squares free in sign: σ_cv² (m² per (CV·m)²), the
    /// heading variance per turn and per radian (rad²) and per metre on the
    /// odometry bridge (rad²/m). A coefficient the
    /// fit keeps at zero that is negative here is one the runs contradict,
    /// not merely one they cannot measure.
    pub unconstrained: [f64; 4],
    /// RMS heading error of the turns, °, and their mean size, °.
    pub turn_rms_error_deg: f64,
    /// Mean turn, °.
    pub turn_mean_deg: f64,
    /// RMS translation error of single frame-to-frame straight steps, m
    /// (for reference: most of it does not stay).
    pub step_rms_error_m: f64,
    /// Spearman's rank correlation of those steps' errors with their
    /// predicted `CV · d`: how well the error model the logs' egomotion
    /// used orders its steps' actual errors.
    pub step_error_rank_correlation: f64,
    /// Steps driven on the odometry bridge.
    pub bridged_steps: usize,
    /// Heading variance a metre on the odometry bridge adds, rad²/m,
    /// measured on the bridged steps themselves; `None` with fewer than 3.
    pub bridge_heading_var_per_m: Option<f64>,
    /// The same, fitted at the end point beside the other coefficients, in
    /// the differences from straight runs (`--against`): what of it stays.
    /// Reported as a check; the decision takes the direct figure, which
    /// rests on every bridged step rather than on a few per run.
    pub bridge_heading_var_per_m_at_end: Option<f64>,
}

impl CostFit {
    /// The coefficients as the decision takes them.
    pub fn costs(&self) -> DecisionCosts {
        DecisionCosts {
            step_sigma_per_cv: self.step_sigma_per_cv,
            heading_var_per_rad: self.heading_var_per_rad,
            heading_var_per_turn: self.heading_var_per_turn,
            bridge_heading_var_per_m: self
                .bridge_heading_var_per_m
                .unwrap_or(DecisionCosts::default().bridge_heading_var_per_m),
        }
    }
}

/// Puts `fit` into the decision's coefficients file at `path`, as `ubf
/// model fit-costs --write` does: its `against_straight` part when the runs
/// were fitted against straight ones, else its `levels` part, with `by`
/// (the command) as that part's provenance; the other part stays as the
/// file had it (as built in, if there is no file yet). The file is written
/// whole: to a temporary name, then renamed.
pub fn write_fitted(path: &Path, fit: &CostFit, by: &str) -> Result<(), String> {
    let mut fitted = match ubf_core::config::read_text_bounded(path, ubf_core::config::MOST_SETTINGS_BYTES) {
        Ok(text) => FittedCosts::parse(&text).map_err(|e| format!("{}:{e}", path.display()))?,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => FittedCosts::built_in().clone(),
        Err(e) => return Err(format!("{}: {e}", path.display())),
    };
    let part = Fitted { by: by.to_owned(), costs: fit.costs() };
    if fit.paired > 0 {
        fitted.against_straight = part;
    } else {
        fitted.levels = part;
    }
    ubf_session::atomic::write(path, fitted.to_file().as_bytes()).map_err(|e| format!("{}: {e}", path.display()))
}

/// One stereo frame as a log records it.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Frame {
    /// The true pose.
    pub truth: Pose2,
    /// Egomotion's pose.
    pub ego: Pose2,
    /// Whether egomotion matched the frame.
    pub matched: bool,
    /// The matched step's fused CV.
    pub step_cv: Option<f64>,
}

impl Frame {
    /// The squared distance between egomotion's position and the truth, m².
    pub fn error2(&self) -> f64 {
        (self.ego.x - self.truth.x).powi(2) + (self.ego.y - self.truth.y).powi(2)
    }
}

/// What one log says of its whole run.
#[derive(Clone, Debug, Default)]
struct RunSummary {
    /// Where each turn ended, and how far it turned, rad.
    turns: Vec<((f64, f64), f64)>,
    /// Σ (CV · d)² over the matched straight steps, m².
    step_cv_m2: f64,
    /// Where each step egomotion did not match (driven on the odometry
    /// bridge) ended, and the metres it drove.
    bridged: Vec<((f64, f64), f64)>,
    /// The true end position.
    end: (f64, f64),
    /// The squared end-point error, m².
    error2: f64,
}

/// Every `trajectory.csv` under `dirs` (searched recursively), or the files
/// themselves.
pub fn find_logs(dirs: &[PathBuf]) -> Result<Vec<PathBuf>, CostFitError> {
    fn walk(path: &Path, out: &mut Vec<PathBuf>) -> Result<(), CostFitError> {
        if path.is_file() {
            out.push(path.to_owned());
            return Ok(());
        }
        let read = |source| CostFitError::Read { path: path.to_owned(), source };
        let mut entries: Vec<PathBuf> =
            std::fs::read_dir(path).map_err(read)?.filter_map(|e| e.ok().map(|e| e.path())).collect();
        entries.sort();
        for entry in entries {
            // A link to a folder is not followed: one to `..` or `/` would
            // walk forever, or the whole disk.
            if entry.is_dir() && !entry.is_symlink() {
                walk(&entry, out)?;
            } else if entry.file_name().is_some_and(|n| n == "trajectory.csv") {
                out.push(entry);
            }
        }
        Ok(())
    }
    let mut out = Vec::new();
    for dir in dirs {
        walk(dir, &mut out)?;
    }
    Ok(out)
}

/// A stretch of a log between frames: a turn, from frame `from` to `to`
/// with every interval between them turning, or one interval without a
/// turn, from frame `from` to the next.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Stretch {
    /// A whole turn: until the robot stops turning.
    Turn {
        /// Its first frame.
        from: usize,
        /// Its last frame.
        to: usize,
    },
    /// An interval without a turn.
    Interval {
        /// Its first frame.
        from: usize,
    },
}

/// `frames` cut into turns and the intervals between them, in order.
pub(crate) fn stretches(frames: &[Frame]) -> Vec<Stretch> {
    let turning = |k: usize| turned(&frames[k + 1].truth.relative_to(&frames[k].truth));
    let mut out = Vec::new();
    let mut k = 0;
    while k + 1 < frames.len() {
        if turning(k) {
            let mut to = k + 1;
            while to + 1 < frames.len() && turning(to) {
                to += 1;
            }
            out.push(Stretch::Turn { from: k, to });
            k = to;
        } else {
            out.push(Stretch::Interval { from: k });
            k += 1;
        }
    }
    out
}

/// The stereo frames of the log at `path`.
pub(crate) fn read_frames(path: &Path) -> Result<Vec<Frame>, CostFitError> {
    let text = ubf_core::config::read_text_bounded(path, ubf_session::scenario::Work::MOST_LOG_BYTES)
        .map_err(|source| CostFitError::Read { path: path.to_owned(), source })?;
    let format = |line: usize, message: String| CostFitError::Format { path: path.to_owned(), line, message };
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap_or_default().split(',').collect();
    let column =
        |name: &str| header.iter().position(|h| *h == name).ok_or_else(|| format(1, format!("no `{name}` column")));
    let names =
        ["true_x", "true_y", "true_theta", "ego_x", "ego_y", "ego_theta", "ego_failures", "ego_step_cv", "frame"];
    let index: Vec<usize> = names.iter().map(|n| column(n)).collect::<Result<_, _>>()?;
    let mut frames = Vec::new();
    let (mut last_frame, mut last_failures) = (None, 0.0);
    for (n, line) in lines.enumerate() {
        let fields: Vec<&str> = line.split(',').collect();
        let value = |k: usize| -> Result<Option<f64>, CostFitError> {
            let text = fields.get(index[k]).copied().unwrap_or("");
            if text.is_empty() {
                return Ok(None);
            }
            text.parse::<f64>().map(Some).map_err(|_| format(n + 2, format!("`{}` is not a number", names[k])))
        };
        let Some(frame) = value(8)? else { continue };
        if Some(frame) == last_frame {
            continue;
        }
        last_frame = Some(frame);
        let (Some(tx), Some(ty), Some(tt)) = (value(0)?, value(1)?, value(2)?) else {
            return Err(format(n + 2, "no ground truth: a log from a real robot cannot be fitted".into()));
        };
        let (Some(ex), Some(ey), Some(et), Some(failures)) = (value(3)?, value(4)?, value(5)?, value(6)?) else {
            continue;
        };
        frames.push(Frame {
            truth: Pose2::new(tx, ty, tt),
            ego: Pose2::new(ex, ey, et),
            matched: failures == last_failures,
            step_cv: value(7)?,
        });
        last_failures = failures;
    }
    Ok(frames)
}

/// Least squares of `y = c·x` over `rows` with only the `active`
/// coefficients non-zero, each free in sign (all zero if singular). A term
/// that is zero in every row says nothing and is kept at zero.
pub(crate) fn least_squares<const N: usize>(rows: &[([f64; N], f64)], active: [bool; N]) -> [f64; N] {
    let index: Vec<usize> = (0..N).filter(|&k| active[k] && rows.iter().any(|(x, _)| x[k] != 0.0)).collect();
    let n = index.len();
    if n == 0 {
        // Nothing to fit (nalgebra's LU of a 0 × 0 matrix panics).
        return [0.0; N];
    }
    let mut a = nalgebra::DMatrix::<f64>::zeros(n, n);
    let mut b = nalgebra::DVector::<f64>::zeros(n);
    for (x, y) in rows {
        for (i, &p) in index.iter().enumerate() {
            b[i] += x[p] * y;
            for (j, &q) in index.iter().enumerate() {
                a[(i, j)] += x[p] * x[q];
            }
        }
    }
    let solution = a.lu().solve(&b).unwrap_or_else(|| nalgebra::DVector::zeros(n));
    let mut out = [0.0; N];
    for (i, &p) in index.iter().enumerate() {
        out[p] = solution[i];
    }
    out
}

/// Least squares of `y = c·x` over `rows` with every coefficient ≥ 0 and
/// only the `allowed` ones non-zero: the unconstrained solution, refitted
/// without the most negative coefficient until none is.
pub(crate) fn non_negative_least_squares<const N: usize>(rows: &[([f64; N], f64)], allowed: [bool; N]) -> [f64; N] {
    let mut active = allowed;
    loop {
        let c = least_squares(rows, active);
        let negative = (0..N).filter(|&k| c[k] < 0.0).min_by(|&a, &b| c[a].total_cmp(&c[b]));
        match negative {
            Some(k) => active[k] = false,
            None => return c,
        }
        if !active.iter().any(|a| *a) {
            return [0.0; N];
        }
    }
}

impl RunSummary {
    /// What the end-point form's coefficients multiply: Σ (CV·d)², the
    /// turns' Σ lever² and Σ |turn|·lever², and the bridged steps'
    /// Σ metres·lever².
    fn features(&self) -> [f64; 4] {
        let lever2 = |(x, y): (f64, f64)| (self.end.0 - x).powi(2) + (self.end.1 - y).powi(2);
        let per_turn: f64 = self.turns.iter().map(|(at, _)| lever2(*at)).sum();
        let per_rad: f64 = self.turns.iter().map(|(at, t)| t * lever2(*at)).sum();
        let bridged: f64 = self.bridged.iter().map(|(at, metres)| metres * lever2(*at)).sum();
        [self.step_cv_m2, per_turn, per_rad, bridged]
    }
}

/// What the logs read so far hold of single turns, steps and bridged
/// steps, reported beside the fit.
#[derive(Default)]
struct Samples {
    /// (|turn| rad, heading error² rad²) of each turn egomotion matched.
    turns: Vec<(f64, f64)>,
    /// (CV·d, translation error² m²) of each matched straight step.
    steps: Vec<(f64, f64)>,
    /// (metres driven, heading error² rad²) of each bridged step.
    bridged: Vec<(f64, f64)>,
}

impl Samples {
    /// Reads the log at `path`: its turns and steps join the samples, and
    /// its run's summary is returned (`None` for a log without frames).
    fn read(&mut self, path: &Path) -> Result<Option<RunSummary>, CostFitError> {
        let frames = read_frames(path)?;
        let mut run = RunSummary::default();
        for stretch in stretches(&frames) {
            match stretch {
                Stretch::Turn { from, to } => {
                    let (a, b) = (frames[from], frames[to]);
                    let turned = angle_difference(b.truth.theta, a.truth.theta);
                    run.turns.push(((b.truth.x, b.truth.y), turned.abs()));
                    if a.matched && b.matched {
                        let error = angle_difference(angle_difference(b.ego.theta, a.ego.theta), turned);
                        self.turns.push((turned.abs(), error * error));
                    }
                }
                Stretch::Interval { from } => {
                    let (a, b) = (frames[from], frames[from + 1]);
                    let true_step = b.truth.relative_to(&a.truth);
                    let driven = true_step.x.hypot(true_step.y);
                    if !b.matched {
                        if driven > 0.0 {
                            run.bridged.push(((b.truth.x, b.truth.y), driven));
                        }
                        if drove_straight(&true_step) {
                            let error = angle_difference(angle_difference(b.ego.theta, a.ego.theta), true_step.theta);
                            self.bridged.push((driven, error * error));
                        }
                    }
                    let matched_straight = a.matched && b.matched && drove_straight(&true_step);
                    if let Some(cv) = b.step_cv.filter(|_| matched_straight) {
                        let ego_step = b.ego.relative_to(&a.ego);
                        let error = (ego_step.x - true_step.x).hypot(ego_step.y - true_step.y);
                        self.steps.push((cv * driven, error * error));
                        run.step_cv_m2 += (cv * driven).powi(2);
                    }
                }
            }
        }
        Ok(frames.last().map(|last| {
            run.end = (last.truth.x, last.truth.y);
            run.error2 = last.error2();
            run
        }))
    }
}

/// The scenario and seed of the run whose log is `path`, as the
/// `report.json` beside it names them.
fn run_name(path: &Path) -> Result<(String, u64), CostFitError> {
    let report = path.with_file_name("report.json");
    let fail = |message: String| CostFitError::Report { path: report.clone(), message };
    let text = ubf_core::config::read_text_bounded(&report, ubf_core::config::MOST_SETTINGS_BYTES)
        .map_err(|e| fail(e.to_string()))?;
    let value: serde_json::Value = serde_json::from_str(&text).map_err(|e| fail(e.to_string()))?;
    match (value["scenario"].as_str(), value["seed"].as_u64()) {
        (Some(scenario), Some(seed)) => Ok((scenario.to_owned(), seed)),
        _ => Err(fail("no `scenario` name and `seed`".into())),
    }
}

/// Fits the coefficients to the logs at `paths`: to their end points as
/// they are, or, with logs of straight runs in `against`, to each log's
/// difference from the straight run of its scenario and seed (a log that
/// is itself in `against` is not fitted).
pub fn fit_costs(paths: &[PathBuf], against: &[PathBuf]) -> Result<CostFit, CostFitError> {
    let mut samples = Samples::default();
    let mut straight = std::collections::BTreeMap::new();
    for path in against {
        if let Some(run) = samples.read(path)? {
            straight.insert(run_name(path)?, run);
        }
    }
    // What stays in the end point, fitted over the runs at once:
    // e² ≈ σ_cv² · Σ (CV·d)² + Σ_turns (per_turn + per_rad · |turn|) · lever²,
    // or the same of the differences from the straight runs, there with
    // + bridge · Σ_bridged d · lever².
    let mut rows: Vec<([f64; 4], f64)> = Vec::new();
    let fitted: Vec<&PathBuf> = paths.iter().filter(|p| !against.contains(p)).collect();
    for path in &fitted {
        let Some(run) = samples.read(path)? else { continue };
        if against.is_empty() {
            rows.push((run.features(), run.error2));
            continue;
        }
        let (scenario, seed) = run_name(path)?;
        let Some(base) = straight.get(&(scenario.clone(), seed)) else {
            return Err(CostFitError::Unpaired { path: path.to_path_buf(), scenario, seed });
        };
        let (x, b) = (run.features(), base.features());
        rows.push((std::array::from_fn(|k| x[k] - b[k]), run.error2 - base.error2));
    }
    let Samples { turns, steps, bridged } = samples;
    let logs = fitted.len() + against.len();
    if turns.len() < 3 || steps.len() < 3 || rows.is_empty() {
        return Err(CostFitError::TooLittle { logs, turns: turns.len(), steps: steps.len(), runs: rows.len() });
    }
    // The bridge only in differences: across routes, runs that bridge more
    // are runs whose visual steps are worse too, and the bridge took their
    // share (twelve times what a bridged step costs).
    let paired = !against.is_empty();
    let allowed = [true, true, true, paired];
    let [step_var_per_cv2, per_turn, per_rad, bridge] = non_negative_least_squares(&rows, allowed);
    let unconstrained = least_squares(&rows, allowed);
    let mean = |v: &[(f64, f64)], f: &dyn Fn(&(f64, f64)) -> f64| v.iter().map(f).sum::<f64>() / v.len() as f64;
    Ok(CostFit {
        logs,
        turns: turns.len(),
        steps: steps.len(),
        paired: if against.is_empty() { 0 } else { rows.len() },
        heading_var_per_rad: per_rad,
        heading_var_per_turn: per_turn,
        step_sigma_per_cv: step_var_per_cv2.sqrt(),
        unconstrained,
        bridge_heading_var_per_m_at_end: paired.then_some(bridge),
        turn_rms_error_deg: mean(&turns, &|t| t.1).sqrt().to_degrees(),
        turn_mean_deg: mean(&turns, &|t| t.0).to_degrees(),
        step_rms_error_m: mean(&steps, &|s| s.1).sqrt(),
        step_error_rank_correlation: rank_correlation(&steps),
        bridged_steps: bridged.len(),
        bridge_heading_var_per_m: (bridged.len() >= 3).then(|| {
            let (metres, variance) = bridged.iter().fold((0.0, 0.0), |(m, v), b| (m + b.0, v + b.1));
            variance / metres
        }),
    })
}

/// Spearman's rank correlation of the pairs' two values (ties take their
/// mean rank).
fn rank_correlation(pairs: &[(f64, f64)]) -> f64 {
    fn ranks(values: Vec<f64>) -> Vec<f64> {
        let mut order: Vec<usize> = (0..values.len()).collect();
        order.sort_by(|&a, &b| values[a].total_cmp(&values[b]));
        let mut ranks = vec![0.0; values.len()];
        let mut start = 0;
        while start < order.len() {
            let mut end = start + 1;
            while end < order.len() && values[order[end]] == values[order[start]] {
                end += 1;
            }
            for &i in &order[start..end] {
                ranks[i] = (start + end - 1) as f64 / 2.0;
            }
            start = end;
        }
        ranks
    }
    let (a, b) = (ranks(pairs.iter().map(|p| p.0).collect()), ranks(pairs.iter().map(|p| p.1).collect()));
    let n = a.len() as f64;
    let mean = (n - 1.0) / 2.0;
    let (mut ab, mut aa, mut bb) = (0.0, 0.0, 0.0);
    for (x, y) in a.iter().zip(&b) {
        ab += (x - mean) * (y - mean);
        aa += (x - mean).powi(2);
        bb += (y - mean).powi(2);
    }
    if aa > 0.0 && bb > 0.0 {
        ab / (aa * bb).sqrt()
    } else {
        0.0
    }
}

/// What `ubf model fit-costs` prints.
impl std::fmt::Display for CostFit {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(f, "logs            {} ({} turns, {} straight steps)", self.logs, self.turns, self.steps)?;
        if self.paired > 0 {
            writeln!(
                f,
                "fitted          {} runs, each as its difference from the straight run of its scenario and seed",
                self.paired
            )?;
        }
        writeln!(
            f,
            "turns           mean {:.1}°, RMS heading error {:.3}°",
            self.turn_mean_deg, self.turn_rms_error_deg
        )?;
        writeln!(
            f,
            "steps           RMS translation error {:.4} m; rank correlation with CV·d {:.3}",
            self.step_rms_error_m, self.step_error_rank_correlation
        )?;
        match self.bridge_heading_var_per_m {
            Some(v) => writeln!(
                f,
                "bridged         {} steps on odometry: heading variance {v:.3e} rad² per metre ({:.2}° per √m)",
                self.bridged_steps,
                v.sqrt().to_degrees()
            )?,
            None => writeln!(
                f,
                "bridged         {} steps on odometry: too few to measure; default kept",
                self.bridged_steps
            )?,
        }
        if let Some(v) = self.bridge_heading_var_per_m_at_end {
            writeln!(f, "                fitted at the end point beside the others: {v:.3e} rad² per metre")?;
        }
        let [cv2, per_turn, per_rad, bridge] = self.unconstrained;
        let bridge = match self.bridge_heading_var_per_m_at_end {
            Some(_) => format!(", per bridged metre {bridge:.3e}"),
            None => String::new(),
        };
        writeln!(
            f,
            "free in sign    σ_cv² {cv2:.3e}, heading variance per turn {per_turn:.3e}, per radian {per_rad:.3e}{bridge} \
             (a negative one is contradicted by the runs; the decision takes it as 0)"
        )?;
        if self.paired > 0 {
            writeln!(f, "as the decision's costs (paste into ActionAiding(costs: ...)):")?;
        } else {
            writeln!(
                f,
                "as the levels a run's predicted σ takes (the decision's own costs are fitted --against straight runs):"
            )?;
        }
        writeln!(
            f,
            "  (step_sigma_per_cv: {:.4e}, heading_var_per_rad: {:.4e}, heading_var_per_turn: {:.4e}, \
             bridge_heading_var_per_m: {:.4e})",
            self.step_sigma_per_cv,
            self.heading_var_per_rad,
            self.heading_var_per_turn,
            self.costs().bridge_heading_var_per_m
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The columns the fit reads, as `ubf run` writes them.
    const HEADER: &str = "time_s,true_x,true_y,true_theta,ego_x,ego_y,ego_theta,ego_failures,ego_step_cv,frame\n";

    #[test]
    fn a_log_is_cut_into_whole_turns_and_the_intervals_between() {
        // Headings at the frames: straight, a turn over two intervals, then
        // straight again; a turn of a fifth of a degree is no turn.
        let headings = [0.0, 0.0, 10.0, 20.0, 20.0, 20.2];
        let frames: Vec<Frame> = headings
            .iter()
            .enumerate()
            .map(|(k, h)| {
                let pose = Pose2::new(0.3 * k as f64, 0.0, f64::to_radians(*h));
                Frame { truth: pose, ego: pose, matched: true, step_cv: Some(0.1) }
            })
            .collect();
        let expected = [
            Stretch::Interval { from: 0 },
            Stretch::Turn { from: 1, to: 3 },
            Stretch::Interval { from: 3 },
            Stretch::Interval { from: 4 },
        ];
        assert_eq!(stretches(&frames), expected);
        assert_eq!(stretches(&frames[..1]), []);
    }

    #[test]
    fn rank_correlation_is_spearmans() {
        let rising: Vec<(f64, f64)> = (0..10).map(|i| (f64::from(i), f64::from(i).powi(3))).collect();
        assert!((rank_correlation(&rising) - 1.0).abs() < 1e-12);
        let falling: Vec<(f64, f64)> = rising.iter().map(|&(a, b)| (a, -b)).collect();
        assert!((rank_correlation(&falling) + 1.0).abs() < 1e-12);
        // Ranks 1 2 3 4 5 against 2 1 4 3 5: 1 − 6·4/(5·24) = 0.8.
        let swapped = [(1.0, 2.0), (2.0, 1.0), (3.0, 4.0), (4.0, 3.0), (5.0, 5.0)];
        assert!((rank_correlation(&swapped) - 0.8).abs() < 1e-12);
    }

    #[test]
    fn least_squares_recover_coefficients_and_keep_them_non_negative() {
        let xs = [[1.0, 0.0, 2.0], [0.5, 3.0, 1.0], [2.0, 1.0, 0.0], [1.0, 1.0, 1.0], [0.0, 2.0, 5.0]];
        let exact: Vec<([f64; 3], f64)> = xs.iter().map(|x| (*x, 2.0 * x[0] + 0.5 * x[1] + 0.1 * x[2])).collect();
        let c = non_negative_least_squares(&exact, [true; 3]);
        for (got, want) in c.iter().zip([2.0, 0.5, 0.1]) {
            assert!((got - want).abs() < 1e-9, "{c:?}");
        }
        // A coefficient the data want negative is dropped, not kept below 0.
        let negative: Vec<([f64; 3], f64)> = xs.iter().map(|x| (*x, 2.0 * x[0] - 0.5 * x[1])).collect();
        let c = non_negative_least_squares(&negative, [true; 3]);
        assert!(c.iter().all(|v| *v >= 0.0), "{c:?}");
        assert_eq!(c[1], 0.0, "{c:?}");
        // Rows whose every term is zero (runs with no egomotion step) fit
        // nothing, and say so with zeros.
        let nothing: Vec<([f64; 3], f64)> = vec![([0.0; 3], 1.0); 4];
        assert_eq!(non_negative_least_squares(&nothing, [true; 3]), [0.0; 3]);
        assert_eq!(non_negative_least_squares(&exact, [false; 3]), [0.0; 3]);
    }

    #[test]
    fn a_log_is_read_into_turns_steps_and_its_end_point() {
        // Straight legs and turns; egomotion overshoots every turn by 0.01
        // rad, so the end point is off by what the last legs inherit.
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("trajectory.csv");
        let mut text = String::from(HEADER);
        let (mut truth, mut ego, mut frame) = (Pose2::default(), Pose2::default(), 0);
        let mut push = |t: &Pose2, e: &Pose2, frame: u32| {
            text += &format!("0,{},{},{},{},{},{},0,0.1,{frame}\n", t.x, t.y, t.theta, e.x, e.y, e.theta);
        };
        for leg in 0..6 {
            for _ in 0..4 {
                frame += 1;
                truth = truth.compose(&Pose2::new(0.3, 0.0, 0.0));
                ego = ego.compose(&Pose2::new(0.3, 0.0, 0.0));
                push(&truth, &ego, frame);
            }
            // Turns that drive on as they end, as tracking's do.
            let turn = if leg % 2 == 0 { 0.5 } else { -0.5 };
            for _ in 0..3 {
                frame += 1;
                truth = truth.compose(&Pose2::new(0.1, 0.0, turn / 3.0));
                ego = ego.compose(&Pose2::new(0.1, 0.0, (turn + 0.01) / 3.0));
                push(&truth, &ego, frame);
            }
        }
        std::fs::write(&path, text).unwrap();
        let fit = fit_costs(std::slice::from_ref(&path), &[]).unwrap();
        assert_eq!((fit.logs, fit.turns), (1, 6));
        assert!((fit.turn_rms_error_deg - 0.01f64.to_degrees()).abs() < 1e-6, "{fit:?}");
        assert!((fit.turn_mean_deg - 0.5f64.to_degrees()).abs() < 1e-6, "{fit:?}");
        assert!(fit.step_rms_error_m < 0.01, "steps inherit only the turns' error: {fit:?}");
        // A log without ground truth is refused with its line.
        std::fs::write(&path, format!("{HEADER}0,,,,1,2,3,0,,1\n")).unwrap();
        let e = fit_costs(&[path], &[]).unwrap_err().to_string();
        assert!(e.contains(":2:") && e.contains("ground truth"), "{e}");
    }

    #[test]
    fn the_bridge_drift_is_measured_per_metre() {
        // 0.3 m steps; egomotion fails on frames 6 to 10 and drifts 0.01
        // rad on each: 1e-4 rad² per 0.3 m.
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("trajectory.csv");
        let mut text = String::from(HEADER);
        let (mut ego_theta, mut failures) = (0.0, 0);
        for frame in 1..=20 {
            let x = 0.3 * f64::from(frame);
            let bridged = (6..=10).contains(&frame);
            if bridged {
                ego_theta += 0.01;
                failures += 1;
            }
            let cv = if bridged { String::new() } else { "0.1".into() };
            text += &format!("0,{x},0,0,{x},0,{ego_theta},{failures},{cv},{frame}\n");
        }
        std::fs::write(&path, text).unwrap();
        // The fit needs turns too: a second log of short legs and turns.
        let frames = read_frames(&path).unwrap();
        assert_eq!(frames.iter().filter(|f| !f.matched).count(), 5);
        let mut logs = vec![path.clone()];
        let turning = dir.path().join("turning").join("trajectory.csv");
        std::fs::create_dir_all(turning.parent().unwrap()).unwrap();
        let mut text = String::from(HEADER);
        // Legs of two 0.3 m steps, each followed by a turn on the spot.
        let (mut pose, mut frame) = (Pose2::default(), 0);
        for _ in 0..4 {
            for step in [Pose2::new(0.3, 0.0, 0.0), Pose2::new(0.3, 0.0, 0.0), Pose2::new(0.0, 0.0, 0.2)] {
                pose = pose.compose(&step);
                frame += 1;
                let (x, y, theta) = (pose.x, pose.y, pose.theta);
                text += &format!("0,{x},{y},{theta},{x},{y},{theta},0,0.1,{frame}\n");
            }
        }
        std::fs::write(&turning, text).unwrap();
        logs.push(turning);
        let fit = fit_costs(&logs, &[]).unwrap();
        assert_eq!(fit.bridged_steps, 5);
        let measured = fit.bridge_heading_var_per_m.unwrap();
        assert!((measured - 1e-4 / 0.3).abs() < 1e-12, "{measured}");
        assert_eq!(fit.costs().bridge_heading_var_per_m, measured);
    }

    /// Writes a run's log and report under `dir/NAME/seed-SEED`: legs of
    /// four 0.3 m steps with a turn of `turn` rad on the spot after each,
    /// egomotion overshooting every turn by `overshoot` rad.
    fn write_run(dir: &Path, name: &str, seed: u64, turn: f64, overshoot: f64) -> PathBuf {
        let run = dir.join(name).join(format!("seed-{seed}"));
        std::fs::create_dir_all(&run).unwrap();
        let mut text = String::from(HEADER);
        let (mut truth, mut ego, mut frame) = (Pose2::default(), Pose2::default(), 0);
        for leg in 0..4 {
            let steps = [Pose2::new(0.3, 0.0, 0.0); 4];
            let sign = if leg % 2 == 0 { 1.0 } else { -1.0 };
            let turns = [(Pose2::new(0.0, 0.0, sign * turn), Pose2::new(0.0, 0.0, sign * (turn + overshoot)))];
            for (t, e) in steps.iter().map(|s| (*s, *s)).chain(turns.into_iter().filter(|_| turn > 0.0)) {
                truth = truth.compose(&t);
                ego = ego.compose(&e);
                frame += 1;
                text += &format!(
                    "0,{},{},{},{},{},{},0,0.1,{frame}\n",
                    truth.x, truth.y, truth.theta, ego.x, ego.y, ego.theta
                );
            }
        }
        std::fs::write(run.join("trajectory.csv"), text).unwrap();
        std::fs::write(run.join("report.json"), format!("{{\"scenario\": \"route\", \"seed\": {seed}}}")).unwrap();
        run.join("trajectory.csv")
    }

    #[test]
    fn against_straight_runs_each_run_is_fitted_as_its_difference_from_its_own() {
        let dir = tempfile::tempdir().unwrap();
        let straight: Vec<PathBuf> = (1..=3).map(|seed| write_run(dir.path(), "straight", seed, 0.0, 0.0)).collect();
        // Turns of 0.2, 0.4 and 0.6 rad, each overshot by a tenth of itself.
        let turning: Vec<PathBuf> =
            (1..=3).map(|seed| write_run(dir.path(), "turning", seed, 0.2 * seed as f64, 0.02 * seed as f64)).collect();
        let fit = fit_costs(&[straight.clone(), turning.clone()].concat(), &straight).unwrap();
        assert_eq!((fit.logs, fit.paired), (6, 3), "{fit:?}");
        // Written where the decision reads its coefficients: this part
        // replaced, the other kept.
        let file = dir.path().join("decision_costs.ron");
        write_fitted(&file, &fit, "ubf model fit-costs turning --against straight").unwrap();
        let written = FittedCosts::parse(&std::fs::read_to_string(&file).unwrap()).unwrap();
        assert_eq!(written.against_straight.costs, fit.costs());
        assert_eq!(written.against_straight.by, "ubf model fit-costs turning --against straight");
        assert_eq!(written.levels, FittedCosts::built_in().levels);
        // The straight runs end exactly where they are: what the turning
        // runs' errors differ by is the turns', not the steps'.
        assert_eq!(fit.step_sigma_per_cv, 0.0, "{fit:?}");
        assert!(fit.heading_var_per_rad + fit.heading_var_per_turn > 0.0, "{fit:?}");
        // No run bridged a step: the bridge's fourth term is fitted, as
        // nothing. Across runs as they are it is left out.
        assert_eq!(fit.bridge_heading_var_per_m_at_end, Some(0.0), "{fit:?}");
        assert_eq!(fit_costs(&turning, &[]).unwrap().bridge_heading_var_per_m_at_end, None);
        // A run without its straight run is refused, named.
        let e = fit_costs(&turning, &straight[..2]).unwrap_err().to_string();
        assert!(e.contains("seed-3") && e.contains("`route` and seed 3"), "{e}");
        // And so is one whose report is gone.
        std::fs::remove_file(turning[0].with_file_name("report.json")).unwrap();
        let e = fit_costs(&turning, &straight).unwrap_err().to_string();
        assert!(e.contains("report.json"), "{e}");
    }
}
