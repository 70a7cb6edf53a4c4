//! The client against the robot maker's own simulator, AMRISim, when one is
//! running: the same square and goal as against the emulator.
//!
//! ```sh
//! Xvfb :99 & DISPLAY=:99 ./AMRISim --no-gui -R powerbot --nomap &
//! UBF_AMRISIM=tcp://127.0.0.1:8101 cargo test -p ubf-robots --test amrisim -- --ignored --test-threads 1
//! ```
//!
//! `docs/deploy.md` says how to build AMRISim headless.

mod common;

use ubf_core::Robot;
use ubf_robots::arcos::client::{ArcosRobot, ConnectOptions};
use ubf_robots::arcos::link;
use ubf_robots::model::RobotModel;

/// A session with the simulator `UBF_AMRISIM` names, retried for half a
/// minute: AMRISim takes a while to load its model and start listening, and
/// a test started beside it should wait rather than fail.
fn connect() -> ArcosRobot {
    let address = std::env::var("UBF_AMRISIM").expect("set UBF_AMRISIM=tcp://host:8101 to a running AMRISim");
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(30);
    loop {
        let session = link::open(&address, 9600)
            .map_err(ubf_core::RobotError::from)
            .and_then(|link| ArcosRobot::connect(link, RobotModel::powerbot(), &ConnectOptions::default()));
        match session {
            Ok(robot) => return robot,
            Err(e) if std::time::Instant::now() < deadline => {
                eprintln!("AMRISim at {address} not ready ({e}); retrying");
                std::thread::sleep(std::time::Duration::from_millis(500));
            }
            Err(e) => panic!("no Powerbot session with AMRISim at {address} in 30 s: {e}"),
        }
    }
}

#[test]
#[ignore = "needs a running AMRISim: set UBF_AMRISIM"]
fn amrisim_reads_the_config_and_drives_a_square() {
    let mut robot = connect();
    let config = robot.config().expect("AMRISim answers CONFIG").clone();
    assert_eq!(config.subtype, "powerbot");
    assert!(config.settings.trans_vel_max > 0, "{config:?}");
    common::drive_square(&mut robot);
    robot.shutdown().unwrap();
}

#[test]
#[ignore = "needs a running AMRISim: set UBF_AMRISIM"]
fn amrisim_drives_to_a_goal_on_heading_commands() {
    let mut robot = connect();
    common::go_to_goal(&mut robot, (1.5, 1.0));
    robot.shutdown().unwrap();
}
