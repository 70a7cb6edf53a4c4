//! The simulated world: walls, boxes, landmarks and people, from a scenario
//! file.
//!
//! A corridor runs along the world's x axis from `x = 0` to `x = length`,
//! between walls at `y = ±width/2`, closed at both ends. (The thesis's
//! figures run their corridor along y; here the robot starting at heading 0
//! looks down the corridor.)

use super::geometry::{Circle, Point, Segment};
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use serde::Deserialize;
use ubf_core::config::{coordinate_m, non_negative, positive, unit_interval, Check};
use ubf_core::Descriptor;

/// A point on the floor, m.
#[derive(Clone, Copy, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Xy {
    /// m.
    #[serde(deserialize_with = "coordinate_m")]
    pub x: f64,
    /// m.
    #[serde(deserialize_with = "coordinate_m")]
    pub y: f64,
}

/// A velocity on the floor, m/s: each component within ±10 m/s (faster
/// than anyone walks or runs, so a slip of the keyboard is caught; the
/// speed itself, up to 14 m/s, is not bounded further).
#[derive(Clone, Copy, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VelocityXy {
    /// m/s.
    #[serde(deserialize_with = "walking_m_s")]
    pub x: f64,
    /// m/s.
    #[serde(deserialize_with = "walking_m_s")]
    pub y: f64,
}

fn walking_m_s<'de, D: serde::Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    ubf_core::config::number_in(d, -10.0..=10.0, "from -10 to 10 m/s")
}

/// A corridor: two side walls and two end walls.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CorridorConfig {
    /// Wall to wall, m (0.01 to 10 000).
    #[serde(deserialize_with = "ubf_core::config::extent_m")]
    pub width: f64,
    /// End to end, m (0.01 to 10 000).
    #[serde(deserialize_with = "ubf_core::config::extent_m")]
    pub length: f64,
}

/// A straight wall.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WallConfig {
    /// One end.
    pub from: Xy,
    /// The other end.
    pub to: Xy,
}

/// A box standing on the floor, sides along the axes.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BoxConfig {
    /// Centre, m.
    #[serde(deserialize_with = "coordinate_m")]
    pub x: f64,
    /// Centre, m.
    #[serde(deserialize_with = "coordinate_m")]
    pub y: f64,
    /// Extent along x, m.
    #[serde(deserialize_with = "positive")]
    pub length: f64,
    /// Extent along y, m.
    #[serde(deserialize_with = "positive")]
    pub width: f64,
}

/// A corridor wall.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
pub enum Side {
    /// The wall at `y = +width/2`.
    Left,
    /// The wall at `y = −width/2`.
    Right,
}

/// A stretch of side wall with no features on it (thesis §4.4.10.2).
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FeaturelessConfig {
    /// Which wall.
    pub side: Side,
    /// Where the stretch starts, m along the corridor.
    #[serde(deserialize_with = "coordinate_m")]
    pub from: f64,
    /// Where it ends, m along the corridor.
    #[serde(deserialize_with = "coordinate_m")]
    pub to: f64,
}

/// A landmark at a given place.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LandmarkConfig {
    /// m.
    #[serde(deserialize_with = "coordinate_m")]
    pub x: f64,
    /// m.
    #[serde(deserialize_with = "coordinate_m")]
    pub y: f64,
    /// Height above the floor, m.
    #[serde(default = "LandmarkConfig::default_z", deserialize_with = "coordinate_m")]
    pub z: f64,
}

impl LandmarkConfig {
    fn default_z() -> f64 {
        1.0
    }
}

/// The most landmarks a world may hold, people's features counted: far
/// more than any corridor shows a camera (the thesis's had 16 to 80), and
/// few enough that matching a frame's against the last stays within a
/// fraction of a second.
pub const MOST_RANDOM_LANDMARKS: u32 = 10_000;

fn landmark_count<'de, D: serde::Deserializer<'de>>(d: D) -> Result<u32, D::Error> {
    let count = u32::deserialize(d)?;
    if count > MOST_RANDOM_LANDMARKS {
        return Err(serde::de::Error::custom(format!("{count}: at most {MOST_RANDOM_LANDMARKS} landmarks")));
    }
    Ok(count)
}

/// Landmarks drawn at random on the corridor's walls, as in the thesis's
/// simulations (§4.2.1): some on the side walls, the rest on the far end.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RandomLandmarks {
    /// How many, at most [`MOST_RANDOM_LANDMARKS`].
    #[serde(deserialize_with = "landmark_count")]
    pub count: u32,
    /// The share on the side walls; the rest go on the far end wall.
    #[serde(default = "RandomLandmarks::default_side_share", deserialize_with = "unit_interval")]
    pub side_share: f64,
    /// Lowest height, m.
    #[serde(default = "RandomLandmarks::default_min_height", deserialize_with = "non_negative")]
    pub min_height: f64,
    /// Highest height, m.
    #[serde(default = "RandomLandmarks::default_max_height", deserialize_with = "non_negative")]
    pub max_height: f64,
    /// A seed of the layout's own, so that one corridor can be driven with
    /// many run seeds; by default the run's seed draws the layout too.
    #[serde(default)]
    pub seed: Option<u64>,
}

impl RandomLandmarks {
    fn default_side_share() -> f64 {
        0.25
    }
    fn default_min_height() -> f64 {
        0.3
    }
    fn default_max_height() -> f64 {
        2.0
    }
}

/// A person walking at a steady velocity, turning back at the corridor's
/// walls; seen by the sonar as a cylinder and by the camera as landmarks that
/// move (thesis §4.4.10.4).
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PersonConfig {
    /// Where the person is at time 0.
    pub start: Xy,
    /// Walking velocity.
    pub velocity: VelocityXy,
    /// Body radius, m.
    #[serde(default = "PersonConfig::default_radius", deserialize_with = "positive")]
    pub radius: f64,
    /// Features on the person that the camera can pick up, at most
    /// [`MOST_RANDOM_LANDMARKS`].
    #[serde(default = "PersonConfig::default_features", deserialize_with = "landmark_count")]
    pub features: u32,
}

impl PersonConfig {
    fn default_radius() -> f64 {
        0.25
    }
    fn default_features() -> u32 {
        3
    }
}

/// Everything in the simulated world, as written in a scenario file. Empty
/// by default: an open floor.
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WorldConfig {
    /// A corridor along the x axis.
    #[serde(default)]
    pub corridor: Option<CorridorConfig>,
    /// Extra walls.
    #[serde(default)]
    pub walls: Vec<WallConfig>,
    /// Boxes on the floor.
    #[serde(default)]
    pub boxes: Vec<BoxConfig>,
    /// Stretches of corridor wall where random landmarks are never placed.
    #[serde(default)]
    pub featureless: Vec<FeaturelessConfig>,
    /// Landmarks at given places.
    #[serde(default)]
    pub landmarks: Vec<LandmarkConfig>,
    /// Landmarks drawn at random on the corridor's walls.
    #[serde(default)]
    pub random_landmarks: Option<RandomLandmarks>,
    /// People walking about.
    #[serde(default)]
    pub people: Vec<PersonConfig>,
}

impl Check for WorldConfig {
    fn check(&self) -> Result<(), String> {
        // Each frame matches what the camera sees against the last, pair by
        // pair: the world's features together bound a frame's work.
        let features = self.landmarks.len() as u64
            + self.random_landmarks.as_ref().map_or(0, |r| u64::from(r.count))
            + self.people.iter().map(|p| u64::from(p.features)).sum::<u64>();
        if features > u64::from(MOST_RANDOM_LANDMARKS) {
            return Err(format!("{features} landmarks and people's features in all: at most {MOST_RANDOM_LANDMARKS}"));
        }
        for f in &self.featureless {
            if f.from > f.to {
                return Err(format!("featureless stretch from {} to {}: `from` must not exceed `to`", f.from, f.to));
            }
        }
        if let Some(r) = &self.random_landmarks {
            let Some(corridor) = &self.corridor else {
                return Err("random_landmarks are placed on a corridor's walls: add a `corridor`".into());
            };
            if r.min_height > r.max_height {
                return Err(format!(
                    "random_landmarks: min_height {} exceeds max_height {}",
                    r.min_height, r.max_height
                ));
            }
            let wall_free = |side| free_length(&self.featureless, side, corridor.length) > 0.0;
            if r.side_share > 0.0 && !wall_free(Side::Left) && !wall_free(Side::Right) {
                return Err("random_landmarks: both side walls are featureless end to end".into());
            }
        }
        Ok(())
    }
}

/// Metres of `side` wall not covered by featureless stretches.
fn free_length(featureless: &[FeaturelessConfig], side: Side, length: f64) -> f64 {
    let covered = |x: f64| featureless.iter().any(|f| f.side == side && (f.from..=f.to).contains(&x));
    // Fine enough sampling for a feasibility check of hand-written spans.
    let samples = 1000;
    let free = (0..samples).filter(|i| !covered((*i as f64 + 0.5) * length / samples as f64)).count();
    free as f64 * length / samples as f64
}

/// What a landmark is attached to.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Anchor {
    /// Fixed in the world; `normal` is the outward normal of the surface it
    /// is on, if any (landmarks on a wall are seen from one side only).
    Fixed {
        /// Position, m.
        position: [f64; 3],
        /// Surface normal on the floor plane.
        normal: Option<Point>,
    },
    /// Carried by a person.
    Person {
        /// Which person.
        person: usize,
        /// Offset from the person's centre, m.
        offset: [f64; 3],
    },
}

/// One landmark in the world.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WorldLandmark {
    /// Identity, reported to evaluation code only.
    pub id: u32,
    /// Where it is.
    pub anchor: Anchor,
    /// What a descriptor of it looks like when seen head on.
    pub descriptor: Descriptor,
}

/// A walking person.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Person {
    /// The person's settings.
    pub config: PersonConfig,
}

/// The built world.
#[derive(Clone, Debug, PartialEq)]
pub struct World {
    /// Walls and box sides.
    pub segments: Vec<Segment>,
    /// Every landmark, static ones first.
    pub landmarks: Vec<WorldLandmark>,
    /// People.
    pub people: Vec<Person>,
    /// The corridor, if there is one.
    pub corridor: Option<CorridorConfig>,
    /// Stretches of the corridor's side walls with nothing on them.
    pub featureless: Vec<FeaturelessConfig>,
}

fn random_descriptor(rng: &mut ChaCha8Rng) -> Descriptor {
    Descriptor([rng.random(), rng.random(), rng.random(), rng.random()])
}

/// Reflects `x` into `[lo, hi]` like a ball between two walls.
fn bounce(x: f64, lo: f64, hi: f64) -> f64 {
    let span = hi - lo;
    if span <= 0.0 {
        return lo;
    }
    let t = (x - lo).rem_euclid(2.0 * span);
    lo + if t <= span { t } else { 2.0 * span - t }
}

impl World {
    /// Builds the world. `rng` draws the random landmarks (unless they carry
    /// a seed of their own) and every descriptor.
    pub fn build(config: &WorldConfig, rng: &mut ChaCha8Rng) -> World {
        let mut segments = Vec::new();
        if let Some(c) = &config.corridor {
            let (h, l) = (c.width / 2.0, c.length);
            segments.extend([
                Segment::new((0.0, -h), (l, -h)),
                Segment::new((l, -h), (l, h)),
                Segment::new((l, h), (0.0, h)),
                Segment::new((0.0, h), (0.0, -h)),
            ]);
        }
        segments.extend(config.walls.iter().map(|w| Segment::new((w.from.x, w.from.y), (w.to.x, w.to.y))));
        for b in &config.boxes {
            let (x0, x1, y0, y1) =
                (b.x - b.length / 2.0, b.x + b.length / 2.0, b.y - b.width / 2.0, b.y + b.width / 2.0);
            segments.extend([
                Segment::new((x0, y0), (x1, y0)),
                Segment::new((x1, y0), (x1, y1)),
                Segment::new((x1, y1), (x0, y1)),
                Segment::new((x0, y1), (x0, y0)),
            ]);
        }

        let mut landmarks = Vec::new();
        let mut add = |anchor: Anchor, rng: &mut ChaCha8Rng| {
            let id = landmarks.len() as u32;
            landmarks.push(WorldLandmark { id, anchor, descriptor: random_descriptor(rng) });
        };
        for l in &config.landmarks {
            add(Anchor::Fixed { position: [l.x, l.y, l.z], normal: None }, rng);
        }
        if let (Some(r), Some(c)) = (&config.random_landmarks, &config.corridor) {
            let mut own;
            let layout_rng = match r.seed {
                Some(seed) => {
                    own = <ChaCha8Rng as rand::SeedableRng>::seed_from_u64(seed);
                    &mut own
                }
                None => &mut *rng,
            };
            for anchor in random_wall_landmarks(r, c, &config.featureless, layout_rng) {
                add(anchor, rng);
            }
        }
        for (person, p) in config.people.iter().enumerate() {
            for k in 0..p.features {
                let angle = std::f64::consts::TAU * f64::from(k) / f64::from(p.features.max(1));
                let height = 1.0 + 0.6 * f64::from(k % 3) / 2.0;
                let offset = [p.radius * angle.cos(), p.radius * angle.sin(), height];
                add(Anchor::Person { person, offset }, rng);
            }
        }
        World {
            segments,
            landmarks,
            people: config.people.iter().map(|&config| Person { config }).collect(),
            corridor: config.corridor,
            featureless: config.featureless.clone(),
        }
    }

    /// Where person `i` is at `time`.
    pub fn person_position(&self, i: usize, time: f64) -> Point {
        let p = &self.people[i].config;
        let (x, y) = (p.start.x + p.velocity.x * time, p.start.y + p.velocity.y * time);
        match &self.corridor {
            Some(c) => {
                let r = p.radius;
                (bounce(x, r, c.length - r), bounce(y, -c.width / 2.0 + r, c.width / 2.0 - r))
            }
            None => (x, y),
        }
    }

    /// The people as circles at `time`, written into `out`.
    pub fn people_at(&self, time: f64, out: &mut Vec<Circle>) {
        out.clear();
        out.extend(
            (0..self.people.len())
                .map(|i| Circle { c: self.person_position(i, time), r: self.people[i].config.radius }),
        );
    }

    /// Where a landmark is at `time`, and the outward normal of its surface.
    pub fn landmark_at(&self, landmark: &WorldLandmark, time: f64) -> ([f64; 3], Option<Point>) {
        match landmark.anchor {
            Anchor::Fixed { position, normal } => (position, normal),
            Anchor::Person { person, offset } => {
                let (x, y) = self.person_position(person, time);
                let len = offset[0].hypot(offset[1]);
                let normal = (len > 0.0).then(|| (offset[0] / len, offset[1] / len));
                ([x + offset[0], y + offset[1], offset[2]], normal)
            }
        }
    }
}

/// Places `r.count` landmarks: `side_share` of them on the side walls
/// (outside featureless stretches), the rest on the far end wall.
fn random_wall_landmarks(
    r: &RandomLandmarks,
    c: &CorridorConfig,
    featureless: &[FeaturelessConfig],
    rng: &mut ChaCha8Rng,
) -> Vec<Anchor> {
    let (h, l) = (c.width / 2.0, c.length);
    let side_count = (f64::from(r.count) * r.side_share).round() as u32;
    let height = |rng: &mut ChaCha8Rng| {
        if r.max_height > r.min_height {
            rng.random_range(r.min_height..r.max_height)
        } else {
            r.min_height
        }
    };
    let open = |side: Side, x: f64| !featureless.iter().any(|f| f.side == side && (f.from..=f.to).contains(&x));
    let mut anchors = Vec::with_capacity(r.count as usize);
    for _ in 0..side_count {
        // The check guarantees some open wall, so this ends; the bound keeps a
        // nearly closed wall from spinning for long.
        for _ in 0..10_000 {
            let side = if rng.random::<bool>() { Side::Left } else { Side::Right };
            let x = rng.random_range(0.0..l);
            if open(side, x) {
                let (y, normal) = match side {
                    Side::Left => (h, (0.0, -1.0)),
                    Side::Right => (-h, (0.0, 1.0)),
                };
                anchors.push(Anchor::Fixed { position: [x, y, height(rng)], normal: Some(normal) });
                break;
            }
        }
    }
    for _ in side_count..r.count {
        let y = rng.random_range(-h..h);
        anchors.push(Anchor::Fixed { position: [l, y, height(rng)], normal: Some((-1.0, 0.0)) });
    }
    anchors
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    fn corridor_world(seed: u64) -> World {
        let config = WorldConfig {
            corridor: Some(CorridorConfig { width: 6.0, length: 60.0 }),
            featureless: vec![FeaturelessConfig { side: Side::Left, from: 10.0, to: 30.0 }],
            random_landmarks: Some(RandomLandmarks {
                count: 16,
                side_share: 0.5,
                min_height: 0.3,
                max_height: 2.0,
                seed: None,
            }),
            ..WorldConfig::default()
        };
        World::build(&config, &mut ChaCha8Rng::seed_from_u64(seed))
    }

    #[test]
    fn random_landmarks_respect_shares_and_featureless_walls() {
        let world = corridor_world(1);
        assert_eq!(world.landmarks.len(), 16);
        let mut end = 0;
        for lm in &world.landmarks {
            let (p, normal) = world.landmark_at(lm, 0.0);
            if p[0] == 60.0 {
                end += 1;
                assert_eq!(normal, Some((-1.0, 0.0)));
            } else {
                assert!(p[1].abs() == 3.0);
                assert!(!(p[1] > 0.0 && (10.0..=30.0).contains(&p[0])), "{p:?} on a featureless wall");
            }
            assert!((0.3..2.0).contains(&p[2]));
        }
        assert_eq!(end, 8);
        assert_eq!(corridor_world(1), world);
        assert_ne!(corridor_world(2), world);
    }

    #[test]
    fn people_bounce_inside_the_corridor() {
        let config = WorldConfig {
            corridor: Some(CorridorConfig { width: 4.0, length: 10.0 }),
            people: vec![PersonConfig {
                start: Xy { x: 5.0, y: 0.0 },
                velocity: VelocityXy { x: 1.0, y: 0.0 },
                radius: 0.5,
                features: 2,
            }],
            ..WorldConfig::default()
        };
        let world = World::build(&config, &mut ChaCha8Rng::seed_from_u64(0));
        assert_eq!(world.person_position(0, 2.0), (7.0, 0.0));
        // At 6 s the unbounded walk would be at 11, 1.5 past the far limit 9.5.
        assert_eq!(world.person_position(0, 6.0), (8.0, 0.0));
        assert_eq!(world.landmarks.len(), 2);
    }

    #[test]
    fn check_catches_what_types_cannot() {
        let mut config = WorldConfig {
            random_landmarks: Some(RandomLandmarks {
                count: 3,
                side_share: 1.0,
                min_height: 0.0,
                max_height: 1.0,
                seed: None,
            }),
            ..WorldConfig::default()
        };
        assert!(config.check().unwrap_err().contains("add a `corridor`"));
        config.corridor = Some(CorridorConfig { width: 2.0, length: 10.0 });
        assert!(config.check().is_ok());
        config.featureless = vec![
            FeaturelessConfig { side: Side::Left, from: 0.0, to: 10.0 },
            FeaturelessConfig { side: Side::Right, from: -1.0, to: 11.0 },
        ];
        assert!(config.check().unwrap_err().contains("featureless end to end"));
    }
}
