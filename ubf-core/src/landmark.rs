//! Landmarks seen by a stereo camera: the observation type that the
//! simulator's camera model, the image pipeline and the egomotion estimators
//! all share.

use serde::{Deserialize, Serialize};
use std::sync::Arc;

/// A 256-bit binary feature descriptor (the size of ORB's), compared by
/// Hamming distance.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct Descriptor(pub [u64; 4]);

impl Descriptor {
    /// Number of bits in a descriptor.
    pub const BITS: u32 = 256;

    /// Number of differing bits.
    #[inline]
    pub fn hamming(&self, other: &Descriptor) -> u32 {
        self.0.iter().zip(&other.0).map(|(a, b)| (a ^ b).count_ones()).sum()
    }
}

/// Where a landmark appears in the left and right images, pixels from the
/// top-left corner (u to the right, v down).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct StereoPixels {
    /// Left image column.
    pub u_left: f64,
    /// Right image column.
    pub u_right: f64,
    /// Row (the images are rectified: the same in both).
    pub v: f64,
}

impl StereoPixels {
    /// `u_left − u_right`, pixels.
    pub fn disparity(&self) -> f64 {
        self.u_left - self.u_right
    }
}

/// One landmark seen in one stereo frame.
///
/// `point_cam` is in the thesis's camera frame: origin midway between the
/// cameras, x to the right, y ahead (depth), z up; metres. It was
/// triangulated from the (noisy) pixels, never taken from ground truth.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct LandmarkObservation {
    /// The triangulated position in the camera frame.
    pub point_cam: [f64; 3],
    /// The matched pixels it was triangulated from.
    pub pixels: StereoPixels,
    /// The left image's descriptor of the feature.
    pub descriptor: Descriptor,
    /// The simulator's identity of the landmark, for evaluation only; `None`
    /// from real images. Matchers must use the descriptor and position.
    pub source_id: Option<u32>,
}

/// The latest stereo frame's landmarks.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StereoFrame {
    /// Counts frames from 1; 0 means no frame yet. A behaviour sees a new
    /// frame when the number changes.
    pub number: u64,
    /// When the frame was taken, seconds on the controller's clock.
    pub time: f64,
    /// The landmarks matched in both images.
    pub landmarks: Vec<LandmarkObservation>,
    /// The camera that took the frame, so that whoever reads the frame (an
    /// error model, a behaviour) needs no copy of the camera's settings.
    pub calibration: Option<crate::StereoCamera>,
    /// The rectified pair the landmarks were found in, where the camera
    /// keeps it (a rendered or real camera; the geometric model has none):
    /// for logs and recordings. Shared, so copying a frame never copies
    /// its pixels.
    pub images: Option<Arc<StereoImages>>,
}

impl StereoFrame {
    /// Copies `other`, reusing this frame's buffer of landmarks.
    pub fn copy_from(&mut self, other: &StereoFrame) {
        let StereoFrame { number, time, landmarks, calibration, images } = other;
        self.number = *number;
        self.time = *time;
        self.landmarks.clone_from(landmarks);
        self.calibration = *calibration;
        self.images.clone_from(images);
    }
}

/// A rectified stereo pair: two 8-bit grey images of one size, row by row
/// from the top left.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct StereoImages {
    /// Pixels per row.
    pub width: u32,
    /// Rows.
    pub height: u32,
    /// The left image, `width × height` bytes.
    pub left: Vec<u8>,
    /// The right image, `width × height` bytes.
    pub right: Vec<u8>,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hamming_counts_differing_bits() {
        let a = Descriptor([0b1011, 0, u64::MAX, 1]);
        let b = Descriptor([0b0001, 0, 0, 1]);
        assert_eq!(a.hamming(&b), 2 + 64);
        assert_eq!(a.hamming(&a), 0);
    }
}
