//! The simulator end to end: avoidance over many seeds, determinism of every
//! output, and what a run leaves behind.

use std::path::Path;
use ubf::run::{run, EndReason};
use ubf::scenario::Scenario;
use ubf_core::Wraps;

/// The scenario file at `path` from the repository's root.
fn load(path: &str) -> Scenario {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(path);
    Scenario::load(&ubf::registry(), &path).unwrap()
}

/// The scenario file at `path` with each `(from, to)` edit made to its text.
fn edited(path: &str, edits: &[(&str, &str)]) -> Scenario {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(path);
    // An edit that matches nothing would quietly run the file unedited.
    let text = edits.iter().fold(std::fs::read_to_string(&path).unwrap(), |text, (from, to)| {
        assert!(text.contains(from), "{}: `{from}` is not in it", path.display());
        text.replace(from, to)
    });
    Scenario::from_ron(&ubf::registry(), &text).unwrap()
}

/// Every row's value in the column `name` of a run's `trajectory.csv`.
fn trajectory_column(dir: &Path, name: &str) -> Vec<f64> {
    let csv = std::fs::read_to_string(dir.join("trajectory.csv")).unwrap();
    let mut lines = csv.lines();
    let column = lines.next().unwrap().split(',').position(|h| h == name).unwrap();
    lines.map(|l| l.split(',').nth(column).unwrap().parse().unwrap()).collect()
}

/// The child of the root that won each tick (`root/around/..` → `around`),
/// with repeats on consecutive ticks dropped: who drove, in order.
fn top_winners(dir: &Path) -> Vec<String> {
    let csv = std::fs::read_to_string(dir.join("trajectory.csv")).unwrap();
    let mut lines = csv.lines();
    let column = lines.next().unwrap().split(',').position(|h| h == "winner").unwrap();
    let mut winners: Vec<String> =
        lines.map(|l| l.split(',').nth(column).unwrap().split('/').nth(1).unwrap_or("").to_owned()).collect();
    winners.dedup();
    winners
}

#[test]
fn then_ron_goes_to_the_door_through_it_then_to_the_goal() {
    // docs/for-behaviortree-users.md, "do A then B": each waypoint's GoTo
    // drives until it is passed, then falls silent for good.
    let dir = tempfile::tempdir().unwrap();
    let report = run(&load("scenarios/then.ron"), 1, Some(dir.path())).unwrap();
    assert_eq!(report.end, EndReason::GoalReached, "{report:?}");
    assert!(report.reached_goal && report.collisions == 0, "{report:?}");
    assert_eq!(top_winners(dir.path()), ["to-door", "through-door", "to-goal", "Stop"]);
    let (x, y) = (trajectory_column(dir.path(), "true_x"), trajectory_column(dir.path(), "true_y"));
    let nearest =
        |wx: f64, wy: f64| x.iter().zip(&y).map(|(x, y)| (x - wx).hypot(y - wy)).fold(f64::INFINITY, f64::min);
    assert!(nearest(3.0, 2.0) <= 0.3 && nearest(5.0, 2.0) <= 0.3);
}

#[test]
fn without_its_waypoints_then_ron_never_gets_past_the_wall() {
    // The check above can fail: GoTo alone presses against the wall.
    let scenario = edited(
        "scenarios/then.ron",
        &[
            (r#"(behavior: GoTo(waypoint: (x: 3.0, y: 2.0, tolerance: 0.3), slow_radius: 0.0), name: "to-door"),"#, ""),
            (
                r#"(behavior: GoTo(waypoint: (x: 5.0, y: 2.0, tolerance: 0.3), slow_radius: 0.0), name: "through-door"),"#,
                "",
            ),
        ],
    );
    let report = run(&scenario, 1, None).unwrap();
    assert_eq!(report.end, EndReason::NoProgress, "{report:?}");
    assert!(!report.reached_goal);
}

#[test]
fn fallback_ron_goes_round_the_box_only_near_it_and_reaches_the_goal_in_10_seeds() {
    // docs/for-behaviortree-users.md, "try A, else B": "around" speaks only
    // near the box, and "straight" drives before and after it.
    let scenario = load("scenarios/fallback.ron");
    let dir = tempfile::tempdir().unwrap();
    for seed in 0..10 {
        let out = dir.path().join(seed.to_string());
        let report = run(&scenario, seed, Some(&out)).unwrap();
        assert_eq!(report.end, EndReason::GoalReached, "seed {seed}: {report:?}");
        assert!(report.reached_goal && report.collisions == 0, "seed {seed}: {report:?}");
        let winners = top_winners(&out);
        assert_eq!(winners[..3], ["straight", "around", "straight"], "seed {seed}: {winners:?}");
        assert_eq!(winners.last().unwrap(), "Stop", "seed {seed}: {winners:?}");
    }
}

/// How often the robot was handed back, within `within_s`, to the behaviour
/// it was taken from, with a jump in the command each time: two behaviours
/// taking turns every few ticks. A handover that leaves the command as it
/// was (a fallback's two GoTos) is not one.
fn flicks(dir: &Path, within_s: f64) -> usize {
    let csv = std::fs::read_to_string(dir.join("trajectory.csv")).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let column = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (winner, speed, turn) = (column("winner"), column("cmd_velocity"), column("cmd_rot_velocity"));
    let mut spells: Vec<(f64, String)> = Vec::new();
    let mut last_command = (0.0, 0.0);
    for line in lines {
        let fields: Vec<&str> = line.split(',').collect();
        let command: (f64, f64) = (fields[speed].parse().unwrap(), fields[turn].parse().unwrap());
        let jump = (command.0 - last_command.0).abs() > 0.05 || (command.1 - last_command.1).abs() > 0.1;
        last_command = command;
        match spells.last_mut() {
            Some((_, w)) if w == fields[winner] => {}
            Some((_, w)) if !jump => *w = fields[winner].to_owned(),
            _ => spells.push((fields[0].parse().unwrap(), fields[winner].to_owned())),
        }
    }
    spells.windows(3).filter(|w| w[0].1 == w[2].1 && w[2].0 - w[1].0 < within_s).count()
}

#[test]
fn every_shipped_scenario_reaches_its_goal_without_chattering() {
    let dir = tempfile::tempdir().unwrap();
    let mut checked = 0;
    for entry in std::fs::read_dir(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios")).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_stem().unwrap().to_str().unwrap().to_owned();
        let scenario = Scenario::load(&ubf::registry(), &path).unwrap();
        if scenario.goal.is_none() {
            continue;
        }
        for seed in 1..=3 {
            let out = dir.path().join(format!("{name}-{seed}"));
            let report = run(&scenario, seed, Some(&out)).unwrap();
            assert_eq!(report.end, EndReason::GoalReached, "{name} seed {seed}: {report:?}");
            assert_eq!(report.collisions, 0, "{name} seed {seed}: {report:?}");
            // Going round one obstacle hands over twice; noise at an edge
            // may add a flick or two, never the dozens of a tug of war.
            let flicks = flicks(&out, 1.0);
            assert!(flicks <= 2, "{name} seed {seed}: the winner flicked back {flicks} times");
        }
        checked += 1;
    }
    assert!(checked >= 5, "{checked} scenarios with a goal");
}

#[test]
fn a_fallback_to_avoid_collision_alone_never_gets_past_the_box() {
    // The page's warning: under selection the winner's action is taken
    // whole, and AvoidCollision sets no forward speed. It and GoTo take
    // turns in front of the box until the progress check gives up.
    let scenario = edited("scenarios/corridor-box.ron", &[("arbiter: CommandFusion", "arbiter: SimplePriority")]);
    let report = run(&scenario, 1, None).unwrap();
    assert_eq!(report.end, EndReason::NoProgress, "{report:?}");
    assert!(report.final_true_pose.x < 8.0, "{report:?}");
}

#[test]
fn goes_round_a_box_to_the_goal_without_touching_anything_in_30_seeds() {
    let scenario = load("scenarios/corridor-box.ron");
    let mut times = Vec::new();
    for seed in 0..30 {
        let report = run(&scenario, seed, None).unwrap();
        assert_eq!(report.collisions, 0, "seed {seed}: {report:?}");
        assert_eq!(report.end, EndReason::GoalReached, "seed {seed}: {report:?}");
        assert!(report.reached_goal, "seed {seed}: {report:?}");
        times.push(report.ticks);
    }
    // The seeds really drive differently (sonar noise), or this proves little.
    times.sort_unstable();
    times.dedup();
    assert!(times.len() > 5, "{times:?}");
}

#[test]
fn without_avoidance_the_same_robot_hits_the_box() {
    // The check above can fail: drop AvoidCollision and the box is hit.
    let text =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/corridor-box.ron")).unwrap();
    let text = text.replace("(behavior: AvoidCollision(), weight: 2.0),", "");
    let scenario = Scenario::from_ron(&ubf::registry(), &text).unwrap();
    let report = run(&scenario, 0, None).unwrap();
    assert!(report.collisions > 0, "{report:?}");
    assert!(!report.reached_goal);
}

fn outputs(scenario: &Scenario, seed: u64, dir: &Path) -> (String, String, Vec<u8>) {
    run(scenario, seed, Some(dir)).unwrap();
    let mut report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("report.json")).unwrap()).unwrap();
    report.as_object_mut().unwrap().remove("wall_time_s");
    let trajectory = std::fs::read_to_string(dir.join("trajectory.csv")).unwrap();
    let plot = std::fs::read(dir.join("plot.png")).unwrap();
    (report.to_string(), trajectory, plot)
}

#[test]
fn same_scenario_and_seed_give_byte_identical_outputs() {
    let scenario = load("scenarios/corridor-box.ron");
    let dir = tempfile::tempdir().unwrap();
    let a = outputs(&scenario, 7, &dir.path().join("a"));
    let b = outputs(&scenario, 7, &dir.path().join("b"));
    assert_eq!(a.0, b.0, "report.json");
    assert!(a.1 == b.1, "trajectory.csv differs");
    assert!(a.2 == b.2, "plot.png differs");
    let c = outputs(&scenario, 8, &dir.path().join("c"));
    assert_ne!(a.1, c.1, "another seed, another run");
}

#[test]
fn a_run_leaves_a_report_a_trajectory_and_a_plot() {
    let scenario = load("scenarios/corridor-box.ron");
    let dir = tempfile::tempdir().unwrap();
    let report = run(&scenario, 1, Some(dir.path())).unwrap();

    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("report.json")).unwrap()).unwrap();
    for field in [
        "scenario",
        "seed",
        "ticks",
        "sim_time_s",
        "distance_m",
        "reached_goal",
        "collisions",
        "final_true_pose",
        "final_estimated_pose",
        "wall_time_s",
    ] {
        assert!(json.get(field).is_some(), "report.json lacks {field}");
    }

    let csv = std::fs::read_to_string(dir.path().join("trajectory.csv")).unwrap();
    let mut lines = csv.lines();
    let header = lines.next().unwrap();
    assert!(
        header.starts_with(
            "time_s,true_x,true_y,true_theta,pose_x,pose_y,pose_theta,odom_x,odom_y,odom_theta,ego_x,ego_y"
        ),
        "{header}"
    );
    assert!(header.ends_with("winner,vote:root/Stop,vote:root/AvoidCollision,vote:root/GoTo"), "{header}");
    assert_eq!(lines.count() as u64, report.ticks);

    let png = std::fs::read(dir.path().join("plot.png")).unwrap();
    assert_eq!(&png[1..4], b"PNG");
    // The map, with its legend in a column of its own at the right, and the
    // panel of speed, turn rate and votes underneath (420 px).
    let image = image::load_from_memory(&png).unwrap().into_rgb8();
    assert_eq!(image.width(), 1400);
    assert!(image.height() >= 300 + 420, "no room for the timeline: {}", image.height());
    let legend_column = (1170..1400).flat_map(|x| (0..200).map(move |y| (x, y)));
    let inked = legend_column.filter(|&(x, y)| image.get_pixel(x, y).0.iter().all(|&c| c < 100)).count();
    assert!(inked > 100, "nothing written in the legend column");
}

#[test]
fn camera_egomotion_and_action_aiding_runs_repeat_exactly() {
    // The thesis's corridor with every random source on: the layout, pixel
    // noise, RANSAC and the zig-zag's turning points.
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("lab/scenarios/thesis/table4.ron");
    let text = std::fs::read_to_string(path).unwrap().replace("technique: None", "technique: ZigZag");
    let scenario = Scenario::from_ron(&ubf::registry(), &text).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let a = outputs(&scenario, 3, &dir.path().join("a"));
    let b = outputs(&scenario, 3, &dir.path().join("b"));
    assert_eq!(a.0, b.0, "report.json");
    assert!(a.1 == b.1, "trajectory.csv differs");
    let report: serde_json::Value = serde_json::from_str(&a.0).unwrap();
    assert!(report["journey_cv"].as_f64().unwrap() > 0.0);
    assert!(report["endpoint_error_m"].is_number());
}

#[test]
fn every_aiding_technique_reaches_the_goal_and_does_what_it_says() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("lab/scenarios/thesis/table4.ron");
    let base = std::fs::read_to_string(path).unwrap();
    let mut reports = std::collections::BTreeMap::new();
    // The thesis's objective (the step CV, turns free), which these checks
    // are about.
    for technique in ["None", "ZigZag", "Scan", "Tracking"] {
        let text = base.replace("technique: None", &format!("technique: {technique}, objective: Cv"));
        let report = run(&Scenario::from_ron(&ubf::registry(), &text).unwrap(), 1, None).unwrap();
        assert_eq!(report.end, EndReason::GoalReached, "{technique}: {report:?}");
        assert_eq!(report.collisions, 0, "{technique}");
        reports.insert(technique, report);
    }
    let (none, zigzag, scan, tracking) = (&reports["None"], &reports["ZigZag"], &reports["Scan"], &reports["Tracking"]);
    // Straight at the goal: no detour. The zig-zag drives further; the
    // physical scan takes far longer than anything else.
    assert!(none.path_overhead_pct.unwrap().abs() < 1.0, "{none:?}");
    assert!(zigzag.path_overhead_pct.unwrap() > 3.0, "{zigzag:?}");
    assert!(scan.sim_time_s > 3.0 * none.sim_time_s, "{} vs {}", scan.sim_time_s, none.sim_time_s);
    assert!(scan.sim_time_s > tracking.sim_time_s, "{} vs {}", scan.sim_time_s, tracking.sim_time_s);
    // Aiding brings side-wall landmarks into view: lower journey CV.
    for aided in [zigzag, scan, tracking] {
        assert!(aided.journey_cv.unwrap() < 0.5 * none.journey_cv.unwrap(), "{aided:?}");
    }
}

#[test]
fn aiding_beside_avoidance_never_sits_out_the_time_limit() {
    // Found on held-out layouts: near the goal, ActionAiding's turn on the
    // spot and AvoidCollision's turn away from a wall cancelled under
    // CommandFusion, and the robot sat until the time limit. A stuck turn
    // now goes the long way round, then steers while driving.
    let scenario = edited(
        "lab/scenarios/thesis/route-2-1.ron",
        &[("technique: None", "technique: Tracking, objective: Cv"), ("seed: 21)", "seed: 101)")],
    );
    for seed in [1021, 1022] {
        let report = run(&scenario, seed, None).unwrap();
        assert_eq!(report.end, EndReason::GoalReached, "seed {seed}: {report:?}");
        assert!(report.sim_time_s < 300.0, "seed {seed}: {report:?}");
    }
}

#[test]
fn a_turn_blocked_a_few_degrees_short_steers_on_instead_of_turning_round() {
    // Found on held-out layouts: odometry had put the robot beside a wall,
    // and AvoidCollision's turn away cancelled the last few degrees of the
    // scan's turn on the spot. The stuck turn went the long way round (a
    // full revolution, failing frames all the way), stuck again facing the
    // wall, and the robot repeated this until the time limit. A turn stuck
    // less than a quarter turn short now steers while driving. (Pinned by
    // the wall 0.3 m from the goal by odometry, the robot then dithers for
    // 215 s before its pose creeps into the goal's tolerance: the standard
    // progress check would end the run there, so it is off, to tell the
    // fix from the defect.)
    let scenario = edited(
        "lab/scenarios/thesis/route-2-1.ron",
        &[
            ("technique: None", "technique: Scan"),
            ("seed: 21)", "seed: 909)"),
            ("max_time_s: 2500.0,", "max_time_s: 2500.0, progress: None,"),
        ],
    );
    let report = run(&scenario, 3025, None).unwrap();
    assert_eq!(report.end, EndReason::GoalReached, "{report:?}");
    assert!(report.sim_time_s < 600.0, "{report:?}");
    assert_eq!(report.collisions, 0, "{report:?}");
}

#[test]
fn a_step_a_rotate_then_translate_robot_cannot_take_is_decided_again() {
    // Found running the thesis's rotate-then-translate profile: 1.8 m from
    // the goal beside a wall, AvoidCollision's turn away and the step's own
    // correction back alternated every tick. A robot that turns on the spot
    // before it translates spent each tick turning, never drove, and the
    // step (so the run) lasted until the time limit. A step that gets
    // nowhere now ends, and the next decision starts from where the robot is.
    let scenario = edited(
        "lab/scenarios/thesis/route-2-1.ron",
        &[
            ("technique: None", "technique: Scan"),
            (
                "egomotion: (estimator: Rigid(), odometry_fusion: Off, navigate: false),",
                "egomotion: (estimator: Rigid(), odometry_fusion: Off, navigate: false), \
                 motion: RotateThenTranslate(heading_tolerance_deg: 2.0),",
            ),
        ],
    );
    let report = run(&scenario, 1, None).unwrap();
    assert_eq!(report.end, EndReason::GoalReached, "{report:?}");
    assert!(report.sim_time_s < 600.0, "{report:?}");
}

#[test]
fn the_tracking_list_predicts_the_landmarks_the_camera_then_sees() {
    // ActionAiding with tracking, driven on its own down route 1->2: at each
    // decision it predicts how many landmarks the chosen heading keeps in
    // view; at the end of the step the camera delivers a frame. With look-
    // alikes registered as landmarks of their own and single sightings
    // planned with, as the list did before, it predicted 14.9 where the
    // camera saw 9.7 on these seeds, and this test failed.
    use ubf_behaviors::{ActionAiding, ActionAidingConfig, Technique};
    use ubf_core::{Behavior, BuildContext, Command, Robot, State, Turn};
    use ubf_perception::egomotion::Tracker;
    use ubf_robots::egomotion::EgomotionRobot;
    use ubf_robots::sim::SimRobot;
    let scenario = load("lab/scenarios/thesis/route-1-2.ron");
    let (mut predicted, mut seen, mut steps) = (0.0, 0.0, 0);
    for seed in 0..3 {
        let sim = SimRobot::new(&scenario.robot, &scenario.world, scenario.period_s, seed);
        let camera = scenario.robot.camera.as_ref().unwrap().stereo;
        let tracker = Tracker::new(scenario.robot.egomotion.unwrap(), camera, sim.true_pose(), seed);
        let mut robot = EgomotionRobot::new(sim, Some(tracker));
        let mut aiding =
            ActionAiding::new(ActionAidingConfig::with_technique(Technique::Tracking), &BuildContext::new(seed));
        let mut state = State { goal: scenario.goal, ..State::default() };
        for tick in 0..scenario.max_ticks() {
            state.time = tick as f64 * scenario.period_s;
            robot.sense(&mut state).unwrap();
            let action = aiding.gen_action(&state);
            if !action.is_voting() {
                break;
            }
            let (velocity, rate) = (action.motion.velocity.unwrap_or(0.0), action.motion.rot_velocity.unwrap_or(0.0));
            robot.act(&Command::Drive { velocity, turn: Turn::Rate(rate) }).unwrap();
        }
        let check = aiding.prediction_check();
        predicted += check.mean_predicted * check.steps as f64;
        seen += check.mean_seen * check.steps as f64;
        steps += check.steps;
    }
    assert!(steps > 60, "{steps}");
    let (predicted, seen) = (predicted / steps as f64, seen / steps as f64);
    println!("{steps} steps: {predicted:.1} landmarks predicted in view, {seen:.1} seen");
    assert!((predicted - seen).abs() <= 0.35 * seen, "{predicted:.1} predicted, {seen:.1} seen");
}

#[test]
fn the_safety_guard_latches_a_stop_on_the_simulators_contact_too() {
    // The same guard `ubf drive` puts round a real robot, on the simulator's
    // clock: GoTo alone drives into the box, and after the first contact
    // the robot is held still for good.
    use ubf_core::{BuildContext, Controller, Hold, SafetyGuard, SafetyPolicy, SimClock};
    let text =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/corridor-box.ron")).unwrap();
    let text = text.replace("(behavior: AvoidCollision(), weight: 2.0),", "");
    let scenario = Scenario::from_ron(&ubf::registry(), &text).unwrap();
    let sim = ubf_robots::sim::SimRobot::new(&scenario.robot, &scenario.world, scenario.period_s, 0);
    let policy = SafetyPolicy { resume_after_s: None, ..SafetyPolicy::default() };
    let mut controller = Controller::new(
        SafetyGuard::new(sim, policy),
        scenario.root.build(&BuildContext::new(0)),
        Box::new(SimClock::new(scenario.period_s)),
    );
    controller.set_goal(scenario.goal);
    let mut first_contact = None;
    for tick in 0..600 {
        let record = controller.tick().unwrap();
        if record.hold == Some(Hold::Contact) && first_contact.is_none() {
            first_contact = record.truth.map(|t| (tick, t.pose));
        }
    }
    let (tick, at) = first_contact.expect("the box is hit");
    let end = controller.robot().inner().true_pose();
    assert!(tick < 500 && at.distance_to(end.x, end.y) < 0.05, "held from tick {tick} at {at:?}, ended at {end:?}");
    assert_eq!(controller.robot().inner().collisions(), 1);
}

#[test]
fn the_first_frame_is_anchored_on_many_readings_of_the_head() {
    // Egomotion chains every heading to the first frame's view, placed by
    // the start heading and the head's reading then: that reading is the
    // mean of many, later ones are single. Encoders with 1° of noise, over
    // 100 seeds: one reading scatters by 1°, the mean of 64 by 1/8°.
    use ubf_core::{Robot, State, ANCHOR_READINGS};
    let scenario =
        edited("scenarios/camera-sweep.ron", &[("pan_tilt: ()", "pan_tilt: (resolution_deg: 0.0, noise_deg: 1.0)")]);
    let (mut first, mut later) = (Vec::new(), Vec::new());
    for seed in 0..100 {
        let mut sim = ubf_robots::sim::SimRobot::new(&scenario.robot, &scenario.world, scenario.period_s, seed);
        let mut state = State::default();
        sim.sense(&mut state).unwrap();
        assert_eq!(state.stereo.number, 1, "the first tick takes the first frame");
        first.push(state.stereo.calibration.unwrap().mount.pan_deg);
        sim.sense(&mut state).unwrap();
        later.push(state.camera_aim.unwrap().pan.to_degrees());
    }
    let rms = |v: &[f64]| (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt();
    let expected = 1.0 / (ANCHOR_READINGS as f64).sqrt();
    assert!(rms(&first) < 2.0 * expected, "first frame: {:.3}°", rms(&first));
    assert!(rms(&later) > 0.8, "later readings: {:.3}°", rms(&later));
}

#[test]
fn a_camera_sweeping_on_a_pan_tilt_unit_is_not_taken_for_turns_of_the_robot() {
    // The robot drives 20 m straight while its camera sweeps ±60°: each
    // frame's landmarks are lifted by the angle the unit's encoders read,
    // so the egomotion heading stays on the true one.
    let scenario = load("scenarios/camera-sweep.ron");
    let dir = tempfile::tempdir().unwrap();
    let report = run(&scenario, 1, Some(dir.path())).unwrap();
    assert_eq!(report.end, EndReason::GoalReached, "{report:?}");
    let column = |name| trajectory_column(dir.path(), name);
    let (truth, ego) = (column("true_theta"), column("ego_theta"));
    let (commanded, measured) = (column("camera_pan_cmd"), column("camera_pan"));
    let worst_heading = ego.iter().zip(&truth).map(|(e, t)| (e - t).abs()).fold(0.0, f64::max);
    let widest_pan = measured.iter().map(|p| p.abs()).fold(0.0, f64::max);
    for (tick, (c, m)) in commanded.iter().zip(&measured).enumerate() {
        // The unit follows the sweep within its rate limit.
        assert!((c - m).abs() < 20f64.to_radians(), "tick {tick}: commanded {c}, measured {m}");
    }
    assert!(widest_pan > 55f64.to_radians(), "the camera swept {:.1}°", widest_pan.to_degrees());
    // The log carries the pan, so the plot (and a replay's) draws it.
    let replayed = ubf::replay::read(&dir.path().join("run.mcap")).unwrap();
    assert_eq!(replayed.timeline.camera_pan_deg.len(), replayed.timeline.time.len());
    let logged = replayed.timeline.camera_pan_deg.iter().map(|p| p.abs()).fold(0.0, f64::max);
    assert!((logged - widest_pan.to_degrees()).abs() < 0.01, "{logged}° logged");
    assert!(worst_heading < 2f64.to_radians(), "heading off by {:.2}°", worst_heading.to_degrees());
    assert!(report.endpoint_error_m.unwrap() < 0.5, "{report:?}");
    // Lifted as if the camera looked ahead, no frame matches (every motion
    // looks like a turn no robot makes) and the run is driven on odometry.
    assert!(report.egomotion_failures.unwrap() * 2 < report.egomotion_steps.unwrap(), "{report:?}");
}

#[test]
fn camera_steering_turns_the_camera_and_drives_the_robot_straight() {
    // ActionAiding steering a camera on a pan-tilt unit down route 1->2,
    // with the shipped costs: the robot keeps to the straight line at the
    // goal (no detour, no time spent turning). With odometry's sideways
    // motion fused into egomotion the camera looks for the view of least
    // step CV among the tracking list's landmarks; purely visual or with
    // `Full` fusion, where those looks did not measure better than looking
    // ahead, the costs' zero step term keeps it ahead.
    let steered = [("technique: None", "technique: Tracking, steer: Camera"), ("camera: (", "camera: (pan_tilt: (), ")];
    let widest_pan = |fusion: &str| {
        let fusion = ("odometry_fusion: Off, navigate: false", fusion);
        let scenario = edited("lab/scenarios/thesis/route-1-2.ron", &[steered[0], steered[1], fusion]);
        let dir = tempfile::tempdir().unwrap();
        let report = run(&scenario, 3, Some(dir.path())).unwrap();
        assert_eq!(report.end, EndReason::GoalReached, "{report:?}");
        assert!(report.path_overhead_pct.unwrap() < 1.0, "{report:?}");
        assert!(report.egomotion_failures.unwrap() <= 5, "{report:?}");
        trajectory_column(dir.path(), "camera_pan").iter().map(|p| p.abs().to_degrees()).fold(0.0, f64::max)
    };
    // Fusion crossed with the pose steered by (egomotion's with
    // `navigate: true`, odometry's without), so that it is the fusion that
    // decides.
    for navigate in ["true", "false"] {
        let fused = widest_pan(&format!("odometry_fusion: Sideways, navigate: {navigate}"));
        assert!(fused > 10.0, "navigate {navigate}: with sideways fusion the camera looked at most {fused:.1}° off");
    }
    // Looking ahead, the pan is the course's difference from the heading
    // the robot steers by: a degree or so. So it is purely visual, and with
    // `Full` fusion, where the view of least CV did not measure better.
    for fusion in ["Off", "Full"] {
        let ahead = widest_pan(&format!("odometry_fusion: {fusion}, navigate: true"));
        assert!(ahead < 5.0, "with fusion {fusion}, the camera looked {ahead:.1}° off");
    }
}

#[test]
fn a_scan_budget_bounds_the_time_scanning_adds() {
    // Scanning before every step, the robot stands sweeping and turning
    // most of the run; with a budget of 0.5, the scans and the turns after
    // them take at most half the time spent driving.
    let route = "lab/scenarios/thesis/feature-poor.ron";
    let straight = run(&edited(route, &[]), 1, None).unwrap();
    let every_step = run(&edited(route, &[("technique: None", "technique: Scan")]), 1, None).unwrap();
    let budgeted = run(&edited(route, &[("technique: None", "technique: Scan, scan_budget: 0.5")]), 1, None).unwrap();
    for report in [&straight, &every_step, &budgeted] {
        assert_eq!(report.end, EndReason::GoalReached, "{report:?}");
    }
    let (every_step, budgeted) =
        (every_step.sim_time_s / straight.sim_time_s, budgeted.sim_time_s / straight.sim_time_s);
    assert!(every_step > 3.0, "scanning every step took {every_step:.2}× straight driving's time");
    assert!((1.1..1.5).contains(&budgeted), "a budget of 0.5 took {budgeted:.2}× straight driving's time");
}

/// Route 2->1's edits for a veer odometry does not see, on layout 2121:
/// with seed 104's slip, a robot steering by odometry ends pinned beside a
/// wall.
const VEER: (&str, &str) = ("slip_deg_per_sqrt_m: 0.2", "slip_deg_per_sqrt_m: 0.2, veer_deg_per_m: -0.05");
const LAYOUT_2121: (&str, &str) = ("seed: 21)", "seed: 2121)");

#[test]
fn a_veering_robot_that_navigates_by_egomotion_reaches_the_goal_odometry_puts_in_the_wall() {
    // A veer odometry does not see, with this seed's slip, walks a robot
    // steering by odometry 1.4 m off the goal line, 0.6 m from the wall;
    // odometry puts the goal towards the wall, and the robot, held off the
    // wall by AvoidCollision, never gets there: the progress check gives
    // up. Steering by egomotion (with odometry's sideways motion), it does
    // not.
    let by_odometry = edited("lab/scenarios/thesis/route-2-1.ron", &[VEER, LAYOUT_2121]);
    let report = run(&by_odometry, 104, None).unwrap();
    assert_eq!(report.end, EndReason::NoProgress, "{report:?}");
    assert!(!report.reached_goal, "{report:?}");
    let navigating = ("odometry_fusion: Off, navigate: false", "odometry_fusion: Sideways, navigate: true");
    let by_egomotion = edited("lab/scenarios/thesis/route-2-1.ron", &[VEER, LAYOUT_2121, navigating]);
    let dir = tempfile::tempdir().unwrap();
    let report = run(&by_egomotion, 104, Some(dir.path())).unwrap();
    assert_eq!(report.end, EndReason::GoalReached, "{report:?}");
    assert_eq!(report.collisions, 0, "{report:?}");
    // The report gives the pose the robot steered by at the end: the
    // trajectory's last `pose_*` row, sensed before the last tick's motion
    // (0.1 m of it here). Odometry's own pose (`odom_*`) is off by the
    // veer, 1.9 m.
    let (goal, believed) = (by_egomotion.goal.unwrap(), report.final_estimated_pose);
    let column = |c| *trajectory_column(dir.path(), c).last().unwrap();
    let (steered, wheels) = ([column("pose_x"), column("pose_y")], [column("odom_x"), column("odom_y")]);
    assert!(believed.distance_to(steered[0], steered[1]) < 0.15, "{believed:?} against {steered:?}");
    assert!(goal.reached_by(&believed), "{goal:?}: {believed:?}");
    assert!(believed.distance_to(wheels[0], wheels[1]) > 1.0, "the wheels' own pose is logged: {wheels:?}");
}

#[test]
fn a_veering_robot_whose_heading_the_walls_hold_reaches_the_goal_steering_by_odometry() {
    // The veer case above, steering by odometry, but with the wall compass
    // on: the side sonars trace the corridor's walls, the heading is held
    // to them, and odometry no longer walks the robot 1.4 m off the goal
    // line into the wall: it ends at the goal as it believes, a few
    // decimetres off (the axes are only as sure as the heading was at the
    // first walls).
    let compass =
        ("odometry_fusion: Off, navigate: false),", "odometry_fusion: Off, navigate: false), wall_compass: (),");
    let edits = [VEER, LAYOUT_2121, ("max_time_s: 2500.0", "max_time_s: 200.0"), compass];
    let dir = tempfile::tempdir().unwrap();
    let report = run(&edited("lab/scenarios/thesis/route-2-1.ron", &edits), 104, Some(dir.path())).unwrap();
    assert_eq!(report.end, EndReason::GoalReached, "{report:?}");
    assert_eq!(report.collisions, 0, "{report:?}");
    assert!(report.final_true_pose.y.abs() < 0.5, "{report:?}");
    // Odometry's heading as the compass holds it (the pose steered by)
    // ends within half a degree of the truth; the wheels' own, logged
    // beside it, is off by the veer's 2°.
    let last = |c| trajectory_column(dir.path(), c).last().copied().unwrap();
    let (truth, held, wheels) = (last("true_theta"), last("pose_theta"), last("odom_theta"));
    let off = (held - truth).to_degrees();
    assert!(off.abs() < 0.5, "{off}°");
    assert!((wheels - truth).to_degrees().abs() > 1.5, "{}°", (wheels - truth).to_degrees());
}

#[test]
fn the_walls_hold_egomotions_heading_where_it_bridges_on_odometry() {
    // Landmarks seen to 20 m only: egomotion bridges much of the 40 m on
    // odometry, and its steps rest on one or two landmarks, so its heading
    // drifts. With the wall compass, each wall's correction is a heading
    // fix for egomotion too (`State::heading_fix`), which turns its pose
    // and its keyframes. Over a dozen seeds egomotion's heading at the end
    // is less than half as far off (RMS), while the wheels' own heading is
    // about as far off as without. (It once asserted one seed, where
    // egomotion bridged 2.5° of the wheels' slip; steps on one landmark
    // now measure most of that.)
    let edits = |compass: bool| {
        let mut edits = vec![
            ("seed: 12)", "seed: 2121)"),
            ("outlier_share: 0.08)", "outlier_share: 0.08, max_range_m: 20.0)"),
            (", odometry_fusion: Off, navigate: false)", ")"),
        ];
        if compass {
            edits.push(("egomotion: (estimator: Rigid()),", "egomotion: (estimator: Rigid()), wall_compass: (),"));
        }
        edited("lab/scenarios/thesis/route-1-2.ron", &edits)
    };
    let rms = |errors: Vec<f64>| (errors.iter().map(|e| e * e).sum::<f64>() / errors.len() as f64).sqrt();
    // The RMS heading errors at the end, egomotion's and the wheels', °.
    let heading_errors = |compass: bool| {
        let (mut ego, mut wheels) = (Vec::new(), Vec::new());
        for seed in 100..112 {
            let dir = tempfile::tempdir().unwrap();
            run(&edits(compass), seed, Some(dir.path())).unwrap();
            let last = |c| trajectory_column(dir.path(), c).last().copied().unwrap();
            ego.push((last("ego_theta") - last("true_theta")).to_degrees());
            wheels.push((last("odom_theta") - last("true_theta")).to_degrees());
        }
        (rms(ego), rms(wheels))
    };
    let ((without, wheels_without), (with, wheels_with)) = (heading_errors(false), heading_errors(true));
    // Without the compass 1.24° RMS, with it 0.43°; the wheels 1.26° and
    // 1.21° (when written).
    assert!(without > 1.0 && with < 0.5 && with < 0.5 * without, "{with}° against {without}°");
    assert!(
        (0.8..1.25).contains(&(wheels_with / wheels_without)),
        "the wheels {wheels_with}° against {wheels_without}°"
    );
}

#[test]
fn a_robot_that_gets_nowhere_gives_up_instead_of_bumping_a_wall_to_the_time_limit() {
    // The veer case above, steering by odometry: pinned beside the wall,
    // the robot turns into it again and again. The standard progress check
    // ends the run on the robot's own pose, long before the time limit;
    // turned off, the robot bumps the wall until the time limit.
    let route = "lab/scenarios/thesis/route-2-1.ron";
    let report = run(&edited(route, &[VEER, LAYOUT_2121]), 104, None).unwrap();
    assert_eq!(report.end, EndReason::NoProgress, "{report:?}");
    assert!(report.sim_time_s < 300.0, "{report:?}");
    let off = ("max_time_s: 2500.0,", "max_time_s: 600.0, progress: None,");
    let report = run(&edited(route, &[VEER, LAYOUT_2121, off]), 104, None).unwrap();
    assert_eq!(report.end, EndReason::TimeLimit, "{report:?}");
    assert!(report.collisions > 100, "{report:?}");
    // Where the robot gets somewhere, the check never fires.
    let report = run(&edited(route, &[LAYOUT_2121]), 104, None).unwrap();
    assert_eq!(report.end, EndReason::GoalReached, "{report:?}");
}

#[test]
fn a_run_reports_the_wheels_scale_its_camera_measured() {
    // Route 1→2 with wheels that count 1 % long (0.99 m driven per metre
    // counted), egomotion fusing odometry's sideways motion: the report
    // gives the scale the steps measured, for calibrating the robot. With
    // image-only egomotion nothing measures it.
    let short = ("slip_deg_per_sqrt_m: 0.2", "slip_deg_per_sqrt_m: 0.2, left_scale: 0.99, right_scale: 0.99");
    let fused = ("odometry_fusion: Off, navigate: false", "odometry_fusion: Sideways, navigate: true");
    let report = run(&edited("lab/scenarios/thesis/route-1-2.ron", &[short, fused]), 3, None).unwrap();
    let (scale, sigma) = (report.wheel_scale.unwrap(), report.wheel_scale_sigma.unwrap());
    assert!((scale - 0.99).abs() < 2.0 * sigma && sigma < 0.01, "{scale} ± {sigma}");
    assert!(report.to_string().contains("m driven per metre counted"), "{report}");
    let report = run(&edited("lab/scenarios/thesis/route-1-2.ron", &[short]), 3, None).unwrap();
    assert_eq!((report.wheel_scale, report.wheel_scale_sigma), (None, None), "{report:?}");
}

/// The simulator with its frames handed over `delay` ticks after their
/// pairs were taken, as a real camera's reach the control loop after the
/// feature pipeline: each keeps the time its pair was taken. Odometry is
/// reported every `odometry_every` ticks, and between reports the last one
/// is passed on with its age, as a robot's packets come.
struct LateFrames<R> {
    inner: R,
    delay: u64,
    odometry_every: u64,
    tick: u64,
    taken: std::collections::VecDeque<(u64, ubf_core::StereoFrame)>,
    handed: ubf_core::StereoFrame,
    reported: Option<(f64, ubf_core::Pose2)>,
}

impl<R> LateFrames<R> {
    fn new(inner: R, delay: u64, odometry_every: u64) -> Self {
        LateFrames {
            inner,
            delay,
            odometry_every,
            tick: 0,
            taken: Default::default(),
            handed: Default::default(),
            reported: None,
        }
    }
}

impl<R: ubf_core::Robot> ubf_core::Wraps for LateFrames<R> {
    type Inner = R;
    fn inner(&self) -> &R {
        &self.inner
    }
    fn inner_mut(&mut self) -> &mut R {
        &mut self.inner
    }
}

impl<R: ubf_core::Robot> ubf_core::RobotWrapper for LateFrames<R> {
    fn sense(&mut self, state: &mut ubf_core::State) -> Result<(), ubf_core::RobotError> {
        self.inner.sense(state)?;
        let newest = self.taken.back().map_or(self.handed.number, |(_, frame)| frame.number);
        if state.stereo.number > newest {
            self.taken.push_back((self.tick, state.stereo.clone()));
        }
        while self.taken.front().is_some_and(|(tick, _)| tick + self.delay <= self.tick) {
            self.handed = self.taken.pop_front().unwrap().1;
        }
        state.stereo = self.handed.clone();
        match self.reported {
            Some((at, pose)) if !self.tick.is_multiple_of(self.odometry_every) => {
                state.pose = pose;
                state.sensor_age = state.time - at;
            }
            _ => self.reported = Some((state.time, state.pose)),
        }
        self.tick += 1;
        Ok(())
    }
}

/// Route 1->2's robot with egomotion steering by its pose (with `compass`,
/// a wall compass too, on wheels that veer 0.2°/m), its frames handed over
/// `delay` ticks late and odometry reported every `odometry_every` ticks,
/// driven straight at 0.5 m/s for 40 s: from the tenth second on, at the
/// ticks with a fresh report, how far on average the pose it steered by
/// lagged the truth along the way, and the RMS of its heading's error, rad.
fn steered_lag(compass: bool, delay: u64, odometry_every: u64, seed: u64) -> (f64, f64) {
    use ubf_core::{angle_difference, Command, Robot, State, Turn};
    use ubf_perception::egomotion::Tracker;
    use ubf_robots::egomotion::EgomotionRobot;
    use ubf_robots::sim::SimRobot;
    use ubf_robots::wall_compass::WallCompassRobot;
    let estimate = if compass { "),\n        wall_compass: ()," } else { ")," };
    let veer = if compass { "slip_deg_per_sqrt_m: 0.2, veer_deg_per_m: -0.2" } else { "slip_deg_per_sqrt_m: 0.2" };
    let scenario = edited(
        "lab/scenarios/thesis/route-1-2.ron",
        &[(", odometry_fusion: Off, navigate: false),", estimate), ("slip_deg_per_sqrt_m: 0.2", veer)],
    );
    let sim = SimRobot::new(&scenario.robot, &scenario.world, scenario.period_s, seed);
    let camera = scenario.robot.camera.as_ref().unwrap().stereo;
    let tracker = Tracker::new(scenario.robot.egomotion.unwrap(), camera, sim.true_pose(), seed);
    let inner = WallCompassRobot::new(sim, scenario.robot.wall_compass);
    let mut robot = EgomotionRobot::new(LateFrames::new(inner, delay, odometry_every), Some(tracker));
    let mut state = State::default();
    let (mut lags, mut headings) = (Vec::new(), Vec::new());
    for tick in 0..400u64 {
        state.time = tick as f64 * scenario.period_s;
        robot.sense(&mut state).unwrap();
        if tick >= 100 && tick.is_multiple_of(odometry_every) {
            let truth = robot.ground_truth().unwrap().pose;
            lags.push(truth.x - state.pose.x);
            headings.push(angle_difference(state.pose.theta, truth.theta).powi(2));
        }
        robot.act(&Command::Drive { velocity: 0.5, turn: Turn::Rate(0.0) }).unwrap();
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    (mean(&lags), mean(&headings).sqrt())
}

#[test]
fn a_frame_that_arrives_late_is_matched_to_the_odometry_of_when_it_was_taken() {
    // Driving at 0.5 m/s with every frame handed over 0.2 s after its pair
    // was taken. Matched to the odometry of when it arrived, egomotion put
    // each frame's view 0.1 m short of where odometry read it, and the pose
    // the robot steered by, weighed with odometry's own, lagged the truth
    // by 0.030 m on average against 0.007 m with frames on time: this test
    // failed. Matched to the odometry of when it was taken, a late frame
    // gives egomotion what it would have given on time.
    let ((on_time, _), (late, _)) = (steered_lag(false, 0, 1, 1), steered_lag(false, 2, 1, 1));
    println!("the pose steered by lags the truth by {on_time:.5} m with frames on time, {late:.5} m 0.2 s late");
    assert!(on_time.abs() < 0.02, "{on_time}");
    assert!((late - on_time).abs() < 0.002, "{late} against {on_time}");
}

#[test]
fn a_late_frame_is_placed_in_odometry_as_the_wall_compass_has_turned_it_since() {
    // A wall compass turns odometry's heading when it sees a wall, and
    // egomotion takes in the heading it measured. A frame taken before the
    // turn and handed over after it was matched to the poses odometry had
    // before the turn, so egomotion took in the heading odometry had before
    // the wall corrected it: on wheels that veer 0.2°/m, the pose steered by
    // was 1.32× as far off in heading with frames 0.2 s late as on time
    // (seeds 1–4), and this test failed. With the poses kept turned with
    // odometry, 0.82×.
    let (mut on_time, mut late) = (0.0, 0.0);
    for seed in 1..5 {
        on_time += steered_lag(true, 0, 1, seed).1;
        late += steered_lag(true, 2, 1, seed).1;
    }
    println!("the pose steered by is {on_time:.5} rad off in heading with frames on time, {late:.5} rad 0.2 s late");
    assert!(late < 1.1 * on_time, "{late} against {on_time}");
}

#[test]
fn a_late_frame_between_odometry_reports_takes_odometry_on_the_line_between_them() {
    // Odometry reported every other tick, each report passed on with its
    // age until the next, and frames 0.2 s late (the camera's 2 Hz puts
    // every other frame between two reports): a frame takes odometry
    // interpolated between the reports either side of when its pair was
    // taken, and egomotion gets what fresh odometry and frames on time
    // would have given it (a lag of 0.0072 m against 0.0074). Matched to
    // the odometry of when it arrived, the pose steered by ran 0.0019 m
    // ahead of the truth, and with each report stamped at its tick instead
    // of its age, 0.075 m ahead: this test failed both ways.
    let ((on_time, _), (late, _)) = (steered_lag(false, 0, 1, 1), steered_lag(false, 2, 2, 1));
    println!(
        "the pose steered by lags the truth by {on_time:.5} m with fresh odometry and frames on time, \
         {late:.5} m with odometry every other tick and frames 0.2 s late"
    );
    assert!((late - on_time).abs() < 0.002, "{late} against {on_time}");
}
