//! Axis shaping, applied in this order: invert, deadzone, expo, scale; then the rate limit
//! (in the engine, because it depends on time).

/// How one binding shapes its axis (from the binding's options).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shaping {
    pub deadzone: f64,
    pub expo: f64,
    pub scale: f64,
    pub invert: bool,
    /// Largest change of the shaped value per second; 0: unlimited.
    pub rate: f64,
}

impl Default for Shaping {
    fn default() -> Shaping {
        Shaping { deadzone: 0.0, expo: 0.0, scale: 1.0, invert: false, rate: 0.0 }
    }
}

impl Shaping {
    /// The shaped value of a raw axis reading (without the rate limit). Inside the
    /// deadzone it is exactly 0; outside, the rest of the travel is rescaled so that full
    /// deflection still gives ±scale.
    pub fn apply(&self, raw: f64) -> f64 {
        if !raw.is_finite() {
            return 0.0;
        }
        let mut v = raw.clamp(-1.0, 1.0);
        if self.invert {
            v = -v;
        }
        let dz = self.deadzone.clamp(0.0, 0.99);
        v = if v.abs() <= dz { 0.0 } else { v.signum() * (v.abs() - dz) / (1.0 - dz) };
        let e = self.expo.clamp(0.0, 1.0);
        v = (1.0 - e) * v + e * v * v * v;
        v * self.scale
    }

    /// One step of the rate limit: from `from` towards `to`, moving at most `rate · dt`.
    pub fn limit(&self, from: f64, to: f64, dt: f64) -> f64 {
        if self.rate <= 0.0 {
            return to;
        }
        let step = self.rate * dt.max(0.0);
        if (to - from).abs() <= step { to } else { from + step * (to - from).signum() }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn deadzone_is_exactly_zero_and_full_travel_reaches_scale() {
        let s = Shaping { deadzone: 0.1, scale: 100.0, ..Shaping::default() };
        assert_eq!(s.apply(0.05), 0.0);
        assert_eq!(s.apply(-0.1), 0.0);
        assert!((s.apply(1.0) - 100.0).abs() < 1e-9);
        assert!((s.apply(0.55) - 50.0).abs() < 1e-9);
    }

    #[test]
    fn expo_softens_the_middle_and_keeps_the_ends() {
        let s = Shaping { expo: 0.5, ..Shaping::default() };
        assert!((s.apply(0.5) - (0.25 + 0.0625)).abs() < 1e-9);
        assert!((s.apply(-1.0) + 1.0).abs() < 1e-9);
    }

    #[test]
    fn invert_and_rate_limit() {
        let s = Shaping { invert: true, rate: 2.0, ..Shaping::default() };
        assert_eq!(s.apply(0.25), -0.25);
        assert_eq!(s.limit(0.0, 1.0, 0.1), 0.2);
        assert_eq!(s.limit(0.9, 1.0, 0.1), 1.0);
        assert_eq!(s.apply(f64::NAN), 0.0);
    }
}
