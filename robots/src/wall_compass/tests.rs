use super::*;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

/// The Powerbot's side sonars: two facing left, two facing right.
fn side_units() -> Vec<Pose2> {
    let deg = 1f64.to_radians();
    vec![
        Pose2::new(0.152, 0.278, 90.0 * deg),
        Pose2::new(-0.298, 0.278, 90.0 * deg),
        Pose2::new(0.152, -0.278, -90.0 * deg),
        Pose2::new(-0.298, -0.278, -90.0 * deg),
    ]
}

/// A wall: a point on it and its direction.
#[derive(Clone, Copy)]
struct Wall {
    x: f64,
    y: f64,
    direction: f64,
}

/// The readings of `units` on a robot truly at `pose` between `walls`:
/// each ray's nearest wall along its axis, with 2 cm of noise.
fn readings(pose: &Pose2, walls: &[Wall], rng: &mut ChaCha8Rng) -> Vec<RangeReading> {
    let noise = Normal::new(0.0, 0.02).unwrap();
    side_units()
        .into_iter()
        .map(|mount| {
            let sensor = pose.compose(&mount);
            let (c, s) = (sensor.theta.cos(), sensor.theta.sin());
            let range = walls
                .iter()
                .filter_map(|w| {
                    // Where the ray meets the wall's line.
                    let (dc, ds) = (w.direction.cos(), w.direction.sin());
                    let denom = c * ds - s * dc;
                    let t = ((w.x - sensor.x) * ds - (w.y - sensor.y) * dc) / denom;
                    (denom.abs() > 1e-9 && t > 0.0).then_some(t)
                })
                .fold(f64::INFINITY, f64::min);
            let range = (range < 5.0).then(|| range + noise.sample(rng));
            RangeReading { pose_robot_sensor: mount, range, max_range: 5.0 }
        })
        .collect()
}

/// A corridor 4 m wide along the x axis.
const CORRIDOR: [Wall; 2] = [Wall { x: 0.0, y: 2.0, direction: 0.0 }, Wall { x: 0.0, y: -2.0, direction: 0.0 }];

/// Drives the robot straight along the x axis for `metres` in steps of 6 cm,
/// its odometry turning `veer_deg_per_m` unseen, between `walls(x)`;
/// gives the compass and odometry's last pose.
fn drive(metres: f64, veer_deg_per_m: f64, walls: impl Fn(f64) -> Vec<Wall>) -> (WallCompass, Pose2) {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let mut compass = WallCompass::new(WallCompassConfig::default());
    let mut odometry = Pose2::default();
    let step = 0.06;
    for k in 0..=(metres / step) as usize {
        let truth = Pose2::new(k as f64 * step, 0.0, 0.0);
        if k > 0 {
            let turn = (veer_deg_per_m * step).to_radians();
            odometry = odometry.compose(&Pose2::new(step, 0.0, turn));
        }
        compass.update(&odometry, &readings(&truth, &walls(truth.x), &mut rng));
    }
    (compass, odometry)
}

#[test]
fn walls_hold_a_veering_heading() {
    let (compass, odometry) = drive(40.0, 0.05, |_| CORRIDOR.to_vec());
    // Odometry has turned 2° that the robot never turned.
    assert!((odometry.theta.to_degrees() - 2.0).abs() < 0.01, "{odometry:?}");
    let held = compass.pose();
    assert!(held.theta.to_degrees().abs() < 0.3, "{held:?}");
    assert!(held.y.abs() < 0.2 && odometry.y > 0.6, "{held:?} {odometry:?}");
    assert!(compass.corrections() > 10, "{}", compass.corrections());
}

#[test]
fn without_walls_the_pose_is_odometry() {
    let (compass, odometry) = drive(20.0, 0.05, |_| Vec::new());
    let held = compass.pose();
    assert!(compass.axes().is_none());
    assert!((held.x - odometry.x).abs() < 1e-9 && (held.y - odometry.y).abs() < 1e-9);
    assert!((held.theta - odometry.theta).abs() < 1e-12);
}

#[test]
fn a_wall_off_the_axes_corrects_nothing() {
    // The corridor fixes the axes over its first 7 m; there the left wall
    // gives way to one 7° off them (along the way driven, but beyond the
    // largest correction), and the right wall ends.
    let slanted = |x: f64| {
        if x < 7.0 {
            CORRIDOR.to_vec()
        } else {
            vec![Wall { x: 7.0, y: 2.0, direction: 7f64.to_radians() }]
        }
    };
    let (before, _) = drive(6.5, 0.0, |_| CORRIDOR.to_vec());
    let (compass, odometry) = drive(12.0, 0.0, slanted);
    assert!(before.corrections() > 0);
    assert_eq!(compass.corrections(), before.corrections(), "the slanted wall corrected the heading");
    assert_eq!(compass.pose().theta, before.pose().theta, "{:?}", compass.pose());
    assert!((compass.pose().theta - odometry.theta).abs() < 0.2f64.to_radians(), "{:?}", compass.pose());
}

#[test]
fn driving_a_circle_traces_no_wall() {
    // Round a circle of 1 m radius between the corridor's walls: the side
    // sonars sweep across the walls, never along one.
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let mut compass = WallCompass::new(WallCompassConfig::default());
    for k in 0..720 {
        let angle = (k as f64 * 0.5).to_radians();
        let pose = Pose2::new(angle.sin(), 1.0 - angle.cos(), wrap_angle(angle));
        compass.update(&pose, &readings(&pose, &CORRIDOR, &mut rng));
    }
    assert!(compass.axes().is_none());
}

#[test]
fn a_wall_across_the_way_the_robot_drives_is_no_guide() {
    // Driving at 15° to the walls, the side sonars' echoes land on the
    // wall ahead and behind, along a line that is not the way driven.
    let mut rng = ChaCha8Rng::seed_from_u64(4);
    let mut compass = WallCompass::new(WallCompassConfig::default());
    let heading = 15f64.to_radians();
    for k in 0..300 {
        let pose = Pose2::new(k as f64 * 0.06 * heading.cos(), -1.5 + k as f64 * 0.06 * heading.sin(), heading);
        compass.update(&pose, &readings(&pose, &CORRIDOR, &mut rng));
    }
    assert!(compass.axes().is_none());
}

#[test]
fn one_line_alone_does_not_fix_the_axes() {
    // Only the left wall, and for its first 2 m a cabinet 3° off it: the
    // cabinet's line waits for a second to agree, the wall's lines that
    // follow disagree with it and agree with one another.
    let mut rng = ChaCha8Rng::seed_from_u64(6);
    let mut compass = WallCompass::new(WallCompassConfig::default());
    for k in 0..=200 {
        let pose = Pose2::new(k as f64 * 0.06, 0.0, 0.0);
        if k == 36 {
            assert!(compass.axes().is_none(), "the cabinet's line alone fixed the axes");
        }
        let wall = if pose.x < 2.05 { Wall { x: 0.0, y: 1.5, direction: 3f64.to_radians() } } else { CORRIDOR[0] };
        compass.update(&pose, &readings(&pose, &[wall], &mut rng));
    }
    let axes = compass.axes().expect("two wall lines agree").to_degrees();
    assert!(axes.abs() < 0.5, "{axes}°");
    assert!(compass.pose().theta.to_degrees().abs() < 0.5, "{:?}", compass.pose());
}

#[test]
fn a_pose_that_is_not_finite_is_passed_on_and_forgotten() {
    let mut rng = ChaCha8Rng::seed_from_u64(8);
    let mut compass = WallCompass::new(WallCompassConfig::default());
    for k in 0..=400 {
        let pose = Pose2::new(k as f64 * 0.06, 0.0, 0.0);
        let odometry = if k == 100 { Pose2::new(f64::NAN, 0.0, f64::INFINITY) } else { pose };
        let held = compass.update(&odometry, &readings(&pose, &CORRIDOR, &mut rng));
        assert_eq!(held.x.is_finite(), k != 100);
    }
    let held = compass.pose();
    assert!((held.x - 24.0).abs() < 0.01 && held.y.abs() < 0.05 && held.theta.abs() < 0.01, "{held:?}");
    assert!(compass.corrections() > 0);
}

#[test]
fn a_scanner_creeping_along_a_wall_still_traces_it() {
    // A laser scanner's 41 beams a side within 10° of square, at 4 mm a
    // tick: a side's trace fills up (10 000 echoes) before the span ends,
    // and is fitted all the same.
    let mut rng = ChaCha8Rng::seed_from_u64(9);
    let noise = Normal::new(0.0, 0.01).unwrap();
    let mut compass = WallCompass::new(WallCompassConfig::default());
    let mut odometry = Pose2::default();
    for k in 0..=2500 {
        if k > 0 {
            odometry = odometry.compose(&Pose2::new(0.004, 0.0, 0.1f64.to_radians() * 0.004));
        }
        let beams = (-20..=20).flat_map(|b| [90.0 + 0.5 * b as f64, -90.0 + 0.5 * b as f64]);
        let ranges: Vec<_> = beams
            .map(|deg: f64| {
                let angle = deg.to_radians();
                RangeReading {
                    pose_robot_sensor: Pose2::new(0.0, 0.0, angle),
                    range: Some(2.0 / angle.sin().abs() + noise.sample(&mut rng)),
                    max_range: 30.0,
                }
            })
            .collect();
        compass.update(&odometry, &ranges);
    }
    // Odometry turned 1° the robot never turned; a trace that stopped at
    // its cap would have corrected none of it.
    assert!(compass.corrections() >= 3, "{}", compass.corrections());
    assert!(compass.pose().theta.to_degrees().abs() < 0.75, "{:?}", compass.pose());
}

#[test]
fn clutter_traces_no_wall() {
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let scatter = Normal::new(1.5_f64, 0.5).unwrap();
    let mut compass = WallCompass::new(WallCompassConfig::default());
    for k in 0..500 {
        let pose = Pose2::new(k as f64 * 0.06, 0.0, 0.0);
        let ranges: Vec<_> = side_units()
            .into_iter()
            .map(|mount| RangeReading {
                pose_robot_sensor: mount,
                range: Some(scatter.sample(&mut rng).clamp(0.1, 4.9)),
                max_range: 5.0,
            })
            .collect();
        compass.update(&pose, &ranges);
    }
    assert!(compass.axes().is_none());
    assert_eq!(compass.corrections(), 0);
}

#[test]
fn odometry_since_the_last_update_is_laid_from_the_corrected_pose() {
    let (compass, odometry) = drive(30.0, 0.05, |_| CORRIDOR.to_vec());
    let ahead = odometry.compose(&Pose2::new(0.5, 0.0, 0.1));
    let expected = compass.pose().compose(&Pose2::new(0.5, 0.0, 0.1));
    let corrected = compass.corrected(&ahead);
    assert!((corrected.x - expected.x).abs() < 1e-9 && (corrected.y - expected.y).abs() < 1e-9, "{corrected:?}");
    assert!((corrected.theta - expected.theta).abs() < 1e-9);
    assert_ne!(compass.pose().theta, odometry.theta);
}

#[test]
fn a_first_wall_from_long_ago_does_not_pin_the_axes() {
    // A cabinet 3.5° off square for the first 2 m, then 30 m with no wall
    // at all, then the corridor: by then the heading may have drifted more
    // than the cabinet and the corridor's first line disagree, so the
    // corridor's own lines fix the axes, and odometry (exact here) is left
    // as it is.
    let walls = |x: f64| {
        if x < 2.05 {
            vec![Wall { x: 0.0, y: 1.5, direction: 3.5f64.to_radians() }]
        } else if x < 32.0 {
            Vec::new()
        } else {
            CORRIDOR.to_vec()
        }
    };
    let (compass, odometry) = drive(80.0, 0.0, walls);
    let axes = compass.axes().expect("the corridor fixes the axes").to_degrees();
    assert!(axes.abs() < 0.5, "{axes}°");
    assert!((compass.pose().theta - odometry.theta).to_degrees().abs() < 1.0, "{:?}", compass.pose());
}
