//! `ubf run` and `ubf replay`.

use super::{CliError, Exit, Outcome};
use crate::run::{run_until, EndReason, Live, Outputs};
use crate::scenario::Scenario;
use crate::watch::{LoadTree, TreeWatch};
use std::path::{Path, PathBuf};
use ubf_core::{BuildContext, Registry};

/// How `ubf run` reads its file and says what it got.
#[derive(Clone, Copy, Debug)]
pub(super) struct RunFlags {
    /// Print the report as JSON.
    pub json: bool,
    /// Run beyond the bound on ticks.
    pub huge: bool,
    /// Take edits of the tree while running.
    pub watch: bool,
    /// Replace an earlier run's output in `--out`.
    pub overwrite: bool,
}

/// Runs a scenario and prints its report; a run a behaviour ended, or
/// Ctrl-C, still reports, but does not pass.
pub(super) fn command(
    registry: &Registry,
    file: &Path,
    seed: Option<u64>,
    outputs: Option<Outputs>,
    RunFlags { json, huge, watch, overwrite }: RunFlags,
    mut live: Option<Live>,
) -> Outcome {
    let load = move |registry: &Registry, file: &Path| match huge {
        true => Scenario::load_unbounded(registry, file),
        false => Scenario::load(registry, file),
    };
    let scenario = load(registry, file).map_err(CliError::bad_input)?;
    let seed = seed.unwrap_or(scenario.seed);
    if let Some(outputs) = &outputs {
        let renders = scenario.robot.camera.as_ref().is_some_and(|camera| camera.images.is_some());
        if outputs.images && !renders {
            return Err(CliError::bad_input(format!(
                "--log-images: {}'s robot has no camera that renders images (`robot.camera.images`), so there \
                 are none to log",
                file.display()
            )));
        }
        if !huge {
            scenario.check_logs().map_err(|e| CliError::bad_input(format!("{}: {e}", file.display())))?;
        }
        super::out_dir::prepare(outputs.dir, &super::out_dir::RUN, overwrite)?;
    }
    if let Some(live) = live.as_mut().filter(|_| watch) {
        let registry = registry.clone();
        let load_tree: LoadTree = Box::new(move |file| Ok(load(&registry, file).map_err(|e| e.to_string())?.root));
        live.trees = Some(Box::new(TreeWatch::new(file, scenario.root.clone(), BuildContext::new(seed), load_tree)));
    }
    let stop = crate::drive::install_stop_flag();
    let report = run_until(&scenario, seed, outputs, live, &stop).map_err(|e| CliError::failed_in(file, e))?;
    super::show(&report, json)?;
    if let Some(outputs) = outputs.filter(|_| !json) {
        println!("outputs         {}/{{report.json, trajectory.csv, run.mcap, plot.png}}", outputs.dir.display());
    }
    Ok(match report.end {
        EndReason::BehaviorFailed => Exit::Failure,
        EndReason::Interrupted => Exit::Interrupted,
        EndReason::GoalReached | EndReason::TimeLimit | EndReason::NoProgress => Exit::Success,
    })
}

/// Prints a run's summary from its log and draws its plot again.
pub(super) fn replay(file: &Path, plot: Option<PathBuf>) -> Outcome {
    let replayed = crate::replay::read(file).map_err(CliError::bad_input)?;
    let Some(run) = &replayed.run else {
        let why = replayed.cut_short.as_ref().map_or(String::new(), |e| format!(" ({e})"));
        return Err(CliError::bad_input(format!(
            "{}: no /run message: not a ubf run log, or cut before its start{why}",
            file.display()
        )));
    };
    println!("scenario        {} (seed {})", run.scenario, run.seed);
    println!("ticks logged    {}", replayed.timeline.time.len());
    let end_time = replayed.timeline.time.last().copied().unwrap_or(0.0);
    println!("logged until    {end_time:.1} s");
    println!("decisions       {}", replayed.decisions.len());
    println!("collisions      {}", replayed.collisions.len());
    match &replayed.report {
        Some(report) => {
            let number = |key: &str| report[key].as_f64().map_or("—".to_owned(), |v| format!("{v:.3}"));
            println!("ended           {}", report["end"].as_str().unwrap_or("?"));
            println!("distance        {} m", number("distance_m"));
            println!("estimate error  {} m", number("estimate_error_m"));
            if report["endpoint_error_m"].is_number() {
                println!("egomotion error {} m at the last frame", number("endpoint_error_m"));
            }
        }
        None => println!(
            "ended           not recorded: the log stops early{}",
            replayed.cut_short.as_ref().map_or(String::new(), |e| format!(" ({e})"))
        ),
    }
    let plot = plot.unwrap_or_else(|| {
        let stem = file.file_stem().map_or("run".into(), |s| s.to_string_lossy().into_owned());
        file.with_file_name(format!("{stem}-replay.png"))
    });
    let title = format!("{} (seed {}), from its log", run.scenario, run.seed);
    crate::plot::draw_replayed(&replayed, &title, &plot).map_err(CliError::failed)?;
    println!("plot            {}", plot.display());
    Ok(Exit::Success)
}

/// Serves a scenario's simulated robot on ROS 2 until Ctrl-C (or
/// `max_time` simulated seconds).
pub(super) fn simulate(
    registry: &Registry,
    file: &Path,
    seed: Option<u64>,
    speed: f64,
    max_time_s: Option<f64>,
    cmd_vel_stamped: bool,
) -> Outcome {
    let scenario = Scenario::load(registry, file).map_err(CliError::bad_input)?;
    let seed = seed.unwrap_or(scenario.seed);
    let stop = crate::drive::install_stop_flag();
    let commands = if cmd_vel_stamped { "TwistStamped" } else { "Twist" };
    eprintln!(
        "serving {} (seed {seed}) as a ROS 2 robot: /cmd_vel ({commands}) in; /odom, /tf, /scan out",
        scenario.name
    );
    let serving = ubf_session::simulate::Serving { seed, speed, max_time_s, cmd_vel_stamped };
    let served = ubf_session::simulate::serve(&scenario, serving, &stop).map_err(CliError::failed)?;
    let pose = served.true_pose;
    eprintln!(
        "stopped after {} ticks; the robot stands at ({:.3}, {:.3}) m, {:.1}°",
        served.ticks,
        pose.x,
        pose.y,
        pose.theta.to_degrees()
    );
    Ok(if stop.load(std::sync::atomic::Ordering::SeqCst) { Exit::Interrupted } else { Exit::Success })
}

/// `--speed`: a finite factor from 0.01 to 1000.
pub(super) fn parse_speed(text: &str) -> Result<f64, String> {
    match text.parse::<f64>() {
        Ok(speed) if (0.01..=1000.0).contains(&speed) => Ok(speed),
        _ => Err(format!("`{text}` is not a speed from 0.01 to 1000 (times real time)")),
    }
}

/// A time in seconds: finite, above 0, at most a million.
pub(super) fn parse_seconds(text: &str) -> Result<f64, String> {
    match text.parse::<f64>() {
        Ok(s) if s > 0.0 && s <= 1e6 => Ok(s),
        _ => Err(format!("`{text}` is not a time from 0 to 1000000 seconds")),
    }
}
