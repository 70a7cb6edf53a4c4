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
//!
//! A pair calibrated but never rectified (each camera's `K` and `D`, and
//! the rotation `R` and translation `T` from the left camera to the right,
//! as OpenCV's `stereoCalibrate` returns them) is first given its
//! rectifying rotations and projections by [`stereo_rectify`], OpenCV's
//! `stereoRectify` with its defaults (zero disparity at infinity, no
//! scaling).

use crate::source::StereoPair;
use crate::stereo::{PrincipalPoint, StereoCamera};
use image::{GrayImage, Luma};
use nalgebra::{Matrix3, Rotation3, Vector3};
use serde::Deserialize;
use std::path::{Path, PathBuf};

/// What is wrong with a calibration, and where: the file, then the line
/// and column or the field.
#[derive(Debug, thiserror::Error)]
pub enum CalibrationError {
    /// A file could not be read.
    #[error("{}: {source}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// A problem inside the file at `path`.
    #[error("{}:{problem}", path.display())]
    InFile {
        /// The file.
        path: PathBuf,
        /// What and where.
        problem: Box<CalibrationError>,
    },
    /// Malformed YAML, where the parser places it.
    #[error("{line}:{column}: {message}")]
    Yaml {
        /// Line, from 1.
        line: usize,
        /// Column, from 1.
        column: usize,
        /// The parser's message.
        message: String,
    },
    /// Malformed YAML the parser does not place.
    #[error(" {0}")]
    YamlUnplaced(String),
    /// A field that is there but wrong.
    #[error(" {field}: {problem}")]
    Field {
        /// The field (or fields).
        field: &'static str,
        /// What is wrong with it.
        problem: String,
    },
    /// Two projections that do not make a rectified pair.
    #[error("{0}")]
    NotRectified(String),
    /// A problem with the pair in `files`.
    #[error("{files}: {problem}")]
    Pair {
        /// The file, or the two files.
        files: String,
        /// What is wrong.
        problem: Box<CalibrationError>,
    },
}

impl CalibrationError {
    fn field(field: &'static str, problem: impl Into<String>) -> Self {
        CalibrationError::Field { field, problem: problem.into() }
    }

    fn read(path: &Path) -> impl FnOnce(std::io::Error) -> CalibrationError + '_ {
        move |source| CalibrationError::Read { path: path.to_owned(), source }
    }

    fn in_file(path: &Path) -> impl FnOnce(CalibrationError) -> CalibrationError + '_ {
        move |problem| CalibrationError::InFile { path: path.to_owned(), problem: Box::new(problem) }
    }
}

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

/// The most bytes a calibration file may hold: a stereo calibration is a
/// few kilobytes, and the YAML parser's time grows with the square of its
/// nesting (a 200 kB file of brackets took 23 s).
const MOST_CALIBRATION_BYTES: u64 = 64 << 10;

/// A calibration file's text, if it is a regular file of at most
/// [`MOST_CALIBRATION_BYTES`].
fn read_calibration(path: &Path) -> Result<String, CalibrationError> {
    let bytes = ubf_core::config::read_bounded(path, MOST_CALIBRATION_BYTES).map_err(CalibrationError::read(path))?;
    String::from_utf8(bytes)
        .map_err(|e| CalibrationError::read(path)(std::io::Error::new(std::io::ErrorKind::InvalidData, e.utf8_error())))
}

impl CameraInfo {
    /// Reads a ROS `camera_info` YAML file (as `camera_calibration` writes
    /// it). Errors name the file, and the line and column where YAML knows
    /// them.
    pub fn load(path: &Path) -> Result<CameraInfo, CalibrationError> {
        Self::from_yaml(&read_calibration(path)?).map_err(CalibrationError::in_file(path))
    }

    /// Reads `camera_info` YAML text; the error starts with `line:column:`
    /// when the YAML is malformed, or names the field.
    pub fn from_yaml(text: &str) -> Result<CameraInfo, CalibrationError> {
        let yaml: YamlCameraInfo = parse_yaml(text)?;
        if !matches!(yaml.distortion_model.as_str(), "plumb_bob" | "rational_polynomial") {
            let problem = format!("{:?}; plumb_bob is understood", yaml.distortion_model);
            return Err(CalibrationError::field("distortion_model", problem));
        }
        let d = plumb_bob("distortion_coefficients", &yaml.distortion_coefficients)?;
        let info = CameraInfo {
            width: yaml.image_width,
            height: yaml.image_height,
            k: fixed("camera_matrix", &yaml.camera_matrix, 3, 3)?,
            d,
            r: fixed("rectification_matrix", &yaml.rectification_matrix, 3, 3)?,
            p: fixed("projection_matrix", &yaml.projection_matrix, 3, 4)?,
        };
        check_size(info.width, info.height)?;
        if info.k[0] <= 0.0 || info.k[4] <= 0.0 || info.p[0] <= 0.0 || info.p[5] <= 0.0 {
            return Err(CalibrationError::field("camera_matrix, projection_matrix", "focal lengths must be positive"));
        }
        Ok(info)
    }
}

/// A stereo pair's calibration before rectification, as OpenCV's
/// `stereoCalibrate` returns it: each camera's intrinsics and distortion,
/// and the motion from the left camera's frame to the right one's
/// (`x_right = R · x_left + T`).
#[derive(Clone, Debug, PartialEq)]
pub struct StereoCalibrationFile {
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// The left camera's intrinsic matrix, row major.
    pub k1: [f64; 9],
    /// The left camera's distortion (k1, k2, p1, p2, k3).
    pub d1: [f64; 5],
    /// The right camera's intrinsic matrix, row major.
    pub k2: [f64; 9],
    /// The right camera's distortion.
    pub d2: [f64; 5],
    /// Rotation from the left camera's frame to the right's, row major.
    pub r: [f64; 9],
    /// Translation from the left camera's frame to the right's, m (about
    /// `(−baseline, 0, 0)` for a right camera to the right).
    pub t: [f64; 3],
}

#[derive(Deserialize)]
struct YamlStereo {
    image_width: u32,
    image_height: u32,
    #[serde(alias = "M1", alias = "cameraMatrix1")]
    #[serde(rename = "K1")]
    k1: YamlMatrix,
    #[serde(alias = "distCoeffs1")]
    #[serde(rename = "D1")]
    d1: YamlMatrix,
    #[serde(alias = "M2", alias = "cameraMatrix2")]
    #[serde(rename = "K2")]
    k2: YamlMatrix,
    #[serde(alias = "distCoeffs2")]
    #[serde(rename = "D2")]
    d2: YamlMatrix,
    #[serde(rename = "R")]
    r: YamlMatrix,
    #[serde(rename = "T")]
    t: YamlMatrix,
}

/// A matrix's numbers, checked against its expected shape.
fn fixed<const N: usize>(
    name: &'static str,
    m: &YamlMatrix,
    rows: usize,
    cols: usize,
) -> Result<[f64; N], CalibrationError> {
    let ok = m.rows == rows && m.cols == cols && m.data.len() == N && m.data.iter().all(|v| v.is_finite());
    ok.then(|| m.data.clone().try_into().ok()).flatten().ok_or_else(|| {
        let got = format!("{} × {} with {}", m.rows, m.cols, m.data.len());
        CalibrationError::field(name, format!("expected {rows} × {cols} finite numbers, got {got}"))
    })
}

/// Distortion coefficients as (k1, k2, p1, p2, k3): fewer are padded with
/// zeros; more must be zero (the rational and thin-prism terms are not
/// modelled).
fn plumb_bob(name: &'static str, m: &YamlMatrix) -> Result<[f64; 5], CalibrationError> {
    if m.data.len() > 5 && m.data[5..].iter().any(|&c| c != 0.0) {
        return Err(CalibrationError::field(name, "only k1, k2, p1, p2, k3 are understood"));
    }
    let mut d = [0.0; 5];
    for (slot, &c) in d.iter_mut().zip(&m.data) {
        if !c.is_finite() {
            return Err(CalibrationError::field(name, "not finite"));
        }
        *slot = c;
    }
    Ok(d)
}

/// Parses YAML into `T`; the error starts with `line:column:` where YAML
/// knows them.
fn parse_yaml<T: serde::de::DeserializeOwned>(text: &str) -> Result<T, CalibrationError> {
    serde_norway::from_str(text).map_err(|e| match e.location() {
        Some(at) => CalibrationError::Yaml { line: at.line(), column: at.column(), message: e.to_string() },
        None => CalibrationError::YamlUnplaced(e.to_string()),
    })
}

/// Checks an image size read from a calibration file.
fn check_size(width: u32, height: u32) -> Result<(), CalibrationError> {
    let side = 8..=crate::stereo::MAX_IMAGE_SIDE_PX;
    if side.contains(&width) && side.contains(&height) {
        Ok(())
    } else {
        Err(CalibrationError::field(
            "image_width, image_height",
            format!("{width} × {height}; each 8 to {}", crate::stereo::MAX_IMAGE_SIDE_PX),
        ))
    }
}

impl StereoCalibrationFile {
    /// Reads the YAML OpenCV's `FileStorage` writes (`%YAML` header and
    /// `!!opencv-matrix` tags allowed): `image_width`, `image_height`, and
    /// the matrices `K1` (or `M1`, `cameraMatrix1`), `D1` (`distCoeffs1`),
    /// `K2`, `D2`, `R` and `T`. Errors name the file, and the line and
    /// column or the field.
    pub fn load(path: &Path) -> Result<StereoCalibrationFile, CalibrationError> {
        Self::from_yaml(&read_calibration(path)?).map_err(CalibrationError::in_file(path))
    }

    /// Reads OpenCV `FileStorage` YAML text.
    pub fn from_yaml(text: &str) -> Result<StereoCalibrationFile, CalibrationError> {
        // OpenCV's own header (`%YAML:1.0` in older versions) and tags are
        // not YAML every parser takes; blanking them keeps line numbers.
        let plain: String = text
            .lines()
            .map(|line| if line.starts_with("%YAML") { "" } else { line })
            .map(|line| line.replace("!!opencv-matrix", ""))
            .collect::<Vec<_>>()
            .join("\n");
        let yaml: YamlStereo = parse_yaml(&plain)?;
        check_size(yaml.image_width, yaml.image_height)?;
        let file = StereoCalibrationFile {
            width: yaml.image_width,
            height: yaml.image_height,
            k1: fixed("K1", &yaml.k1, 3, 3)?,
            d1: plumb_bob("D1", &yaml.d1)?,
            k2: fixed("K2", &yaml.k2, 3, 3)?,
            d2: plumb_bob("D2", &yaml.d2)?,
            r: fixed("R", &yaml.r, 3, 3)?,
            t: if yaml.t.rows == 1 { fixed("T", &yaml.t, 1, 3)? } else { fixed("T", &yaml.t, 3, 1)? },
        };
        if file.k1[0] <= 0.0 || file.k1[4] <= 0.0 || file.k2[0] <= 0.0 || file.k2[4] <= 0.0 {
            return Err(CalibrationError::field("K1, K2", "focal lengths must be positive"));
        }
        let r = Matrix3::from_row_slice(&file.r);
        if ((r.transpose() * r) - Matrix3::identity()).norm() > 1e-3 || r.determinant() < 0.0 {
            return Err(CalibrationError::field("R", "not a rotation matrix"));
        }
        let t = Vector3::from(file.t);
        if t.x.abs() <= t.y.abs() || t.norm() == 0.0 {
            let problem = format!(
                "({}, {}, {}); the cameras must sit side by side (|T.x| > |T.y|)",
                file.t[0], file.t[1], file.t[2]
            );
            return Err(CalibrationError::field("T", problem));
        }
        Ok(file)
    }
}

/// Normalised image coordinates of raw pixel `(u, v)`, undistorted as
/// OpenCV's `undistortPoints` does by default (five fixed-point
/// iterations), so that [`stereo_rectify`] places the principal points
/// where OpenCV does.
fn undistort(k: &[f64; 9], d: &[f64; 5], u: f64, v: f64) -> (f64, f64) {
    let [k1, k2, p1, p2, k3] = *d;
    let y0 = (v - k[5]) / k[4];
    let x0 = (u - k[2] - k[1] * y0) / k[0];
    let (mut x, mut y) = (x0, y0);
    for _ in 0..5 {
        let r2 = x * x + y * y;
        let inverse = 1.0 / (1.0 + r2 * (k1 + r2 * (k2 + r2 * k3)));
        if inverse < 0.0 {
            return (x0, y0);
        }
        let dx = 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x);
        let dy = p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y;
        (x, y) = ((x0 - dx) * inverse, (y0 - dy) * inverse);
    }
    (x, y)
}

/// The rectifying rotations and projections of a horizontal pair, as
/// OpenCV's `stereoRectify` computes them with its defaults
/// (`CALIB_ZERO_DISPARITY`, `alpha = −1`): each camera is turned half of
/// the rotation between them, then both so that their x axis lies along
/// the baseline; the new focal length is the mean of the two vertical
/// ones, and the common principal point centres the undistorted image
/// corners. Returned as the two cameras' `camera_info`.
pub fn stereo_rectify(calibration: &StereoCalibrationFile) -> (CameraInfo, CameraInfo) {
    let c = calibration;
    let r = Rotation3::from_matrix(&Matrix3::from_row_slice(&c.r));
    let t = Vector3::from(c.t);
    let half = Rotation3::new(-0.5 * r.scaled_axis());
    let t_half = half * t;
    // Turn the baseline onto the x axis.
    let axis = Vector3::new(t_half.x.signum(), 0.0, 0.0);
    let w = t_half.cross(&axis);
    let w = if w.norm() > 0.0 { w * ((t_half.x.abs() / t_half.norm()).acos() / w.norm()) } else { w };
    let onto_x = Rotation3::new(w);
    let r1 = (onto_x * half.inverse()).into_inner();
    let r2 = (onto_x * half).into_inner();
    let t_rectified = r2 * t;
    let focal = 0.5 * (c.k1[4] + c.k2[4]);
    // Each camera's principal point: the one that centres its undistorted,
    // rotated image corners; with zero disparity, both get their mean.
    let (w_px, h_px) = (f64::from(c.width), f64::from(c.height));
    let centre = |k: &[f64; 9], d: &[f64; 5], rotation: &Matrix3<f64>| {
        let mut sum = (0.0, 0.0);
        for (u, v) in [(0.0, 0.0), (w_px - 1.0, 0.0), (0.0, h_px - 1.0), (w_px - 1.0, h_px - 1.0)] {
            // OpenCV passes the corners as 32-bit floats.
            let (x, y) = undistort(k, d, f64::from(u as f32), f64::from(v as f32));
            let p = rotation * Vector3::new(x, y, 1.0);
            sum = (sum.0 + focal * p.x / p.z, sum.1 + focal * p.y / p.z);
        }
        ((w_px - 1.0) / 2.0 - sum.0 / 4.0, (h_px - 1.0) / 2.0 - sum.1 / 4.0)
    };
    let (a, b) = (centre(&c.k1, &c.d1, &r1), centre(&c.k2, &c.d2, &r2));
    let (cx, cy) = (0.5 * (a.0 + b.0), 0.5 * (a.1 + b.1));
    let projection = |shift: f64| [focal, 0.0, cx, shift, 0.0, focal, cy, 0.0, 0.0, 0.0, 1.0, 0.0];
    let row_major = |m: &Matrix3<f64>| {
        let mut out = [0.0; 9];
        for (i, slot) in out.iter_mut().enumerate() {
            *slot = m[(i / 3, i % 3)];
        }
        out
    };
    let info = |k: [f64; 9], d: [f64; 5], r: &Matrix3<f64>, p: [f64; 12]| CameraInfo {
        width: c.width,
        height: c.height,
        k,
        d,
        r: row_major(r),
        p,
    };
    (info(c.k1, c.d1, &r1, projection(0.0)), info(c.k2, c.d2, &r2, projection(t_rectified.x * focal)))
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
    pub fn new(left: &CameraInfo, right: &CameraInfo) -> Result<Rectifier, CalibrationError> {
        let (pl, pr) = (&left.p, &right.p);
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-6 * a.abs().max(1.0);
        let not_rectified = CalibrationError::NotRectified;
        if (left.width, left.height) != (right.width, right.height) {
            return Err(not_rectified("the two cameras' images differ in size".into()));
        }
        if !(close(pl[0], pr[0]) && close(pl[5], pr[5]) && close(pl[6], pr[6]) && close(pl[0], pl[5])) {
            return Err(not_rectified(format!(
                "projection_matrix: the pair is not rectified to one camera (fx {} and {}, fy {} and {}, cy {} and \
                 {}; fx must equal fy)",
                pl[0], pr[0], pl[5], pr[5], pl[6], pr[6]
            )));
        }
        let baseline = (pl[3] - pr[3]) / pl[0];
        if baseline <= 0.0 || pr[7] != 0.0 || pr[11] != 0.0 {
            return Err(not_rectified(format!(
                "projection_matrix: the right camera must sit to the right of the left one, along x only \
                 (P[0,3] {} and {})",
                pl[3], pr[3]
            )));
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
        ubf_core::config::Check::check(&camera).map_err(not_rectified)?;
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

/// The rectifier for a pair calibrated but never rectified, from the
/// OpenCV `FileStorage` file at `path` (see [`StereoCalibrationFile`]).
pub fn load_stereo(path: &Path) -> Result<Rectifier, CalibrationError> {
    let (left, right) = stereo_rectify(&StereoCalibrationFile::load(path)?);
    Rectifier::new(&left, &right)
        .map_err(|e| CalibrationError::Pair { files: path.display().to_string(), problem: Box::new(e) })
}

/// The rectifier for the pair whose `camera_info` files are `left` and
/// `right`.
pub fn load_pair(left: &Path, right: &Path) -> Result<Rectifier, CalibrationError> {
    Rectifier::new(&CameraInfo::load(left)?, &CameraInfo::load(right)?).map_err(|e| CalibrationError::Pair {
        files: format!("{} and {}", left.display(), right.display()),
        problem: Box::new(e),
    })
}
