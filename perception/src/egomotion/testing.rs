//! What the egomotion tests share: landmarks seen exactly from a pose,
//! and frames and runs made of them.

use super::config::{EgomotionConfig, EstimatorKind};
use super::tracker::Tracker;
use crate::stereo::StereoCamera;
use rand_chacha::ChaCha8Rng;
use ubf_core::{Descriptor, EgomotionState, LandmarkObservation, Pose2, StereoFrame};

/// Observations of `points` (world frame, metres) from `pose`, exact.
pub(super) fn frame(points: &[[f64; 3]], pose: Pose2, camera: &StereoCamera) -> Vec<LandmarkObservation> {
    points
        .iter()
        .enumerate()
        .filter_map(|(i, p)| {
            let (dx, dy) = (p[0] - pose.x, p[1] - pose.y);
            let (s, c) = pose.theta.sin_cos();
            let robot = [c * dx + s * dy, -s * dx + c * dy, p[2]];
            let cam = camera.mount.robot_to_cam(robot);
            let px = camera.project(cam)?;
            let mut bits = [0u64; 4];
            bits[i % 4] = 0x9e37_79b9_7f4a_7c15u64.rotate_left(i as u32 * 7);
            bits[(i + 1) % 4] = (i as u64).wrapping_mul(0xff51_afd7_ed55_8ccd);
            Some(LandmarkObservation {
                point_cam: cam,
                pixels: px,
                descriptor: Descriptor(bits),
                source_id: Some(i as u32),
            })
        })
        .collect()
}

/// A KITTI-like rig: 707 px focal length, 0.54 m baseline, 1226 × 370
/// px, 1.65 m up.
pub(super) fn kitti_rig() -> StereoCamera {
    StereoCamera {
        width_px: 1226,
        height_px: 370,
        focal_px: 707.0,
        baseline_m: 0.54,
        mount: ubf_core::CameraMount::ahead(0.0, 0.0, 1.65),
        ..StereoCamera::default()
    }
}

/// Twelve landmarks 6–22.5 m ahead, alternately 2.5 m left and right.
pub(super) fn landmarks() -> Vec<[f64; 3]> {
    (0..12).map(|i| [6.0 + i as f64 * 1.5, if i % 2 == 0 { 2.5 } else { -2.5 }, 0.5 + 0.1 * i as f64]).collect()
}

/// The state of a tracker with `estimator` after a frame of [`landmarks`]
/// from each of `poses`, half a second apart, odometry exact.
pub(super) fn run(estimator: EstimatorKind, poses: &[Pose2]) -> EgomotionState {
    let camera = StereoCamera::default();
    let config = EgomotionConfig { estimator, ..EgomotionConfig::default() };
    let mut tracker = Tracker::new(config, camera, poses[0], 1);
    for (n, pose) in poses.iter().enumerate() {
        let f = StereoFrame {
            number: n as u64 + 1,
            time: n as f64 * 0.5,
            landmarks: frame(&landmarks(), *pose, &camera),
            calibration: None,
            images: None,
        };
        tracker.update(&f, pose);
    }
    tracker.state()
}

/// `frame`, with every point moved by a fixed pseudo-random offset of
/// up to `size` m per axis: noise that is the same for two trackers.
pub(super) fn disturbed(mut observations: Vec<LandmarkObservation>, seed: u64, size: f64) -> Vec<LandmarkObservation> {
    for o in &mut observations {
        let h = (o.source_id.unwrap_or(0) as u64 + 1).wrapping_mul(0x9e37_79b9_7f4a_7c15) ^ seed;
        for (k, v) in o.point_cam.iter_mut().enumerate() {
            let bits = h.rotate_left(13 * k as u32 + 7) >> 11;
            *v += size * (bits as f64 / (1u64 << 53) as f64 - 0.5);
        }
    }
    observations
}

/// A standard normal draw (Box–Muller).
pub(super) fn standard_normal(rng: &mut ChaCha8Rng) -> f64 {
    use rand::Rng;
    let (u, v): (f64, f64) = (rng.random::<f64>().max(1e-12), rng.random());
    (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
}

/// A frame of `landmarks` without images or calibration.
pub(super) fn at(number: u64, time: f64, landmarks: Vec<LandmarkObservation>) -> StereoFrame {
    StereoFrame { number, time, landmarks, calibration: None, images: None }
}

/// Observations of `points` (world frame) from `pose` by a rig whose
/// disparities are `offset_px` short of what `camera`, its calibration,
/// assumes (the true depth is `f·B / (d + offset_px)`): each pixel is
/// projected exactly, moved by Gaussian noise of `sigma_px`, and
/// triangulated by the calibration. Landmarks outside the images, or
/// whose disparity the noise and offset leave under a pixel, are not seen.
pub(super) fn seen_with_offset(
    points: &[[f64; 3]],
    pose: Pose2,
    camera: &StereoCamera,
    offset_px: f64,
    sigma_px: f64,
    rng: &mut ChaCha8Rng,
) -> Vec<LandmarkObservation> {
    let rig = StereoCamera { disparity_offset_px: camera.disparity_offset_px + offset_px, ..*camera };
    let exact = frame(points, pose, &rig);
    exact
        .into_iter()
        .filter(|o| rig.in_images(&o.pixels))
        .filter_map(|mut o| {
            o.pixels.u_left += sigma_px * standard_normal(rng);
            o.pixels.u_right += sigma_px * standard_normal(rng);
            o.pixels.v += sigma_px * standard_normal(rng);
            if o.pixels.disparity() < 1.0 {
                return None;
            }
            o.point_cam = camera.triangulate(&o.pixels)?;
            Some(o)
        })
        .collect()
}
