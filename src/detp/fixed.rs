//! Order-free power: every segment carries an integer number of power units, and a disc's sum is an
//! integer, so adding the same segments in any order, on any thread, through any engine — or adding
//! and later removing some — gives the same bits. Floating point enters only once per segment (when
//! its power is quantised) and once per disc (when the sum is turned into irradiance).

/// Power units of one segment.
pub type Units = u32;

/// A disc's accumulated units. Signed, so that removing a segment is adding its negation.
pub type Acc = i64;

/// The scale between units and watts (or any power unit the scene uses).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PowerScale {
    /// Watts per unit.
    pub watts_per_unit: f64,
}

impl PowerScale {
    /// A scale whose largest segment power `max_watts` maps to 2³¹ units: quantisation error below
    /// 2⁻³¹ of the largest power, and room in an [`Acc`] for 2³² such segments on one disc.
    pub fn for_max_power(max_watts: f64) -> Self {
        assert!(
            max_watts.is_finite() && max_watts > 0.0,
            "segment power must be finite and positive, got {max_watts}"
        );
        Self {
            watts_per_unit: max_watts / f64::from(1u32 << 31),
        }
    }

    /// Units for `watts`, rounded to nearest (at least 1 for any positive power, so no segment that
    /// carries power is silently dropped).
    pub fn units(&self, watts: f64) -> Units {
        let u = (watts / self.watts_per_unit).round();
        assert!(
            (0.0..=f64::from(u32::MAX)).contains(&u),
            "power {watts} out of range for scale {}",
            self.watts_per_unit
        );
        if watts > 0.0 {
            (u as Units).max(1)
        } else {
            0
        }
    }

    /// Watts for an accumulated sum.
    pub fn watts(&self, acc: Acc) -> f64 {
        acc as f64 * self.watts_per_unit
    }
}

/// Adds `sign · units` to `acc`. Overflow cannot happen while the store holds fewer than 2³² segments
/// (each ≤ 2³² − 1 units), which `store::SegmentStore` checks; the debug build checks it here too.
#[inline]
pub fn add(acc: &mut Acc, units: Units, sign: i8) {
    let delta = i64::from(units) * i64::from(sign);
    debug_assert!(
        acc.checked_add(delta).is_some(),
        "power accumulator overflow"
    );
    *acc = acc.wrapping_add(delta);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantisation_is_relative_and_never_drops_power() {
        let s = PowerScale::for_max_power(3.0);
        assert_eq!(s.units(3.0), 1 << 31);
        assert_eq!(s.units(1e-30), 1);
        assert_eq!(s.units(0.0), 0);
        let w = s.watts(i64::from(s.units(1.234_567)));
        assert!((w - 1.234_567).abs() <= s.watts_per_unit);
    }

    #[test]
    fn add_then_remove_is_exact_in_any_order() {
        let units = [5u32, 1 << 31, 7, 123_456_789, 1];
        let mut a: Acc = 0;
        for &u in &units {
            add(&mut a, u, 1);
        }
        let mut b: Acc = 0;
        for &u in units.iter().rev() {
            add(&mut b, u, 1);
        }
        assert_eq!(a, b);
        for &u in &units[1..3] {
            add(&mut a, u, -1);
        }
        let mut c: Acc = 0;
        for &u in [units[0], units[3], units[4]].iter() {
            add(&mut c, u, 1);
        }
        assert_eq!(a, c);
    }
}
