//! Floating-point error bounds in the style of pbrt-v4 (`util/float.h`).

/// Machine epsilon for rounding to nearest, half of `f64::EPSILON` (pbrt's `MachineEpsilon`).
pub const MACHINE_EPSILON: f64 = f64::EPSILON * 0.5;

/// Bound on the relative error of `n` chained floating-point operations: nε/(1−nε).
#[inline]
pub fn gamma(n: u32) -> f64 {
    let ne = f64::from(n) * MACHINE_EPSILON;
    ne / (1.0 - ne)
}

/// Turns −0.0 into +0.0 so that `1/x` and sign tests treat both zeros alike (pbrt's DDA does so).
#[inline]
pub fn positive_zero(x: f64) -> f64 {
    if x == 0.0 {
        0.0
    } else {
        x
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gamma_grows_with_operation_count() {
        assert!(gamma(1) > 0.0);
        assert!(gamma(3) > gamma(2));
        assert!((gamma(3) - 3.0 * MACHINE_EPSILON).abs() < 1e-30);
    }

    #[test]
    fn negative_zero_becomes_positive() {
        assert!(positive_zero(-0.0).is_sign_positive());
        assert_eq!(positive_zero(-2.0), -2.0);
    }
}
