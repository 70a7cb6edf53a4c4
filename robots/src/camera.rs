//! Cameras on any robot: a wrapper that takes stereo pairs from a
//! [`CameraSource`], runs the feature pipeline on a thread of its own, and
//! puts the newest frame's landmarks in the state, so the control loop
//! never waits for an image.

use crate::timed_readings::TimedReadings;
use crossbeam_channel::{Receiver, TryRecvError};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};
use ubf_core::{Aim, LandmarkObservation, PanTilt, Robot, RobotError, RobotWrapper, State, StereoImages, Wraps};
use ubf_perception::features::{FeatureConfig, PipelineError, StereoPipeline};
use ubf_perception::source::{CameraSource, SourceError};
use ubf_perception::StereoCamera;

/// What went wrong with the camera: the fault a [`RobotError::Camera`]
/// carries.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum CameraFault {
    /// The source could not give a pair (a device gone, an unreadable
    /// file).
    #[error(transparent)]
    Source(#[from] SourceError),
    /// The feature pipeline refused a pair.
    #[error(transparent)]
    Pipeline(#[from] PipelineError),
    /// A recorded pair's time, s, is too far off to be waited for.
    #[error("a pair's time, {0} s, is beyond any clock")]
    TimeBeyondAnyClock(f64),
    /// The camera's thread panicked, with this message.
    #[error("the camera's thread panicked: {0}")]
    Panicked(String),
}

/// A processed pair: when it was taken, what was found in it, and the pair
/// itself. The instant becomes a time on the controller's clock when the
/// frame reaches a tick ([`CameraRobot`]'s `sense`).
type Frame = (Instant, Vec<LandmarkObservation>, Arc<StereoImages>);

/// The camera's thread and what comes out of it.
struct CameraThread {
    frames: Receiver<Result<Frame, CameraFault>>,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

/// Wraps a robot with a stereo camera, on a pan-tilt unit or not. Without
/// a camera it passes everything straight through.
pub struct CameraRobot<R> {
    inner: R,
    camera: Option<(StereoCamera, CameraThread)>,
    frames: u64,
    /// The unit the camera rides on, and the tilt it holds, rad.
    pan_tilt: Option<(Box<dyn PanTilt>, f64)>,
    /// The unit's recent readings, for the angles when a pair was taken.
    head: TimedReadings<Instant, Aim>,
    /// The unit's first reading, the mean of many: frames take it until
    /// the head is first sent anywhere, as egomotion's map is anchored on
    /// the first frame.
    anchor: Option<Aim>,
    /// When the unit was first sent anywhere: until then it stands where
    /// it started, and a frame takes the `anchor`.
    first_command: Option<Instant>,
}

impl<R: Robot> CameraRobot<R> {
    /// `inner` without a camera.
    pub fn without_camera(inner: R) -> Self {
        CameraRobot {
            inner,
            camera: None,
            frames: 0,
            pan_tilt: None,
            head: TimedReadings::default(),
            anchor: None,
            first_command: None,
        }
    }

    /// `inner` with pairs from `source`, calibrated as `camera`. With
    /// `paced`, pairs are taken at the times the source gives (a recording
    /// replayed in real time); otherwise as fast as they come (a live
    /// camera, which paces itself).
    pub fn new(
        inner: R,
        mut source: Box<dyn CameraSource + Send>,
        camera: StereoCamera,
        features: FeatureConfig,
        paced: bool,
    ) -> Result<Self, RobotError> {
        // One frame of slack: a slow pipeline drops pairs rather than
        // falling ever further behind.
        let (sender, frames) = crossbeam_channel::bounded(1);
        let stop = Arc::new(AtomicBool::new(false));
        let flag = Arc::clone(&stop);
        let pipeline = StereoPipeline::new(camera, features);
        let thread = std::thread::Builder::new()
            .name("stereo-camera".into())
            .spawn(move || {
                // A panic here would leave the robot driving on a camera
                // that no longer delivers: it becomes a camera fault.
                let run = || take_pairs(source.as_mut(), &pipeline, &sender, &flag, paced);
                if let Err(panic) = ubf_core::catch_reported(run) {
                    let why = ubf_core::panic_message(panic.as_ref());
                    let _ = sender.send(Err(CameraFault::Panicked(why)));
                }
            })
            .map_err(RobotError::Io)?;
        Ok(CameraRobot {
            inner,
            camera: Some((camera, CameraThread { frames, stop, thread: Some(thread) })),
            frames: 0,
            pan_tilt: None,
            head: TimedReadings::default(),
            anchor: None,
            first_command: None,
        })
    }

    /// The camera rides on `unit`, holding its mount's tilt: the unit is
    /// aimed by [`Robot::aim_camera`], its encoders are read every tick
    /// into [`State::camera_aim`], and each new frame's calibration
    /// carries the mount at the angles of when its pair was taken,
    /// interpolated between the readings either side. Until the head is
    /// first sent anywhere, a frame takes the first tick's reading, many
    /// readings' mean ([`PanTilt::anchor_reading`]), since egomotion's
    /// map is anchored on the first frame.
    pub fn with_pan_tilt(mut self, unit: Box<dyn PanTilt>) -> Self {
        let tilt = self.camera.as_ref().map_or(0.0, |(camera, _)| camera.mount.tilt_deg.to_radians());
        self.pan_tilt = Some((unit, tilt));
        self
    }

    /// Frames delivered so far.
    pub fn frames(&self) -> u64 {
        self.frames
    }
}

/// The camera thread's work: pairs from `source` through `pipeline` into
/// `frames` until `stop`, the source ends, or it fails (the failure sent
/// on). With `paced`, each pair waits for its time from the first.
fn take_pairs(
    source: &mut (dyn CameraSource + Send),
    pipeline: &StereoPipeline,
    frames: &crossbeam_channel::Sender<Result<Frame, CameraFault>>,
    stop: &AtomicBool,
    paced: bool,
) {
    let started = Instant::now();
    let mut first_time = None;
    while !stop.load(Ordering::Relaxed) {
        let pair = match source.next_pair() {
            Ok(Some(pair)) => pair,
            Ok(None) => return,
            Err(e) => {
                let _ = frames.send(Err(e.into()));
                return;
            }
        };
        if paced {
            let offset = pair.time - *first_time.get_or_insert(pair.time);
            let Some(due) = Duration::try_from_secs_f64(offset.max(0.0)).ok().and_then(|d| started.checked_add(d))
            else {
                let _ = frames.send(Err(CameraFault::TimeBeyondAnyClock(pair.time)));
                return;
            };
            // In short naps, so that a stop is not kept waiting.
            while !stop.load(Ordering::Relaxed) && Instant::now() < due {
                std::thread::sleep(due.saturating_duration_since(Instant::now()).min(Duration::from_millis(50)));
            }
        }
        let taken = Instant::now();
        let found = pipeline.process(&pair.left, &pair.right).map_err(CameraFault::from);
        let frame = found.map(|landmarks| (taken, landmarks, Arc::new(pair.into_images())));
        match frames.try_send(frame) {
            Ok(()) | Err(crossbeam_channel::TrySendError::Full(_)) => {}
            Err(crossbeam_channel::TrySendError::Disconnected(_)) => return,
        }
    }
}

impl<R: Robot> Wraps for CameraRobot<R> {
    type Inner = R;
    fn inner(&self) -> &R {
        &self.inner
    }
    fn inner_mut(&mut self) -> &mut R {
        &mut self.inner
    }
}

impl<R: Robot> RobotWrapper for CameraRobot<R> {
    fn sense(&mut self, state: &mut State) -> Result<(), RobotError> {
        self.inner.sense(state)?;
        if let Some((unit, _)) = &mut self.pan_tilt {
            // The first tick's reading, before the tree has sent the head
            // anywhere, anchors egomotion's map: it is many readings' mean.
            let (at, aim) = match self.anchor {
                None => (Instant::now(), *self.anchor.insert(unit.anchor_reading()?)),
                Some(_) => unit.measured_at()?,
            };
            self.head.push(at, aim);
            state.camera_aim = Some(aim);
        }
        let Some((camera, thread)) = &mut self.camera else { return Ok(()) };
        loop {
            match thread.frames.try_recv() {
                Ok(Ok((taken, landmarks, images))) => {
                    // The angles when the pair was taken: the anchor's while
                    // the head stood where it started.
                    let aim = match (&self.pan_tilt, self.first_command) {
                        (None, _) => None,
                        (Some(_), Some(sent)) if taken >= sent => self.head.at(taken),
                        (Some(_), _) => self.anchor,
                    };
                    self.frames += 1;
                    state.stereo.number = self.frames;
                    // On the controller's clock: the tick's time less how
                    // long ago the pair was taken.
                    state.stereo.time = state.time - taken.elapsed().as_secs_f64();
                    state.stereo.landmarks = landmarks;
                    let mount = aim.map_or(camera.mount, |aim| camera.mount.aimed(aim.pan, aim.tilt));
                    state.stereo.calibration = Some(StereoCamera { mount, ..*camera });
                    state.stereo.images = Some(images);
                }
                Ok(Err(fault)) => return Err(RobotError::Camera(Box::new(fault))),
                // No new pair, or the source has ended: the last frame stays.
                Err(TryRecvError::Empty | TryRecvError::Disconnected) => return Ok(()),
            }
        }
    }

    fn shutdown(&mut self) -> Result<(), RobotError> {
        // A unit's driver halts the head as it goes.
        self.pan_tilt = None;
        if let Some((_, thread)) = &mut self.camera {
            thread.stop.store(true, Ordering::Relaxed);
            if let Some(handle) = thread.thread.take() {
                let _ = handle.join();
            }
        }
        self.inner.shutdown()
    }

    fn aim_camera(&mut self, pan: f64) -> Result<(), RobotError> {
        match &mut self.pan_tilt {
            Some((unit, tilt)) => {
                self.first_command.get_or_insert_with(Instant::now);
                unit.command(Aim { pan, tilt: *tilt })
            }
            None => self.inner.aim_camera(pan),
        }
    }
}
