//! A disc radius from the local density of crossings: each disc keeps its k nearest crossings
//! among those within d, and its radius r_i is the distance of the k-th (d when fewer than k
//! cross within d).
//!
//! # Which crossings, exactly
//! A crossing's distance from the disc centre is [`crossing_distance_sq`], one function of the
//! stored numbers (the very |x − c|² that [`crate::detp::disc::crosses`] compares with d²), so every
//! engine computes the same bits. Crossings are ordered totally by (ρ² bits, power units, the
//! segment's number in its store) — ρ² ≥ 0, so its bits order as its values — and a disc keeps the
//! k smallest in a bounded max-heap. The kept set is a function of the set of crossings alone,
//! whatever the order they arrive in, the engine, the thread count or how partial heaps are merged
//! (union, then the k smallest): engines agree bit for bit by construction.
//!
//! # The estimate
//! With k kept, r_i = √ρ²_k (the k-th) and the estimate is the power of the **k − 1 nearer**
//! crossings over π r_i²: the k-th crossing lies on the rim and only sets the radius. Counting it
//! too would give the k-nearest-neighbour density estimator's known bias k/(k − 1) in a uniform
//! field (for crossings of intensity λ, E[1/(π r_k²)] = λ/(k − 1)); without it the estimate of a
//! uniform field is unbiased (powers are independent of distances), which the tests check. Hence
//! k ≥ 2. With fewer than k crossings within d, r_i = d and every crossing within d counts (the
//! paper's estimate at d).

use std::collections::BinaryHeap;

use glam::DVec3;

use super::fixed::Acc;
use super::store::Segment;
use super::tally::Tally;

/// The smallest k: the k-th crossing only sets the radius, so k = 1 would count nothing.
pub const MIN_K: usize = 2;

/// The exponent of k(N): MSE ∝ (k/N)² + 1/k is least at k ∝ N^(2/3) (`docs/theory.md`).
pub const K_EXPONENT: f64 = 2.0 / 3.0;

/// k(N) = max([`MIN_K`], round(k_ref·(N/N_ref)^(2/3))): the crossings a disc keeps at `photons`
/// photons, for `k_ref` at `photons_ref` (k_ref at every N when `photons_ref` is None). Rounded
/// half away from zero, so the value is a fixed function of the three integers.
pub fn k_for(k_ref: u64, photons: u64, photons_ref: Option<u64>) -> usize {
    let k = match photons_ref {
        None => k_ref as f64,
        Some(n_ref) => k_ref as f64 * (photons as f64 / n_ref as f64).powf(K_EXPONENT),
    };
    (k.round() as usize).max(MIN_K)
}

/// |x − c|² for the point x where segment `s` meets the plane of the disc (c, n), computed as
/// [`crate::detp::disc::crosses`] computes it (glam's operations in its order). Meaningful for a
/// pair `crosses` accepted.
#[inline]
pub fn crossing_distance_sq(s: &Segment, c: DVec3, n: DVec3) -> f64 {
    let (o, v) = (s.o(), s.d());
    let denom = v.dot(n);
    let w = c - o;
    let num = w.dot(n);
    let t = num / denom;
    let x = v * t - w;
    x.length_squared()
}

/// One crossing as a disc keeps it; the derived order (field by field) is the total order.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub struct Crossing {
    /// Bits of ρ² (non-negative, so bit order is value order).
    pub rho_sq_bits: u64,
    /// Power units.
    pub power: u32,
    /// The segment's number in its store.
    pub seg: u32,
}

/// Bytes one kept crossing costs (the memory model charges n_P · k of them).
pub const CROSSING_BYTES: usize = std::mem::size_of::<Crossing>();

/// The k smallest crossings seen so far (a max-heap: the largest kept is at the top).
#[derive(Clone, Debug, Default)]
pub struct Kept(BinaryHeap<Crossing>);

impl Kept {
    /// Offers `x`: kept if fewer than `k` are held or it precedes the largest held.
    #[inline]
    pub fn offer(&mut self, k: usize, x: Crossing) {
        if self.0.len() < k {
            self.0.push(x);
        } else if let Some(mut top) = self.0.peek_mut() {
            if x < *top {
                *top = x;
            }
        }
    }

    /// The kept crossings, nearest first.
    pub fn sorted(&self) -> Vec<Crossing> {
        self.0.clone().into_sorted_vec()
    }

    /// Crossings held.
    pub fn len(&self) -> usize {
        self.0.len()
    }

    /// None held?
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    /// The disc's radius and counted power (see the module doc), for k and the largest radius d.
    pub fn select(&self, k: usize, d: f64) -> Selected {
        let full = self.0.len() >= k;
        let all: Acc = self.0.iter().map(|x| Acc::from(x.power)).sum();
        let units = match self.0.peek() {
            Some(top) if full => all - Acc::from(top.power),
            _ => all,
        };
        let radius = match self.0.peek() {
            Some(top) if full => f64::from_bits(top.rho_sq_bits).sqrt(),
            _ => d,
        };
        Selected {
            radius,
            units,
            full,
        }
    }
}

/// What a disc's kept crossings give.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Selected {
    /// r_i: the k-th crossing's distance, or d with fewer than k.
    pub radius: f64,
    /// Power units counted: the k − 1 nearer crossings, or all within d with fewer than k.
    pub units: Acc,
    /// k crossings were found within d (false: r_i = d).
    pub full: bool,
}

/// The k-nearest-crossings tally (k ≥ [`MIN_K`]).
#[derive(Clone, Copy, Debug)]
pub struct Nearest {
    /// Crossings kept per disc.
    pub k: usize,
}

impl Nearest {
    /// The tally for `k` (panics below [`MIN_K`]: the spec refuses such k first).
    pub fn new(k: usize) -> Self {
        assert!(k >= MIN_K, "k-nearest crossings needs k ≥ {MIN_K}, got {k}");
        Self { k }
    }
}

impl Tally for Nearest {
    type State = Kept;

    fn empty(&self) -> Kept {
        Kept::default()
    }

    #[inline]
    fn offer(
        &self,
        state: &mut Kept,
        s: &Segment,
        seg: u32,
        disc: impl FnOnce() -> (DVec3, DVec3),
    ) {
        let (c, n) = disc();
        let rho_sq = crossing_distance_sq(s, c, n);
        state.offer(
            self.k,
            Crossing {
                rho_sq_bits: rho_sq.to_bits(),
                power: s.power,
                seg,
            },
        );
    }

    fn merge(&self, into: &mut Kept, from: Kept) {
        if into.len() < from.len() {
            let small = std::mem::replace(into, from);
            return self.merge(into, small);
        }
        for x in from.0 {
            into.offer(self.k, x);
        }
    }
}

#[cfg(test)]
mod tests;
