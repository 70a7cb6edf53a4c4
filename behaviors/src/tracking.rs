//! The landmark tracking list (thesis §3.5.2.1): where usable landmarks are,
//! remembered after they leave the field of view, so that headings can be
//! evaluated in software instead of by turning to look.

use serde::Deserialize;
use ubf_core::config::{non_negative, positive};
use ubf_core::{Descriptor, LandmarkObservation, Pose2, StereoCamera};
use ubf_perception::egomotion::MatchConfig;

/// Settings of the tracking list.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct TrackingConfig {
    /// Descriptor matching against the list (eq. 30–34).
    #[serde(default)]
    pub matching: MatchConfig,
    /// Position gate (eq. 35) at zero range, m…
    #[serde(deserialize_with = "non_negative")]
    pub gate_m: f64,
    /// …growing by this much per metre of range, as stereo depth error does.
    #[serde(deserialize_with = "non_negative")]
    pub gate_per_m: f64,
    /// Drop a landmark once the robot sees it from this much further round
    /// than when it last saw it (the thesis: 20°, as descriptor matching falls
    /// below 80 % past about 30°).
    #[serde(deserialize_with = "positive")]
    pub drop_viewpoint_deg: f64,
}

impl Default for TrackingConfig {
    fn default() -> Self {
        TrackingConfig { matching: MatchConfig::default(), gate_m: 0.5, gate_per_m: 0.05, drop_viewpoint_deg: 20.0 }
    }
}

/// One remembered landmark.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrackedLandmark {
    /// World position on the floor plane, m (eq. 28–29).
    pub position: (f64, f64),
    /// Height above the floor, m.
    pub height: f64,
    /// Its descriptor when last seen.
    pub descriptor: Descriptor,
    /// The world direction from the robot to it when last seen, as a unit
    /// vector (eq. 37).
    pub seen_along: (f64, f64),
    /// Times it was seen where the list expected it. A landmark seen once
    /// may be a wrong stereo match or a look-alike of another; it is
    /// planned with only once seen again within the gate.
    pub sightings: u32,
}

/// What one update did, for tests and logs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TrackingUpdate {
    /// Observations matched to a remembered landmark.
    pub matched: usize,
    /// Observations registered as new landmarks (unconfirmed until seen
    /// again within the gate).
    pub registered: usize,
    /// Observations that looked like a confirmed landmark but lay outside
    /// its gate: a look-alike or a wrong stereo match, ignored.
    pub outside_gate: usize,
    /// Observations ignored because two remembered landmarks looked alike.
    pub ambiguous: usize,
    /// Landmarks dropped for a changed viewpoint.
    pub dropped: usize,
}

/// The tracking list.
#[derive(Clone, Debug, Default)]
pub struct TrackingList {
    config: TrackingConfig,
    entries: Vec<TrackedLandmark>,
    /// Scratch: the entries within an observation's gate.
    in_gate: Vec<usize>,
}

/// `(x, y)` scaled to unit length (the x axis for a zero vector).
fn unit(x: f64, y: f64) -> (f64, f64) {
    let length = x.hypot(y);
    if length > 0.0 {
        (x / length, y / length)
    } else {
        (1.0, 0.0)
    }
}

/// Where an observation is in the world, from the robot's pose (eq. 25–29):
/// on the floor plane, and its height above the floor, m.
pub fn world_position(observation: &LandmarkObservation, camera: &StereoCamera, pose: &Pose2) -> [f64; 3] {
    let [forward, left, height] = camera.mount.cam_to_robot(observation.point_cam);
    let (x, y) = pose.transform_point(forward, left);
    [x, y, height]
}

impl TrackingList {
    /// An empty list.
    pub fn new(config: TrackingConfig) -> Self {
        TrackingList { config, entries: Vec::new(), in_gate: Vec::new() }
    }

    /// The remembered landmarks.
    pub fn landmarks(&self) -> &[TrackedLandmark] {
        &self.entries
    }

    /// The landmarks seen at least twice where expected: those worth
    /// planning with.
    pub fn confirmed(&self) -> impl Iterator<Item = &TrackedLandmark> {
        self.entries.iter().filter(|e| e.sightings >= 2)
    }

    /// Forgets everything.
    pub fn clear(&mut self) {
        self.entries.clear();
    }

    /// Takes in one frame's observations seen from `pose`. Each is matched
    /// by descriptor (nearest, within the threshold, clearly nearer than the
    /// second, eq. 30–34) among the landmarks within its position gate
    /// (eq. 35) and updates it, or, failing that, is registered as a new,
    /// unconfirmed landmark. One that resembles a confirmed landmark lying
    /// outside its gate is a look-alike or a wrong stereo match and is
    /// ignored: it must not enter the list as a landmark of its own.
    pub fn observe(
        &mut self,
        observations: &[LandmarkObservation],
        camera: &StereoCamera,
        pose: &Pose2,
    ) -> TrackingUpdate {
        let mut update = TrackingUpdate::default();
        for obs in observations {
            let [x, y, height] = world_position(obs, camera, pose);
            let position = (x, y);
            let range = pose.distance_to(position.0, position.1);
            let seen_along = unit(position.0 - pose.x, position.1 - pose.y);
            let fresh = TrackedLandmark { position, height, descriptor: obs.descriptor, seen_along, sightings: 1 };
            let gate = self.config.gate_m + self.config.gate_per_m * range;
            self.in_gate.clear();
            self.in_gate.extend((0..self.entries.len()).filter(|&i| {
                let e = &self.entries[i].position;
                (e.0 - position.0).hypot(e.1 - position.1) <= gate
            }));
            let matching = &self.config.matching;
            match matching.best_match(&obs.descriptor, self.in_gate.iter().map(|&i| &self.entries[i].descriptor)) {
                Ok(k) => {
                    // The thesis keeps only the latest position (§3.5.2.1).
                    let entry = &mut self.entries[self.in_gate[k]];
                    *entry = TrackedLandmark { sightings: entry.sightings + 1, ..fresh };
                    update.matched += 1;
                }
                Err(true) => update.ambiguous += 1,
                Err(false) => {
                    let confirmed = self.entries.iter().filter(|e| e.sightings >= 2).map(|e| &e.descriptor);
                    if matching.best_match(&obs.descriptor, confirmed).is_ok() {
                        update.outside_gate += 1;
                    } else {
                        self.entries.push(fresh);
                        update.registered += 1;
                    }
                }
            }
        }
        update
    }

    /// After a step: drops every landmark the robot now sees from more than
    /// the drop angle away from where it last saw it (eq. 37).
    pub fn prune(&mut self, pose: &Pose2) -> usize {
        let cos_limit = self.config.drop_viewpoint_deg.to_radians().cos();
        let before = self.entries.len();
        self.entries.retain(|e| {
            let now = unit(e.position.0 - pose.x, e.position.1 - pose.y);
            now.0 * e.seen_along.0 + now.1 * e.seen_along.1 >= cos_limit
        });
        before - self.entries.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn calibration() -> StereoCamera {
        StereoCamera { focal_px: 554.0, ..StereoCamera::default() }
    }

    fn obs(point_cam: [f64; 3], seed: u64) -> LandmarkObservation {
        let d = Descriptor([seed.wrapping_mul(0x9e37_79b9_7f4a_7c15), seed.rotate_left(17), !seed, seed << 3]);
        LandmarkObservation { point_cam, descriptor: d, ..LandmarkObservation::default() }
    }

    #[test]
    fn converts_camera_to_world() {
        // 10 m ahead, 2 m right and 0.5 m above the cameras of a robot at
        // (1, 1) facing +y.
        let p = world_position(
            &obs([2.0, 10.0, 0.5], 1),
            &calibration(),
            &Pose2::new(1.0, 1.0, std::f64::consts::FRAC_PI_2),
        );
        let height = calibration().mount.height + 0.5;
        assert!((p[0] - 3.0).abs() < 1e-12 && (p[1] - 11.0).abs() < 1e-12 && (p[2] - height).abs() < 1e-12, "{p:?}");
    }

    #[test]
    fn registers_then_matches_then_drops() {
        let mut list = TrackingList::new(TrackingConfig::default());
        let pose = Pose2::default();
        let seen = [obs([-1.0, 5.0, 0.0], 1), obs([2.0, 8.0, 0.0], 2)];
        assert_eq!(list.observe(&seen, &calibration(), &pose).registered, 2);
        // The same landmarks a step later: matched, not registered again.
        let later = Pose2::new(0.5, 0.0, 0.0);
        let again = [obs([-1.0, 4.5, 0.0], 1), obs([2.0, 7.5, 0.0], 2)];
        let u = list.observe(&again, &calibration(), &later);
        assert_eq!((u.matched, u.registered), (2, 0));
        assert_eq!(list.landmarks().len(), 2);
        // Driving past the first landmark turns the view of it by far more
        // than 20°; the far one stays.
        assert_eq!(list.prune(&Pose2::new(4.0, 0.0, 0.0)), 1);
        assert_eq!(list.landmarks().len(), 1);
    }

    #[test]
    fn a_lookalike_outside_the_gate_is_not_a_landmark() {
        let mut list = TrackingList::new(TrackingConfig::default());
        let pose = Pose2::default();
        list.observe(&[obs([0.0, 5.0, 0.0], 1)], &calibration(), &pose);
        assert_eq!(list.confirmed().count(), 0, "seen once: not yet planned with");
        list.observe(&[obs([0.0, 5.1, 0.0], 1)], &calibration(), &pose);
        assert_eq!(list.confirmed().count(), 1);
        let u = list.observe(&[obs([0.0, 15.0, 0.0], 1)], &calibration(), &pose);
        assert_eq!((u.registered, u.outside_gate), (0, 1));
        assert_eq!(list.landmarks().len(), 1);
        assert!((list.landmarks()[0].position.0 - 5.1).abs() < 1e-9);
        // A different landmark there is a landmark.
        let mut other = obs([0.0, 15.0, 0.0], 1);
        other.descriptor = Descriptor(other.descriptor.0.map(|w| !w));
        let u = list.observe(&[other], &calibration(), &pose);
        assert_eq!(u.registered, 1);
    }

    #[test]
    fn a_first_sighting_out_of_place_never_confirms() {
        // A wrong stereo match registered the landmark 10 m off; the next
        // sightings register and confirm it where it is.
        let mut list = TrackingList::new(TrackingConfig::default());
        let pose = Pose2::default();
        list.observe(&[obs([0.0, 15.0, 0.0], 1)], &calibration(), &pose);
        list.observe(&[obs([0.0, 5.0, 0.0], 1)], &calibration(), &pose);
        list.observe(&[obs([0.0, 5.1, 0.0], 1)], &calibration(), &pose);
        let confirmed: Vec<_> = list.confirmed().collect();
        assert_eq!(confirmed.len(), 1);
        assert!((confirmed[0].position.0 - 5.1).abs() < 1e-9);
    }
}
