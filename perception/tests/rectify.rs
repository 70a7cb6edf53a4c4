//! Our rectification against OpenCV's, on the same calibration: OpenCV
//! 5.0.0's `FileStorage` wrote the unrectified calibration (`K1`, `D1`,
//! `K2`, `D2`, `R`, `T`) into `data/stereo.yaml`, its `stereoRectify` and
//! `initUndistortRectifyMap` the two camera_info files in `data/` and the
//! sample points below (`scripts/rectify-reference.py` regenerates all).

use std::path::Path;
use ubf_perception::rectify::{stereo_rectify, CameraInfo, Rectifier, StereoCalibrationFile};

/// (camera, rectified u, v, OpenCV's raw x, y).
const OPENCV: &[(&str, u32, u32, f64, f64)] = &[
    ("left", 0, 0, 94.6614, 73.6903),
    ("left", 160, 0, 207.3454, 55.1292),
    ("left", 320, 0, 337.0241, 39.0692),
    ("left", 480, 0, 480.7654, 27.3158),
    ("left", 640, 0, 632.4764, 21.1570),
    ("left", 800, 0, 784.2974, 21.1369),
    ("left", 960, 0, 928.3911, 26.9766),
    ("left", 1120, 0, 1058.6609, 37.6358),
    ("left", 0, 90, 87.4007, 146.0302),
    ("left", 160, 90, 201.0925, 130.7958),
    ("left", 320, 90, 332.7471, 117.4664),
    ("left", 480, 90, 479.2102, 107.4717),
    ("left", 640, 90, 634.0283, 101.8475),
    ("left", 800, 90, 788.9230, 101.0598),
    ("left", 960, 90, 935.6546, 104.9350),
    ("left", 1120, 90, 1067.8063, 112.6969),
    ("left", 0, 180, 82.4131, 221.3772),
    ("left", 160, 180, 196.9039, 210.0423),
    ("left", 320, 180, 330.0717, 199.9049),
    ("left", 480, 180, 478.5899, 191.9673),
    ("left", 640, 180, 635.7349, 186.9843),
    ("left", 800, 180, 792.9188, 185.3356),
    ("left", 960, 180, 941.6057, 186.9651),
    ("left", 1120, 180, 1075.1442, 191.3922),
    ("left", 0, 270, 79.9783, 298.8503),
    ("left", 160, 270, 195.0168, 291.8189),
    ("left", 320, 270, 329.1634, 285.1997),
    ("left", 480, 270, 478.9804, 279.5324),
    ("left", 640, 270, 637.5753, 275.2709),
    ("left", 800, 270, 796.1696, 272.7024),
    ("left", 960, 270, 946.0470, 271.8957),
    ("left", 1120, 270, 1080.4152, 272.6864),
    ("left", 0, 360, 80.2610, 377.4071),
    ("left", 160, 360, 195.5664, 374.8892),
    ("left", 320, 360, 330.1110, 371.9611),
    ("left", 480, 360, 480.4138, 368.6821),
    ("left", 640, 360, 639.5211, 365.1935),
    ("left", 800, 360, 798.5886, 361.6853),
    ("left", 960, 360, 948.8416, 358.3542),
    ("left", 1120, 360, 1083.4449, 355.3610),
    ("left", 0, 450, 83.2994, 455.9225),
    ("left", 160, 450, 198.5783, 457.9207),
    ("left", 320, 450, 332.9221, 458.6946),
    ("left", 480, 450, 482.8767, 457.8209),
    ("left", 640, 450, 641.5379, 455.1256),
    ("left", 800, 450, 800.1227, 450.6992),
    ("left", 960, 450, 949.9205, 444.8631),
    ("left", 1120, 450, 1084.1545, 438.1012),
    ("left", 0, 540, 89.0030, 533.2752),
    ("left", 160, 540, 203.9670, 539.5847),
    ("left", 320, 540, 337.5229, 543.9080),
    ("left", 480, 540, 486.3122, 545.3548),
    ("left", 640, 540, 643.5883, 543.4419),
    ("left", 800, 540, 800.7551, 538.1588),
    ("left", 960, 540, 949.2877, 529.9439),
    ("left", 1120, 540, 1082.5658, 519.5912),
    ("left", 0, 630, 97.1582, 608.4354),
    ("left", 160, 630, 211.5412, 618.6553),
    ("left", 320, 630, 343.7630, 626.2202),
    ("left", 480, 630, 490.6228, 629.8042),
    ("left", 640, 630, 645.6342, 628.6308),
    ("left", 800, 630, 800.5075, 622.5892),
    ("left", 960, 630, 947.0198, 612.2221),
    ("left", 1120, 630, 1078.8005, 598.6091),
    ("right", 0, 0, 89.5788, 64.7268),
    ("right", 160, 0, 203.5241, 46.3364),
    ("right", 320, 0, 333.8592, 30.2432),
    ("right", 480, 0, 477.6549, 18.1033),
    ("right", 640, 0, 629.1626, 11.1316),
    ("right", 800, 0, 781.0193, 9.9162),
    ("right", 960, 0, 925.7910, 14.3118),
    ("right", 1120, 0, 1057.5717, 23.4262),
    ("right", 0, 90, 83.3957, 137.4371),
    ("right", 160, 90, 198.3592, 122.3180),
    ("right", 320, 90, 330.5761, 108.9221),
    ("right", 480, 90, 476.8986, 98.5547),
    ("right", 640, 90, 631.2686, 92.1964),
    ("right", 800, 90, 785.9656, 90.3544),
    ("right", 960, 90, 933.1938, 92.9712),
    ("right", 1120, 90, 1066.7272, 99.4025),
    ("right", 0, 180, 79.3431, 212.9273),
    ("right", 160, 180, 195.1090, 201.6025),
    ("right", 320, 180, 328.7545, 191.3227),
    ("right", 480, 180, 476.9664, 183.0073),
    ("right", 640, 180, 633.4588, 177.3782),
    ("right", 800, 180, 790.2502, 174.8497),
    ("right", 960, 180, 939.2820, 175.4531),
    ("right", 1120, 180, 1074.0963, 178.8071),
    ("right", 0, 270, 77.6623, 290.3564),
    ("right", 160, 270, 193.9659, 283.1896),
    ("right", 320, 270, 328.5205, 276.3195),
    ("right", 480, 270, 477.9073, 270.2553),
    ("right", 640, 270, 635.6992, 265.4434),
    ("right", 800, 270, 793.7565, 262.1961),
    ("right", 960, 270, 943.8629, 260.6330),
    ("right", 1120, 270, 1079.4230, 260.6447),
    ("right", 0, 360, 78.4892, 368.7370),
    ("right", 160, 360, 195.0336, 365.9164),
    ("right", 320, 360, 329.9358, 362.6115),
    ("right", 480, 360, 479.7344, 358.9088),
    ("right", 640, 360, 637.9521, 354.9700),
    ("right", 800, 360, 796.3967, 350.9995),
    ("right", 960, 360, 946.8033, 347.2034),
    ("right", 1120, 360, 1082.5366, 343.7469),
    ("right", 0, 450, 81.8498, 447.0085),
    ("right", 160, 450, 198.3238, 448.5384),
    ("right", 320, 450, 332.9957, 448.8098),
    ("right", 480, 450, 482.4261, 447.4857),
    ("right", 640, 450, 640.1789, 444.4413),
    ("right", 800, 450, 798.1168, 439.7706),
    ("right", 960, 450, 948.0360, 433.7633),
    ("right", 1120, 450, 1083.3601, 426.8562),
    ("right", 0, 540, 87.6596, 524.1149),
    ("right", 160, 540, 203.7567, 529.8154),
    ("right", 320, 540, 337.6308, 533.5296),
    ("right", 480, 540, 485.9274, 534.5075),
    ("right", 640, 540, 642.3423, 532.3434),
    ("right", 800, 540, 798.8990, 527.0220),
    ("right", 960, 540, 947.5629, 518.9125),
    ("right", 1120, 540, 1081.9135, 508.7149),
    ("right", 0, 630, 95.7285, 599.0812),
    ("right", 160, 630, 211.1658, 608.5974),
    ("right", 320, 630, 343.7104, 615.4822),
    ("right", 480, 630, 490.1534, 618.5953),
    ("right", 640, 630, 644.4092, 617.2632),
    ("right", 800, 630, 798.7639, 611.3655),
    ("right", 960, 630, 945.4560, 601.3459),
    ("right", 1120, 630, 1078.3140, 588.1536),
];

fn load(name: &str) -> CameraInfo {
    CameraInfo::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data").join(format!("{name}.yaml"))).unwrap()
}

/// The largest disagreement, px, between `rectifier`'s tables and
/// OpenCV's at the sample points.
fn worst_disagreement(rectifier: &Rectifier) -> f64 {
    let (left, right) = rectifier.tables();
    let mut worst = 0.0f64;
    for &(camera, u, v, x, y) in OPENCV {
        let table = if camera == "left" { left } else { right };
        let [ours_x, ours_y] = table.source_of(u, v).unwrap();
        worst = worst.max((f64::from(ours_x) - x).abs()).max((f64::from(ours_y) - y).abs());
    }
    worst
}

#[test]
fn remap_tables_agree_with_opencv_within_a_tenth_of_a_pixel() {
    let worst = worst_disagreement(&Rectifier::new(&load("left"), &load("right")).unwrap());
    eprintln!("worst disagreement with OpenCV: {worst} px");
    assert!(worst < 0.1, "worst disagreement {worst} px");
    assert_eq!(OPENCV.len(), 128);
}

#[test]
fn the_rectified_pair_has_the_projections_calibration() {
    let camera = Rectifier::new(&load("left"), &load("right")).unwrap().camera();
    assert_eq!((camera.width_px, camera.height_px), (1280, 720));
    assert!((camera.baseline_m - 0.12).abs() < 1e-3, "{}", camera.baseline_m);
    assert!((camera.focal_px - 906.3).abs() < 1e-6);
    assert_eq!(camera.disparity_offset_px, 0.0, "CALIB_ZERO_DISPARITY");
}

#[test]
fn broken_camera_info_is_refused_with_its_place() {
    let text = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/left.yaml")).unwrap();
    let err = CameraInfo::from_yaml(&text.replace("rows: 3\n  cols: 4", "rows: 3\n  cols: 3")).unwrap_err().to_string();
    assert!(err.contains("projection_matrix: expected 3 × 4"), "{err}");
    let err = CameraInfo::from_yaml(&text.replace("image_height: 720", "image_height: [720")).unwrap_err().to_string();
    assert!(err.starts_with("2:"), "{err}");
    let err = CameraInfo::from_yaml(&text.replace("plumb_bob", "equidistant")).unwrap_err().to_string();
    assert!(err.contains("distortion_model"), "{err}");
    // Swapped cameras put the right one on the left.
    assert!(Rectifier::new(&load("right"), &load("left")).unwrap_err().to_string().contains("to the right"));
}

fn stereo_file() -> StereoCalibrationFile {
    StereoCalibrationFile::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/stereo.yaml")).unwrap()
}

#[test]
fn stereo_rectify_gives_opencvs_rotations_and_projections() {
    let (left, right) = stereo_rectify(&stereo_file());
    for (ours, theirs) in [(&left, load("left")), (&right, load("right"))] {
        assert_eq!((ours.k, ours.d), (theirs.k, theirs.d));
        for (a, b) in ours.r.iter().zip(&theirs.r) {
            assert!((a - b).abs() < 1e-9, "R {:?} against OpenCV's {:?}", ours.r, theirs.r);
        }
        for (a, b) in ours.p.iter().zip(&theirs.p) {
            assert!((a - b).abs() < 1e-4, "P {:?} against OpenCV's {:?}", ours.p, theirs.p);
        }
    }
}

#[test]
fn an_unrectified_calibration_is_rectified_as_opencv_does_it() {
    let (left, right) = stereo_rectify(&stereo_file());
    let worst = worst_disagreement(&Rectifier::new(&left, &right).unwrap());
    eprintln!("worst disagreement with OpenCV, from K, D, R, T: {worst} px");
    assert!(worst < 0.1, "worst disagreement {worst} px");
}

#[test]
fn a_broken_stereo_calibration_is_refused_with_its_place() {
    let text = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/stereo.yaml")).unwrap();
    // OpenCV before 4 wrote `%YAML:1.0`; both headers are read.
    let old = text.replace("%YAML 1.2", "%YAML:1.0");
    assert_eq!(StereoCalibrationFile::from_yaml(&old).unwrap(), stereo_file());
    let err = StereoCalibrationFile::from_yaml(&text.replace("image_height: 720", "image_height: [720"))
        .unwrap_err()
        .to_string();
    assert!(err.starts_with("4:"), "{err}");
    let err = StereoCalibrationFile::from_yaml(&text.replacen("rows: 3", "rows: 2", 1)).unwrap_err().to_string();
    assert!(err.contains("K1: expected 3 × 3"), "{err}");
    let err = StereoCalibrationFile::from_yaml(&text.replace("T: !!opencv-matrix", "Tx: !!opencv-matrix"))
        .unwrap_err()
        .to_string();
    assert!(err.contains("missing field `T`"), "{err}");
    // Cameras one above the other are not a horizontal pair.
    let err = StereoCalibrationFile::from_yaml(&text.replace("[ -0.12, 0.0030000000000000001,", "[ 0.001, -0.12,"))
        .unwrap_err()
        .to_string();
    assert!(err.contains("side by side"), "{err}");
}
