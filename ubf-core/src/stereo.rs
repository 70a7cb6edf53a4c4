//! The stereo camera: where a point appears in both images, and where a
//! matched pair of pixels says the point is.
//!
//! Frames. The *camera frame* is the thesis's: origin midway between the two
//! cameras, x to the right, y ahead along the optical axes, z up. The *robot
//! frame* is x forward, y left, z up, at the robot's centre of rotation on
//! the floor. Images are rectified: both cameras share the focal length and
//! the rows; the right camera's principal point may sit a fixed number of
//! columns from the left's (the disparity offset). Pixels count from the
//! top-left corner, and the continuous coordinate of pixel k's centre is
//! k + ½ (calibration tools put it at k: see [`PrincipalPoint`]).

use crate::config::{finite, positive};
use crate::StereoPixels;
use serde::{Deserialize, Serialize};

/// Where the camera pair sits on the robot and where it looks.
///
/// A pair bolted on looks where `pan_deg` and `tilt_deg` say, straight ahead
/// by default. On a pan-tilt unit the angles are the unit's measured ones at
/// the frame: the simulator and `ubf drive` write them into each frame's
/// calibration, so everything that lifts a landmark into the robot frame
/// (egomotion, the tracking list, the logs) follows the camera. Both axes
/// pass through the pair's centre, at (`forward`, `left`, `height`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CameraMount {
    /// Metres ahead of the centre of rotation. The thesis mounted its
    /// cameras over the wheel axle (§3.5.1.4): 0.
    #[serde(default, deserialize_with = "finite")]
    pub forward: f64,
    /// Metres to the left of the centreline.
    #[serde(default, deserialize_with = "finite")]
    pub left: f64,
    /// Metres above the floor.
    #[serde(deserialize_with = "finite")]
    pub height: f64,
    /// Where the optical axes point, degrees counter-clockwise from the
    /// robot's heading.
    #[serde(default, deserialize_with = "finite", skip_serializing_if = "is_zero")]
    pub pan_deg: f64,
    /// Degrees above the horizontal.
    #[serde(default, deserialize_with = "finite", skip_serializing_if = "is_zero")]
    pub tilt_deg: f64,
}

impl CameraMount {
    /// A pair at (`forward`, `left`, `height`) looking straight ahead.
    pub const fn ahead(forward: f64, left: f64, height: f64) -> Self {
        CameraMount { forward, left, height, pan_deg: 0.0, tilt_deg: 0.0 }
    }

    /// The same mount looking `pan` and `tilt` radians (a pan-tilt unit's
    /// measured angles).
    pub fn aimed(self, pan: f64, tilt: f64) -> Self {
        CameraMount { pan_deg: pan.to_degrees(), tilt_deg: tilt.to_degrees(), ..self }
    }

    /// Whether the optical axes point straight ahead, level.
    pub fn looks_ahead(&self) -> bool {
        self.pan_deg == 0.0 && self.tilt_deg == 0.0
    }

    /// A point in the robot frame, in the camera frame.
    pub fn robot_to_cam(&self, p: [f64; 3]) -> [f64; 3] {
        let d = [p[0] - self.forward, p[1] - self.left, p[2] - self.height];
        if self.looks_ahead() {
            return [-d[1], d[0], d[2]];
        }
        let (sp, cp) = self.pan_deg.to_radians().sin_cos();
        let (st, ct) = self.tilt_deg.to_radians().sin_cos();
        // Undo the pan about the vertical, then the tilt about the pair's
        // baseline.
        let (ahead, left) = (cp * d[0] + sp * d[1], -sp * d[0] + cp * d[1]);
        let (along, up) = (ct * ahead + st * d[2], -st * ahead + ct * d[2]);
        [-left, along, up]
    }

    /// A point in the camera frame, in the robot frame.
    pub fn cam_to_robot(&self, p: [f64; 3]) -> [f64; 3] {
        if self.looks_ahead() {
            return [p[1] + self.forward, -p[0] + self.left, p[2] + self.height];
        }
        let (sp, cp) = self.pan_deg.to_radians().sin_cos();
        let (st, ct) = self.tilt_deg.to_radians().sin_cos();
        let (along, left, up) = (p[1], -p[0], p[2]);
        let (ahead, z) = (ct * along - st * up, st * along + ct * up);
        [cp * ahead - sp * left + self.forward, sp * ahead + cp * left + self.left, z + self.height]
    }
}

impl Default for CameraMount {
    fn default() -> Self {
        CameraMount::ahead(0.0, 0.0, 1.0)
    }
}

/// A calibrated, rectified stereo pair.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct StereoCamera {
    /// Image width, pixels.
    pub width_px: u32,
    /// Image height, pixels.
    pub height_px: u32,
    /// Focal length, pixels. The default gives a 60° horizontal field of
    /// view at 640 pixels.
    #[serde(deserialize_with = "positive")]
    pub focal_px: f64,
    /// Distance between the two cameras' centres, m. The default is the
    /// thesis's 60 cm (§4.4.10.1, figure 39).
    #[serde(deserialize_with = "positive")]
    pub baseline_m: f64,
    /// Where the pair sits on the robot.
    #[serde(default)]
    pub mount: CameraMount,
    /// The left camera's principal point; unset, the image centre.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub principal_point: Option<PrincipalPoint>,
    /// The right camera's principal point column minus the left's, pixels:
    /// Middlebury's `doffs`; 0 for a pair rectified to share it (KITTI,
    /// OpenCV's `stereoRectify` with `CALIB_ZERO_DISPARITY`). A point's
    /// depth is `focal_px · baseline_m / (disparity + disparity_offset_px)`.
    #[serde(default, deserialize_with = "finite", skip_serializing_if = "is_zero")]
    pub disparity_offset_px: f64,
}

fn is_zero(v: &f64) -> bool {
    *v == 0.0
}

/// A principal point, pixels, as calibration tools write it (OpenCV's and
/// ROS's `K`, KITTI's `P0`: `cx`, `cy`, with the first pixel's centre at
/// (0, 0)).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PrincipalPoint {
    /// Column, pixels.
    #[serde(deserialize_with = "finite")]
    pub x: f64,
    /// Row, pixels.
    #[serde(deserialize_with = "finite")]
    pub y: f64,
}

impl Default for StereoCamera {
    fn default() -> Self {
        StereoCamera {
            width_px: 640,
            height_px: 480,
            focal_px: 320.0 / 30f64.to_radians().tan(),
            baseline_m: 0.6,
            mount: CameraMount::default(),
            principal_point: None,
            disparity_offset_px: 0.0,
        }
    }
}

/// The largest image side a calibration may give, pixels.
pub const MAX_IMAGE_SIDE_PX: u32 = 8_192;
/// The widest field of view a calibration may give (a rectified pinhole
/// pair cannot see 180°), degrees.
pub const MAX_FIELD_OF_VIEW_DEG: f64 = 170.0;

impl crate::config::Check for StereoCamera {
    /// Image sides within 8 to 16 384 pixels, a field of view up to 170°
    /// and a focal length up to 10⁶ pixels: beyond these no real pair
    /// exists, and the error model's tables would not fit in memory.
    fn check(&self) -> Result<(), String> {
        for (name, side) in [("width_px", self.width_px), ("height_px", self.height_px)] {
            if !(8..=MAX_IMAGE_SIDE_PX).contains(&side) {
                return Err(format!("{name}: {side} pixels; a camera's image side is 8 to {MAX_IMAGE_SIDE_PX}"));
            }
        }
        let half_side = f64::from(self.width_px.max(self.height_px)) / 2.0;
        let fov = 2.0 * (half_side / self.focal_px).atan().to_degrees();
        if fov > MAX_FIELD_OF_VIEW_DEG {
            return Err(format!(
                "focal_px: {} gives a {fov:.1}° field of view over {half_side:.0} pixels; at most \
                 {MAX_FIELD_OF_VIEW_DEG}° (focal_px at least {:.1})",
                self.focal_px,
                half_side / (MAX_FIELD_OF_VIEW_DEG / 2.0).to_radians().tan()
            ));
        }
        if self.focal_px > 1e6 {
            return Err(format!("focal_px: {}; at most 1e6 pixels", self.focal_px));
        }
        if let Some(p) = self.principal_point {
            let (w, h) = (f64::from(self.width_px), f64::from(self.height_px));
            if !(0.0..w).contains(&p.x) || !(0.0..h).contains(&p.y) {
                return Err(format!("principal_point: ({}, {}) lies outside the {w} × {h} image", p.x, p.y));
            }
        }
        if self.disparity_offset_px.abs() >= f64::from(self.width_px) {
            return Err(format!(
                "disparity_offset_px: {}; its size must be less than the image width, {}",
                self.disparity_offset_px, self.width_px
            ));
        }
        Ok(())
    }
}

impl StereoCamera {
    /// The left camera's principal point column, in continuous image
    /// coordinates (pixel k's centre at k + ½).
    pub fn cx(&self) -> f64 {
        self.principal_point.map_or(f64::from(self.width_px) / 2.0, |p| p.x + 0.5)
    }

    /// The principal point row, in continuous image coordinates.
    pub fn cy(&self) -> f64 {
        self.principal_point.map_or(f64::from(self.height_px) / 2.0, |p| p.y + 0.5)
    }

    /// The horizontal field of view of one camera, radians.
    pub fn horizontal_fov(&self) -> f64 {
        let right = f64::from(self.width_px) - self.cx();
        (self.cx() / self.focal_px).atan() + (right / self.focal_px).atan()
    }

    /// How far above and below its optical axis one camera sees, radians.
    pub fn vertical_reach(&self) -> [f64; 2] {
        let below = f64::from(self.height_px) - self.cy();
        [(self.cy() / self.focal_px).atan(), (below / self.focal_px).atan()]
    }

    /// Where `p` (camera frame) appears in both images, or `None` when it is
    /// not in front of the cameras. The pixels may lie outside the images:
    /// see [`StereoCamera::in_images`].
    pub fn project(&self, p: [f64; 3]) -> Option<StereoPixels> {
        let [x, y, z] = p;
        if y <= 0.0 {
            return None;
        }
        let half = self.baseline_m / 2.0;
        let f = self.focal_px;
        Some(StereoPixels {
            u_left: f * (x + half) / y + self.cx(),
            u_right: f * (x - half) / y + self.cx() + self.disparity_offset_px,
            v: -f * z / y + self.cy(),
        })
    }

    /// Whether both pixels fall inside the images.
    pub fn in_images(&self, px: &StereoPixels) -> bool {
        let w = f64::from(self.width_px);
        let h = f64::from(self.height_px);
        let inside = |u: f64| (0.0..w).contains(&u);
        inside(px.u_left) && inside(px.u_right) && (0.0..h).contains(&px.v)
    }

    /// Where a matched pair of pixels puts the point, camera frame (thesis
    /// eq. 12–14, with the origin moved from the left camera to the middle of
    /// the pair). `None` for a disparity that is not positive once the
    /// disparity offset is added.
    pub fn triangulate(&self, px: &StereoPixels) -> Option<[f64; 3]> {
        let disparity = px.disparity() + self.disparity_offset_px;
        if disparity <= 0.0 || !disparity.is_finite() {
            return None;
        }
        let depth = self.focal_px * self.baseline_m / disparity;
        let x = (px.u_left - self.cx()) * depth / self.focal_px - self.baseline_m / 2.0;
        let z = -(px.v - self.cy()) * depth / self.focal_px;
        Some([x, depth, z])
    }

    /// The standard deviation of a triangulated depth at `depth` metres when
    /// each image column has Gaussian noise of `pixel_sigma`: the disparity's
    /// σ is √2·pixel_sigma, and depth σ ≈ depth² σ_d / (f T).
    pub fn depth_sigma(&self, depth: f64, pixel_sigma: f64) -> f64 {
        depth * depth * std::f64::consts::SQRT_2 * pixel_sigma / (self.focal_px * self.baseline_m)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn a_point_ahead_projects_symmetrically() {
        let cam = StereoCamera::default();
        let px = cam.project([0.0, 10.0, 0.0]).unwrap();
        assert!((px.u_left - cam.cx() - (cam.cx() - px.u_right)).abs() < 1e-9);
        assert!((px.disparity() - cam.focal_px * 0.6 / 10.0).abs() < 1e-9);
        assert_eq!(px.v, cam.cy());
        assert!(cam.project([0.0, -1.0, 0.0]).is_none());
    }

    #[test]
    fn default_field_of_view_is_sixty_degrees() {
        assert!((StereoCamera::default().horizontal_fov().to_degrees() - 60.0).abs() < 1e-9);
    }

    #[test]
    fn mount_round_trips() {
        let close = |a: [f64; 3], b: [f64; 3]| a.iter().zip(b).all(|(a, b)| (a - b).abs() < 1e-12);
        let ahead = CameraMount::ahead(0.2, -0.1, 1.1);
        let p = [3.0, 1.0, 0.4];
        assert!(close(ahead.cam_to_robot(ahead.robot_to_cam(p)), p));
        // A point ahead of the robot is ahead of the camera (y), and one to
        // the robot's left is to the camera's left (negative x).
        let ahead_left = ahead.robot_to_cam([5.0, 1.0, 1.1]);
        assert!(ahead_left[1] > 0.0 && ahead_left[0] < 0.0);
        for (pan, tilt) in [(0.7, 0.0), (-1.2, 0.3), (3.0, -0.5)] {
            let aimed = ahead.aimed(pan, tilt);
            assert!(close(aimed.cam_to_robot(aimed.robot_to_cam(p)), p));
        }
    }

    #[test]
    fn a_panned_and_tilted_mount_looks_where_it_is_aimed() {
        let close = |a: [f64; 3], b: [f64; 3]| a.iter().zip(b).all(|(a, b)| (a - b).abs() < 1e-12);
        let mount = CameraMount::ahead(0.2, 0.0, 1.0);
        // Panned 90° left, a point 3 m to the robot's left of the pair is
        // 3 m down the optical axis; one ahead of the robot is to the
        // camera's right.
        let left = mount.aimed(std::f64::consts::FRAC_PI_2, 0.0);
        assert!(close(left.robot_to_cam([0.2, 3.0, 1.0]), [0.0, 3.0, 0.0]));
        assert!(close(left.robot_to_cam([1.2, 0.0, 1.0]), [1.0, 0.0, 0.0]));
        // Tilted 90° up, a point above the pair is down the optical axis.
        let up = mount.aimed(0.0, std::f64::consts::FRAC_PI_2);
        assert!(close(up.robot_to_cam([0.2, 0.0, 4.0]), [0.0, 3.0, 0.0]));
        // Angles of zero are the fixed mount exactly.
        assert_eq!(mount.aimed(0.0, 0.0), mount);
    }

    #[test]
    fn a_principal_point_and_disparity_offset_move_the_pixels_not_the_point() {
        let cam = StereoCamera {
            principal_point: Some(PrincipalPoint { x: 301.5, y: 250.0 }),
            disparity_offset_px: 12.0,
            ..StereoCamera::default()
        };
        let px = cam.project([0.0, 10.0, 0.0]).unwrap();
        assert!((px.v - 250.5).abs() < 1e-12, "the optical axis meets the row of cy");
        assert!((px.u_left - 302.0 - cam.focal_px * 0.3 / 10.0).abs() < 1e-9);
        assert!((px.disparity() + 12.0 - cam.focal_px * 0.6 / 10.0).abs() < 1e-9);
        let p = cam.triangulate(&px).unwrap();
        assert!(p.iter().zip([0.0, 10.0, 0.0]).all(|(a, b)| (a - b).abs() < 1e-9), "{p:?}");
    }

    #[test]
    fn a_principal_point_outside_the_image_is_refused() {
        use crate::config::Check;
        let cam =
            StereoCamera { principal_point: Some(PrincipalPoint { x: 700.0, y: 10.0 }), ..StereoCamera::default() };
        assert!(cam.check().unwrap_err().contains("principal_point"));
        let cam = StereoCamera { disparity_offset_px: 1e9, ..StereoCamera::default() };
        assert!(cam.check().unwrap_err().contains("disparity_offset_px"));
    }

    proptest! {
        #[test]
        fn triangulation_inverts_projection(x in -5.0..5.0f64, y in 0.5..60.0f64, z in -2.0..2.0f64) {
            let cam = StereoCamera::default();
            let p = cam.triangulate(&cam.project([x, y, z]).unwrap()).unwrap();
            prop_assert!((p[0] - x).abs() < 1e-9 * y.max(1.0));
            prop_assert!((p[1] - y).abs() < 1e-9 * y * y);
            prop_assert!((p[2] - z).abs() < 1e-9 * y.max(1.0));
        }
    }
}
