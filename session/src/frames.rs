//! Stereo image files: `ubf frames` records the rendered pairs of a
//! scenario run into a directory, and `ubf pipeline` replays a directory
//! (such a recording, or a KITTI odometry sequence) through the feature
//! pipeline and the rigid egomotion estimator, timing each stage (the same
//! files the OpenCV comparison script reads) and, with ground truth,
//! measuring its accuracy.

use crate::scenario::Scenario;
use serde::Serialize;
use std::io::Write;
use std::ops::ControlFlow;
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::sync::{Arc, Mutex, PoisonError};
use std::time::Instant;
use ubf_core::{
    BuildContext, Controller, Ends, Pose2, Session, SessionEnd, SimClock, StereoFrame, TickRecord, TickSink,
};
use ubf_perception::egomotion::{DisparityOffsetEstimate, EgomotionConfig, Tracker};
use ubf_perception::features::{FeatureConfig, StereoPipeline};
use ubf_perception::kitti::{self, Accuracy};
use ubf_perception::rectify::Rectified;
use ubf_perception::source::{CameraSource, ImageDirectory, ImageDirectoryWriter, StereoPair};
use ubf_perception::StereoCamera;
use ubf_robots::sim::render::RenderConfig;
use ubf_robots::sim::SimRobot;

/// The file beside `frames.csv` that holds the pair's calibration.
pub const CAMERA_FILE: &str = "camera.ron";

/// Instead of [`CAMERA_FILE`], a recording of raw (unrectified) pairs holds
/// the two cameras' ROS `camera_info` files, and is rectified on replay.
pub const RAW_LEFT_INFO: &str = "left.yaml";
/// The right camera's `camera_info`; see [`RAW_LEFT_INFO`].
pub const RAW_RIGHT_INFO: &str = "right.yaml";
/// Or, instead of the two `camera_info` files, OpenCV's stereo calibration
/// of the raw pairs (`K1`, `D1`, `K2`, `D2`, `R`, `T`).
pub const RAW_STEREO_CALIBRATION: &str = "stereo.yaml";

/// Why a recording could not be made, or a directory of pairs replayed.
#[derive(Debug, thiserror::Error)]
pub enum FramesError {
    /// The scenario's robot has no camera to record.
    #[error("the scenario's robot has no camera: add `camera: ()`")]
    NoCamera,
    /// An option does not fit the directory.
    #[error("{0}")]
    Options(String),
    /// The directory holds more than one calibration.
    #[error("{0}")]
    Calibration(String),
    /// The raw pair's calibration files could not be used.
    #[error(transparent)]
    Rectification(#[from] ubf_perception::rectify::CalibrationError),
    /// `camera.ron` is not a camera.
    #[error("{}:{source}", path.display())]
    CameraFile {
        /// The file.
        path: PathBuf,
        /// Where and why it failed.
        source: ubf_core::config::RonError,
    },
    /// A file could not be read or written.
    #[error("{}: {source}", path.display())]
    File {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// A pair could not be read or written.
    #[error(transparent)]
    Source(#[from] ubf_perception::source::SourceError),
    /// A pair the pipeline refused (its size does not match the calibration).
    #[error("{}: pair {number}: {source} (in {})", index.display(), calibration.display())]
    Pair {
        /// The directory's list of pairs.
        index: PathBuf,
        /// The pair's number, from 1.
        number: u64,
        /// The calibration it was checked against.
        calibration: PathBuf,
        /// Why.
        source: ubf_perception::features::PipelineError,
    },
    /// The directory lists no pairs.
    #[error("{}: no pairs listed", .0.display())]
    NoPairs(PathBuf),
    /// The recorded run failed.
    #[error(transparent)]
    Run(#[from] ubf_core::ControllerError),
    /// A bug: the recorded run panicked outside the behaviours.
    #[error("internal error: {0}")]
    Panic(String),
}

impl FramesError {
    /// An I/O error on `path`.
    fn file(path: &Path) -> impl FnOnce(std::io::Error) -> FramesError + '_ {
        move |source| FramesError::File { path: path.to_owned(), source }
    }
}

/// Runs `scenario` with rendered images (turned on if the camera uses the
/// geometric model) and writes every pair into `dir`, with the camera's
/// calibration. Returns the number of pairs.
pub fn record(scenario: &Scenario, seed: u64, dir: &Path, max_frames: usize) -> Result<usize, FramesError> {
    let mut scenario = scenario.clone();
    let camera = scenario.robot.camera.as_mut().ok_or(FramesError::NoCamera)?;
    camera.images.get_or_insert_with(RenderConfig::default);
    let stereo = camera.stereo;
    // At most this many pairs: the frames the run has time for, or fewer.
    let bound = ((camera.rate_hz * scenario.max_time_s).ceil() as usize).min(max_frames);
    let writer = ImageDirectoryWriter::create(dir)?;
    let calibration =
        ron::ser::to_string_pretty(&stereo, ron::ser::PrettyConfig::default()).expect("a camera always serialises");
    let path = dir.join(CAMERA_FILE);
    std::fs::write(&path, calibration).map_err(FramesError::file(&path))?;

    let sim = SimRobot::new(&scenario.robot, &scenario.world, scenario.period_s, seed);
    let root = scenario.root.build(&BuildContext::new(seed));
    let mut controller = Controller::new(sim, root, Box::new(SimClock::new(scenario.period_s)));
    controller.set_goal(scenario.goal);
    let progress = crate::sweep::progress_bar(bound as u64, "pairs");
    let pairs = Arc::new(Mutex::new(PairRecorder { writer, frame: 0, progress }));
    controller.add_sink(Box::new(pairs.clone()));
    let ends = Ends { at_goal: true, max_ticks: Some(scenario.max_ticks()), ..Ends::default() };
    let mut session = Session::new(controller, ends);
    let ended = session.run(&AtomicBool::new(false), |record| {
        let enough = record.state.stereo.number as usize >= max_frames;
        if enough {
            ControlFlow::Break(())
        } else {
            ControlFlow::Continue(())
        }
    });
    let (controller, shutdown) = session.finish();
    match ended {
        SessionEnd::Failed(e) => return Err(e.into()),
        SessionEnd::Panicked(why) => return Err(FramesError::Panic(why)),
        _ => shutdown?,
    }
    drop(controller);
    let recorder = Arc::into_inner(pairs).expect("the controller, the only other holder, is gone");
    let recorder = recorder.into_inner().unwrap_or_else(PoisonError::into_inner);
    recorder.progress.finish_and_clear();
    Ok(recorder.writer.finish()?)
}

/// A sink writing each new frame's pair of images into a recording.
struct PairRecorder {
    writer: ImageDirectoryWriter,
    /// The last frame written.
    frame: u64,
    progress: indicatif::ProgressBar,
}

impl TickSink for PairRecorder {
    fn record(&mut self, record: &TickRecord) -> std::io::Result<()> {
        let frame = &record.state.stereo;
        if frame.number == self.frame {
            return Ok(());
        }
        self.frame = frame.number;
        let Some(pair) = frame.images.as_deref().and_then(|images| StereoPair::from_images(frame.time, images)) else {
            return Ok(());
        };
        self.writer.push(&pair).map_err(std::io::Error::other)?;
        self.progress.inc(1);
        Ok(())
    }
}

/// The most bytes [`record`] writes for `scenario` and at most
/// `max_frames` pairs: the scenario's frames (rendered or not, `record`
/// renders them) as uncompressed grey images, an upper bound, since PNG
/// compresses rendered noise little.
pub fn recording_bytes(scenario: &Scenario, max_frames: usize) -> u64 {
    let work = scenario.work();
    work.camera_pairs.min(max_frames as u64).saturating_mul(work.pair_bytes)
}

/// What replaying a directory measured.
#[derive(Clone, Debug, Serialize)]
pub struct PipelineReport {
    /// What the directory held.
    pub layout: Layout,
    /// Pairs processed.
    pub frames: usize,
    /// Landmarks triangulated per pair, mean.
    pub landmarks_mean: f64,
    /// Median time of the feature pipeline per pair (detect and describe
    /// both images, match them, refine, triangulate), ms.
    pub pipeline_ms_median: f64,
    /// Median time of the egomotion step per pair (match to the keyframes,
    /// rigid estimate), ms.
    pub egomotion_ms_median: f64,
    /// Median end-to-end time per pair, ms.
    pub total_ms_median: f64,
    /// 1000 / the median end-to-end time.
    pub frames_per_s: f64,
    /// Egomotion steps that found no motion.
    pub failures: u32,
    /// The visual odometry's end pose: x, y (m), heading (rad).
    pub final_pose: [f64; 3],
    /// The egomotion limits used: top speed, m/s, and turn rate, °/s.
    pub limits: [f64; 2],
    /// How far the right image sits below the left (negative: above), px:
    /// the median of the pairs' estimates, which the pipeline corrects in
    /// whole rows. `None` if no pair gave one.
    pub row_offset_px: Option<f64>,
    /// The rig's disparity offset as the frames put it, px: the
    /// calibration's plus what egomotion read from the steps (the median of
    /// the steps' readings weighed by their precision). The value to put in
    /// `camera.ron` as `disparity_offset_px` if other drives agree. `None`
    /// if no step gave a reading.
    pub disparity_offset_px: Option<f64>,
    /// The calibration's disparity offset (or `--disparity-offset`'s), px.
    pub calibrated_disparity_offset_px: f64,
    /// Steps whose readings [`PipelineReport::disparity_offset_px`] rests on.
    pub disparity_offset_steps: usize,
    /// Whether the landmarks were corrected by the estimate as it settled
    /// (the default, once enough steps have read it), or only the estimate
    /// reported (`--keep-disparity-offset`, or too few readings).
    pub disparity_offset_corrected: bool,
    /// Frames whose egomotion step failed or rested on too few landmarks
    /// to trust.
    pub starving_frames: usize,
    /// The end pose's position σ by egomotion's covariance, with failed
    /// and starving steps counted at their larger uncertainty, m.
    pub pose_sigma_m: f64,
    /// What the user should know: a rig out of line, stretches of frames
    /// with too few landmarks.
    pub warnings: Vec<ReplayWarning>,
    /// With ground truth: the estimate's accuracy.
    #[serde(flatten)]
    pub accuracy: Option<Accuracy>,
}

/// Something a replay found that the user should know.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ReplayWarning {
    /// The first and last frame it concerns (1 the first pair), if it
    /// concerns a stretch.
    pub frames: Option<[u64; 2]>,
    /// What it is, in words.
    pub message: String,
}

/// From this vertical offset on, px, the rig is reported out of line (if
/// five pairs or more gave an estimate).
const RECALIBRATE_ROW_OFFSET_PX: f64 = 0.5;

/// From this difference between the disparity offset the frames read and
/// the calibration's on, px, the user is told to recalibrate (if twenty
/// steps or more gave a reading): a landmark 10 px of disparity off (30 m
/// on KITTI) is then 1 % too near or too far, the size of KITTI's whole
/// error budget.
const RECALIBRATE_DISPARITY_OFFSET_PX: f64 = 0.1;

/// A stretch of starving frames being gathered: first and last frame, the
/// fewest landmarks a pair had and a step rested on, failed steps.
#[derive(Clone, Copy, Debug)]
struct Starving {
    frames: [u64; 2],
    fewest_landmarks: usize,
    fewest_consistent: Option<usize>,
    failed: usize,
}

impl Starving {
    fn warning(&self, trusted: usize) -> ReplayWarning {
        let [first, last] = self.frames;
        let span = if first == last { format!("frame {first}") } else { format!("frames {first}–{last}") };
        let consistent = match self.fewest_consistent {
            Some(n) => format!(", {n} consistent in a step at fewest"),
            None => String::new(),
        };
        let failed = match self.failed {
            0 => String::new(),
            n => format!(", {n} failed step{}", if n == 1 { "" } else { "s" }),
        };
        ReplayWarning {
            frames: Some(self.frames),
            message: format!(
                "{span}: too few landmarks to trust egomotion ({} a pair at fewest{consistent}{failed}; \
                 {trusted} consistent are trusted); the pose's uncertainty is raised accordingly",
                self.fewest_landmarks
            ),
        }
    }
}

/// The layouts of a directory of stereo pairs that `ubf pipeline` reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Layout {
    /// `frames.csv` and `camera.ron` (or two `camera_info` files), as `ubf
    /// frames` writes.
    Recording,
    /// A KITTI odometry sequence.
    Kitti,
}

impl Layout {
    /// The file that lists the pairs.
    fn index(self) -> &'static str {
        match self {
            Layout::Recording => "frames.csv",
            Layout::Kitti => "times.txt",
        }
    }

    /// The file the calibration comes from.
    fn calibration(self) -> &'static str {
        match self {
            Layout::Recording => CAMERA_FILE,
            Layout::Kitti => "calib.txt",
        }
    }
}

impl std::fmt::Display for Layout {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Layout::Recording => "recording",
            Layout::Kitti => "kitti",
        })
    }
}

/// How to replay a directory.
#[derive(Clone, Debug, Default)]
pub struct ReplayOptions {
    /// The feature pipeline's settings.
    pub features: FeatureConfig,
    /// The fastest motion egomotion accepts, m/s (default: the robot's
    /// 0.6 for a recording, a road vehicle's 40 for a KITTI sequence).
    pub max_speed: Option<f64>,
    /// The fastest turn egomotion accepts, °/s (default: the robot's 100
    /// for a recording, 90 for a KITTI sequence).
    pub max_turn_rate_deg: Option<f64>,
    /// Ground-truth poses for a KITTI sequence (default: its `poses.txt`).
    pub poses: Option<PathBuf>,
    /// How far from a keyframe a frame may be matched to it, m (default:
    /// the tracker's 10).
    pub keyframe_range_m: Option<f64>,
    /// Replaces the calibration's disparity offset, px.
    pub disparity_offset_px: Option<f64>,
    /// Leave the landmarks as the calibration's disparity offset puts
    /// them, the offset the frames read only reported (egomotion's
    /// `disparity_offset: Report`). By default they are corrected by it
    /// once it has settled (`Correct`): on KITTI 06 and each of its
    /// perturbed copies that took the drift down (docs/perception.md).
    pub keep_disparity_offset: bool,
    /// Write every landmark of every pair here (CSV): pair, pixels (the
    /// first pixel's centre at (0, 0), as calibration tools count), the
    /// disparity as matched, the point in the camera frame, and the
    /// disparity offset the point was triangulated with (the depth is
    /// `focal_px · baseline_m / (disparity_px + disparity_offset_px)`).
    /// Every landmark found in the pair is written, matched or not, as
    /// egomotion triangulates it when the pair comes in: with the
    /// calibration's offset (or `disparity_offset_px`'s) until the offset
    /// read from the frames has settled, and from then on corrected by it,
    /// unless `keep_disparity_offset`. (A pair kept as a keyframe is
    /// triangulated again with later corrections; the file keeps the first.)
    /// A landmark the correction puts at or beyond infinity is left out, as
    /// egomotion leaves it out.
    pub landmarks: Option<PathBuf>,
}

/// The header of the landmarks CSV that `ubf pipeline --landmarks` writes:
/// see [`ReplayOptions::landmarks`].
pub const LANDMARKS_HEADER: &str = "pair,u_left_px,u_right_px,v_px,disparity_px,x_m,y_m,z_m,disparity_offset_px";

/// A KITTI sequence's egomotion limits, for a car on public roads: 40 m/s
/// (144 km/h) and 90 °/s.
const ROAD_VEHICLE_LIMITS: (f64, f64) = (40.0, 90.0);

/// A replayed directory: the report, and the estimated and true paths.
#[derive(Clone, Debug)]
pub struct Replay {
    /// What was measured.
    pub report: PipelineReport,
    /// Egomotion's pose after each pair.
    pub estimate: Vec<Pose2>,
    /// The ground truth at each pair, when there is one.
    pub truth: Option<Vec<Pose2>>,
}

/// Replays `dir` (a recording with `frames.csv` and `camera.ron`, or a
/// KITTI odometry sequence) through the pipeline and the rigid estimator on
/// this thread. There is no odometry on replay, so the odometry gate is off
/// and an outage is bridged by standing still.
pub fn replay(dir: &Path, options: &ReplayOptions) -> Result<Replay, FramesError> {
    let (layout, camera, mut source, truth, limits, pairs) = if kitti::is_sequence(dir) {
        let sequence = kitti::open(dir, options.poses.as_deref())?;
        let pairs = sequence.pairs.len();
        (
            Layout::Kitti,
            sequence.camera,
            Box::new(sequence.pairs) as Box<dyn CameraSource>,
            sequence.truth,
            ROAD_VEHICLE_LIMITS,
            pairs,
        )
    } else {
        if let Some(poses) = &options.poses {
            return Err(FramesError::Options(format!(
                "--poses {}: ground truth is read for KITTI sequences only",
                poses.display()
            )));
        }
        let defaults = EgomotionConfig::default();
        let raw = ImageDirectory::open(dir)?;
        let pairs = raw.len();
        let (left, right, stereo) =
            (dir.join(RAW_LEFT_INFO), dir.join(RAW_RIGHT_INFO), dir.join(RAW_STEREO_CALIBRATION));
        let calibrations: Vec<&str> = [
            (dir.join(CAMERA_FILE).exists(), CAMERA_FILE),
            (left.exists() || right.exists(), "left.yaml/right.yaml"),
            (stereo.exists(), RAW_STEREO_CALIBRATION),
        ]
        .into_iter()
        .filter_map(|(present, name)| present.then_some(name))
        .collect();
        if calibrations.len() > 1 {
            return Err(FramesError::Calibration(format!(
                "{}: holds {} ({CAMERA_FILE} describes rectified images; the others, raw images to rectify); keep \
                 the one that describes its images",
                dir.display(),
                calibrations.join(" and ")
            )));
        }
        let (camera, source): (StereoCamera, Box<dyn CameraSource>) = if stereo.exists() {
            let rectifier = ubf_perception::rectify::load_stereo(&stereo)?;
            (rectifier.camera(), Box::new(Rectified::new(raw, rectifier)))
        } else if left.exists() || right.exists() {
            let rectifier = ubf_perception::rectify::load_pair(&left, &right)?;
            (rectifier.camera(), Box::new(Rectified::new(raw, rectifier)))
        } else {
            (load_camera(dir)?, Box::new(raw))
        };
        (Layout::Recording, camera, source, None, (defaults.max_speed, defaults.max_turn_rate_deg), pairs)
    };
    let camera = match options.disparity_offset_px {
        None => camera,
        Some(offset) => {
            let camera = StereoCamera { disparity_offset_px: offset, ..camera };
            ubf_core::config::Check::check(&camera)
                .map_err(|e| FramesError::Options(format!("--disparity-offset {offset}: {e}")))?;
            camera
        }
    };
    let limits = [options.max_speed.unwrap_or(limits.0), options.max_turn_rate_deg.unwrap_or(limits.1)];
    let config = EgomotionConfig {
        max_speed: limits[0],
        max_turn_rate_deg: limits[1],
        odometry_gate: None,
        keyframe_range_m: options.keyframe_range_m.unwrap_or(EgomotionConfig::default().keyframe_range_m),
        disparity_offset: if options.keep_disparity_offset {
            DisparityOffsetEstimate::Report
        } else {
            DisparityOffsetEstimate::Correct
        },
        ..EgomotionConfig::default()
    };
    let index = dir.join(layout.index());
    let pipeline = StereoPipeline::new(camera, options.features);
    let mut tracker = Tracker::new(config, camera, Pose2::default(), 0);
    let (mut pipeline_ms, mut egomotion_ms, mut total_ms) = (Vec::new(), Vec::new(), Vec::new());
    let mut estimate = Vec::new();
    let mut landmarks = 0usize;
    let progress = crate::sweep::progress_bar(pairs as u64, "pairs");
    let mut landmark_log = match &options.landmarks {
        None => None,
        Some(path) => {
            let file = std::fs::File::create(path).map_err(FramesError::file(path))?;
            let mut log = std::io::BufWriter::new(file);
            writeln!(log, "{LANDMARKS_HEADER}").map_err(FramesError::file(path))?;
            Some((log, path))
        }
    };
    let mut number = 0;
    let (mut row_offsets, mut warnings, mut starving, mut starving_frames) = (Vec::new(), Vec::new(), None, 0);
    while let Some(pair) = source.next_pair()? {
        number += 1;
        let started = Instant::now();
        let (observed, pair_report) = pipeline.process_pair(&pair.left, &pair.right).map_err(|source| {
            FramesError::Pair { index: index.clone(), number, calibration: dir.join(layout.calibration()), source }
        })?;
        row_offsets.extend(pair_report.row_offset_px);
        let processed = Instant::now();
        landmarks += observed.len();
        if let Some((log, path)) = &mut landmark_log {
            // The points as egomotion takes them for this pair, so that the
            // file and the path agree: triangulated with the offset the
            // tracker corrects the landmarks by when it matches the pair (the
            // calibration's until the frames' reading has settled, and
            // throughout with --keep-disparity-offset).
            let applied = tracker.applied_disparity_offset();
            let used = StereoCamera { disparity_offset_px: camera.disparity_offset_px + applied, ..camera };
            for l in &observed {
                // A landmark the correction puts at or beyond infinity (its
                // disparity no longer positive) is left out, as egomotion
                // leaves it out.
                let point = if applied == 0.0 { Some(l.point_cam) } else { used.triangulate(&l.pixels) };
                let (p, Some([x, y, z])) = (&l.pixels, point) else { continue };
                writeln!(
                    log,
                    "{number},{:.4},{:.4},{:.4},{:.4},{x:.4},{y:.4},{z:.4},{:.4}",
                    p.u_left - 0.5,
                    p.u_right - 0.5,
                    p.v - 0.5,
                    p.disparity(),
                    used.disparity_offset_px
                )
                .map_err(FramesError::file(path))?;
            }
        }
        let frame = StereoFrame { number, time: pair.time, landmarks: observed, calibration: None, images: None };
        let odometry = tracker.state().pose.unwrap_or_default();
        let seen = frame.landmarks.len();
        tracker.update(&frame, &odometry);
        let done = Instant::now();
        if tracker.starving() {
            starving_frames += 1;
            let consistent = tracker.step_landmarks();
            let failed = usize::from(consistent.is_none());
            let stretch = starving.get_or_insert(Starving {
                frames: [number, number],
                fewest_landmarks: seen,
                fewest_consistent: consistent,
                failed: 0,
            });
            stretch.frames[1] = number;
            stretch.fewest_landmarks = stretch.fewest_landmarks.min(seen);
            stretch.fewest_consistent = match (stretch.fewest_consistent, consistent) {
                (Some(a), Some(b)) => Some(a.min(b)),
                (a, b) => a.or(b),
            };
            stretch.failed += failed;
        } else if let Some(stretch) = starving.take() {
            let warning = stretch.warning(config.trusted_landmarks);
            eprintln!("warning: {}", warning.message);
            warnings.push(warning);
        }
        estimate.push(tracker.state().pose.unwrap_or_default());
        pipeline_ms.push((processed - started).as_secs_f64() * 1e3);
        egomotion_ms.push((done - processed).as_secs_f64() * 1e3);
        total_ms.push((done - started).as_secs_f64() * 1e3);
        progress.inc(1);
    }
    progress.finish_and_clear();
    if number == 0 {
        return Err(FramesError::NoPairs(index));
    }
    if let Some((log, path)) = &mut landmark_log {
        log.flush().map_err(FramesError::file(path))?;
    }
    if let Some(stretch) = starving.take() {
        let warning = stretch.warning(config.trusted_landmarks);
        eprintln!("warning: {}", warning.message);
        warnings.push(warning);
    }
    let estimated = row_offsets.len();
    let row_offset_px = (estimated > 0).then(|| ubf_perception::median(&mut row_offsets));
    let confirmed = estimated >= 5;
    if let Some(offset) = row_offset_px.filter(|o| confirmed && o.abs() >= RECALIBRATE_ROW_OFFSET_PX) {
        let warning = ReplayWarning {
            frames: None,
            message: format!(
                "the right image sits {:.2} px {} the left (median of {estimated} pairs): the rig is out of line and \
                 needs recalibrating; the pipeline corrects it in whole rows meanwhile",
                offset.abs(),
                if offset > 0.0 { "below" } else { "above" }
            ),
        };
        eprintln!("warning: {}", warning.message);
        warnings.insert(0, warning);
    }
    let read = tracker.disparity_offset();
    let disparity_offset_steps = read.map_or(0, |r| r.readings);
    let disparity_offset_px = read.map(|r| camera.disparity_offset_px + r.px);
    if let Some(px) = disparity_offset_px.filter(|px| {
        disparity_offset_steps >= 20 && (px - camera.disparity_offset_px).abs() >= RECALIBRATE_DISPARITY_OFFSET_PX
    }) {
        let warning = ReplayWarning {
            frames: None,
            message: format!(
                "the frames put the rig's disparity offset at {px:+.2} px, the calibration at {:+.2} px (median of \
                 {disparity_offset_steps} steps): put `disparity_offset_px: {px:.2}` in {CAMERA_FILE} if other drives \
                 agree{}",
                camera.disparity_offset_px,
                if options.keep_disparity_offset { "" } else { "; the landmarks were corrected by it as it settled" }
            ),
        };
        eprintln!("warning: {}", warning.message);
        warnings.push(warning);
    }
    let covariance = tracker.pose_covariance();
    let pose = tracker.state().pose.unwrap_or_default();
    let total = ubf_perception::median(&mut total_ms);
    let report = PipelineReport {
        layout,
        frames: number as usize,
        landmarks_mean: landmarks as f64 / number as f64,
        pipeline_ms_median: ubf_perception::median(&mut pipeline_ms),
        egomotion_ms_median: ubf_perception::median(&mut egomotion_ms),
        total_ms_median: total,
        frames_per_s: 1e3 / total,
        failures: tracker.state().failures,
        final_pose: [pose.x, pose.y, pose.theta],
        limits,
        row_offset_px,
        disparity_offset_px,
        calibrated_disparity_offset_px: camera.disparity_offset_px,
        disparity_offset_steps,
        disparity_offset_corrected: tracker.applied_disparity_offset() != 0.0,
        starving_frames,
        pose_sigma_m: (covariance[(0, 0)] + covariance[(1, 1)]).sqrt(),
        warnings,
        accuracy: truth.as_deref().and_then(|truth| kitti::accuracy(&estimate, truth)),
    };
    Ok(Replay { report, estimate, truth })
}

/// The calibration in `dir`'s `camera.ron`, checked; the default camera if
/// there is none.
pub fn load_camera(dir: &Path) -> Result<StereoCamera, FramesError> {
    let path = dir.join(CAMERA_FILE);
    let bytes = match ubf_core::config::read_bounded(&path, ubf_core::config::MOST_SETTINGS_BYTES) {
        Ok(bytes) => bytes,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(StereoCamera::default()),
        Err(e) => return Err(FramesError::file(&path)(e)),
    };
    ubf_core::config::utf8_text(bytes)
        .and_then(|text| ubf_core::config::from_ron::<ubf_core::config::Checked<StereoCamera>>(&text))
        .map(|checked| checked.0)
        .map_err(|source| FramesError::CameraFile { path, source })
}

/// What `ubf pipeline` prints.
impl std::fmt::Display for PipelineReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(
            f,
            "{} stereo pairs ({}), {:.0} landmarks each on average",
            self.frames, self.layout, self.landmarks_mean
        )?;
        writeln!(f,
            "median per pair: features and stereo {:.2} ms, egomotion {:.2} ms, total {:.2} ms ({:.0} pairs/s on one core)",
            self.pipeline_ms_median, self.egomotion_ms_median, self.total_ms_median, self.frames_per_s
        )?;
        writeln!(
            f,
            "egomotion: {} failures; end pose ({:.2}, {:.2}) m, {:.1}°; limits {} m/s, {} °/s",
            self.failures,
            self.final_pose[0],
            self.final_pose[1],
            self.final_pose[2].to_degrees(),
            self.limits[0],
            self.limits[1]
        )?;
        if let Some(offset) = self.row_offset_px {
            writeln!(f, "right image {offset:+.2} px below the left; end pose σ {:.2} m", self.pose_sigma_m)?;
        }
        if let Some(offset) = self.disparity_offset_px {
            writeln!(
                f,
                "disparity offset by the frames {offset:+.2} px (calibration {:+.2}, {} steps; {})",
                self.calibrated_disparity_offset_px,
                self.disparity_offset_steps,
                if self.disparity_offset_corrected { "corrected" } else { "reported only" }
            )?;
        }
        for warning in &self.warnings {
            writeln!(f, "warning: {}", warning.message)?;
        }
        if let Some(a) = &self.accuracy {
            let lengths: Vec<String> = a.segment_lengths_m.iter().map(|l| format!("{l}")).collect();
            writeln!(f, "path {:.1} m; end point off by {:.2} % of it", a.path_m, a.endpoint_drift_pct)?;
            writeln!(
                f,
                "KITTI error over {} m segments: translation {:.2} %, rotation {:.4} °/m",
                lengths.join(", "),
                a.translation_error_pct,
                a.rotation_error_deg_per_m
            )?;
            writeln!(
                f,
                "per step (median): translation error {:.2} %, scale {:.3}, rotation {:.4} °/m",
                a.step_translation_error_pct_median, a.step_scale_median, a.step_rotation_error_deg_per_m_median
            )?;
        }
        Ok(())
    }
}
