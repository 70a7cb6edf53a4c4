//! What the client tests do against any ARCOS server: the emulator here,
//! AMRISim in `amrisim.rs`.

#![allow(dead_code)]

use std::time::Duration;
use ubf_core::{Command, Pose2, Robot, State, Turn};
use ubf_robots::arcos::client::ArcosRobot;

/// Drives `robot` at `command` for `seconds`, sensing every 100 ms.
pub fn drive(robot: &mut ArcosRobot, command: Command, seconds: f64, state: &mut State) {
    let ticks = (seconds / 0.1).round() as usize;
    for _ in 0..ticks {
        robot.sense(state).unwrap();
        robot.act(&command).unwrap();
        std::thread::sleep(Duration::from_millis(100));
    }
    robot.sense(state).unwrap();
}

/// Senses for `seconds` with no command but a PULSE (the watchdog stays
/// quiet while a position or heading setpoint runs).
pub fn watch(robot: &mut ArcosRobot, seconds: f64, state: &mut State) {
    let ticks = (seconds / 0.1).round() as usize;
    for _ in 0..ticks {
        robot.keep_alive().unwrap();
        robot.sense(state).unwrap();
        std::thread::sleep(Duration::from_millis(100));
    }
    robot.sense(state).unwrap();
}

fn wrap(a: f64) -> f64 {
    a.sin().atan2(a.cos())
}

/// Closed loop on the odometry the client decodes: four 1 m legs with 90°
/// turns on RVEL. Asserts that the square closes; returns the final state.
pub fn drive_square(robot: &mut ArcosRobot) -> State {
    let mut state = State::default();
    drive(robot, Command::Stop, 0.3, &mut state);
    let origin = state.pose;
    for leg in 0..4 {
        let (start, heading) = (state.pose, origin.theta + f64::from(leg) * std::f64::consts::FRAC_PI_2);
        while (state.pose.x - start.x).hypot(state.pose.y - start.y) < 0.97 {
            // Hold the leg's heading while driving.
            let correction = (2.0 * wrap(heading - state.pose.theta)).clamp(-0.3, 0.3);
            drive(robot, Command::Drive { velocity: 0.3, turn: Turn::Rate(correction) }, 0.1, &mut state);
        }
        let next = heading + std::f64::consts::FRAC_PI_2;
        while wrap(next - state.pose.theta).abs() > 0.02 {
            let rate = (2.0 * wrap(next - state.pose.theta)).clamp(-0.6, 0.6);
            drive(robot, Command::Drive { velocity: 0.0, turn: Turn::Rate(rate) }, 0.1, &mut state);
        }
    }
    drive(robot, Command::Stop, 0.3, &mut state);
    let end = state.pose.relative_to(&origin);
    assert!(end.x.hypot(end.y) < 0.15, "the square closes: {:?}", end);
    assert!(end.theta.abs() < 0.05, "{:?}", end);
    state
}

/// Drives to `goal` (world frame) steering with HEAD commands at no more
/// than 30°/s; asserts it ends within 0.1 m and never turned faster.
pub fn go_to_goal(robot: &mut ArcosRobot, goal: (f64, f64)) -> State {
    let mut state = State::default();
    drive(robot, Command::Stop, 0.3, &mut state);
    let max_rate = 30f64.to_radians();
    let mut fastest = 0.0f64;
    for _ in 0..600 {
        let (dx, dy) = (goal.0 - state.pose.x, goal.1 - state.pose.y);
        let distance = dx.hypot(dy);
        if distance < 0.05 {
            break;
        }
        let heading = dy.atan2(dx);
        let aligned = wrap(heading - state.pose.theta).abs() < 0.3;
        let velocity = if aligned { (0.8 * distance).min(0.4) } else { 0.0 };
        drive(robot, Command::Drive { velocity, turn: Turn::Heading { heading, max_rate } }, 0.1, &mut state);
        fastest = fastest.max(state.rot_velocity.abs());
    }
    drive(robot, Command::Stop, 1.0, &mut state);
    let miss = Pose2::new(goal.0, goal.1, 0.0).distance_to(state.pose.x, state.pose.y);
    assert!(miss < 0.1, "ended {miss:.3} m from the goal: {:?}", state.pose);
    assert!(fastest <= max_rate * 1.05, "turned at {:.1}°/s", fastest.to_degrees());
    state
}
