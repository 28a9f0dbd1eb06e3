//! The oracle: every segment against every disc, with the one exact test [`Discs::crossed_by`].
//!
//! Parallel over discs (each disc's sum is written by one task), so the result does not depend on
//! the thread count; sums are integers, so it does not depend on the order either.

use rayon::prelude::*;

use super::disc::Discs;
use super::fixed::Acc;
use super::store::SegmentStore;
use super::tally::{Power, Tally};

/// Adds `sign ×` the power of every segment that crosses disc `i` to `acc[i]`, for every disc `i`
/// (or only the discs listed in `subset`). Returns the number of ray–disc tests made
/// (segments × discs tested).
///
/// # Panics
/// If `acc` is shorter than the number of discs, or `subset` names a disc that does not exist.
pub fn accumulate(
    store: &SegmentStore,
    discs: &Discs,
    subset: Option<&[u32]>,
    sign: i8,
    acc: &mut [Acc],
) -> u64 {
    accumulate_with(store, discs, subset, &Power { sign }, acc)
}

/// [`accumulate`] for any [`Tally`]: offers every crossing of disc `i` to `acc[i]`.
pub fn accumulate_with<T: Tally>(
    store: &SegmentStore,
    discs: &Discs,
    subset: Option<&[u32]>,
    tally: &T,
    acc: &mut [T::State],
) -> u64 {
    assert!(acc.len() >= discs.len(), "one accumulator per disc");
    let sum = |i: usize| -> T::State {
        let mut a = tally.empty();
        let (c, n) = (discs.centers[i], discs.normals[i]);
        for (k, s) in store.segments.iter().enumerate() {
            if discs.crossed_by(s, i) {
                tally.offer(&mut a, s, k as u32, || (c, n));
            }
        }
        a
    };
    let tested = match subset {
        None => {
            acc[..discs.len()]
                .par_iter_mut()
                .enumerate()
                .for_each(|(i, a)| tally.merge(a, sum(i)));
            discs.len()
        }
        Some(ids) => {
            let sums: Vec<T::State> = ids.par_iter().map(|&i| sum(i as usize)).collect();
            for (&i, s) in ids.iter().zip(sums) {
                tally.merge(&mut acc[i as usize], s);
            }
            ids.len()
        }
    };
    tested as u64 * store.len() as u64
}

#[cfg(test)]
mod tests {
    use glam::DVec3;

    use super::*;
    use crate::detp::fixed::PowerScale;
    use crate::detp::store::Segment;

    fn store() -> SegmentStore {
        let seg = |x: f64, p: u32| Segment::new(DVec3::new(x, 0.0, 1.0), -DVec3::Z, 0.5, 2.0, p, 0);
        SegmentStore::new(
            vec![seg(0.0, 3), seg(0.05, 5), seg(0.5, 7)],
            PowerScale::for_max_power(1.0),
        )
    }

    #[test]
    fn sums_the_crossing_segments_and_counts_every_pair() {
        let discs = Discs::new(
            vec![
                DVec3::ZERO,
                DVec3::new(0.5, 0.0, 0.0),
                DVec3::new(3.0, 0.0, 0.0),
            ],
            vec![DVec3::Z; 3],
            0.1,
        )
        .unwrap();
        let mut acc = vec![0; 3];
        let tests = accumulate(&store(), &discs, None, 1, &mut acc);
        assert_eq!(acc, vec![8, 7, 0]);
        assert_eq!(tests, 9);
        let tests = accumulate(&store(), &discs, Some(&[1]), -1, &mut acc);
        assert_eq!(acc, vec![8, 0, 0]);
        assert_eq!(tests, 3);
    }
}
