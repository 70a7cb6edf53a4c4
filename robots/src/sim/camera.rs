//! The simulated stereo camera: landmarks projected into both images, kept
//! only where a real pair would match them, disturbed in pixel space, and
//! triangulated. Noise is never added to depths directly: the skewed,
//! growing depth error of real stereo comes out of the triangulation.

use super::descriptor::DescriptorCache;
use super::geometry::Segment;
use super::pan_tilt::PanTiltConfig;
use super::render::{RenderConfig, Renderer};
use super::world::{World, WorldLandmark};
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use serde::Deserialize;
use std::sync::Arc;
use ubf_core::config::{non_negative, positive, shown, unit_interval, Check};
use ubf_core::{Aim, CameraMount, LandmarkObservation, Pose2, StereoImages, StereoPixels};
use ubf_perception::features::StereoPipeline;
use ubf_perception::StereoCamera;

/// The simulated camera's settings, as written in a scenario file.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SimCameraConfig {
    /// The calibrated pair and its mounting.
    #[serde(default, deserialize_with = "ubf_core::config::checked")]
    pub stereo: StereoCamera,
    /// Frames per second. The thesis's cameras ran at 2 Hz (§3.3.2).
    #[serde(deserialize_with = "positive")]
    pub rate_hz: f64,
    /// Standard deviation of the Gaussian noise on every pixel coordinate.
    #[serde(deserialize_with = "non_negative")]
    pub pixel_noise_px: f64,
    /// Round pixel coordinates to whole pixels after the noise.
    #[serde(default)]
    pub quantize: bool,
    /// The share of matches that are wrong: their right-image column is
    /// replaced by a random one along the same row.
    #[serde(default, deserialize_with = "unit_interval")]
    pub outlier_share: f64,
    /// Smallest disparity a match can have, px.
    #[serde(deserialize_with = "non_negative")]
    pub min_disparity_px: f64,
    /// Nearest depth at which features are matched, m (the image bounds
    /// already impose the pair's minimum stereo distance, §4.4.10.1).
    #[serde(default, deserialize_with = "non_negative")]
    pub min_depth_m: f64,
    /// Farthest distance at which a feature is still detected, m.
    #[serde(deserialize_with = "positive")]
    pub max_range_m: f64,
    /// Largest angle between the two cameras' lines of sight at a feature
    /// for left and right descriptors still to match, ° (thesis §4.4.10.3:
    /// 30°, reached at 1.1 m with a 60 cm baseline).
    #[serde(deserialize_with = "positive")]
    pub max_stereo_viewpoint_deg: f64,
    /// Largest angle between the line of sight and a wall's normal at which a
    /// feature on the wall is still detected, °.
    #[serde(deserialize_with = "positive")]
    pub max_incidence_deg: f64,
    /// Bits of a descriptor flipped at random in every observation (image
    /// noise), out of 256.
    pub descriptor_noise_bits: u32,
    /// Render images and find the landmarks in them with the feature
    /// pipeline, instead of projecting the landmarks (the geometric camera
    /// model, the default). The settings above then do not apply; what the
    /// pipeline finds is what there is.
    #[serde(default)]
    pub images: Option<RenderConfig>,
    /// A pan-tilt unit under the pair; none (a fixed camera) by default.
    /// Each frame then looks where the unit truly points, and its
    /// calibration carries the angles the unit's encoders read.
    #[serde(default)]
    pub pan_tilt: Option<PanTiltConfig>,
}

impl SimCameraConfig {
    /// Why the camera could never see a landmark, or could not run, if so:
    /// its nearest matchable depth beyond its farthest (detection range, or
    /// the depth of the smallest disparity), pixel noise beyond 100 px,
    /// more frames a second than a simulation can take, or more flipped
    /// bits than a descriptor has.
    pub fn check(&self) -> Result<(), String> {
        let stereo_limit = if self.min_disparity_px > 0.0 {
            self.stereo.focal_px * self.stereo.baseline_m / self.min_disparity_px
        } else {
            f64::INFINITY
        };
        let farthest = self.max_range_m.min(stereo_limit);
        if self.images.is_none() && self.min_depth_m >= farthest {
            return Err(format!(
                "camera: min_depth_m {} is beyond the farthest depth it can match, {farthest:.2} m \
                 (max_range_m {}, or the depth of a {} px disparity); it would see nothing",
                self.min_depth_m, self.max_range_m, self.min_disparity_px
            ));
        }
        if self.pixel_noise_px > 100.0 {
            return Err(format!("camera: pixel_noise_px {}: at most 100 px", shown(self.pixel_noise_px)));
        }
        if self.rate_hz > 1000.0 {
            return Err(format!("camera: rate_hz {}: at most 1000 frames a second", shown(self.rate_hz)));
        }
        let held_tilt = self.pan_tilt.map_or(0.0, |unit| unit.tilt_deg);
        if let Some(unit) = &self.pan_tilt {
            unit.check()?;
        }
        if self.images.is_some() && (held_tilt != 0.0 || self.stereo.mount.tilt_deg != 0.0) {
            return Err("camera: the renderer draws level views only; a tilted camera needs the geometric model \
                        (no `images`)"
                .into());
        }
        if self.descriptor_noise_bits > 256 {
            return Err(format!("camera: descriptor_noise_bits {}: a descriptor has 256", self.descriptor_noise_bits));
        }
        Ok(())
    }
}

impl Default for SimCameraConfig {
    fn default() -> Self {
        SimCameraConfig {
            stereo: StereoCamera::default(),
            rate_hz: 2.0,
            pixel_noise_px: 0.2,
            quantize: false,
            outlier_share: 0.0,
            min_disparity_px: 1.0,
            min_depth_m: 0.0,
            max_range_m: 80.0,
            max_stereo_viewpoint_deg: 30.0,
            max_incidence_deg: 75.0,
            descriptor_noise_bits: 4,
            images: None,
            pan_tilt: None,
        }
    }
}

/// The camera on the simulated robot.
#[derive(Clone, Debug)]
pub struct SimCamera {
    config: SimCameraConfig,
    next_frame: f64,
    frames: u64,
    /// With rendered images: the renderer (built at the first frame, from
    /// the world) and the pipeline, and the last pair.
    rendered: Option<(Renderer, StereoPipeline)>,
    last_images: Option<Arc<StereoImages>>,
    /// The threshold angles of the landmarks seen so far.
    descriptors: DescriptorCache,
}

/// The angle between two directions on the floor, signed, radians.
fn signed_angle(from: (f64, f64), to: (f64, f64)) -> f64 {
    (from.0 * to.1 - from.1 * to.0).atan2(from.0 * to.0 + from.1 * to.1)
}

impl SimCamera {
    /// A camera with these settings; its first frame is at time 0.
    pub fn new(config: SimCameraConfig) -> Self {
        SimCamera {
            config,
            next_frame: 0.0,
            frames: 0,
            rendered: None,
            last_images: None,
            descriptors: DescriptorCache::default(),
        }
    }

    /// The settings.
    pub fn config(&self) -> &SimCameraConfig {
        &self.config
    }

    /// How many frames it has taken.
    pub fn frames(&self) -> u64 {
        self.frames
    }

    /// If a frame is due at `time`, takes it from the true `pose` into `out`
    /// and returns its number. `aim` is where a pan-tilt unit truly points
    /// the pair (`None` for a fixed camera).
    pub fn capture(
        &mut self,
        time: f64,
        pose: &Pose2,
        aim: Option<Aim>,
        world: &World,
        rng: &mut ChaCha8Rng,
        out: &mut Vec<LandmarkObservation>,
    ) -> Option<u64> {
        // A hair of slack so that 0.5 s frames land on 0.1 s ticks.
        if time + 1e-9 < self.next_frame {
            return None;
        }
        self.next_frame += 1.0 / self.config.rate_hz;
        if self.next_frame <= time {
            self.next_frame = time + 1.0 / self.config.rate_hz;
        }
        self.frames += 1;
        out.clear();
        // Where the pair truly is: the unit's angles replace the mount's.
        let mount = match aim {
            Some(a) => self.config.stereo.mount.aimed(a.pan, a.tilt),
            None => self.config.stereo.mount,
        };
        if let Some(render) = self.config.images {
            let stereo = self.config.stereo;
            let (renderer, pipeline) = self.rendered.get_or_insert_with(|| {
                let seed = rng.random();
                (Renderer::new(world, stereo, render, seed), StereoPipeline::new(stereo, render.features))
            });
            let (left, right) = renderer.render_from(pose, &mount, self.frames);
            // The renderer makes images of the calibrated size, which is all
            // the pipeline can refuse.
            out.extend(pipeline.process(&left, &right).unwrap_or_default());
            let (width, height) = left.dimensions();
            let images = StereoImages { width, height, left: left.into_raw(), right: right.into_raw() };
            self.last_images = Some(Arc::new(images));
            return Some(self.frames);
        }
        for landmark in &world.landmarks {
            if let Some(observation) = self.observe(landmark, time, pose, &mount, world, rng) {
                out.push(observation);
            }
        }
        Some(self.frames)
    }

    /// The last pair of rendered images, if the camera renders them.
    pub fn last_images(&self) -> Option<&Arc<StereoImages>> {
        self.last_images.as_ref()
    }

    fn observe(
        &mut self,
        landmark: &WorldLandmark,
        time: f64,
        pose: &Pose2,
        mount: &CameraMount,
        world: &World,
        rng: &mut ChaCha8Rng,
    ) -> Option<LandmarkObservation> {
        let c = &self.config;
        let stereo = &c.stereo;
        let (p_world, normal) = world.landmark_at(landmark, time);
        let (cam_x, cam_y) = pose.transform_point(mount.forward, mount.left);
        let to_landmark = (p_world[0] - cam_x, p_world[1] - cam_y);
        let range = to_landmark.0.hypot(to_landmark.1);
        if range > c.max_range_m || range < 1e-6 {
            return None;
        }
        // Seen from the back of its wall, or too obliquely, a feature is not
        // detected.
        let view = match normal {
            Some(n) => {
                let angle = signed_angle(n, (-to_landmark.0 / range, -to_landmark.1 / range));
                if angle.abs() > c.max_incidence_deg.to_radians() {
                    return None;
                }
                angle
            }
            None => 0.0,
        };
        // Left and right descriptors stop matching when the two lines of
        // sight differ too much.
        if 2.0 * (stereo.baseline_m / 2.0).atan2(range) > c.max_stereo_viewpoint_deg.to_radians() {
            return None;
        }
        if occluded((cam_x, cam_y), (p_world[0], p_world[1]), &world.segments) {
            return None;
        }
        let dx = p_world[0] - pose.x;
        let dy = p_world[1] - pose.y;
        let (s, co) = pose.theta.sin_cos();
        let p_robot = [co * dx + s * dy, -s * dx + co * dy, p_world[2]];
        let p_cam = mount.robot_to_cam(p_robot);
        let exact = stereo.project(p_cam)?;
        if !stereo.in_images(&exact) || p_cam[1] < c.min_depth_m {
            return None;
        }
        let pixels = self.disturb(exact, rng);
        if pixels.disparity() < c.min_disparity_px || !stereo.in_images(&pixels) {
            return None;
        }
        let point_cam = stereo.triangulate(&pixels)?;
        let mut descriptor = self.descriptors.descriptor(landmark, view);
        for _ in 0..c.descriptor_noise_bits {
            let bit = rng.random_range(0..256u32);
            descriptor.0[(bit / 64) as usize] ^= 1 << (bit % 64);
        }
        Some(LandmarkObservation { point_cam, pixels, descriptor, source_id: Some(landmark.id) })
    }

    fn disturb(&self, exact: StereoPixels, rng: &mut ChaCha8Rng) -> StereoPixels {
        let c = &self.config;
        let mut noise = || -> f64 { StandardNormal.sample(&mut *rng) };
        let mut px = StereoPixels {
            u_left: exact.u_left + c.pixel_noise_px * noise(),
            u_right: exact.u_right + c.pixel_noise_px * noise(),
            v: exact.v + c.pixel_noise_px * noise(),
        };
        if c.outlier_share > 0.0 && rng.random::<f64>() < c.outlier_share {
            // A wrong match: some other feature on the same row of the right
            // image, left of the left column (disparity stays positive).
            px.u_right = rng.random_range(0.0..px.u_left.max(1.0));
        }
        if c.quantize {
            px = StereoPixels { u_left: px.u_left.round(), u_right: px.u_right.round(), v: px.v.round() };
        }
        px
    }
}

/// Whether a wall or box side stands between `from` and just short of `to`.
fn occluded(from: (f64, f64), to: (f64, f64), segments: &[Segment]) -> bool {
    // Stop 1 cm short so that the wall a landmark sits on does not hide it.
    let len = (to.0 - from.0).hypot(to.1 - from.1);
    let k = ((len - 0.01) / len).max(0.0);
    let end = (from.0 + (to.0 - from.0) * k, from.1 + (to.1 - from.1) * k);
    segments.iter().any(|s| s.crosses(from, end))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::world::{Anchor, WorldConfig};
    use rand::SeedableRng;
    use ubf_core::Descriptor;

    /// x, y, z and the surface normal of a test landmark.
    type Spot = (f64, f64, f64, Option<(f64, f64)>);

    fn world_with(landmarks: Vec<Spot>) -> World {
        let mut world = World::build(&WorldConfig::default(), &mut ChaCha8Rng::seed_from_u64(0));
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        for (i, (x, y, z, normal)) in landmarks.into_iter().enumerate() {
            world.landmarks.push(WorldLandmark {
                id: i as u32,
                anchor: Anchor::Fixed { position: [x, y, z], normal },
                descriptor: Descriptor([rng.random(), rng.random(), rng.random(), rng.random()]),
            });
        }
        world
    }

    fn frame(config: SimCameraConfig, world: &World, pose: Pose2, seed: u64) -> Vec<LandmarkObservation> {
        let mut out = Vec::new();
        SimCamera::new(config)
            .capture(0.0, &pose, None, world, &mut ChaCha8Rng::seed_from_u64(seed), &mut out)
            .unwrap();
        out
    }

    #[test]
    fn noiseless_observation_triangulates_to_the_truth() {
        let world = world_with(vec![(10.0, 1.0, 1.5, None)]);
        let config = SimCameraConfig { pixel_noise_px: 0.0, descriptor_noise_bits: 0, ..SimCameraConfig::default() };
        let obs = frame(config, &world, Pose2::default(), 0);
        assert_eq!(obs.len(), 1);
        // 10 m ahead, 1 m left, 0.5 m above the 1 m high camera.
        let expected = [-1.0, 10.0, 0.5];
        for (a, b) in obs[0].point_cam.iter().zip(expected) {
            assert!((a - b).abs() < 1e-9, "{:?}", obs[0].point_cam);
        }
        assert_eq!(obs[0].source_id, Some(0));
    }

    #[test]
    fn visibility_rules() {
        let world = world_with(vec![
            (10.0, 0.0, 1.0, None),             // 0: visible
            (-5.0, 0.0, 1.0, None),             // 1: behind
            (0.9, 0.0, 1.0, None),              // 2: too near: stereo viewpoint over 30°
            (10.0, 0.0, 1.0, Some((1.0, 0.0))), // 3: on the back of a wall
            (5.0, 2.0, 1.0, Some((0.0, -1.0))), // 4: on a side wall, 68° off its normal
            (8.0, 0.5, 1.0, Some((0.0, -1.0))), // 5: grazing, 86° from the normal
            (200.0, 0.0, 1.0, None),            // 6: beyond detection range
        ]);
        let config = SimCameraConfig { pixel_noise_px: 0.0, ..SimCameraConfig::default() };
        let seen: Vec<u32> = frame(config, &world, Pose2::default(), 0).iter().filter_map(|o| o.source_id).collect();
        assert_eq!(seen, [0, 4]);
    }

    #[test]
    fn a_tilted_camera_needs_the_geometric_model() {
        let unit = PanTiltConfig { tilt_deg: 10.0, ..PanTiltConfig::default() };
        let rendered = SimCameraConfig {
            images: Some(RenderConfig::default()),
            pan_tilt: Some(unit),
            ..SimCameraConfig::default()
        };
        assert!(rendered.check().unwrap_err().contains("level views only"));
        assert_eq!(SimCameraConfig { images: None, ..rendered.clone() }.check(), Ok(()));
        let panned = PanTiltConfig { tilt_deg: 0.0, ..unit };
        assert_eq!(SimCameraConfig { pan_tilt: Some(panned), ..rendered }.check(), Ok(()));
    }

    #[test]
    fn walls_occlude() {
        let mut world = world_with(vec![(10.0, 0.0, 1.0, None)]);
        world.segments.push(Segment::new((5.0, -1.0), (5.0, 1.0)));
        assert!(frame(SimCameraConfig::default(), &world, Pose2::default(), 0).is_empty());
    }

    #[test]
    fn depth_error_grows_with_the_square_of_depth() {
        // Pixel noise alone gives a depth σ near the first-order prediction
        // Z²·√2·σ_px/(f·T) at 10 m and at 30 m.
        let config = SimCameraConfig::default();
        let cam = config.stereo;
        for depth in [10.0, 30.0] {
            let world = world_with(vec![(depth, 0.0, 1.0, None)]);
            let errors: Vec<f64> = (0..2000)
                .map(|seed| frame(config.clone(), &world, Pose2::default(), seed)[0].point_cam[1] - depth)
                .collect();
            let mean = errors.iter().sum::<f64>() / errors.len() as f64;
            let sd = (errors.iter().map(|e| (e - mean).powi(2)).sum::<f64>() / (errors.len() - 1) as f64).sqrt();
            let predicted = cam.depth_sigma(depth, config.pixel_noise_px);
            assert!((sd / predicted - 1.0).abs() < 0.1, "at {depth} m: σ {sd} vs predicted {predicted}");
        }
    }
}
