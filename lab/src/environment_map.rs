//! `ubf experiment where-aiding-pays`: a map of the environments in which
//! action aiding beats driving straight, and by how much.
//!
//! The base is route 1→2 (a 4 m × 62 m corridor, 40 landmarks, the rigid
//! estimator, the end-point objective). One factor at a time is varied
//! around it: corridor width, landmark count, the share of landmarks on the
//! side walls, a featureless stretch of both walls, the camera's detection
//! range, and pixel noise (which sets how well a turn is estimated). For
//! each environment every technique runs on the development seeds; the
//! aided technique with the least mean end-point error is then run, beside
//! straight driving, on held-out seeds in a held-out landmark layout, and
//! its gain is reported from those runs only, so that choosing the best of
//! four (the zig-zag, the scan, tracking and camera steering) does not
//! flatter it.

use crate::experiment::{load_route, variant, Aid, ExperimentError};
use serde::Serialize;
use std::ops::Range;
use ubf_behaviors::{DecisionObjective, Technique};
use ubf_core::Registry;
use ubf_perception::egomotion::{EstimatorKind, RigidConfig};
use ubf_perception::error_model::ErrorModelKind;
use ubf_robots::sim::{FeaturelessConfig, Side};
use ubf_session::run::{run, RunReport};
use ubf_session::scenario::Scenario;
use ubf_session::sweep::run_parallel;

/// One environment: the factor varied and its level.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct EnvironmentCell {
    /// The factor varied.
    pub factor: &'static str,
    /// Its level, as text with its unit.
    pub level: String,
    /// Whether this is the base route's own level.
    pub base: bool,
    /// The aided technique with the least mean error on the development
    /// seeds.
    pub best: &'static str,
    /// Mean end-point error driving straight, held-out runs, m.
    pub straight_m: f64,
    /// Mean end-point error of `best`, held-out runs, m.
    pub aided_m: f64,
    /// `aided_m / straight_m`: below 1 aiding pays.
    pub ratio: f64,
    /// 95 % confidence interval of the ratio (delta method on its log).
    pub ratio_ci95: [f64; 2],
}

/// The map.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct EnvironmentMap {
    /// Seeds the best technique was chosen on.
    pub development_seeds: [u64; 2],
    /// Seeds and landmark layout the gains were measured on.
    pub held_out_seeds: [u64; 2],
    /// The held-out landmark layout's seed.
    pub held_out_layout_seed: u64,
    /// Every environment.
    pub cells: Vec<EnvironmentCell>,
}

/// A change to the base scenario.
type Change = Box<dyn Fn(&mut Scenario) + Sync>;
/// A factor's level: its label, whether it is the base route's, and the
/// change it makes.
type Level = (String, bool, Change);

/// The levels `values` of one factor, labelled by `label`, the one equal to
/// `base` marked as the base route's, each applied by `apply`.
fn levels<T: Copy + PartialEq + Sync + 'static>(
    values: [T; 4],
    base: T,
    label: impl Fn(T) -> String,
    apply: fn(&mut Scenario, T),
) -> Vec<Level> {
    values
        .into_iter()
        .map(|v| {
            let change: Change = Box::new(move |s: &mut Scenario| apply(s, v));
            (label(v), v == base, change)
        })
        .collect()
}

/// The factors and their levels.
fn factors() -> Vec<(&'static str, Vec<Level>)> {
    vec![
        (
            "corridor width",
            levels(
                [2.4, 4.0, 6.0, 8.0],
                4.0,
                |w| format!("{w} m"),
                |s, w| {
                    if let Some(c) = s.world.corridor.as_mut() {
                        c.width = w;
                    }
                },
            ),
        ),
        (
            "landmarks",
            levels(
                [10, 20, 40, 80],
                40,
                |n| format!("{n}"),
                |s, n| {
                    if let Some(r) = s.world.random_landmarks.as_mut() {
                        r.count = n;
                    }
                },
            ),
        ),
        (
            "side-wall share",
            levels(
                [0.25, 0.5, 0.8, 1.0],
                0.8,
                |share| format!("{:.0} %", 100.0 * share),
                |s, share| {
                    if let Some(r) = s.world.random_landmarks.as_mut() {
                        r.side_share = share;
                    }
                },
            ),
        ),
        (
            "featureless stretch",
            levels(
                [0.0, 10.0, 20.0, 30.0],
                0.0,
                |length| format!("{length} m"),
                |s, length| {
                    if length > 0.0 {
                        for side in [Side::Left, Side::Right] {
                            s.world.featureless.push(FeaturelessConfig { side, from: 10.0, to: 10.0 + length });
                        }
                    }
                },
            ),
        ),
        (
            "detection range",
            levels(
                [20.0, 40.0, 60.0, 80.0],
                80.0,
                |range| format!("{range} m"),
                |s, range| {
                    if let Some(c) = s.robot.camera.as_mut() {
                        c.max_range_m = range;
                    }
                },
            ),
        ),
        (
            "pixel noise",
            levels(
                [0.047, 0.1, 0.3, 1.0],
                0.047,
                |noise| format!("{noise} px"),
                |s, noise| {
                    if let Some(c) = s.robot.camera.as_mut() {
                        c.pixel_noise_px = noise;
                    }
                },
            ),
        ),
    ]
}

const AIDED: [Aid; 4] =
    [Aid::robot(Technique::ZigZag), Aid::robot(Technique::Scan), Aid::robot(Technique::Tracking), Aid::CAMERA];

fn mean_sd(values: &[f64]) -> (f64, f64) {
    let n = values.len().max(1) as f64;
    let mean = values.iter().sum::<f64>() / n;
    let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0).max(1.0);
    (mean, var.sqrt())
}

fn errors(reports: &[Result<RunReport, String>]) -> Result<Vec<f64>, ExperimentError> {
    reports
        .iter()
        .map(|r| match r {
            Ok(report) => Ok(report.endpoint_error_m.unwrap_or(f64::NAN)),
            Err(message) => Err(ExperimentError::Scenario { name: "where-aiding-pays", message: message.clone() }),
        })
        .collect()
}

/// Runs the map: the best aided technique chosen on `development`, its gain
/// measured on `held_out` seeds in the layout drawn from `layout_seed`.
/// `progress` is told of each environment finished.
pub fn where_aiding_pays(
    registry: &Registry,
    development: Range<u64>,
    held_out: Range<u64>,
    layout_seed: u64,
    jobs: usize,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<EnvironmentMap, ExperimentError> {
    let (base, zigzag) = load_route(registry, 0)?;
    let rigid = EstimatorKind::Rigid(RigidConfig::default());
    let objective = DecisionObjective::EndPoint;
    let factors = factors();
    let total: usize = factors.iter().map(|(_, levels)| levels.len()).sum();
    let mut cells: Vec<EnvironmentCell> = Vec::new();
    for (factor, levels) in &factors {
        for (text, is_base, change) in levels {
            // Every factor's base level is the base route: run it once.
            if let Some(done) = cells.iter().find(|c| c.base).filter(|_| *is_base) {
                cells.push(EnvironmentCell { factor, level: text.clone(), ..done.clone() });
                progress(cells.len(), total);
                continue;
            }
            let mut environment = base.clone();
            change(&mut environment);
            let width = environment.world.corridor.map_or(4.0, |c| c.width);
            let offset = zigzag * width / 4.0;
            let scenario = |technique| {
                variant(registry, &environment, technique, offset, objective, ErrorModelKind::default(), rigid)
            };
            // Development: every aided technique.
            let aided: Vec<Scenario> = AIDED.iter().map(|&t| scenario(t)).collect::<Result<_, _>>()?;
            let tasks: Vec<(usize, u64)> =
                (0..aided.len()).flat_map(|i| development.clone().map(move |s| (i, s))).collect();
            let reports =
                run_parallel(&tasks, jobs, |&(i, seed)| run(&aided[i], seed, None).map_err(|e| e.to_string()));
            let errs = errors(&reports)?;
            let per = development.clone().count();
            let best = (0..aided.len())
                .min_by(|&a, &b| {
                    let m = |i: usize| mean_sd(&errs[i * per..(i + 1) * per]).0;
                    m(a).total_cmp(&m(b))
                })
                .unwrap_or(0);
            // Held out: the chosen technique beside straight driving, in
            // another layout.
            let mut held = environment.clone();
            if let Some(r) = held.world.random_landmarks.as_mut() {
                r.seed = Some(layout_seed);
            }
            let pair = [
                variant(
                    registry,
                    &held,
                    Aid::robot(Technique::None),
                    offset,
                    objective,
                    ErrorModelKind::default(),
                    rigid,
                )?,
                variant(registry, &held, AIDED[best], offset, objective, ErrorModelKind::default(), rigid)?,
            ];
            let tasks: Vec<(usize, u64)> = (0..2).flat_map(|i| held_out.clone().map(move |s| (i, s))).collect();
            let reports = run_parallel(&tasks, jobs, |&(i, seed)| run(&pair[i], seed, None).map_err(|e| e.to_string()));
            let errs = errors(&reports)?;
            let n = held_out.clone().count();
            let (straight, s_sd) = mean_sd(&errs[..n]);
            let (aided_m, a_sd) = mean_sd(&errs[n..]);
            let ratio = aided_m / straight;
            let log_se = ((a_sd / aided_m).powi(2) / n as f64 + (s_sd / straight).powi(2) / n as f64).sqrt();
            let z = ubf_session::sweep::t95(n.saturating_sub(1));
            cells.push(EnvironmentCell {
                factor,
                level: text.clone(),
                base: *is_base,
                best: AIDED[best].name(),
                straight_m: straight,
                aided_m,
                ratio,
                ratio_ci95: [ratio * (-z * log_se).exp(), ratio * (z * log_se).exp()],
            });
            progress(cells.len(), total);
        }
    }
    Ok(EnvironmentMap {
        development_seeds: [development.start, development.end],
        held_out_seeds: [held_out.start, held_out.end],
        held_out_layout_seed: layout_seed,
        cells,
    })
}

/// The table `ubf experiment where-aiding-pays` prints.
impl std::fmt::Display for EnvironmentMap {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(f,
            "Best aided technique (chosen on seeds {}..{}) over straight driving, end-point error on seeds {}..{} in layout {}",
            self.development_seeds[0],
            self.development_seeds[1],
            self.held_out_seeds[0],
            self.held_out_seeds[1],
            self.held_out_layout_seed
        )?;
        writeln!(
            f,
            "{:<20} {:>9} {:>9} {:>11} {:>10} {:>7} {:>16}",
            "factor", "level", "best", "straight m", "aided m", "ratio", "95 % CI"
        )?;
        for c in &self.cells {
            let base = if c.base { " (base)" } else { "" };
            writeln!(
                f,
                "{:<20} {:>9} {:>9} {:>11.3} {:>10.3} {:>7.2} [{:>5.2}, {:>5.2}]{base}",
                c.factor, c.level, c.best, c.straight_m, c.aided_m, c.ratio, c.ratio_ci95[0], c.ratio_ci95[1]
            )?;
        }
        Ok(())
    }
}
