//! `ubf drive --dry-run`: the robot looked at with its motors off.

use super::camera::EquippedRobot;
use super::robot_file::{DriveConfig, ROS2_CONNECTION};
use super::{connect, DriveError};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};
use ubf_core::{Pose2, Robot, RobotError, State, Wraps};
use ubf_robots::arcos::client::ArcosRobot;
use ubf_robots::model::RobotModel;

/// How far, ° (left), and for how long, s, the dry run turns a pan-tilt
/// head before aiming it ahead: long enough to watch which way it went.
const PAN_CHECK_DEG: f64 = 20.0;

const PAN_CHECK_S: f64 = 3.0;

/// `--dry-run`: connect without enabling the motors, print who the robot is
/// and its configuration, then its odometry and nearest sonar echo once a
/// second until stopped; a pan-tilt head is turned left and back, its
/// commanded and measured angles shown. Output that cannot be written (a closed pipe) ends
/// the run like Ctrl-C: the session is closed either way.
pub fn dry_run(config: &DriveConfig, model: &RobotModel, stop: &AtomicBool) -> Result<(), DriveError> {
    if config.connection == ROS2_CONNECTION {
        return Err(DriveError::NoDryRun);
    }
    let camera = config.open_camera()?;
    let robot = connect(config, model, false, Pose2::default())?;
    let mut robot = config.equip(robot, camera, Pose2::default())?;
    let result = show_robot(&mut robot, config, model, stop, &mut std::io::stdout().lock());
    let closed = robot.shutdown().map_err(DriveError::Robot);
    match result {
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => closed,
        Err(e) => Err(DriveError::Output(e)),
        Ok(Err(e)) => Err(e.into()),
        Ok(Ok(())) => closed,
    }
}

/// The dry run's report: I/O errors are the output's, the inner ones the
/// robot's.
fn show_robot(
    robot: &mut EquippedRobot<ArcosRobot>,
    config: &DriveConfig,
    model: &RobotModel,
    stop: &AtomicBool,
    out: &mut impl std::io::Write,
) -> std::io::Result<Result<(), RobotError>> {
    let arcos = robot.inner().inner().inner();
    let id = arcos.identity().clone();
    writeln!(out, "robot           {} ({} {})", id.name, id.class, id.subclass)?;
    writeln!(
        out,
        "model           {}: max {:.2} m/s, {:.0}°/s, {} sonars",
        model.name,
        model.max_velocity,
        model.max_rot_velocity_deg,
        model.sonar.len()
    )?;
    match arcos.config() {
        Some(c) => {
            writeln!(
                out,
                "controller      {} {}, serial {}, name {}",
                c.robot_type, c.subtype, c.serial_number, c.name
            )?;
            writeln!(
                out,
                "tops            {} mm/s, {}°/s, {} mm/s², {}°/s²; SIP every {} ms; host baud code {}",
                c.trans_vel_top, c.rot_vel_top, c.trans_acc_top, c.rot_acc_top, c.sip_cycle_ms, c.host_baud
            )?;
        }
        None => writeln!(out, "controller      sent no CONFIG reply")?,
    }
    let limits = robot.limits();
    writeln!(out, "limits in use   {:.2} m/s, {:.0}°/s", limits.max_velocity, limits.max_rot_velocity.to_degrees())?;
    writeln!(out, "motors          left disabled (dry run)")?;
    let pan_tilt = config.camera.as_ref().and_then(|c| c.pan_tilt.as_ref());
    if let Some(unit) = pan_tilt {
        writeln!(
            out,
            "pan-tilt        on {}: turning {PAN_CHECK_DEG}° left for {PAN_CHECK_S} s, then ahead (a head that turns \
             right first needs `invert_pan: true`)",
            unit.connection
        )?;
    }
    let mut state = State::default();
    let started = Instant::now();
    let mut last_shown = Instant::now();
    while !stop.load(Ordering::SeqCst) && config.max_time_s.is_none_or(|t| started.elapsed().as_secs_f64() < t) {
        // Wake often enough to PULSE within the 500 ms; show once a second.
        std::thread::sleep(Duration::from_millis(250));
        let pan = if started.elapsed().as_secs_f64() < PAN_CHECK_S { PAN_CHECK_DEG.to_radians() } else { 0.0 };
        let aimed = if pan_tilt.is_some() { robot.aim_camera(pan) } else { Ok(()) };
        if let Err(e) = aimed
            .and_then(|()| robot.inner_mut().inner_mut().inner_mut().keep_alive())
            .and_then(|_| robot.sense(&mut state))
        {
            return Ok(Err(e));
        }
        if last_shown.elapsed() < Duration::from_secs(1) {
            continue;
        }
        last_shown = Instant::now();
        let nearest = state.nearest_range().map_or("none".into(), |r| format!("{r:.2} m"));
        writeln!(
            out,
            "odometry        ({:.3}, {:.3}) m, {:.1}°; nearest sonar echo {nearest}; battery {:.1} V",
            state.pose.x,
            state.pose.y,
            state.pose.theta.to_degrees(),
            state.battery_volts.unwrap_or(f64::NAN)
        )?;
        if let Some(aim) = state.camera_aim {
            writeln!(
                out,
                "pan-tilt        commanded {:.1}°, measured {:.2}° (tilt {:.2}°)",
                pan.to_degrees(),
                aim.pan.to_degrees(),
                aim.tilt.to_degrees()
            )?;
        }
        if config.camera.is_some() {
            writeln!(
                out,
                "camera          frame {}: {} landmarks; egomotion {} steps, {} failures",
                state.stereo.number,
                state.stereo.landmarks.len(),
                state.egomotion.steps,
                state.egomotion.failures
            )?;
        }
        out.flush()?;
    }
    Ok(Ok(()))
}
