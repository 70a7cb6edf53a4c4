//! Rectification: a calibrated but unrectified stereo pair made into the
//! rectified pair the pipeline expects, by a remap table per camera
//! computed once.
//!
//! Each camera's calibration is what ROS's `camera_info` carries (and
//! OpenCV's `stereoRectify` computes): the intrinsic matrix `K`, the
//! distortion coefficients `D` (`plumb_bob`: k1, k2, p1, p2, k3), the
//! rectifying rotation `R` and the rectified projection `P`. The table maps
//! every rectified pixel to where the raw image is sampled, as OpenCV's
//! `initUndistortRectifyMap` does; pixel centres are at integer
//! coordinates, as in both of those tools.

use crate::source::StereoPair;
use crate::stereo::{PrincipalPoint, StereoCamera};
use image::{GrayImage, Luma};
use nalgebra::{Matrix3, Vector3};
use serde::Deserialize;
use std::path::Path;

/// One camera's calibration, as a ROS `camera_info` file gives it.
#[derive(Clone, Debug, PartialEq)]
pub struct CameraInfo {
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// Intrinsic matrix, row major.
    pub k: [f64; 9],
    /// Distortion, `plumb_bob`: k1, k2, p1, p2, k3 (fewer are padded with
    /// zeros).
    pub d: [f64; 5],
    /// Rectifying rotation, row major.
    pub r: [f64; 9],
    /// Rectified projection, 3 × 4, row major.
    pub p: [f64; 12],
}

#[derive(Deserialize)]
struct YamlMatrix {
    rows: usize,
    cols: usize,
    data: Vec<f64>,
}

#[derive(Deserialize)]
struct YamlCameraInfo {
    image_width: u32,
    image_height: u32,
    distortion_model: String,
    camera_matrix: YamlMatrix,
    distortion_coefficients: YamlMatrix,
    rectification_matrix: YamlMatrix,
    projection_matrix: YamlMatrix,
}

impl CameraInfo {
    /// Reads a ROS `camera_info` YAML file (as `camera_calibration` writes
    /// it). Errors name the file, and the line and column where YAML knows
    /// them.
    pub fn load(path: &Path) -> Result<CameraInfo, String> {
        let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
        Self::from_yaml(&text).map_err(|e| format!("{}:{e}", path.display()))
    }

    /// Reads `camera_info` YAML text; the error starts with `line:column:`
    /// when the YAML is malformed, or names the field.
    pub fn from_yaml(text: &str) -> Result<CameraInfo, String> {
        let yaml: YamlCameraInfo = serde_norway::from_str(text).map_err(|e| match e.location() {
            Some(at) => format!("{}:{}: {e}", at.line(), at.column()),
            None => format!(" {e}"),
        })?;
        fn fixed<const N: usize>(name: &str, m: &YamlMatrix, rows: usize, cols: usize) -> Result<[f64; N], String> {
            let ok = m.rows == rows && m.cols == cols && m.data.len() == N && m.data.iter().all(|v| v.is_finite());
            ok.then(|| m.data.clone().try_into().ok()).flatten().ok_or_else(|| {
                format!(
                    " {name}: expected {rows} × {cols} finite numbers, got {} × {} with {}",
                    m.rows,
                    m.cols,
                    m.data.len()
                )
            })
        }
        if !matches!(yaml.distortion_model.as_str(), "plumb_bob" | "rational_polynomial") {
            return Err(format!(" distortion_model: {:?}; plumb_bob is understood", yaml.distortion_model));
        }
        let coefficients = &yaml.distortion_coefficients.data;
        if coefficients.len() > 5 && coefficients[5..].iter().any(|&c| c != 0.0) {
            return Err(" distortion_coefficients: only k1, k2, p1, p2, k3 are understood".into());
        }
        let mut d = [0.0; 5];
        for (slot, &c) in d.iter_mut().zip(coefficients) {
            if !c.is_finite() {
                return Err(" distortion_coefficients: not finite".into());
            }
            *slot = c;
        }
        let info = CameraInfo {
            width: yaml.image_width,
            height: yaml.image_height,
            k: fixed("camera_matrix", &yaml.camera_matrix, 3, 3)?,
            d,
            r: fixed("rectification_matrix", &yaml.rectification_matrix, 3, 3)?,
            p: fixed("projection_matrix", &yaml.projection_matrix, 3, 4)?,
        };
        if !(8..=crate::stereo::MAX_IMAGE_SIDE_PX).contains(&info.width)
            || !(8..=crate::stereo::MAX_IMAGE_SIDE_PX).contains(&info.height)
        {
            return Err(format!(" image_width, image_height: {} × {}; each 8 to 16 384", info.width, info.height));
        }
        if info.k[0] <= 0.0 || info.k[4] <= 0.0 || info.p[0] <= 0.0 || info.p[5] <= 0.0 {
            return Err(" camera_matrix, projection_matrix: focal lengths must be positive".into());
        }
        Ok(info)
    }
}

/// Where each rectified pixel samples the raw image.
#[derive(Clone, Debug)]
pub struct RemapTable {
    width: u32,
    height: u32,
    /// Raw-image coordinates per rectified pixel, row by row.
    map: Vec<[f32; 2]>,
}

impl RemapTable {
    /// The table for one camera, as OpenCV's `initUndistortRectifyMap(K,
    /// D, R, P)` computes it.
    pub fn new(info: &CameraInfo) -> RemapTable {
        let k = Matrix3::from_row_slice(&info.k);
        let r = Matrix3::from_row_slice(&info.r);
        let p = &info.p;
        let new_k = Matrix3::new(p[0], p[1], p[2], p[4], p[5], p[6], p[8], p[9], p[10]);
        // A rectified pixel's ray, in the raw camera's frame.
        let back = (new_k * r).try_inverse().unwrap_or_else(Matrix3::identity);
        let [k1, k2, p1, p2, k3] = info.d;
        let mut map = Vec::with_capacity(info.width as usize * info.height as usize);
        for v in 0..info.height {
            for u in 0..info.width {
                let ray = back * Vector3::new(f64::from(u), f64::from(v), 1.0);
                let (x, y) = (ray.x / ray.z, ray.y / ray.z);
                let r2 = x * x + y * y;
                let radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
                let xd = x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x);
                let yd = y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y;
                let raw = k * Vector3::new(xd, yd, 1.0);
                map.push([raw.x as f32, raw.y as f32]);
            }
        }
        RemapTable { width: info.width, height: info.height, map }
    }

    /// Where rectified pixel `(u, v)` samples the raw image.
    pub fn source_of(&self, u: u32, v: u32) -> Option<[f32; 2]> {
        (u < self.width && v < self.height).then(|| self.map[(v * self.width + u) as usize])
    }

    /// The rectified image: each pixel interpolated bilinearly from `raw`,
    /// black where it samples outside it.
    pub fn apply(&self, raw: &GrayImage) -> GrayImage {
        let (w, h) = (raw.width() as i64, raw.height() as i64);
        let pixel = |x: i64, y: i64| -> f32 {
            if x < 0 || y < 0 || x >= w || y >= h {
                0.0
            } else {
                f32::from(raw.get_pixel(x as u32, y as u32)[0])
            }
        };
        GrayImage::from_fn(self.width, self.height, |u, v| {
            let [x, y] = self.map[(v * self.width + u) as usize];
            if !(x > -1.0 && y > -1.0 && x < w as f32 && y < h as f32) {
                return Luma([0]);
            }
            let (x0, y0) = (x.floor(), y.floor());
            let (ax, ay) = (x - x0, y - y0);
            let (x0, y0) = (x0 as i64, y0 as i64);
            let top = pixel(x0, y0) * (1.0 - ax) + pixel(x0 + 1, y0) * ax;
            let bottom = pixel(x0, y0 + 1) * (1.0 - ax) + pixel(x0 + 1, y0 + 1) * ax;
            Luma([(top * (1.0 - ay) + bottom * ay).round().clamp(0.0, 255.0) as u8])
        })
    }
}

/// A calibrated pair's two remap tables, and the rectified pair they make.
#[derive(Clone, Debug)]
pub struct Rectifier {
    left: RemapTable,
    right: RemapTable,
    camera: StereoCamera,
}

impl Rectifier {
    /// The rectifier for a pair, checking that the two projections describe
    /// a rectified pair: the same focal lengths and principal row, the
    /// right camera displaced along x only.
    pub fn new(left: &CameraInfo, right: &CameraInfo) -> Result<Rectifier, String> {
        let (pl, pr) = (&left.p, &right.p);
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-6 * a.abs().max(1.0);
        if (left.width, left.height) != (right.width, right.height) {
            return Err("the two cameras' images differ in size".into());
        }
        if !(close(pl[0], pr[0]) && close(pl[5], pr[5]) && close(pl[6], pr[6]) && close(pl[0], pl[5])) {
            return Err(format!(
                "projection_matrix: the pair is not rectified to one camera (fx {} and {}, fy {} and {}, cy {} and \
                 {}; fx must equal fy)",
                pl[0], pr[0], pl[5], pr[5], pl[6], pr[6]
            ));
        }
        let baseline = (pl[3] - pr[3]) / pl[0];
        if baseline <= 0.0 || pr[7] != 0.0 || pr[11] != 0.0 {
            return Err(format!(
                "projection_matrix: the right camera must sit to the right of the left one, along x only \
                 (P[0,3] {} and {})",
                pl[3], pr[3]
            ));
        }
        let camera = StereoCamera {
            width_px: left.width,
            height_px: left.height,
            focal_px: pl[0],
            baseline_m: baseline,
            principal_point: Some(PrincipalPoint { x: pl[2], y: pl[6] }),
            disparity_offset_px: pr[2] - pl[2],
            ..StereoCamera::default()
        };
        ubf_core::config::Check::check(&camera)?;
        Ok(Rectifier { left: RemapTable::new(left), right: RemapTable::new(right), camera })
    }

    /// The rectified pair's calibration (its mount the default; set it
    /// where the pair sits on the robot).
    pub fn camera(&self) -> StereoCamera {
        self.camera
    }

    /// The two tables, left and right.
    pub fn tables(&self) -> (&RemapTable, &RemapTable) {
        (&self.left, &self.right)
    }

    /// A raw pair, rectified.
    pub fn rectify(&self, raw: &StereoPair) -> StereoPair {
        StereoPair { time: raw.time, left: self.left.apply(&raw.left), right: self.right.apply(&raw.right) }
    }
}

/// A source of raw pairs, rectified as they come.
pub struct Rectified<S> {
    source: S,
    rectifier: Rectifier,
}

impl<S> Rectified<S> {
    /// `source`'s pairs through `rectifier`.
    pub fn new(source: S, rectifier: Rectifier) -> Self {
        Rectified { source, rectifier }
    }
}

impl<S: crate::source::CameraSource> crate::source::CameraSource for Rectified<S> {
    fn next_pair(&mut self) -> Result<Option<StereoPair>, crate::source::SourceError> {
        Ok(self.source.next_pair()?.map(|raw| self.rectifier.rectify(&raw)))
    }
}

/// The rectifier for the pair whose `camera_info` files are `left` and
/// `right`.
pub fn load_pair(left: &Path, right: &Path) -> Result<Rectifier, String> {
    Rectifier::new(&CameraInfo::load(left)?, &CameraInfo::load(right)?)
        .map_err(|e| format!("{} and {}: {e}", left.display(), right.display()))
}
