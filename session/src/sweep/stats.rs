//! The statistics a sweep's summary gives each report field: mean,
//! spread and a 95 % confidence interval that respects a field's sign.

use crate::run::RunReport;
use serde::Serialize;

/// Mean, spread and 95 % confidence interval of one report field.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FieldStats {
    /// Runs that reported the field.
    pub n: usize,
    /// Mean.
    pub mean: f64,
    /// Sample standard deviation (0 for one run).
    pub sd: f64,
    /// 95 % confidence interval of the mean; `None` below two runs, where
    /// it means nothing.
    pub ci95: Option<[f64; 2]>,
    /// How the interval was found: `t` (Student's t), or `bootstrap` (the
    /// percentile bootstrap of the mean) for a field with no negative value
    /// whose t interval would reach below zero.
    pub ci95_method: Option<&'static str>,
}

/// Resamples of the bootstrap interval.
const BOOTSTRAP_RESAMPLES: usize = 4000;

/// The percentile bootstrap 95 % interval of the mean of `values`, with a
/// fixed seed so that a summary is reproducible.
fn bootstrap_ci95(values: &[f64]) -> [f64; 2] {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(0);
    let n = values.len();
    let mut means: Vec<f64> = (0..BOOTSTRAP_RESAMPLES)
        .map(|_| (0..n).map(|_| values[rng.random_range(0..n)]).sum::<f64>() / n as f64)
        .collect();
    means.sort_by(f64::total_cmp);
    let at = |q: f64| means[((q * (BOOTSTRAP_RESAMPLES - 1) as f64).round() as usize).min(BOOTSTRAP_RESAMPLES - 1)];
    [at(0.025), at(0.975)]
}

/// The two-sided 95 % quantile of Student's t with `dof` degrees of freedom.
pub fn t95(dof: usize) -> f64 {
    const TABLE: [f64; 30] = [
        12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306, 2.262, 2.228, 2.201, 2.179, 2.160, 2.145, 2.131,
        2.120, 2.110, 2.101, 2.093, 2.086, 2.080, 2.074, 2.069, 2.064, 2.060, 2.056, 2.052, 2.048, 2.045, 2.042,
    ];
    match dof {
        0 => f64::NAN,
        1..=30 => TABLE[dof - 1],
        _ => {
            // Cornish–Fisher expansion around the normal quantile; within
            // 1e-4 of the exact value from 30 degrees of freedom up.
            let z: f64 = 1.959_964;
            let v = dof as f64;
            z + (z.powi(3) + z) / (4.0 * v) + (5.0 * z.powi(5) + 16.0 * z.powi(3) + 3.0 * z) / (96.0 * v * v)
        }
    }
}

/// Mean, standard deviation and confidence interval of `values`.
pub fn stats(values: &[f64]) -> FieldStats {
    let n = values.len();
    let mean = values.iter().sum::<f64>() / n as f64;
    let sd = if n > 1 { (values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1) as f64).sqrt() } else { 0.0 };
    if n < 2 {
        return FieldStats { n, mean, sd, ci95: None, ci95_method: None };
    }
    let half = t95(n - 1) * sd / (n as f64).sqrt();
    let (ci95, method) = if mean - half < 0.0 && values.iter().all(|v| *v >= 0.0) {
        (bootstrap_ci95(values), "bootstrap")
    } else {
        ([mean - half, mean + half], "t")
    };
    FieldStats { n, mean, sd, ci95: Some(ci95), ci95_method: Some(method) }
}

/// Every numeric leaf of a report, with dotted names.
pub(super) fn numeric_fields(report: &RunReport) -> Vec<(String, f64)> {
    numeric_leaves(&serde_json::to_value(report).expect("a report always serialises"))
}

/// Every numeric leaf of a report read as JSON, with dotted names (booleans
/// as 0 and 1), leaving out `seed` and `wall_time_s`.
pub(super) fn numeric_leaves(report: &serde_json::Value) -> Vec<(String, f64)> {
    fn walk(prefix: &str, value: &serde_json::Value, out: &mut Vec<(String, f64)>) {
        match value {
            serde_json::Value::Number(n) => out.extend(n.as_f64().map(|v| (prefix.to_owned(), v))),
            serde_json::Value::Bool(b) => out.push((prefix.to_owned(), f64::from(u8::from(*b)))),
            serde_json::Value::Object(map) => {
                for (key, v) in map {
                    let name = if prefix.is_empty() { key.clone() } else { format!("{prefix}.{key}") };
                    walk(&name, v, out);
                }
            }
            _ => {}
        }
    }
    let mut out = Vec::new();
    walk("", report, &mut out);
    out.retain(|(name, _)| name != "seed" && name != "wall_time_s");
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn t_quantiles() {
        assert_eq!(t95(1), 12.706);
        assert_eq!(t95(29), 2.045);
        // Exact values: 2.0211 at 40, 1.9840 at 100.
        assert!((t95(40) - 2.0211).abs() < 2e-4);
        assert!((t95(100) - 1.9840).abs() < 2e-4);
    }

    #[test]
    fn stats_of_a_known_sample() {
        let s = stats(&[1.0, 2.0, 3.0, 4.0]);
        assert_eq!(s.mean, 2.5);
        assert!((s.sd - 1.290_994).abs() < 1e-6);
        let half = 3.182 * s.sd / 2.0;
        assert!((s.ci95.unwrap()[1] - (2.5 + half)).abs() < 1e-12);
        assert_eq!(s.ci95_method, Some("t"));
        // One run: no interval at all, not a zero-width one.
        assert_eq!(stats(&[5.0]).ci95, None);
        // Errors cannot be negative, nor can their interval: three skewed
        // end-point errors whose t interval reaches −6.7 m.
        let skewed = stats(&[0.3, 0.5, 24.0]);
        let [low, high] = skewed.ci95.unwrap();
        assert_eq!(skewed.ci95_method, Some("bootstrap"));
        assert!((0.3..=24.0).contains(&low) && low < skewed.mean && skewed.mean < high && high <= 24.0, "{skewed:?}");
        // A field that can be negative keeps its t interval.
        assert_eq!(stats(&[-1.0, 0.5, 2.0]).ci95_method, Some("t"));
    }
}
