//! What is traced: Poisson sphere processes, finite (built into a real grid) or infinite (generated
//! lazily where rays go: per ray in the reach boxes of its walk, or block by block for rays that
//! share a realisation), with one or several radius classes.

pub mod finite;
pub mod infinite;
pub mod lazy;
pub mod tube;

/// The radius laws live with the samplers (`sample::radius`), below `theory`, which integrates them.
pub use crate::sample::radius;
pub use crate::sample::radius::{RadiusClass, RadiusDist, RadiusDraw};

/// The class mark of a generated sphere: class i with probability α_i, from one uniform (none
/// when there is a single class). Shared by the infinite scene's engines, which must consume
/// their streams identically.
#[derive(Clone, Debug)]
pub struct ClassMarks {
    /// Cumulative fractions, the last one ∞ (so that every uniform finds a class).
    bounds: Vec<f64>,
}

impl ClassMarks {
    /// The marks of `classes` (fractions validated to sum to 1).
    pub fn new(classes: &[RadiusClass]) -> Self {
        let mut acc = 0.0;
        let mut bounds: Vec<f64> = classes
            .iter()
            .map(|c| {
                acc += c.fraction;
                acc
            })
            .collect();
        if let Some(last) = bounds.last_mut() {
            *last = f64::INFINITY;
        }
        Self { bounds }
    }

    /// The next sphere's class from `rng`.
    #[inline(always)]
    pub fn draw<R: rand::Rng + ?Sized>(&self, rng: &mut R) -> usize {
        if self.bounds.len() <= 1 {
            return 0;
        }
        let v: f64 = rng.gen();
        self.bounds.iter().position(|&c| v < c).unwrap_or(0)
    }
}
