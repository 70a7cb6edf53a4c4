//! `ubf model fit-costs`: the egomotion error coefficients the end-point
//! decision weighs, measured from run logs (`trajectory.csv` files with
//! ground truth) instead of guessed.
//!
//! From each log the frames are taken (the rows where the stereo frame's
//! number changes) and the motion between consecutive frames compared with
//! the truth:
//!
//! - **Turns.** A stretch of frames over which the robot turned on the spot
//!   is one turn. The heading error it leaves, `e = Δθ_ego − Δθ_true`
//!   between the matched frames on either side, is fitted as
//!   `E[e²] = per_turn + per_rad · |Δθ_true|` by least squares.
//! - **Steps.** Between two matched frames of straight driving, the
//!   translation error `|Δp_ego − Δp_true|` is fitted as
//!   `E[e²] = (σ_cv · CV · d)²` through the origin, with `CV` the later
//!   frame's fused step CV and `d` the metres driven.

use serde::Serialize;
use std::path::{Path, PathBuf};
use ubf_behaviors::decision::DecisionCosts;
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
    /// The logs hold too few turns or steps to fit.
    #[error("too little to fit: {turns} turn(s) and {steps} straight step(s) in {logs} log(s); need 3 of each")]
    TooLittle {
        /// Logs read.
        logs: usize,
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
    /// Heading variance a turn leaves, per radian turned, rad².
    pub heading_var_per_rad: f64,
    /// Heading variance any turn leaves, rad².
    pub heading_var_per_turn: f64,
    /// Translation σ per unit of step CV and metre driven.
    pub step_sigma_per_cv: f64,
    /// RMS heading error of the turns, °, and their mean size, °.
    pub turn_rms_error_deg: f64,
    /// Mean turn, °.
    pub turn_mean_deg: f64,
    /// RMS translation error of the straight steps, m.
    pub step_rms_error_m: f64,
}

impl CostFit {
    /// The coefficients as the decision takes them.
    pub fn costs(&self) -> DecisionCosts {
        DecisionCosts {
            step_sigma_per_cv: self.step_sigma_per_cv,
            heading_var_per_rad: self.heading_var_per_rad,
            heading_var_per_turn: self.heading_var_per_turn,
        }
    }
}

/// One stereo frame as a log records it.
#[derive(Clone, Copy, Debug)]
struct Frame {
    truth: Pose2,
    ego: Pose2,
    matched: bool,
    step_cv: Option<f64>,
}

/// A turn on the spot: the true heading changed by more than this between
/// frames while the robot moved less than `STILL_M`.
const TURNING_RAD: f64 = 0.5 * std::f64::consts::PI / 180.0;
const STILL_M: f64 = 0.05;

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
            if entry.is_dir() {
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

fn read_frames(path: &Path) -> Result<Vec<Frame>, CostFitError> {
    let text = std::fs::read_to_string(path).map_err(|source| CostFitError::Read { path: path.to_owned(), source })?;
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

/// Least squares of `y = a + b·x` with `a, b ≥ 0`.
fn fit_line_non_negative(points: &[(f64, f64)]) -> (f64, f64) {
    let n = points.len() as f64;
    let (sx, sy) = points.iter().fold((0.0, 0.0), |(a, b), (x, y)| (a + x, b + y));
    let (mx, my) = (sx / n, sy / n);
    let sxx: f64 = points.iter().map(|(x, _)| (x - mx).powi(2)).sum();
    let sxy: f64 = points.iter().map(|(x, y)| (x - mx) * (y - my)).sum();
    let slope = if sxx > 0.0 { sxy / sxx } else { 0.0 };
    let intercept = my - slope * mx;
    if slope < 0.0 {
        return (my.max(0.0), 0.0);
    }
    if intercept < 0.0 {
        let sxx0: f64 = points.iter().map(|(x, _)| x * x).sum();
        let sxy0: f64 = points.iter().map(|(x, y)| x * y).sum();
        return (0.0, if sxx0 > 0.0 { (sxy0 / sxx0).max(0.0) } else { 0.0 });
    }
    (intercept, slope)
}

/// Fits the coefficients to the logs at `paths`.
pub fn fit_costs(paths: &[PathBuf]) -> Result<CostFit, CostFitError> {
    // (|turn| rad, e² rad²) and (CV·d, e² m²).
    let mut turns: Vec<(f64, f64)> = Vec::new();
    let mut steps: Vec<(f64, f64)> = Vec::new();
    for path in paths {
        let frames = read_frames(path)?;
        let mut k = 0;
        while k + 1 < frames.len() {
            let (a, b) = (frames[k], frames[k + 1]);
            let true_step = b.truth.relative_to(&a.truth);
            let turning = true_step.theta.abs() > TURNING_RAD && true_step.x.hypot(true_step.y) < STILL_M;
            if turning {
                // The whole turn: until the robot stops turning on the spot.
                let mut end = k + 1;
                while end + 1 < frames.len() {
                    let s = frames[end + 1].truth.relative_to(&frames[end].truth);
                    if !(s.theta.abs() > TURNING_RAD && s.x.hypot(s.y) < STILL_M) {
                        break;
                    }
                    end += 1;
                }
                let (a, b) = (frames[k], frames[end]);
                if a.matched && b.matched {
                    let turned = angle_difference(b.truth.theta, a.truth.theta);
                    let error = angle_difference(angle_difference(b.ego.theta, a.ego.theta), turned);
                    turns.push((turned.abs(), error * error));
                }
                k = end;
                continue;
            }
            let driven = true_step.x.hypot(true_step.y);
            if a.matched && b.matched && driven >= STILL_M && true_step.theta.abs() <= TURNING_RAD {
                if let Some(cv) = b.step_cv {
                    let ego_step = b.ego.relative_to(&a.ego);
                    let error = (ego_step.x - true_step.x).hypot(ego_step.y - true_step.y);
                    steps.push((cv * driven, error * error));
                }
            }
            k += 1;
        }
    }
    if turns.len() < 3 || steps.len() < 3 {
        return Err(CostFitError::TooLittle { logs: paths.len(), turns: turns.len(), steps: steps.len() });
    }
    let (per_turn, per_rad) = fit_line_non_negative(&turns);
    let (sxx, sxy) = steps.iter().fold((0.0, 0.0), |(a, b), (x, y)| (a + x * x * x * x, b + x * x * y));
    let step_var_per_cv2 = if sxx > 0.0 { (sxy / sxx).max(0.0) } else { 0.0 };
    let mean = |v: &[(f64, f64)], f: &dyn Fn(&(f64, f64)) -> f64| v.iter().map(f).sum::<f64>() / v.len() as f64;
    Ok(CostFit {
        logs: paths.len(),
        turns: turns.len(),
        steps: steps.len(),
        heading_var_per_rad: per_rad,
        heading_var_per_turn: per_turn,
        step_sigma_per_cv: step_var_per_cv2.sqrt(),
        turn_rms_error_deg: mean(&turns, &|t| t.1).sqrt().to_degrees(),
        turn_mean_deg: mean(&turns, &|t| t.0).to_degrees(),
        step_rms_error_m: mean(&steps, &|s| s.1).sqrt(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_line_is_fitted_and_kept_non_negative() {
        let points: Vec<(f64, f64)> = (0..10).map(|i| (f64::from(i), 2.0 + 3.0 * f64::from(i))).collect();
        let (a, b) = fit_line_non_negative(&points);
        assert!((a - 2.0).abs() < 1e-9 && (b - 3.0).abs() < 1e-9);
        let falling: Vec<(f64, f64)> = (0..10).map(|i| (f64::from(i), 10.0 - f64::from(i))).collect();
        assert_eq!(fit_line_non_negative(&falling).1, 0.0);
        let through_zero: Vec<(f64, f64)> = (1..10).map(|i| (f64::from(i), -1.0 + 2.0 * f64::from(i))).collect();
        let (a, b) = fit_line_non_negative(&through_zero);
        assert_eq!(a, 0.0);
        assert!(b > 1.5 && b < 2.0, "{b}");
    }

    #[test]
    fn coefficients_come_back_from_synthetic_logs() {
        // A log whose egomotion overshoots every turn by sqrt(1e-4·|turn|):
        // a heading variance of 1e-4 rad² per radian turned, and none per
        // turn.
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("trajectory.csv");
        let mut text =
            String::from("time_s,true_x,true_y,true_theta,ego_x,ego_y,ego_theta,ego_failures,ego_step_cv,frame\n");
        let (mut x, mut theta, mut ego_theta, mut frame) = (0.0, 0.0, 0.0, 0);
        let mut push = |x: f64, theta: f64, ego_x: f64, ego_theta: f64, frame: u32| {
            text += &format!("0,{x},0,{theta},{ego_x},0,{ego_theta},0,0.1,{frame}\n");
        };
        for leg in 0..12 {
            for _ in 0..4 {
                frame += 1;
                x += 0.3;
                push(x, theta, x * 1.0, ego_theta, frame);
            }
            let turn: f64 = if leg % 2 == 0 { 0.5 } else { -0.25 };
            let overshoot = (1e-4 * turn.abs()).sqrt();
            for _ in 0..3 {
                frame += 1;
                theta += turn / 3.0;
                ego_theta += (turn + overshoot) / 3.0;
                push(x, theta, x, ego_theta, frame);
            }
        }
        std::fs::write(&path, text).unwrap();
        let fit = fit_costs(&[path]).unwrap();
        assert_eq!(fit.turns, 12);
        assert!((fit.heading_var_per_rad - 1e-4).abs() < 1e-8, "{fit:?}");
        assert!(fit.heading_var_per_turn < 1e-9, "{fit:?}");
        // The steps are exact but for the heading error they inherit.
        assert!(fit.step_rms_error_m < 0.03, "{fit:?}");
    }
}
