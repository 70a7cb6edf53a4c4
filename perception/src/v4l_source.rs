//! Live stereo pairs from two Video4Linux cameras (the `v4l` feature).
//!
//! Each camera is opened at the calibrated size in 8-bit grey if it offers
//! it, else YUYV (whose luma is the grey image), and streamed through
//! memory-mapped buffers. The two are read one after the other, so their
//! exposures are as far apart as one frame at most: on a moving robot use
//! cameras that trigger together. The pipeline expects rectified pairs:
//! cameras mechanically aligned, or a stereo module that rectifies on
//! board. This source has been compiled, not run against cameras.

use crate::source::{CameraSource, SourceError, StereoPair};
use image::GrayImage;
use std::path::{Path, PathBuf};
use std::time::Instant;
use v4l::buffer::Type;
use v4l::io::mmap::Stream;
use v4l::io::traits::CaptureStream;
use v4l::video::Capture;
use v4l::{Device, FourCC};

/// One camera's stream and the layout of its frames.
struct Camera {
    path: PathBuf,
    stream: Stream<'static>,
    /// Bytes per row, and whether pixels are YUYV (two bytes, luma first).
    stride: usize,
    yuyv: bool,
    size: (u32, u32),
}

impl Camera {
    fn open(path: &Path, width: u32, height: u32) -> Result<Camera, SourceError> {
        let io = |source| SourceError::Io { path: path.to_owned(), source };
        let device = Device::with_path(path).map_err(io)?;
        let mut format = device.format().map_err(io)?;
        (format.width, format.height) = (width, height);
        let mut chosen = None;
        for fourcc in [FourCC::new(b"GREY"), FourCC::new(b"YUYV")] {
            format.fourcc = fourcc;
            let got = device.set_format(&format).map_err(io)?;
            if got.fourcc == fourcc && (got.width, got.height) == (width, height) {
                chosen = Some(got);
                break;
            }
        }
        let format = chosen.ok_or_else(|| SourceError::Image {
            path: path.to_owned(),
            message: format!("offers neither 8-bit grey nor YUYV at {width}×{height}"),
        })?;
        let stream = Stream::with_buffers(&device, Type::VideoCapture, 4).map_err(io)?;
        let yuyv = format.fourcc == FourCC::new(b"YUYV");
        // Some drivers leave the stride at 0: rows are then packed.
        let packed = width as usize * if yuyv { 2 } else { 1 };
        Ok(Camera {
            path: path.to_owned(),
            stream,
            stride: (format.stride as usize).max(packed),
            yuyv,
            size: (width, height),
        })
    }

    fn grab(&mut self) -> Result<GrayImage, SourceError> {
        let (buffer, _) = self.stream.next().map_err(|source| SourceError::Io { path: self.path.clone(), source })?;
        let (w, h) = (self.size.0 as usize, self.size.1 as usize);
        let step = if self.yuyv { 2 } else { 1 };
        if buffer.len() < self.stride * (h - 1) + w * step {
            return Err(SourceError::Image { path: self.path.clone(), message: "short frame".into() });
        }
        let mut pixels = Vec::with_capacity(w * h);
        for row in buffer.chunks(self.stride).take(h) {
            pixels.extend(row.iter().step_by(step).take(w));
        }
        GrayImage::from_raw(self.size.0, self.size.1, pixels)
            .ok_or_else(|| SourceError::Image { path: self.path.clone(), message: "short frame".into() })
    }
}

/// A stereo pair of Video4Linux cameras.
pub struct V4lStereo {
    left: Camera,
    right: Camera,
    started: Instant,
}

impl V4lStereo {
    /// Opens the two devices (`/dev/video0`, …) at `width` × `height`.
    pub fn open(left: &Path, right: &Path, width: u32, height: u32) -> Result<V4lStereo, SourceError> {
        Ok(V4lStereo {
            left: Camera::open(left, width, height)?,
            right: Camera::open(right, width, height)?,
            started: Instant::now(),
        })
    }
}

impl CameraSource for V4lStereo {
    fn next_pair(&mut self) -> Result<Option<StereoPair>, SourceError> {
        let time = self.started.elapsed().as_secs_f64();
        let left = self.left.grab()?;
        let right = self.right.grab()?;
        Ok(Some(StereoPair { time, left, right }))
    }
}

#[cfg(test)]
mod tests {
    fn is_send<T: Send>() {}

    #[test]
    fn the_source_can_move_to_the_camera_thread() {
        is_send::<super::V4lStereo>();
    }
}
