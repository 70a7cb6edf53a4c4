//! `ubf experiment` and `ubf model`: the thesis's experiments and the
//! landmark error model.

use super::{CameraArgs, CliError, Exit, ExperimentCommand, ModelCommand, Outcome};
use crate::scenario::Scenario;
use std::path::PathBuf;
use ubf_behaviors::DecisionObjective;
use ubf_core::Registry;
use ubf_lab::experiment::{thesis_endpoint, thesis_table2, thesis_table4, EndpointOptions};
use ubf_perception::egomotion::OdometryFusion;
use ubf_perception::error_model::ErrorModelKind;

/// Runs one experiment and prints its table (or JSON). Its many runs say
/// each warning once.
pub(super) fn command(registry: &Registry, which: ExperimentCommand) -> Outcome {
    let _once = super::repeated_warnings::say_once();
    experiment(registry, which)
}

fn experiment(registry: &Registry, which: ExperimentCommand) -> Outcome {
    match which {
        ExperimentCommand::WhereAidingPays { seeds, held_out_seeds, layout_seed, jobs, plot, json } => {
            let runs = 3 * seeds.clone().count() + 2 * held_out_seeds.clone().count();
            if runs == 0 || runs > 100_000 {
                return Err(CliError::bad_input("need 1 to 20000 seeds in each set"));
            }
            let bar = crate::sweep::progress_bar(24, "environments");
            let progress = |done: usize, total: usize| {
                bar.set_length(total as u64);
                bar.set_position(done as u64);
            };
            let jobs = jobs.unwrap_or_else(super::cores);
            let map = ubf_lab::environment_map::where_aiding_pays(
                registry,
                seeds,
                held_out_seeds,
                layout_seed,
                jobs,
                &progress,
            );
            bar.finish_and_clear();
            let map = map.map_err(CliError::failed)?;
            let drawn = plot.as_ref().map(|path| ubf_lab::figures::draw_environment_map(&map, path).map(|()| path));
            super::show(&map, json)?;
            match drawn {
                Some(Ok(path)) => eprintln!("wrote {}", path.display()),
                Some(Err(e)) => return Err(CliError::failed(e)),
                None => {}
            }
        }
        ExperimentCommand::ThesisTable2 { step, trials, jobs, json } => {
            if !(step.is_finite() && step > 0.0 && step < 10.0) || trials == 0 || trials > 100_000 {
                return Err(CliError::bad_input("need 0 < --step < 10 m and 1 ≤ --trials ≤ 100000"));
            }
            let shares: Vec<f64> = (0..=20).map(|k| f64::from(k) / 100.0).collect();
            let jobs = jobs.unwrap_or_else(super::cores);
            let table = thesis_table2(registry, step, trials, &shares, jobs).map_err(CliError::failed)?;
            super::show(&table, json)?;
        }
        ExperimentCommand::ThesisTable4 { seeds, objective, jobs, json } => {
            let table = thesis_table4(registry, seeds, jobs.unwrap_or_else(super::cores), objective)
                .map_err(CliError::failed)?;
            super::show(&table, json)?;
        }
        ExperimentCommand::ThesisEndpoint {
            seeds,
            jobs,
            json,
            rendered,
            layout_seed,
            objective,
            model,
            rotate_then_translate,
            odometry_fusion,
        } => {
            let profile = rotate_then_translate.then(ubf_robots::sim::MotionProfile::rotate_then_translate);
            let jobs = jobs.unwrap_or_else(super::cores);
            let options =
                EndpointOptions { seeds, jobs, rendered, layout_seed, objective, model, profile, odometry_fusion };
            let result = thesis_endpoint(registry, &options).map_err(CliError::failed)?;
            super::show(&result, json)?;
        }
    }
    Ok(Exit::Success)
}

/// Fits, prints or draws the landmark error model, or fits the decision's
/// costs from run logs.
pub(super) fn model(registry: &Registry, action: ModelCommand) -> Outcome {
    use ubf_perception::error_model::{corridor_heights, fit_exponential, FitReport, GeometricModel};
    let args: &CameraArgs = match &action {
        ModelCommand::Fit { camera, .. } | ModelCommand::Heatmap { camera, .. } => camera,
        ModelCommand::FitCosts { logs, check, against, write, json } => {
            return fit_costs(logs, *check, against, write.as_deref(), *json)
        }
    };
    if !(args.step.is_finite() && args.step > 0.0) {
        return Err(CliError::bad_input("--step must be a positive number of metres"));
    }
    let camera = match &args.scenario {
        None => ubf_perception::StereoCamera::default(),
        Some(file) => {
            let scenario = Scenario::load(registry, file).map_err(CliError::bad_input)?;
            scenario.robot.camera.map(|c| c.stereo).unwrap_or_default()
        }
    };
    let geometric = GeometricModel::new(&camera, args.step);
    let depths = [args.depths[0].max(geometric.min_depth()), args.depths[1]];
    if depths[1] <= depths[0] {
        return Err(CliError::bad_input(format!(
            "--depths: FAR must exceed the camera's nearest stereo depth, {:.2} m (with this camera)",
            depths[0]
        )));
    }
    let planar = fit_exponential(|x, y, _| geometric.cv(x, y), &camera, depths, None, 0.25);
    let heights = args.heights.unwrap_or_else(|| corridor_heights(&camera));
    let with_height = fit_exponential(|x, y, z| geometric.cv_3d(x, y, z), &camera, depths, Some(heights), 0.25);
    match action {
        ModelCommand::Fit { json: true, .. } => {
            let both = serde_json::json!({ "planar": planar, "with_height": with_height });
            println!("{}", serde_json::to_string_pretty(&both).expect("a fit report always serialises"));
        }
        ModelCommand::Fit { .. } => {
            println!(
                "camera          f = {:.1} px, T = {:.3} m, {}×{} px, {:.2} m above the floor",
                camera.focal_px, camera.baseline_m, camera.width_px, camera.height_px, camera.mount.height
            );
            println!("model step      {} m; fitted over depths {:.2}–{:.2} m", args.step, depths[0], depths[1]);
            let row = |name: &str, a: String, b: String| println!("{name:<16}{a:<34}{b}");
            row("", "planar (eq. 24)".into(), "3D (§5.3.1)".into());
            row("CV(x, y, z)", "α·exp(β·y)·exp(−γ·|x|)".into(), "α·exp(β·y)·exp(−γ·|x|)·exp(−δ·|z|)".into());
            row(
                "fitted to",
                "eq. 16–23 at the cameras' level".into(),
                format!("eq. 16–23 in rows too, z {:.2} to {:.2} m", heights[0], heights[1]),
            );
            let both =
                |name: &str, value: &dyn Fn(&FitReport) -> String| row(name, value(&planar), value(&with_height));
            both("points", &|f| f.samples.to_string());
            both("α", &|f| format!("{:.6e}", f.model.alpha));
            both("β", &|f| format!("{:.5} 1/m", f.model.beta));
            both("γ", &|f| format!("{:.5} 1/m", f.model.gamma));
            both("δ", &|f| {
                if f.height_range_m.is_some() {
                    format!("{:.5} 1/m", f.model.delta)
                } else {
                    "—".into()
                }
            });
            both("R² of ln CV", &|f| format!("{:.4}", f.r_squared_log));
            both("relative error", &|f| {
                format!("median {:.1} %, p95 {:.1} %", 100.0 * f.median_relative_error, 100.0 * f.p95_relative_error)
            });
            both("pair ordering", &|f| format!("{:.1} % as eq. 16–23 ranks them", 100.0 * f.pair_order_agreement));
        }
        // Answered before a camera was needed.
        ModelCommand::FitCosts { .. } => {}
        ModelCommand::Heatmap { exponential, out, .. } => {
            let m = planar.model;
            let (title, cv): (&str, &dyn Fn(f64, f64) -> f64) = if exponential {
                ("Fitted exponential model (eq. 24)", &|x, y| m.cv(x, y))
            } else {
                ("Geometric error model (eq. 16-23)", &|x, y| geometric.cv(x, y))
            };
            ubf_lab::figures::draw_error_model(title, cv, &camera, depths[1], &out).map_err(CliError::failed)?;
            println!("wrote {}", out.display());
        }
    }
    Ok(Exit::Success)
}

fn fit_costs(
    logs: &[PathBuf],
    check: bool,
    against: &[PathBuf],
    write: Option<&std::path::Path>,
    json: bool,
) -> Outcome {
    use ubf_lab::cost_fit::{find_logs, fit_costs};
    let paths = find_logs(logs).map_err(CliError::bad_input)?;
    let against = find_logs(against).map_err(CliError::bad_input)?;
    if check {
        let forms = ubf_lab::cost_forms::check_forms(&paths).map_err(CliError::bad_input)?;
        super::show(&forms, json)?;
    } else {
        let fit = fit_costs(&paths, &against).map_err(CliError::bad_input)?;
        super::show(&fit, json)?;
        if let Some(file) = write {
            let by: Vec<String> = std::env::args().skip(1).collect();
            ubf_lab::cost_fit::write_fitted(file, &fit, &format!("ubf {}", by.join(" "))).map_err(CliError::failed)?;
            eprintln!("written to {}", file.display());
        }
    }
    Ok(Exit::Success)
}

/// Parses `end-point` or `cv`.
pub(super) fn parse_objective(text: &str) -> Result<DecisionObjective, String> {
    match text {
        "end-point" => Ok(DecisionObjective::EndPoint),
        "cv" => Ok(DecisionObjective::Cv),
        _ => Err("expected `end-point` or `cv`".into()),
    }
}

/// Parses `off`, `sideways` or `full`.
pub(super) fn parse_fusion(text: &str) -> Result<OdometryFusion, String> {
    match text {
        "off" => Ok(OdometryFusion::Off),
        "sideways" => Ok(OdometryFusion::Sideways),
        "full" => Ok(OdometryFusion::Full),
        _ => Err("expected `off`, `sideways` or `full`".into()),
    }
}

/// Parses an error model's name.
pub(super) fn parse_model(text: &str) -> Result<ErrorModelKind, String> {
    match text {
        "geometric" => Ok(ErrorModelKind::Geometric),
        "geometric-3d" => Ok(ErrorModelKind::Geometric3d),
        "fitted-exponential" => Ok(ErrorModelKind::FittedExponential),
        "fitted-exponential-3d" => Ok(ErrorModelKind::FittedExponential3d),
        _ => Err("expected `geometric`, `geometric-3d`, `fitted-exponential` or `fitted-exponential-3d`".into()),
    }
}

/// Splits `A..B` into two numbers of metres, naming each (`depth`,
/// `height`) and the form (`NEAR..FAR`) in its errors.
fn parse_metres_pair(text: &str, form: &str, each: &str) -> Result<[f64; 2], String> {
    let (a, b) = text.split_once("..").ok_or_else(|| format!("expected {form}, in metres"))?;
    let number = |s: &str| s.trim().parse::<f64>().map_err(|_| format!("`{s}` is not a {each} in metres"));
    Ok([number(a)?, number(b)?])
}

/// Parses `LOW..HIGH` heights relative to the cameras, in metres.
pub(super) fn parse_heights(text: &str) -> Result<[f64; 2], String> {
    let [low, high] = parse_metres_pair(text, "LOW..HIGH", "height")?;
    if !(low.is_finite() && high.is_finite() && low <= high && low >= -100.0 && high <= 100.0) {
        return Err(format!("`{text}`: need −100 ≤ LOW ≤ HIGH ≤ 100 m"));
    }
    Ok([low, high])
}

/// Parses `NEAR..FAR` depths in metres.
pub(super) fn parse_depths(text: &str) -> Result<[f64; 2], String> {
    let [near, far] = parse_metres_pair(text, "NEAR..FAR", "depth")?;
    if !(near.is_finite() && far.is_finite() && 0.0 < near && near < far && far <= 1000.0) {
        return Err(format!("`{text}`: need 0 < NEAR < FAR ≤ 1000 m"));
    }
    Ok([near, far])
}
