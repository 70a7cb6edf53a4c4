//! Rendered stereo images of the simulated world: what the cameras would
//! see, for the feature pipeline to find landmarks in.
//!
//! Walls are vertical, so a column of the image sees one wall point at one
//! depth: each column casts one ray on the floor plane, and its rows are
//! wall, floor or ceiling by their elevation. Surfaces carry smooth,
//! low-contrast shading (real paint and lighting, no corners a detector
//! would take for features); featureless stretches are perfectly uniform;
//! each wall landmark is a poster of black and white cells, a pattern of
//! its own, centred where the landmark is. People are not drawn. Pixel
//! noise comes from a hash of the seed, the frame and the pixel, so the
//! same seed gives the same images.

use super::geometry::Segment;
use super::hash::splitmix as mix;
use super::world::{Anchor, Side, World};
use image::GrayImage;
use serde::Deserialize;
use ubf_core::config::{non_negative, positive};
use ubf_core::{CameraMount, Pose2};
use ubf_perception::features::FeatureConfig;
use ubf_perception::source::{CameraSource, SourceError, StereoPair};
use ubf_perception::StereoCamera;

/// Rendering settings, as written in a scenario file.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RenderConfig {
    /// Height of the walls and the ceiling, m.
    #[serde(deserialize_with = "positive")]
    pub wall_height_m: f64,
    /// Standard deviation of the pixel noise, grey levels.
    #[serde(deserialize_with = "non_negative")]
    pub noise: f64,
    /// Side of a landmark's poster, m.
    #[serde(deserialize_with = "positive")]
    pub poster_m: f64,
    /// The feature pipeline's settings.
    #[serde(default, deserialize_with = "ubf_core::config::checked")]
    pub features: FeatureConfig,
}

impl Default for RenderConfig {
    fn default() -> Self {
        RenderConfig { wall_height_m: 2.5, noise: 2.0, poster_m: 0.42, features: FeatureConfig::default() }
    }
}

/// Cells across a poster: a black ring round 5 × 5 cells of the landmark's
/// own pattern.
const POSTER_CELLS: usize = 7;

/// A landmark's poster on a wall.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Poster {
    /// Centre along the wall from its first end, m.
    along: f64,
    /// Centre height, m.
    height: f64,
    /// The inner cells, a bit each, row by row from the top.
    pattern: u32,
}

/// One wall as the renderer needs it.
#[derive(Clone, Debug, PartialEq)]
struct Wall {
    segment: Segment,
    length: f64,
    /// Stretches along the wall (m from its first end) with nothing on them.
    featureless: Vec<(f64, f64)>,
    posters: Vec<Poster>,
}

/// A uniform number in [0, 1) from a hash.
fn unit(h: u64) -> f64 {
    (h >> 11) as f64 / (1u64 << 53) as f64
}

/// Smooth value noise in [−1, 1]: random values on a lattice `cell` apart,
/// blended with a smoothstep, so it has no corners.
fn value_noise(surface: u64, a: f64, b: f64, cell: f64) -> f64 {
    let (fa, fb) = (a / cell, b / cell);
    let (ia, ib) = (fa.floor(), fb.floor());
    let (ta, tb) = (fa - ia, fb - ib);
    let smooth = |t: f64| t * t * (3.0 - 2.0 * t);
    let (sa, sb) = (smooth(ta), smooth(tb));
    let at = |da: f64, db: f64| {
        let key = ((ia + da) as i64 as u64).wrapping_mul(0x1f1f_1f1f) ^ ((ib + db) as i64 as u64) << 32 ^ surface;
        2.0 * unit(mix(key)) - 1.0
    };
    let low = at(0.0, 0.0) * (1.0 - sa) + at(1.0, 0.0) * sa;
    let high = at(0.0, 1.0) * (1.0 - sa) + at(1.0, 1.0) * sa;
    low * (1.0 - sb) + high * sb
}

/// The renderer for one world.
#[derive(Clone, Debug)]
pub struct Renderer {
    camera: StereoCamera,
    config: RenderConfig,
    walls: Vec<Wall>,
    seed: u64,
}

/// The grey of a black and a white poster cell.
const INK: f64 = 25.0;
const PAPER: f64 = 235.0;

impl Renderer {
    /// A renderer of `world` as `camera` sees it, its noise drawn from
    /// `seed`.
    pub fn new(world: &World, camera: StereoCamera, config: RenderConfig, seed: u64) -> Self {
        let mut walls: Vec<Wall> = world
            .segments
            .iter()
            .map(|&segment| {
                let length = (segment.b.0 - segment.a.0).hypot(segment.b.1 - segment.a.1);
                Wall { segment, length, featureless: Vec::new(), posters: Vec::new() }
            })
            .collect();
        // Featureless stretches of the corridor's side walls.
        if let Some(c) = &world.corridor {
            for f in &world.featureless {
                let y = match f.side {
                    Side::Left => c.width / 2.0,
                    Side::Right => -c.width / 2.0,
                };
                for wall in &mut walls {
                    let (a, b) = (wall.segment.a, wall.segment.b);
                    if (a.1 - y).abs() < 1e-9 && (b.1 - y).abs() < 1e-9 {
                        // Along-wall coordinates of the stretch's two ends.
                        let along = |x: f64| (x - a.0).abs();
                        let (s0, s1) = (along(f.from), along(f.to));
                        wall.featureless.push((s0.min(s1), s0.max(s1)));
                    }
                }
            }
        }
        // Each wall landmark's poster goes on the wall it sits on.
        for landmark in &world.landmarks {
            let Anchor::Fixed { position, normal: Some(_) } = landmark.anchor else { continue };
            let p = (position[0], position[1]);
            let on = walls.iter_mut().find(|w| w.segment.distance_to(p) < 0.02);
            if let Some(wall) = on {
                let a = wall.segment.a;
                let along = (p.0 - a.0).hypot(p.1 - a.1);
                let pattern = (landmark.descriptor.0[0] & 0x1ff_ffff) as u32;
                wall.posters.push(Poster { along, height: position[2], pattern });
            }
        }
        Renderer { camera, config, walls, seed }
    }

    /// The camera the images are for.
    pub fn camera(&self) -> &StereoCamera {
        &self.camera
    }

    /// The left and right images from a robot at `pose`; `frame` varies the
    /// noise from one frame to the next.
    pub fn render(&self, pose: &Pose2, frame: u64) -> (GrayImage, GrayImage) {
        self.render_from(pose, &self.camera.mount, frame)
    }

    /// The same, with the pair where `mount` puts it: a pan-tilt unit's
    /// angle at the frame (level views only: its tilt is not drawn).
    pub fn render_from(&self, pose: &Pose2, mount: &CameraMount, frame: u64) -> (GrayImage, GrayImage) {
        let centre = pose.transform_point(mount.forward, mount.left);
        let (s, c) = (pose.theta + mount.pan_deg.to_radians()).sin_cos();
        // The camera frame's x points to the robot's right.
        let right = (s, -c);
        let half = self.camera.baseline_m / 2.0;
        let eye = |side: f64| (centre.0 + side * half * right.0, centre.1 + side * half * right.1);
        (
            self.render_eye(eye(-1.0), (c, s), right, 0.0, frame << 1),
            self.render_eye(eye(1.0), (c, s), right, self.camera.disparity_offset_px, frame << 1 | 1),
        )
    }

    /// One camera's image; `cx_offset` moves its principal point (the right
    /// camera's disparity offset).
    fn render_eye(
        &self,
        eye: (f64, f64),
        forward: (f64, f64),
        right: (f64, f64),
        cx_offset: f64,
        image_key: u64,
    ) -> GrayImage {
        let cam = &self.camera;
        let (w, h) = (cam.width_px, cam.height_px);
        let (f, cx, cy) = (cam.focal_px, cam.cx() + cx_offset, cam.cy());
        let eye_height = cam.mount.height;
        let ceiling = self.config.wall_height_m;
        let mut image = GrayImage::new(w, h);
        let noise_key = mix(self.seed ^ mix(image_key));
        // The posters a column crosses, with the poster cell column it sees:
        // found once per column, not per pixel.
        let mut across: Vec<(&Poster, usize)> = Vec::new();
        for px in 0..w {
            let lateral = (f64::from(px) + 0.5 - cx) / f;
            // Per unit of depth along the optical axis.
            let dir = (forward.0 + lateral * right.0, forward.1 + lateral * right.1);
            let hit = self
                .walls
                .iter()
                .enumerate()
                .filter_map(|(i, wall)| wall.segment.ray_hit_at(eye, dir).map(|(t, share)| (t, share, i)))
                .min_by(|a, b| a.0.total_cmp(&b.0));
            let column = hit.map(|(depth, share, i)| (depth, i, self.wall_column(i, share, &mut across)));
            for py in 0..h {
                let down = (f64::from(py) + 0.5 - cy) / f;
                let grey = match column {
                    Some((depth, i, (along, featureless)))
                        if (0.0..=ceiling).contains(&(eye_height - down * depth)) =>
                    {
                        self.wall_grey(i, along, featureless, &across, eye_height - down * depth)
                    }
                    _ if down > 0.0 => {
                        let depth = eye_height / down;
                        let (x, y) = (eye.0 + depth * dir.0, eye.1 + depth * dir.1);
                        110.0 + 8.0 * value_noise(1, x, y, 0.7)
                    }
                    _ if down < 0.0 => {
                        let depth = (ceiling - eye_height) / -down;
                        let (x, y) = (eye.0 + depth * dir.0, eye.1 + depth * dir.1);
                        195.0 + 5.0 * value_noise(2, x, y, 1.3)
                    }
                    _ => 150.0,
                };
                let n = mix(noise_key ^ (u64::from(py) << 32 | u64::from(px)));
                // Triangular noise with the configured standard deviation.
                let noise = (unit(n) + unit(mix(n)) - 1.0) * 6f64.sqrt() * self.config.noise;
                image.put_pixel(px, py, image::Luma([(grey + noise).round().clamp(0.0, 255.0) as u8]));
            }
        }
        image
    }

    /// What a column sees of wall `i` at `share` of its length: how far
    /// along it is, whether that stretch is featureless, and (into
    /// `across`) the posters it crosses with the cell column of each.
    fn wall_column<'a>(&'a self, i: usize, share: f64, across: &mut Vec<(&'a Poster, usize)>) -> (f64, bool) {
        let wall = &self.walls[i];
        let along = share * wall.length;
        let size = self.config.poster_m;
        let cells = POSTER_CELLS as f64 / size;
        across.clear();
        across.extend(wall.posters.iter().filter_map(|poster| {
            let a = along - (poster.along - size / 2.0);
            (0.0..size).contains(&a).then_some((poster, (a * cells) as usize))
        }));
        (along, wall.featureless.iter().any(|&(from, to)| (from..=to).contains(&along)))
    }

    /// The grey of wall `i` at `along` metres and `height` metres, given
    /// what [`Renderer::wall_column`] found for the column.
    fn wall_grey(&self, i: usize, along: f64, featureless: bool, across: &[(&Poster, usize)], height: f64) -> f64 {
        let size = self.config.poster_m;
        let cells = POSTER_CELLS as f64 / size;
        for &(poster, col) in across {
            let b = (poster.height + size / 2.0) - height;
            if (0.0..size).contains(&b) {
                let row = (b * cells) as usize;
                if col == 0 || row == 0 || col >= POSTER_CELLS - 1 || row >= POSTER_CELLS - 1 {
                    return INK;
                }
                let bit = (row - 1) * (POSTER_CELLS - 2) + (col - 1);
                return if poster.pattern >> bit & 1 == 1 { PAPER } else { INK };
            }
        }
        if featureless {
            return 160.0;
        }
        150.0 + 10.0 * value_noise(10 + i as u64, along, height, 0.9)
    }
}

/// The renderer as a camera source: the pairs seen along a path of timed
/// poses, then no more.
pub struct RenderedPath {
    renderer: Renderer,
    path: Vec<(f64, Pose2)>,
    next: usize,
}

impl RenderedPath {
    /// Pairs from `renderer` at each `(time, pose)` of `path`, in order.
    pub fn new(renderer: Renderer, path: Vec<(f64, Pose2)>) -> Self {
        RenderedPath { renderer, path, next: 0 }
    }
}

impl CameraSource for RenderedPath {
    fn next_pair(&mut self) -> Result<Option<StereoPair>, SourceError> {
        let Some(&(time, pose)) = self.path.get(self.next) else { return Ok(None) };
        self.next += 1;
        let (left, right) = self.renderer.render(&pose, self.next as u64);
        Ok(Some(StereoPair { time, left, right }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::world::{CorridorConfig, WorldConfig};
    use rand::SeedableRng;
    use ubf_perception::features::StereoPipeline;

    fn corridor_world() -> World {
        let config =
            WorldConfig { corridor: Some(CorridorConfig { length: 30.0, width: 4.0 }), ..WorldConfig::default() };
        let mut world = World::build(&config, &mut rand_chacha::ChaCha8Rng::seed_from_u64(1));
        // Posters at 1.2 m on both walls, every 3 m from 4 m on.
        for k in 0..8 {
            let x = 4.0 + 3.0 * f64::from(k);
            for (y, n) in [(2.0, (0.0, -1.0)), (-2.0, (0.0, 1.0))] {
                world.landmarks.push(crate::sim::world::WorldLandmark {
                    id: world.landmarks.len() as u32,
                    anchor: Anchor::Fixed { position: [x, y, 1.2], normal: Some(n) },
                    descriptor: ubf_core::Descriptor([mix(world.landmarks.len() as u64); 4]),
                });
            }
        }
        world
    }

    #[test]
    fn the_same_seed_and_frame_render_the_same_images() {
        let world = corridor_world();
        let renderer = Renderer::new(&world, StereoCamera::default(), RenderConfig::default(), 7);
        let pose = Pose2::new(1.0, 0.2, 0.1);
        let (a, b) = renderer.render(&pose, 3);
        assert_eq!((a.clone(), b.clone()), renderer.render(&pose, 3));
        assert_ne!(a, renderer.render(&pose, 4).0, "the noise changes from frame to frame");
        assert_ne!(a, b, "the two eyes differ");
    }

    #[test]
    fn a_panned_pair_sees_what_the_robot_turned_as_far_would() {
        // With the pair over the centre of rotation, panning it by 0.4 rad
        // is the same view as turning the robot by 0.4 rad.
        let world = corridor_world();
        let renderer = Renderer::new(&world, StereoCamera::default(), RenderConfig::default(), 7);
        let panned = renderer.camera().mount.aimed(0.4, 0.0);
        assert_eq!(
            renderer.render_from(&Pose2::new(1.0, 0.2, 0.1), &panned, 3),
            renderer.render(&Pose2::new(1.0, 0.2, 0.5), 3)
        );
        assert_ne!(renderer.render(&Pose2::new(1.0, 0.2, 0.1), 3), renderer.render(&Pose2::new(1.0, 0.2, 0.5), 3));
    }

    #[test]
    fn the_pipeline_finds_the_posters_where_they_are() {
        // Landmarks triangulated from rendered images lie on the posters or
        // at the far end's corners, and there are many of them.
        let world = corridor_world();
        let camera = StereoCamera::default();
        let renderer = Renderer::new(&world, camera, RenderConfig::default(), 7);
        let pose = Pose2::new(0.5, 0.0, 0.0);
        let (left, right) = renderer.render(&pose, 0);
        let landmarks = StereoPipeline::new(camera, FeatureConfig::default()).process(&left, &right).unwrap();
        assert!(landmarks.len() > 40, "{}", landmarks.len());
        let (mut on_walls, mut lateral_errors) = (0, Vec::new());
        for l in &landmarks {
            let p = camera.mount.cam_to_robot(l.point_cam);
            let (x, y) = pose.transform_point(p[0], p[1]);
            let within = |v: f64, lo: f64, hi: f64| (lo..=hi).contains(&v);
            // Depth errors grow as depth², about 5 % at 30 m here.
            let near = |v: f64, truth: f64| (v - truth).abs() < 0.002 * x * x + 0.05;
            let poster = near(y.abs(), 2.0) && within(p[2], 0.95, 1.45) && within(x, 3.7, 25.3);
            // Where the end wall meets a side wall and the floor or the
            // ceiling, the corner looks different from each eye.
            let far_corner = (x - 30.0).abs() < 3.0 && (y.abs() - 2.0).abs() < 0.3;
            if poster {
                lateral_errors.push(y.abs() - 2.0);
            }
            if poster || far_corner {
                on_walls += 1;
            }
        }
        assert!(on_walls as f64 > 0.9 * landmarks.len() as f64, "{on_walls} of {}", landmarks.len());
        // Sub-pixel disparity puts the posters on their walls to centimetres.
        let rms = (lateral_errors.iter().map(|e| e * e).sum::<f64>() / lateral_errors.len() as f64).sqrt();
        assert!(lateral_errors.len() > 30 && rms < 0.05, "{} posters, rms {rms}", lateral_errors.len());
    }

    #[test]
    fn a_rendered_path_is_a_camera_source() {
        let renderer = Renderer::new(&corridor_world(), StereoCamera::default(), RenderConfig::default(), 7);
        let path = vec![(0.0, Pose2::new(0.5, 0.0, 0.0)), (0.5, Pose2::new(0.8, 0.0, 0.0))];
        let mut source = RenderedPath::new(renderer.clone(), path);
        let first = source.next_pair().unwrap().unwrap();
        assert_eq!((first.left, first.right), renderer.render(&Pose2::new(0.5, 0.0, 0.0), 1));
        assert_eq!(source.next_pair().unwrap().unwrap().time, 0.5);
        assert!(source.next_pair().unwrap().is_none());
    }

    #[test]
    fn plain_walls_give_no_features() {
        let mut world = corridor_world();
        world.landmarks.clear();
        let camera = StereoCamera::default();
        let (left, right) =
            Renderer::new(&world, camera, RenderConfig::default(), 7).render(&Pose2::new(0.5, 0.0, 0.0), 0);
        let landmarks = StereoPipeline::new(camera, FeatureConfig::default()).process(&left, &right).unwrap();
        // The far end's corners with the floor and ceiling at most.
        assert!(landmarks.len() <= 6, "{}", landmarks.len());
    }
}
