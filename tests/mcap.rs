//! `run.mcap`, read back with the MCAP project's own Rust reader: every
//! topic there, the poses where the report says, the same bytes for the
//! same seed, and a log cut short still readable up to its last chunk.
//! (`scripts/mcap-check.py` does the same with its Python reader.)

use std::collections::BTreeMap;
use std::path::Path;
use ubf::run::run;
use ubf::scenario::Scenario;

fn scenario() -> Scenario {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("lab/scenarios/thesis/route-1-2.ron");
    let text = std::fs::read_to_string(path).unwrap().replace("technique: None", "technique: Tracking");
    Scenario::from_ron(&ubf::registry(), &text).unwrap()
}

/// What a log holds: messages per topic, each topic's schema name, and the
/// error reading stopped at, if any.
struct Read {
    topics: BTreeMap<String, Vec<serde_json::Value>>,
    schemas: BTreeMap<String, String>,
    error: Option<String>,
}

/// Reads a log's bytes.
fn read(bytes: &[u8], options: enumset::EnumSet<mcap::read::Options>) -> Read {
    let (mut topics, mut schemas) = (BTreeMap::<String, Vec<serde_json::Value>>::new(), BTreeMap::new());
    let mut error = None;
    for message in mcap::MessageStream::new_with_options(bytes, options).unwrap() {
        match message {
            Ok(m) => {
                let value: serde_json::Value = serde_json::from_slice(&m.data).unwrap();
                schemas.insert(
                    m.channel.topic.clone(),
                    m.channel.schema.as_ref().map_or(String::new(), |s| s.name.clone()),
                );
                topics.entry(m.channel.topic.clone()).or_default().push(value);
            }
            Err(e) => {
                error = Some(e.to_string());
                break;
            }
        }
    }
    Read { topics, schemas, error }
}

#[test]
fn a_run_log_reads_back_and_a_cut_one_up_to_its_last_chunk() {
    let dir = tempfile::tempdir().unwrap();
    let report = run(&scenario(), 4, Some(dir.path())).unwrap();
    let bytes = std::fs::read(dir.path().join("run.mcap")).unwrap();
    let Read { topics, schemas, error } = read(&bytes, enumset::EnumSet::empty());
    assert_eq!(error, None);
    for topic in ["/pose/true", "/pose/odometry", "/pose/wheels", "/pose/egomotion", "/tree", "/ranges"] {
        assert_eq!(topics[topic].len() as u64, report.ticks, "{topic}: one message a tick");
    }
    for topic in ["/goal", "/scene", "/world", "/run", "/report"] {
        assert_eq!(topics[topic].len(), 1, "{topic}");
    }
    assert_eq!(schemas["/pose/true"], "foxglove.PoseInFrame");
    assert_eq!(schemas["/scene"], "foxglove.SceneUpdate");
    // One set of observed landmarks per stereo frame (2 Hz over the run).
    let frames = topics["/observations"].len() as f64;
    assert!((frames - 2.0 * report.sim_time_s).abs() < 3.0, "{frames} frames in {} s", report.sim_time_s);
    // The last true pose is the report's, less up to two ticks' motion (the
    // log has the pose the tick sensed, a tick behind the body, and the
    // body moves once more after the last tick).
    let position = |k: usize| {
        let p = &topics["/pose/true"][k]["pose"]["position"];
        (p["x"].as_f64().unwrap(), p["y"].as_f64().unwrap())
    };
    let n = topics["/pose/true"].len();
    let ((x0, y0), (x, y)) = (position(n - 2), position(n - 1));
    let tick_motion = (x - x0).hypot(y - y0);
    assert!(
        report.final_true_pose.distance_to(x, y) < 2.0 * tick_motion + 0.01,
        "({x}, {y}) against {:?}, a tick moving {tick_motion} m",
        report.final_true_pose
    );
    assert_eq!(topics["/report"][0]["end"], "goal_reached");
    let tick = &topics["/tree"][10];
    assert!(tick["nodes"].as_array().unwrap().iter().any(|n| n["path"] == "root/ActionAiding"), "{tick}");

    // Same seed, same bytes.
    let again = tempfile::tempdir().unwrap();
    run(&scenario(), 4, Some(again.path())).unwrap();
    assert!(std::fs::read(again.path().join("run.mcap")).unwrap() == bytes, "run.mcap differs for the same seed");

    // A log cut short, as a killed process leaves it: read up to the cut.
    let cut = &bytes[..bytes.len() * 6 / 10];
    let topics = read(cut, mcap::read::Options::IgnoreEndMagic.into()).topics;
    let kept = topics.get("/tree").map_or(0, Vec::len) as u64;
    assert!(kept > report.ticks / 3 && kept < report.ticks, "{kept} of {} ticks read from the cut log", report.ticks);
}

#[test]
fn ubf_replay_redraws_the_plot_from_the_log_alone() {
    let dir = tempfile::tempdir().unwrap();
    let report = run(&scenario(), 5, Some(dir.path())).unwrap();
    let log = dir.path().join("run.mcap");
    let redrawn = dir.path().join("again.png");
    let ubf = |args: &[&str]| std::process::Command::new(env!("CARGO_BIN_EXE_ubf")).args(args).output().unwrap();
    let out = ubf(&["replay", log.to_str().unwrap(), "--plot", redrawn.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let summary = String::from_utf8_lossy(&out.stdout);
    assert!(summary.contains(&format!("ticks logged    {}", report.ticks)), "{summary}");
    assert!(summary.contains("ended           goal_reached"), "{summary}");
    // The same picture as the run drew, but for the caption.
    let (original, again) =
        (image::open(dir.path().join("plot.png")).unwrap().into_rgb8(), image::open(&redrawn).unwrap().into_rgb8());
    assert_eq!(original.dimensions(), again.dimensions());
    let differing = original.enumerate_pixels().filter(|(x, y, p)| *y >= 40 && again.get_pixel(*x, *y) != *p).count();
    assert_eq!(differing, 0, "the redrawn plot differs below the caption");
    // A log a killed run left: replayed as far as it goes.
    let bytes = std::fs::read(&log).unwrap();
    let cut = dir.path().join("cut.mcap");
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
    let out = ubf(&["replay", cut.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(String::from_utf8_lossy(&out.stdout).contains("not recorded: the log stops early"));
    assert!(dir.path().join("cut-replay.png").is_file());
    // Not a log at all.
    let out = ubf(&["replay", dir.path().join("plot.png").to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn a_damaged_log_is_refused_or_read_as_far_as_it_goes_never_a_crash() {
    use rand::{Rng, SeedableRng};
    let dir = tempfile::tempdir().unwrap();
    run(&scenario(), 6, Some(dir.path())).unwrap();
    let bytes = std::fs::read(dir.path().join("run.mcap")).unwrap();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
    let damaged = dir.path().join("damaged.mcap");
    for case in 0..300 {
        let mut b = bytes.clone();
        match case % 3 {
            // Bytes flipped anywhere, lengths and compressed data included
            // (a corrupted chunk length once asked for 9·10¹⁸ bytes).
            0 => (0..20).for_each(|_| {
                let at = rng.random_range(0..b.len());
                b[at] = rng.random();
            }),
            1 => b.truncate(rng.random_range(0..b.len())),
            _ => {
                let at = rng.random_range(8..b.len().min(4000) - 8);
                b[at..at + 8].fill(0xff);
            }
        }
        std::fs::write(&damaged, &b).unwrap();
        // Ok (perhaps cut short) or an error naming the file: both fine.
        if let Err(e) = ubf::replay::read(&damaged) {
            assert!(e.to_string().contains("damaged.mcap"), "{e}");
        }
    }
}

/// A source that yields `bytes`, interrupted by a signal on every other
/// read, then fails as a disk does.
struct FailingAfter<'a> {
    bytes: &'a [u8],
    interrupted: bool,
}

impl std::io::Read for FailingAfter<'_> {
    fn read(&mut self, into: &mut [u8]) -> std::io::Result<usize> {
        self.interrupted = !self.interrupted;
        if self.interrupted {
            return Err(std::io::ErrorKind::Interrupted.into());
        }
        if self.bytes.is_empty() {
            return Err(std::io::Error::other("input/output error on the disk"));
        }
        let n = into.len().min(self.bytes.len());
        into[..n].copy_from_slice(&self.bytes[..n]);
        self.bytes = &self.bytes[n..];
        Ok(n)
    }
}

#[test]
fn a_log_whose_disk_fails_is_an_error_not_a_log_cut_short() {
    let dir = tempfile::tempdir().unwrap();
    run(&scenario(), 6, Some(dir.path())).unwrap();
    let bytes = std::fs::read(dir.path().join("run.mcap")).unwrap();
    let half = &bytes[..bytes.len() / 2];
    let name = Path::new("run.mcap");
    // The same half of a log: ended there, it is a log cut short ...
    let ended = ubf::replay::read_from(half, name).unwrap();
    assert!(ended.cut_short.is_some() && !ended.timeline.time.is_empty());
    // ... failing there, it is the disk's error, said as such (and reads
    // a signal interrupted on the way are tried again, not taken as its end).
    let failed =
        ubf::replay::read_from(FailingAfter { bytes: half, interrupted: false }, name).unwrap_err().to_string();
    assert!(failed.contains("run.mcap") && failed.contains("input/output error on the disk"), "{failed}");
}

#[test]
fn rendered_pairs_are_logged_as_the_pngs_a_recording_holds() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/rendered-corridor.ron");
    let text = std::fs::read_to_string(path).unwrap().replace("max_time_s: 200.0", "max_time_s: 1.5");
    let scenario = Scenario::from_ron(&ubf::registry(), &text).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let (logged, recorded) = (dir.path().join("run"), dir.path().join("frames"));
    let outputs = ubf::run::Outputs { dir: &logged, images: true, rosbag: false };
    ubf::run::run_until(&scenario, 1, Some(outputs), None, &std::sync::atomic::AtomicBool::new(false)).unwrap();
    ubf::frames::record(&scenario, 1, &recorded, 1).unwrap();

    let bytes = std::fs::read(logged.join("run.mcap")).unwrap();
    let log = read(&bytes, enumset::EnumSet::empty());
    assert_eq!(log.schemas["/camera/left"], "foxglove.CompressedImage");
    let (left, right) = (&log.topics["/camera/left"], &log.topics["/camera/right"]);
    // 15 ticks of 0.1 s and a frame every 0.5 s: frames at 0, 0.5 and 1 s.
    assert_eq!((left.len(), right.len()), (3, 3), "one pair per frame");
    assert_eq!(left[0]["format"], "png");
    assert_eq!(left[0]["frame_id"], "camera_left");
    // The first pair, taken at the start before anything moved, is the
    // recording's first pair, pixel for pixel.
    use base64::Engine;
    for (message, side) in [(&left[0], "left"), (&right[0], "right")] {
        let png = base64::engine::general_purpose::STANDARD.decode(message["data"].as_str().unwrap()).unwrap();
        let from_log = image::load_from_memory(&png).unwrap().into_luma8();
        let from_recording = image::open(recorded.join(side).join("000001.png")).unwrap().into_luma8();
        assert_eq!(from_log.dimensions(), from_recording.dimensions());
        assert!(from_log == from_recording, "{side} image differs from the recording's");
    }
    // Without asking, no images.
    let plain = dir.path().join("plain");
    ubf::run::run(&scenario, 1, Some(&plain)).unwrap();
    let log = read(&std::fs::read(plain.join("run.mcap")).unwrap(), enumset::EnumSet::empty());
    assert!(!log.topics.contains_key("/camera/left"));
}

#[test]
fn the_python_reader_reads_every_message_and_each_fits_its_json_schema() {
    // scripts/mcap-check.py: the MCAP project's Python reader and the
    // `jsonschema` validator, neither written here. Without AvoidCollision
    // the robot drives into the box, so `/collision` is logged too.
    let dir = tempfile::tempdir().unwrap();
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(root.join("scenarios/corridor-box.ron")).unwrap();
    let text =
        text.replace("(behavior: AvoidCollision(), weight: 2.0),", "").replace("max_time_s: 120.0", "max_time_s: 30.0");
    let scenario = Scenario::from_ron(&ubf::registry(), &text).unwrap();
    run(&scenario, 2, Some(dir.path())).unwrap();
    let check = std::process::Command::new("python3")
        .arg(root.join("scripts/mcap-check.py"))
        .arg(dir.path().join("run.mcap"))
        .output()
        .unwrap();
    let said = String::from_utf8_lossy(&check.stdout);
    assert!(check.status.success(), "{said}{}", String::from_utf8_lossy(&check.stderr));
    let topics = ["| /tree | ubf.Tick |", "| /world | ubf.World |", "| /run | ubf.Run |", "| /report | ubf.Report |"];
    for topic in topics.iter().chain(&["| /collision | ubf.Collision |"]) {
        assert!(said.contains(topic), "{said}");
    }
}
