//! `ubf model fit-costs --check`: whether another form of the end-point
//! model would predict what stays in the end point better than the one the
//! decision uses, judged on seeds kept apart.
//!
//! The runs are split by seed (the first two thirds fit, the rest test).
//! Each form is fitted by the same non-negative least squares as
//! [`crate::cost_fit`], either at the end points alone or at every tenth
//! matched frame and the end, and scored by the mean negative
//! log-likelihood of the test runs' end-point errors under its fitted σ (a
//! 2D Gaussian: lower is better).

use crate::cost_fit::{non_negative_least_squares, read_frames, stretches, CostFitError, Stretch};
use serde::Serialize;
use std::path::{Path, PathBuf};
use ubf_behaviors::decision::drove_straight;
use ubf_core::angle_difference;

/// The terms a form may weigh, in the order of a checkpoint's features.
const TERMS: [&str; 5] =
    ["σ_cv² per (CV·d)²", "heading per turn", "heading per radian", "position per turn", "per metre²"];

/// The forms compared: the terms each weighs.
const FORMS: [(&str, [bool; 5]); 4] = [
    ("in use: steps, heading per turn and per radian", [true, true, true, false, false]),
    ("+ position per turn", [true, true, true, true, false]),
    ("+ variance per metre² driven", [true, true, true, false, true]),
    ("all five", [true; 5]),
];

/// A frame where a form's prediction is compared with the error: the
/// features the terms multiply, the squared position error there, and
/// whether it is the run's end.
#[derive(Clone, Copy, Debug)]
struct Checkpoint {
    features: [f64; 5],
    error2: f64,
    end: bool,
}

/// One form's score.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FormScore {
    /// Where it was fitted: `end points` or `every tenth frame`.
    pub fitted_at: &'static str,
    /// The form.
    pub form: &'static str,
    /// Mean negative log-likelihood of the test end points.
    pub nll: f64,
    /// The non-zero fitted coefficients, by term.
    pub coefficients: Vec<(&'static str, f64)>,
}

/// Every form's score, and what they rest on.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FormCheck {
    /// Logs read.
    pub logs: usize,
    /// Seeds fitted on, first and last.
    pub fitted_seeds: [u64; 2],
    /// Seeds tested on, first and last.
    pub tested_seeds: [u64; 2],
    /// End points tested.
    pub tested: usize,
    /// The scores, end-point fits first.
    pub scores: Vec<FormScore>,
}

/// A log's run seed, from the `seed-N` directory a sweep leaves it in.
fn seed_of(path: &Path) -> Option<u64> {
    path.components().rev().find_map(|c| c.as_os_str().to_str()?.strip_prefix("seed-")?.parse().ok())
}

/// The checkpoints of the log at `path`.
fn checkpoints(path: &Path) -> Result<Vec<Checkpoint>, CostFitError> {
    let frames = read_frames(path)?;
    let mut out = Vec::new();
    // The places and sizes of the turns so far; Σ (CV·d)² and Σ d² of the
    // matched straight steps.
    let mut turns: Vec<((f64, f64), f64)> = Vec::new();
    let (mut cv2, mut d2) = (0.0, 0.0);
    let checkpoint = |at: usize, turns: &[((f64, f64), f64)], cv2: f64, d2: f64, end: bool| {
        let f = frames[at];
        let lever2 = |(x, y): (f64, f64)| (f.truth.x - x).powi(2) + (f.truth.y - y).powi(2);
        let per_turn: f64 = turns.iter().map(|(p, _)| lever2(*p)).sum();
        let per_rad: f64 = turns.iter().map(|(p, t)| t * lever2(*p)).sum();
        Checkpoint { features: [cv2, per_turn, per_rad, turns.len() as f64, d2], error2: f.error2(), end }
    };
    for stretch in stretches(&frames) {
        let (Stretch::Turn { from, .. } | Stretch::Interval { from }) = stretch;
        if from % 10 == 9 && frames[from].matched {
            out.push(checkpoint(from, &turns, cv2, d2, false));
        }
        match stretch {
            Stretch::Turn { from, to } => {
                let at = frames[to].truth;
                turns.push(((at.x, at.y), angle_difference(at.theta, frames[from].truth.theta).abs()));
            }
            Stretch::Interval { from } => {
                let (a, b) = (frames[from], frames[from + 1]);
                let step = b.truth.relative_to(&a.truth);
                let matched_straight = a.matched && b.matched && drove_straight(&step);
                if let Some(cv) = b.step_cv.filter(|_| matched_straight) {
                    let d = step.x.hypot(step.y);
                    cv2 += (cv * d).powi(2);
                    d2 += d * d;
                }
            }
        }
    }
    if !frames.is_empty() {
        out.push(checkpoint(frames.len() - 1, &turns, cv2, d2, true));
    }
    Ok(out)
}

/// Scores every form on the logs at `paths` (each in a sweep's
/// `seed-N` directory; at least three seeds).
pub fn check_forms(paths: &[PathBuf]) -> Result<FormCheck, CostFitError> {
    let mut runs = Vec::new();
    for path in paths {
        if let Some(seed) = seed_of(path) {
            runs.push((seed, checkpoints(path)?));
        }
    }
    let mut seeds: Vec<u64> = runs.iter().map(|(s, _)| *s).collect();
    seeds.sort_unstable();
    seeds.dedup();
    if seeds.len() < 3 {
        return Err(CostFitError::TooFewSeeds { seeds: seeds.len() });
    }
    // Seeds are sorted: those before the split fit, the rest test.
    let split = seeds.len() * 2 / 3;
    let cut = seeds[split];
    let train: Vec<Checkpoint> = runs.iter().filter(|(s, _)| *s < cut).flat_map(|(_, c)| c.iter().copied()).collect();
    let test: Vec<Checkpoint> =
        runs.iter().filter(|(s, _)| *s >= cut).flat_map(|(_, c)| c.iter().copied()).filter(|c| c.end).collect();
    let mut scores = Vec::new();
    for (fitted_at, at_ends) in [("end points", true), ("every tenth frame", false)] {
        let rows: Vec<([f64; 5], f64)> =
            train.iter().filter(|c| c.end || !at_ends).map(|c| (c.features, c.error2)).collect();
        for (form, terms) in FORMS {
            let c = non_negative_least_squares(&rows, terms);
            let nll = test
                .iter()
                .map(|t| {
                    let variance = t.features.iter().zip(c).map(|(x, k)| x * k).sum::<f64>().max(1e-6);
                    (variance / 2.0).ln() + t.error2 / variance
                })
                .sum::<f64>()
                / test.len().max(1) as f64;
            let coefficients = TERMS.iter().zip(c).filter(|(_, k)| *k != 0.0).map(|(t, k)| (*t, k)).collect();
            scores.push(FormScore { fitted_at, form, nll, coefficients });
        }
    }
    Ok(FormCheck {
        logs: runs.len(),
        fitted_seeds: [seeds[0], seeds[split - 1]],
        tested_seeds: [cut, seeds[seeds.len() - 1]],
        tested: test.len(),
        scores,
    })
}

/// `x` with three significant digits, as C's `%.3g` writes it.
fn three_digits(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    // `{:.2e}` rounds to three digits and gives the exponent after
    // rounding: "2.34e-5".
    let scientific = format!("{x:.2e}");
    let (mantissa, power) = scientific.split_once('e').expect("exponent format has an `e`");
    let power: i32 = power.parse().expect("exponent format ends in a whole number");
    let trimmed =
        |t: &str| if t.contains('.') { t.trim_end_matches('0').trim_end_matches('.').to_owned() } else { t.to_owned() };
    if (-4..3).contains(&power) {
        let decimals = (2 - power) as usize;
        trimmed(&format!("{x:.decimals$}"))
    } else {
        format!("{}e{}{:02}", trimmed(mantissa), if power < 0 { '-' } else { '+' }, power.abs())
    }
}

/// What `ubf model fit-costs --check` prints.
impl std::fmt::Display for FormCheck {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let [a, b] = self.fitted_seeds;
        let [c, d] = self.tested_seeds;
        writeln!(
            f,
            "{} logs; fitted on seeds {a}..{b}, tested on the end points of seeds {c}..{d} ({})",
            self.logs, self.tested
        )?;
        let mut fitted_at = "";
        for s in &self.scores {
            if s.fitted_at != fitted_at {
                fitted_at = s.fitted_at;
                writeln!(f, "fitted at {fitted_at}:")?;
            }
            let fitted: Vec<String> = s.coefficients.iter().map(|(t, k)| format!("{t} {}", three_digits(*k))).collect();
            writeln!(f, "  {:48} NLL {:+.3}   {}", s.form, s.nll, fitted.join(", "))?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn three_digits_is_c_style_g() {
        let cases =
            [(0.502, "0.502"), (2.34e-5, "2.34e-05"), (0.00453, "0.00453"), (0.0897, "0.0897"), (1234.0, "1.23e+03")];
        for (x, want) in cases {
            assert_eq!(three_digits(x), want);
        }
        assert_eq!(three_digits(0.5), "0.5");
        assert_eq!(three_digits(12.0), "12");
        assert_eq!(three_digits(0.0001234), "0.000123");
    }

    /// A log of legs and turns whose egomotion overshoots each turn by
    /// `overshoot` rad, in the columns `ubf run` writes.
    fn log(dir: &Path, seed: u64, overshoot: f64) -> PathBuf {
        use ubf_core::Pose2;
        let path = dir.join(format!("route/seed-{seed}/trajectory.csv"));
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        let mut text =
            String::from("time_s,true_x,true_y,true_theta,ego_x,ego_y,ego_theta,ego_failures,ego_step_cv,frame\n");
        let (mut truth, mut ego, mut frame) = (Pose2::default(), Pose2::default(), 0);
        // Runs of different lengths, so that the terms are not collinear.
        for leg in 0..4 + seed % 5 {
            for (step, turn) in [(0.3, 0.0); 12].into_iter().chain([(0.0, if leg % 2 == 0 { 0.4 } else { -0.4 })]) {
                frame += 1;
                truth = truth.compose(&Pose2::new(step, 0.0, turn));
                ego = ego.compose(&Pose2::new(step, 0.0, turn + turn.signum() * overshoot));
                let (t, e) = (truth, ego);
                text += &format!("0,{},{},{},{},{},{},0,0.1,{frame}\n", t.x, t.y, t.theta, e.x, e.y, e.theta);
            }
        }
        std::fs::write(&path, text).unwrap();
        path
    }

    #[test]
    fn forms_are_fitted_on_the_first_seeds_and_scored_on_the_rest() {
        let dir = tempfile::tempdir().unwrap();
        let logs: Vec<PathBuf> = (0..6).map(|k| log(dir.path(), 10 + k, 0.002)).collect();
        let check = check_forms(&logs).unwrap();
        assert_eq!((check.logs, check.fitted_seeds, check.tested_seeds, check.tested), (6, [10, 13], [14, 15], 2));
        assert_eq!(check.scores.len(), 2 * FORMS.len());
        assert!(check.scores.iter().all(|s| s.nll.is_finite()), "{check:?}");
        // The errors come from the turns alone, which the form in use weighs.
        let in_use = &check.scores[0];
        assert!(in_use.coefficients.iter().any(|(t, k)| t.starts_with("heading") && *k > 0.0), "{in_use:?}");
        // Fewer than three seeds leave nothing to keep apart.
        let e = check_forms(&logs[..2]).unwrap_err().to_string();
        assert!(e.contains("at least three seeds") && e.contains("found 2"), "{e}");
    }

    #[test]
    fn seeds_come_from_the_sweep_directories() {
        assert_eq!(seed_of(Path::new("out/route~None/seed-104/trajectory.csv")), Some(104));
        assert_eq!(seed_of(Path::new("out/trajectory.csv")), None);
    }
}
