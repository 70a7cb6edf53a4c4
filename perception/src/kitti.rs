//! KITTI odometry sequences as the benchmark ships them, and its accuracy
//! measures.
//!
//! A sequence directory holds `image_0/` (left) and `image_1/` (right)
//! rectified grey PNGs named `000000.png`, `000001.png`, …; `calib.txt`
//! with the projection matrices `P0:` and `P1:` (12 numbers each, row
//! major); `times.txt`, one time in seconds per frame; and, for the
//! training sequences, ground-truth poses (`poses.txt` here, or in the
//! benchmark's `poses/NN.txt`): 12 numbers per frame, the left camera's
//! pose in the first frame's left-camera coordinates (x right, y down, z
//! ahead).
//!
//! The estimator here is planar, so poses are compared in the ground plane
//! (forward = KITTI's z, left = −x, heading about the vertical).

use crate::source::{ImageDirectory, SourceError};
use crate::stereo::{CameraMount, PrincipalPoint, StereoCamera};
use std::path::{Path, PathBuf};
use ubf_core::Pose2;

/// The camera height above the road of KITTI's recording car, m (Geiger et
/// al., IJRR 2013, figure 3).
pub const CAMERA_HEIGHT_M: f64 = 1.65;

/// KITTI's segment lengths for the translational and rotational error, m.
pub const SEGMENT_LENGTHS_M: [f64; 8] = [100.0, 200.0, 300.0, 400.0, 500.0, 600.0, 700.0, 800.0];

/// Whether `dir` looks like a KITTI odometry sequence (`calib.txt` and
/// `image_0/`).
pub fn is_sequence(dir: &Path) -> bool {
    dir.join("calib.txt").is_file() && dir.join("image_0").is_dir()
}

/// An opened sequence.
#[derive(Debug)]
pub struct Sequence {
    /// The rectified pair from `calib.txt`, mounted so that the robot frame
    /// is the left camera's, projected to the road.
    pub camera: StereoCamera,
    /// The pairs, in order.
    pub pairs: ImageDirectory,
    /// The ground truth in the ground plane, one pose per pair, if given.
    pub truth: Option<Vec<Pose2>>,
}

/// Opens the sequence in `dir`, with ground truth from `poses` if given,
/// else from `dir/poses.txt` if it exists.
pub fn open(dir: &Path, poses: Option<&Path>) -> Result<Sequence, SourceError> {
    let camera = read_calibration(&dir.join("calib.txt"))?;
    let times_path = dir.join("times.txt");
    let times = read_numbers(&times_path, 1)?;
    let mut pairs = ImageDirectory::empty(dir, &times_path);
    for (i, time) in times.iter().enumerate() {
        let (left, right) = (format!("image_0/{i:06}.png"), format!("image_1/{i:06}.png"));
        pairs.push(time[0], i + 1, &left, &right).map_err(|message| index_error(&times_path, i + 1, message))?;
    }
    let default_poses = dir.join("poses.txt");
    let poses = poses.map(Path::to_owned).or_else(|| default_poses.is_file().then_some(default_poses));
    let truth = match poses {
        None => None,
        Some(path) => {
            let rows = read_numbers(&path, 12)?;
            if rows.len() != times.len() {
                return Err(index_error(
                    &path,
                    rows.len() + 1,
                    format!("{} poses for {} frames in times.txt", rows.len(), times.len()),
                ));
            }
            Some(rows.iter().map(|m| ground_plane(m)).collect())
        }
    };
    Ok(Sequence { camera, pairs, truth })
}

/// A sequence's text file (its times, poses or calibration), within the
/// bound of any settings file: the longest KITTI sequence's poses are
/// under a megabyte.
fn read_text(path: &Path) -> std::io::Result<String> {
    ubf_core::config::read_text_bounded(path, ubf_core::config::MOST_SETTINGS_BYTES)
}

fn index_error(path: &Path, line: usize, message: String) -> SourceError {
    SourceError::Index { path: path.to_owned(), line, message }
}

/// Lines of `width` numbers (blank lines skipped), with the line of any
/// that is not.
fn read_numbers(path: &Path, width: usize) -> Result<Vec<Vec<f64>>, SourceError> {
    let text = read_text(path).map_err(|source| SourceError::Io { path: path.to_owned(), source })?;
    let mut rows = Vec::new();
    for (i, line) in text.lines().enumerate().filter(|(_, l)| !l.trim().is_empty()) {
        let row: Vec<f64> = line
            .split_whitespace()
            .map(|w| w.parse::<f64>().ok().filter(|v| v.is_finite()))
            .collect::<Option<_>>()
            .filter(|row: &Vec<f64>| row.len() == width)
            .ok_or_else(|| index_error(path, i + 1, format!("expected {width} finite numbers")))?;
        rows.push(row);
    }
    Ok(rows)
}

/// The rectified pair `calib.txt` describes: focal length and principal
/// point from `P0`, the baseline from `P1`'s fourth column (`−f·b`), and
/// the image size from the first left image.
fn read_calibration(path: &Path) -> Result<StereoCamera, SourceError> {
    let text = read_text(path).map_err(|source| SourceError::Io { path: path.to_owned(), source })?;
    let matrix = |name: &str| -> Result<[f64; 12], SourceError> {
        let (i, line) = text
            .lines()
            .enumerate()
            .find(|(_, l)| l.starts_with(&format!("{name}:")))
            .ok_or_else(|| index_error(path, 1, format!("no `{name}:` line")))?;
        let numbers: Vec<f64> = line[name.len() + 1..].split_whitespace().filter_map(|w| w.parse().ok()).collect();
        numbers
            .try_into()
            .ok()
            .filter(|m: &[f64; 12]| m.iter().all(|v| v.is_finite()))
            .ok_or_else(|| index_error(path, i + 1, format!("`{name}:` needs 12 finite numbers")))
    };
    let (p0, p1) = (matrix("P0")?, matrix("P1")?);
    let focal = p0[0];
    let baseline = -p1[3] / p1[0];
    if !(focal > 0.0 && baseline > 0.0 && (p1[0] - focal).abs() < 1e-6 * focal) {
        return Err(index_error(
            path,
            1,
            format!("P0 and P1 do not describe a rectified pair: f = {focal}, {}; baseline {baseline} m", p1[0]),
        ));
    }
    let first = path.with_file_name("image_0").join("000000.png");
    let (width, height) = crate::source::open_image(&first)?
        .into_dimensions()
        .map_err(|e| SourceError::Image { path: first.clone(), message: e.to_string() })?;
    let camera = StereoCamera {
        width_px: width,
        height_px: height,
        focal_px: focal,
        baseline_m: baseline,
        // The midpoint of the pair sits half a baseline right of the left
        // camera, which is the robot frame's origin.
        mount: CameraMount::ahead(0.0, -baseline / 2.0, CAMERA_HEIGHT_M),
        principal_point: Some(PrincipalPoint { x: p0[2], y: p0[6] }),
        disparity_offset_px: p1[2] - p0[2],
    };
    ubf_core::config::Check::check(&camera).map_err(|message| index_error(path, 1, message))?;
    Ok(camera)
}

/// A KITTI pose (3 × 4, row major, camera axes x right, y down, z ahead) in
/// the ground plane: forward, left and the heading of the camera's axis.
pub fn ground_plane(m: &[f64]) -> Pose2 {
    Pose2::new(m[11], -m[3], (-m[2]).atan2(m[10]))
}

/// How far an estimated trajectory is from the truth, KITTI's way and
/// frame by frame.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Accuracy {
    /// Length of the true path, m.
    pub path_m: f64,
    /// End-point error over the path length, %.
    pub endpoint_drift_pct: f64,
    /// KITTI's translational error: over every segment of each length in
    /// `segment_lengths_m` (starts every 10 frames), the end's position
    /// error relative to the segment's start over its length, averaged, %.
    pub translation_error_pct: f64,
    /// KITTI's rotational error over the same segments, °/m.
    pub rotation_error_deg_per_m: f64,
    /// The segment lengths used: KITTI's 100–800 m that fit in the path, or
    /// for a path under 100 m the longest whole 10 m that fits.
    pub segment_lengths_m: Vec<f64>,
    /// Per frame step: median of |estimated − true step| / |true step|, %.
    pub step_translation_error_pct_median: f64,
    /// Per frame step: median of the estimated step's length over the true
    /// one (1 = no scale error).
    pub step_scale_median: f64,
    /// Per frame step: median heading error over the step's length, °/m.
    pub step_rotation_error_deg_per_m_median: f64,
}

/// Compares `estimate` with `truth`, pose by pose (both from the first
/// frame, in the ground plane). `None` for fewer than two poses or a path
/// that does not move.
pub fn accuracy(estimate: &[Pose2], truth: &[Pose2]) -> Option<Accuracy> {
    let n = estimate.len().min(truth.len());
    if n < 2 {
        return None;
    }
    let mut along = vec![0.0; n];
    for i in 1..n {
        along[i] = along[i - 1] + truth[i].distance_to(truth[i - 1].x, truth[i - 1].y);
    }
    let path_m = along[n - 1];
    if path_m <= 0.0 {
        return None;
    }
    let end = estimate[n - 1].distance_to(truth[n - 1].x, truth[n - 1].y);
    let mut lengths: Vec<f64> = SEGMENT_LENGTHS_M.iter().copied().filter(|&l| l <= path_m).collect();
    if lengths.is_empty() && path_m >= 10.0 {
        lengths.push((path_m / 10.0).floor() * 10.0);
    }
    let (mut translation, mut rotation) = (Vec::new(), Vec::new());
    for first in (0..n).step_by(10) {
        for &length in &lengths {
            let Some(last) = (first..n).find(|&j| along[j] >= along[first] + length) else { continue };
            let true_motion = truth[last].relative_to(&truth[first]);
            let estimated = estimate[last].relative_to(&estimate[first]);
            let error = true_motion.relative_to(&estimated);
            translation.push(error.x.hypot(error.y) / length);
            rotation.push(error.theta.abs().to_degrees() / length);
        }
    }
    let mean = |v: &[f64]| if v.is_empty() { f64::NAN } else { v.iter().sum::<f64>() / v.len() as f64 };
    let (mut step_translation, mut step_scale, mut step_rotation) = (Vec::new(), Vec::new(), Vec::new());
    for i in 1..n {
        let true_step = truth[i].relative_to(&truth[i - 1]);
        let step = estimate[i].relative_to(&estimate[i - 1]);
        let length = true_step.x.hypot(true_step.y);
        if length < 1e-3 {
            continue;
        }
        step_translation.push((step.x - true_step.x).hypot(step.y - true_step.y) / length * 100.0);
        step_scale.push(step.x.hypot(step.y) / length);
        step_rotation.push(ubf_core::wrap_angle(step.theta - true_step.theta).abs().to_degrees() / length);
    }
    Some(Accuracy {
        path_m,
        endpoint_drift_pct: end / path_m * 100.0,
        translation_error_pct: mean(&translation) * 100.0,
        rotation_error_deg_per_m: mean(&rotation),
        segment_lengths_m: lengths,
        step_translation_error_pct_median: crate::median(&mut step_translation),
        step_scale_median: crate::median(&mut step_scale),
        step_rotation_error_deg_per_m_median: crate::median(&mut step_rotation),
    })
}

/// Where the shared sample of KITTI 06 (frames 0–50) is: `UBF_DATA` or
/// `../shared/data` beside the checkout, if it holds one.
pub fn shared_sample(manifest_dir: &Path) -> Option<PathBuf> {
    let base = std::env::var_os("UBF_DATA").map(PathBuf::from).unwrap_or_else(|| {
        manifest_dir.ancestors().map(|a| a.join("../shared/data")).find(|p| p.is_dir()).unwrap_or_default()
    });
    let dir = base.join("kitti-06-0-50");
    is_sequence(&dir).then_some(dir)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_straight_drive_seen_exactly_has_no_error_and_a_scaled_one_has_its_scale() {
        let truth: Vec<Pose2> = (0..150).map(|i| Pose2::new(f64::from(i), 0.0, 0.0)).collect();
        let exact = accuracy(&truth, &truth).unwrap();
        assert_eq!(exact.segment_lengths_m, vec![100.0]);
        assert!(exact.translation_error_pct.abs() < 1e-9 && exact.endpoint_drift_pct.abs() < 1e-9);
        let long: Vec<Pose2> = truth.iter().map(|p| Pose2::new(p.x * 1.02, 0.0, 0.0)).collect();
        let scaled = accuracy(&long, &truth).unwrap();
        assert!((scaled.translation_error_pct - 2.0).abs() < 1e-6, "{scaled:?}");
        assert!((scaled.step_scale_median - 1.02).abs() < 1e-9);
        assert!((scaled.endpoint_drift_pct - 2.0).abs() < 1e-6);
    }

    #[test]
    fn a_short_path_uses_the_longest_whole_ten_metres() {
        let truth: Vec<Pose2> = (0..60).map(|i| Pose2::new(f64::from(i), 0.0, 0.0)).collect();
        assert_eq!(accuracy(&truth, &truth).unwrap().segment_lengths_m, vec![50.0]);
    }

    #[test]
    fn kitti_poses_map_to_the_ground_plane() {
        // 2 m ahead and 1 m right, turned 10° to the left (about −y, the
        // camera's up being −y).
        let (s, c) = 10f64.to_radians().sin_cos();
        let m = [c, 0.0, -s, 1.0, 0.0, 1.0, 0.0, 0.0, s, 0.0, c, 2.0];
        let p = ground_plane(&m);
        assert!((p.x - 2.0).abs() < 1e-12 && (p.y + 1.0).abs() < 1e-12);
        assert!((p.theta.to_degrees() - 10.0).abs() < 1e-9, "{p:?}");
    }

    #[test]
    fn the_shared_sample_opens_with_its_calibration() {
        let Some(dir) = shared_sample(Path::new(env!("CARGO_MANIFEST_DIR"))) else {
            eprintln!("SKIPPED: no KITTI sample (set UBF_DATA, or put it at ../shared/data)");
            return;
        };
        let sequence = open(&dir, None).unwrap();
        assert_eq!((sequence.camera.width_px, sequence.camera.height_px), (1226, 370));
        assert!((sequence.camera.baseline_m - 0.537).abs() < 1e-3);
        assert_eq!(sequence.pairs.len(), 51);
        assert_eq!(sequence.truth.unwrap().len(), 51);
    }
}
