//! How much of f64 a scene's coordinates leave for its details, and the tolerances that follow.
//!
//! A coordinate of magnitude M is known to ulp(M) = 2⁻⁵²·M, so a length ℓ (the disc radius d, the
//! scene's size S) measured among coordinates that large keeps 52 − log₂(M/ℓ) bits. Before this
//! module every tolerance was a fixed fraction of M (the tracer's self-intersection offset
//! 10⁻⁹·M, the contact distance 10⁻⁶·M, the index pads 2⁻³⁰·M): right for a scene around the
//! origin (M ≤ S) but growing with the translation, so a Cornell box moved 10¹¹ mm away skipped
//! surfaces within 100 mm of a hit, covered most of its own sample points, and padded every index
//! cell by 93 mm — its quasi-static run listed every segment in every cell and made no progress.
//!
//! Now a tolerance is a fraction of `min(M, 4·S)` — exactly the old value for every scene that
//! holds the origin (then M ≤ S) — with a floor of 2⁻⁴⁰·M, 4096 ulps of the coordinates, above
//! the rounding of any hit point: [`Precision::offset`] (10⁻⁹) and [`Precision::contact`] (10⁻⁶,
//! floor 2⁻³⁶·M). A translated scene then sees the tolerances of the scene at the origin until the
//! floor takes over.
//!
//! [`Precision::check`] refuses a scene whose magnitude leaves fewer than [`BITS_NEEDED`] bits for
//! d or S. Why 20: the crossing of a segment and a disc is then decided to 2⁻²⁰ of d, a bias of at
//! most ~10⁻⁶ relative per crossing, far below any SE a run reaches (10⁸ crossings give 10⁻⁴); and
//! the floor 2⁻⁴⁰·M stays below 2⁻⁸·d, so the tracer never skips a surface farther than d/256 from
//! a hit. Measured (tests/stability.rs, experiments/stability.toml): the Cornell box gives the same
//! irradiance within its SE, most points bit for bit, at every accepted translation, and drifts
//! beyond it once fewer bits remain.

use crate::geom::Aabb;

/// Bits of f64's 52 that must remain for the disc radius and the scene's size at the scene's
/// coordinate magnitude.
pub const BITS_NEEDED: f64 = 20.0;

/// A scene's coordinate magnitude and size.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Precision {
    /// M: the largest |coordinate|.
    pub magnitude: f64,
    /// S: the diagonal of its bounding box.
    pub size: f64,
}

impl Precision {
    /// Of a bounding box.
    pub fn of(b: &Aabb) -> Self {
        Self {
            magnitude: b.magnitude().max(1e-300),
            size: (b.hi - b.lo).length().max(1e-300),
        }
    }

    /// The scale relative tolerances take: M for a scene holding the origin, at most 4·S.
    pub fn scale(&self) -> f64 {
        self.magnitude.min(4.0 * self.size)
    }

    /// 2⁻⁴⁰·M: 4096 ulps of the coordinates, above the rounding of any computed hit point.
    pub fn rounding(&self) -> f64 {
        self.magnitude * (-40f64).exp2()
    }

    /// How far a ray leaving a surface starts looking for the next (self-intersection offset).
    pub fn offset(&self) -> f64 {
        (1e-9 * self.scale()).max(self.rounding())
    }

    /// How close another surface must be along a point's normal to cover it (contact).
    pub fn contact(&self) -> f64 {
        (1e-6 * self.scale()).max(16.0 * self.rounding())
    }

    /// Bits left for a length `len` among coordinates of this magnitude: 52 − log₂(M/len).
    pub fn bits(&self, len: f64) -> f64 {
        52.0 - (self.magnitude / len).log2()
    }

    /// Refuses (with what is lost, in words) a scene whose coordinates leave fewer than
    /// [`BITS_NEEDED`] bits for the disc radius `d` or for its own size.
    pub fn check(&self, d: f64) -> Result<(), String> {
        let (bd, bs) = (self.bits(d), self.bits(self.size));
        if bd >= BITS_NEEDED && bs >= BITS_NEEDED {
            return Ok(());
        }
        let (what, bits) = if bd <= bs {
            (format!("the disc radius d = {d}"), bd)
        } else {
            (format!("the scene's size {:.4}", self.size), bs)
        };
        Err(format!(
            "the scene's coordinates reach {:.3e}, which leaves {bits:.1} bits of f64 for {what}; \
             DETP needs {BITS_NEEDED} (crossings decided to 2⁻²⁰ of d, surfaces resolved to d/256). \
             Move the scene nearer the origin (its size is {:.4}: subtract its centre from every \
             coordinate), or use a larger d (at least {:.3e})",
            self.magnitude,
            self.size,
            self.magnitude * (BITS_NEEDED - 52.0).exp2()
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    fn cornell_at(t: f64) -> Precision {
        Precision::of(&Aabb::new(
            DVec3::splat(t),
            DVec3::splat(t) + DVec3::new(556.0, 548.8, 559.2),
        ))
    }

    #[test]
    fn tolerances_at_the_origin_are_the_old_ones() {
        let p = cornell_at(0.0);
        assert_eq!(p.offset(), 1e-9 * 559.2);
        assert_eq!(p.contact(), 1e-6 * 559.2);
    }

    #[test]
    fn translated_scenes_keep_their_tolerances_until_the_rounding_floor() {
        let at0 = cornell_at(0.0);
        for t in [1e4, 1e6] {
            // 4·S instead of M: the same order as at the origin, not growing with t.
            assert!(cornell_at(t).offset() <= 4.0 * 963.0e-9 * 1.01, "{t}");
        }
        let far = cornell_at(1e10);
        assert_eq!(far.offset(), far.rounding());
        assert!(far.offset() < 1e-3 * 10.0 && far.offset() > at0.offset());
    }

    /// The tester's Cornell box with d = 10 mm: 10¹⁰ mm keeps 22 bits for d, 10¹¹ mm 19: refused,
    /// naming d, the magnitude, and what to do.
    #[test]
    fn a_scene_too_far_for_its_discs_is_refused_naming_the_precision_lost() {
        assert!(cornell_at(1e10).check(10.0).is_ok());
        let e = cornell_at(1e11).check(10.0).expect_err("too far");
        assert!(
            e.contains("disc radius d = 10;") && e.contains("18.8 bits") && e.contains("1.000e11"),
            "{e}"
        );
        assert!(
            cornell_at(0.0).check(1e-9).is_err(),
            "a sub-nm disc in a mm box"
        );
        assert!(cornell_at(0.0).check(1e-3).is_ok());
    }
}
