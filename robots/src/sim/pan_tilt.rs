//! The simulated pan-tilt unit: a pan axis that accelerates, cruises and
//! brakes to the commanded angle within its limits, and encoders that read
//! it with noise and a finite resolution. The tilt holds its set angle.

use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use serde::Deserialize;
use ubf_core::config::{finite, non_negative, positive, shown, Check};
use ubf_core::{anchor_mean, Aim, PanTilt, RobotError};

/// A pan-tilt unit's settings, as written under the camera in a scenario
/// file. The defaults are those of a small serial head (FLIR's PTU-D46
/// class): ±150° of pan at up to 60°/s, encoders to 0.05°.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PanTiltConfig {
    /// The pan's right limit, ° (negative: clockwise from the heading).
    #[serde(deserialize_with = "finite")]
    pub pan_min_deg: f64,
    /// The pan's left limit, °.
    #[serde(deserialize_with = "finite")]
    pub pan_max_deg: f64,
    /// The tilt the unit holds, ° above the horizontal.
    #[serde(deserialize_with = "finite")]
    pub tilt_deg: f64,
    /// Fastest pan, °/s.
    #[serde(deserialize_with = "positive")]
    pub max_rate_deg_s: f64,
    /// Largest pan acceleration, °/s².
    #[serde(deserialize_with = "positive")]
    pub max_acceleration_deg_s2: f64,
    /// The encoders' step, °: readings are whole steps.
    #[serde(deserialize_with = "non_negative")]
    pub resolution_deg: f64,
    /// Standard deviation of the encoders' noise, °.
    #[serde(deserialize_with = "non_negative")]
    pub noise_deg: f64,
}

impl Default for PanTiltConfig {
    fn default() -> Self {
        PanTiltConfig {
            pan_min_deg: -150.0,
            pan_max_deg: 150.0,
            tilt_deg: 0.0,
            max_rate_deg_s: 60.0,
            max_acceleration_deg_s2: 240.0,
            resolution_deg: 0.05,
            noise_deg: 0.02,
        }
    }
}

impl Check for PanTiltConfig {
    /// The limits in order and within a turn either way, and the held tilt
    /// within ±90°.
    fn check(&self) -> Result<(), String> {
        if !(-180.0..=0.0).contains(&self.pan_min_deg) || !(0.0..=180.0).contains(&self.pan_max_deg) {
            return Err(format!(
                "pan_tilt: pan_min_deg {} and pan_max_deg {} must lie within -180..0 and 0..180",
                shown(self.pan_min_deg),
                shown(self.pan_max_deg)
            ));
        }
        if self.tilt_deg.abs() > 90.0 {
            return Err(format!("pan_tilt: tilt_deg {}: within ±90", shown(self.tilt_deg)));
        }
        Ok(())
    }
}

/// The simulated unit; it starts looking straight ahead.
#[derive(Clone, Debug)]
pub struct SimPanTilt {
    config: PanTiltConfig,
    /// True pan, rad, and its rate, rad/s.
    pan: f64,
    rate: f64,
    target: f64,
    rng: ChaCha8Rng,
    /// The noise of [`PanTilt::anchor_reading`]'s readings after the first.
    anchor_rng: ChaCha8Rng,
}

impl SimPanTilt {
    /// A unit with these settings, its encoder noise drawn from `rng`, and
    /// from `anchor_rng` in the extra readings that anchor egomotion's map
    /// (so that taking them leaves every later reading's noise as it was).
    pub fn new(config: PanTiltConfig, rng: ChaCha8Rng, anchor_rng: ChaCha8Rng) -> Self {
        SimPanTilt { config, pan: 0.0, rate: 0.0, target: 0.0, rng, anchor_rng }
    }

    /// Where the unit truly points.
    pub fn true_aim(&self) -> Aim {
        Aim { pan: self.pan, tilt: self.config.tilt_deg.to_radians() }
    }

    /// Moves the pan on by `dt` seconds: towards the target at the largest
    /// rate from which it can still stop there, changed by at most the
    /// acceleration limit.
    pub fn advance(&mut self, dt: f64) {
        let (max_rate, accel) =
            (self.config.max_rate_deg_s.to_radians(), self.config.max_acceleration_deg_s2.to_radians());
        let error = self.target - self.pan;
        let stoppable = (2.0 * accel * error.abs()).sqrt().min(max_rate) * error.signum();
        self.rate += (stoppable - self.rate).clamp(-accel * dt, accel * dt);
        let step = self.rate * dt;
        if step.abs() >= error.abs() && error * step >= 0.0 {
            self.pan = self.target;
            self.rate = 0.0;
        } else {
            self.pan += step;
        }
    }
}

impl PanTilt for SimPanTilt {
    fn command(&mut self, aim: Aim) -> Result<(), RobotError> {
        let c = &self.config;
        self.target = aim.pan.clamp(c.pan_min_deg.to_radians(), c.pan_max_deg.to_radians());
        Ok(())
    }

    fn anchor_reading(&mut self) -> Result<Aim, RobotError> {
        let first = self.measured()?;
        std::mem::swap(&mut self.rng, &mut self.anchor_rng);
        let mean = anchor_mean(first, || self.measured());
        std::mem::swap(&mut self.rng, &mut self.anchor_rng);
        mean
    }

    fn measured(&mut self) -> Result<Aim, RobotError> {
        let c = &self.config;
        let noise: f64 = StandardNormal.sample(&mut self.rng);
        let mut pan = self.pan.to_degrees() + c.noise_deg * noise;
        if c.resolution_deg > 0.0 {
            pan = (pan / c.resolution_deg).round() * c.resolution_deg;
        }
        Ok(Aim { pan: pan.to_radians(), tilt: c.tilt_deg.to_radians() })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    fn unit(config: PanTiltConfig) -> SimPanTilt {
        SimPanTilt::new(config, ChaCha8Rng::seed_from_u64(1), ChaCha8Rng::seed_from_u64(2))
    }

    #[test]
    fn the_pan_keeps_to_its_rate_and_acceleration_and_stops_on_the_target() {
        let mut u = unit(PanTiltConfig::default());
        u.command(Aim { pan: 90f64.to_radians(), tilt: 0.0 }).unwrap();
        let dt = 0.01;
        let (mut last_rate, mut peak) = (0.0_f64, 0.0_f64);
        for _ in 0..400 {
            u.advance(dt);
            // The last step settles onto the target.
            if u.pan != 90f64.to_radians() {
                assert!((u.rate - last_rate).abs() <= 240f64.to_radians() * dt + 1e-12);
            }
            last_rate = u.rate;
            peak = peak.max(u.rate);
            assert!(u.pan <= 90f64.to_radians() + 1e-12, "no overshoot");
        }
        assert!((peak - 60f64.to_radians()).abs() < 1e-9, "cruises at the rate limit");
        assert_eq!(u.pan, 90f64.to_radians());
        // 90° at 60°/s with 0.25 s to reach the rate and to stop: 1.75 s.
        let mut u = unit(PanTiltConfig::default());
        u.command(Aim { pan: 90f64.to_radians(), tilt: 0.0 }).unwrap();
        let ticks = (0..1000).take_while(|_| {
            u.advance(dt);
            u.pan < 90f64.to_radians()
        });
        let t = (ticks.count() + 1) as f64 * dt;
        assert!((t - 1.75).abs() < 0.05, "{t} s");
    }

    #[test]
    fn commands_beyond_the_limits_stop_at_them() {
        let mut u = unit(PanTiltConfig { pan_min_deg: -30.0, pan_max_deg: 45.0, ..PanTiltConfig::default() });
        u.command(Aim { pan: 2.0, tilt: 0.0 }).unwrap();
        (0..1000).for_each(|_| u.advance(0.01));
        assert!((u.true_aim().pan - 45f64.to_radians()).abs() < 1e-12);
        u.command(Aim { pan: -2.0, tilt: 0.0 }).unwrap();
        (0..1000).for_each(|_| u.advance(0.01));
        assert!((u.true_aim().pan + 30f64.to_radians()).abs() < 1e-12);
    }

    #[test]
    fn the_encoders_read_in_whole_steps_near_the_truth() {
        let mut u = unit(PanTiltConfig { resolution_deg: 0.1, noise_deg: 0.02, ..PanTiltConfig::default() });
        u.command(Aim { pan: 0.5, tilt: 0.0 }).unwrap();
        (0..300).for_each(|_| u.advance(0.01));
        for _ in 0..50 {
            let read = u.measured().unwrap().pan.to_degrees();
            assert!(((read / 0.1).round() * 0.1 - read).abs() < 1e-9, "{read}");
            assert!((read - 0.5f64.to_degrees()).abs() < 0.15, "{read}");
        }
    }

    #[test]
    fn limits_out_of_order_are_refused() {
        let bad = PanTiltConfig { pan_min_deg: 10.0, ..PanTiltConfig::default() };
        assert!(bad.check().unwrap_err().contains("pan_min_deg"));
    }
}
