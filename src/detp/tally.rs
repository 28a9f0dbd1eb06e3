//! What an engine does with a crossing it has decided: every engine finds the (segment, disc)
//! pairs that [`crate::detp::disc::crosses`] accepts and hands each to a [`Tally`]. The paper's
//! estimate adds the segment's power to the disc's integer sum ([`Power`]); the k-nearest-crossings
//! radius keeps the disc's k nearest crossings ([`crate::detp::nearest::Nearest`]). Both are
//! order-free (an integer sum; the k smallest under a total order), so every engine, thread count
//! and merge order gives the same bits, and the engines only need to be written once for both.

use glam::DVec3;

use super::fixed::{add, Acc};
use super::store::Segment;

/// A per-disc accumulator kind: how to start one, offer it a crossing, and merge two.
pub trait Tally: Sync {
    /// One disc's state.
    type State: Send;

    /// A disc's state before any crossing.
    fn empty(&self) -> Self::State;

    /// Segment `s` (number `seg` in its store) crosses the disc whose (centre, normal) `disc`
    /// returns: a closure, so that a tally that does not need them (the power sum, in the
    /// engines' innermost loops) never loads them.
    fn offer(
        &self,
        state: &mut Self::State,
        s: &Segment,
        seg: u32,
        disc: impl FnOnce() -> (DVec3, DVec3),
    );

    /// Adds `from`'s crossings to `into` (the two saw disjoint sets of segments).
    fn merge(&self, into: &mut Self::State, from: Self::State);

    /// `n` empty states.
    fn empties(&self, n: usize) -> Vec<Self::State> {
        (0..n).map(|_| self.empty()).collect()
    }
}

/// The paper's tally: `sign ×` the power of every crossing segment, added to the disc's sum.
#[derive(Clone, Copy, Debug)]
pub struct Power {
    /// 1 to add segments, −1 to remove them (quasi-static frames).
    pub sign: i8,
}

impl Tally for Power {
    type State = Acc;

    #[inline]
    fn empty(&self) -> Acc {
        0
    }

    #[inline]
    fn offer(&self, state: &mut Acc, s: &Segment, _: u32, _: impl FnOnce() -> (DVec3, DVec3)) {
        add(state, s.power, self.sign);
    }

    #[inline]
    fn merge(&self, into: &mut Acc, from: Acc) {
        *into += from;
    }
}
