//! The position unwrapping odometry needs: SIP positions wrap at 15 bits.

/// Keeps odometry continuous across the 15-bit wrap of the position
/// accumulators, over any distance and into negative coordinates.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Unwrapper {
    last: Option<(u16, u16)>,
    x: i64,
    y: i64,
}

impl Unwrapper {
    /// Takes a SIP's raw positions; returns the continuous position in
    /// position units since the first SIP.
    pub fn update(&mut self, xpos: u16, ypos: u16) -> (i64, i64) {
        let (x, y) = (xpos & 0x7FFF, ypos & 0x7FFF);
        if let Some((lx, ly)) = self.last {
            self.x += wrapped_difference(x, lx);
            self.y += wrapped_difference(y, ly);
        }
        self.last = Some((x, y));
        (self.x, self.y)
    }
}

/// `new − old` on a 15-bit circle: a jump of more than half the range is a
/// wrap.
fn wrapped_difference(new: u16, old: u16) -> i64 {
    let d = (i64::from(new) - i64::from(old)).rem_euclid(0x8000);
    if d >= 0x4000 {
        d - 0x8000
    } else {
        d
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn positions_unwrap_past_the_wrap_and_below_zero() {
        let mut u = Unwrapper::default();
        u.update(0x7FF0, 5);
        assert_eq!(u.update(0x0010, 3), (0x20, -2));
        // Backwards across zero into negative coordinates.
        let mut v = Unwrapper::default();
        v.update(10, 10);
        assert_eq!(v.update(0x7FF6, 10), (-20, 0));
        // The top bit is not part of the position.
        assert_eq!(v.update(0xFFF6, 10), (-20, 0));
    }
}
