//! Point orderings for the sphere cache: none, Morton (Lebesgue, bit interleaving) and Hilbert.
//!
//! Sorting the points along a space-filling curve makes consecutive points close, so the spheres
//! built around one point keep serving the next ones (fewer re-builds, the paper's m_i). Keys are
//! computed at `bits` per axis over the points' bounding box; the sort is stable (ties keep index
//! order), so the permutation is a deterministic function of the points.
//!
//! Hilbert keys use Skilling's transpose algorithm ("Programming the Hilbert curve", AIP Conf.
//! Proc. 707, 2004), written here (about 30 lines) rather than pulled in as a crate: the candidate
//! checked, `lindel`, has a single 0.1 release, and the tests below check the properties that
//! matter (bijection, face-adjacent consecutive cells).

use glam::DVec3;

/// Which curve orders the points.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Order {
    /// Input order.
    None,
    /// Morton / Lebesgue (Z-order): interleaved coordinate bits.
    Morton,
    /// Hilbert: consecutive keys are face-adjacent cells.
    Hilbert,
}

/// The order in which to visit `points`: a permutation of `0..points.len()`.
///
/// # Panics
/// If `bits` is 0 or above 21 (keys are 3·bits ≤ 63 bits).
pub fn permutation(points: &[DVec3], order: Order, bits: u32) -> Vec<u32> {
    assert!((1..=21).contains(&bits), "bits per axis must be 1..=21");
    let mut perm: Vec<u32> = (0..points.len() as u32).collect();
    if order == Order::None || points.is_empty() {
        return perm;
    }
    let (lo, hi) = points.iter().fold(
        (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    );
    let cells = f64::from(1u32 << bits);
    let max = (1u32 << bits) - 1;
    // A zero-extent axis maps every point to cell 0.
    let scale = (hi - lo).map(|e| if e > 0.0 { cells / e } else { 0.0 });
    let keys: Vec<u64> = points
        .iter()
        .map(|p| {
            let q = ((*p - lo) * scale).to_array();
            let c = q.map(|x| (x as u32).min(max));
            match order {
                Order::Morton => morton(c, bits),
                Order::Hilbert => hilbert(c, bits),
                Order::None => unreachable!(),
            }
        })
        .collect();
    perm.sort_by_key(|&i| keys[i as usize]);
    perm
}

/// Morton key: bit b of axis k goes to bit 3b + (2 − k), x most significant within each triple.
pub fn morton(c: [u32; 3], bits: u32) -> u64 {
    let mut key = 0u64;
    for b in (0..bits).rev() {
        for &x in &c {
            key = (key << 1) | u64::from((x >> b) & 1);
        }
    }
    key
}

/// Hilbert key of cell `c` on a 2^bits cube (Skilling's AxestoTranspose, then the transposed
/// coordinates interleaved like a Morton key).
pub fn hilbert(c: [u32; 3], bits: u32) -> u64 {
    let mut x = c;
    let m = 1u32 << (bits - 1);
    // Inverse undo of excess work.
    let mut q = m;
    while q > 1 {
        let p = q - 1;
        for i in 0..3 {
            if x[i] & q != 0 {
                x[0] ^= p;
            } else {
                let t = (x[0] ^ x[i]) & p;
                x[0] ^= t;
                x[i] ^= t;
            }
        }
        q >>= 1;
    }
    // Gray encode.
    for i in 1..3 {
        x[i] ^= x[i - 1];
    }
    let mut t = 0;
    let mut q = m;
    while q > 1 {
        if x[2] & q != 0 {
            t ^= q - 1;
        }
        q >>= 1;
    }
    for xi in &mut x {
        *xi ^= t;
    }
    morton(x, bits)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn all_cells(bits: u32) -> Vec<[u32; 3]> {
        let n = 1u32 << bits;
        let mut v = Vec::new();
        for z in 0..n {
            for y in 0..n {
                for x in 0..n {
                    v.push([x, y, z]);
                }
            }
        }
        v
    }

    #[test]
    fn consecutive_hilbert_keys_are_face_adjacent_and_keys_are_a_bijection() {
        for bits in 1..=4 {
            let cells = all_cells(bits);
            let mut by_key: Vec<(u64, [u32; 3])> =
                cells.iter().map(|&c| (hilbert(c, bits), c)).collect();
            by_key.sort();
            for (k, (key, _)) in by_key.iter().enumerate() {
                assert_eq!(
                    *key, k as u64,
                    "bits {bits}: keys must be 0..n³ exactly once"
                );
            }
            for w in by_key.windows(2) {
                let dist: i64 = (0..3)
                    .map(|i| (i64::from(w[0].1[i]) - i64::from(w[1].1[i])).abs())
                    .sum();
                assert_eq!(dist, 1, "bits {bits}: {:?} → {:?}", w[0], w[1]);
            }
        }
    }

    #[test]
    fn morton_interleaves_bits_and_is_a_bijection() {
        assert_eq!(morton([1, 0, 0], 1), 0b100);
        assert_eq!(morton([0, 1, 0], 1), 0b010);
        assert_eq!(morton([0, 0, 1], 1), 0b001);
        assert_eq!(morton([0b10, 0b01, 0b11], 2), 0b101_011);
        let cells = all_cells(3);
        let mut keys: Vec<u64> = cells.iter().map(|&c| morton(c, 3)).collect();
        keys.sort_unstable();
        assert_eq!(keys, (0..512).collect::<Vec<u64>>());
    }

    #[test]
    fn permutation_is_stable_and_follows_the_curve() {
        // Four corners of the unit square in z = 0 plus a duplicate: Hilbert visits them along
        // face-adjacent quadrants; the duplicate keeps index order.
        let pts = vec![
            DVec3::new(1.0, 1.0, 0.0),
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
        ];
        assert_eq!(permutation(&pts, Order::None, 4), vec![0, 1, 2, 3, 4]);
        let h = permutation(&pts, Order::Hilbert, 4);
        assert_eq!(h.len(), 5);
        let pos = |i: u32| h.iter().position(|&j| j == i).unwrap();
        assert_eq!(pos(3), pos(1) + 1, "ties keep index order");
        let m = permutation(&pts, Order::Morton, 4);
        assert_eq!(m, vec![1, 3, 4, 2, 0], "x is the most significant bit");
        // Every consecutive pair along the Hilbert order of a full lattice is face-adjacent.
        let lattice: Vec<DVec3> = all_cells(3)
            .iter()
            .map(|c| DVec3::new(f64::from(c[0]), f64::from(c[1]), f64::from(c[2])))
            .collect();
        let p = permutation(&lattice, Order::Hilbert, 3);
        for w in p.windows(2) {
            let d = lattice[w[0] as usize] - lattice[w[1] as usize];
            assert_eq!(d.abs().element_sum(), 1.0);
        }
    }
}
