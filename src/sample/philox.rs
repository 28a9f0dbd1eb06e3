//! Philox2x64-10, the counter-based generator of Salmon, Moraes, Dror and Shaw, "Parallel random
//! numbers: as easy as 1, 2, 3" (SC 2011; the Random123 library), behind `rand_core`'s traits.
//!
//! Why this generator (the choice is argued in full in [`super::rng`]): its output block is a keyed
//! bijection of a 128-bit counter, so a stream is set up by storing two words — no key schedule,
//! no state to warm — and streams told apart by a counter word can never overlap. Ten rounds of
//! one 64×64→128-bit multiply each give 128 bits for ≈ 60 instructions.
//!
//! The block function is pinned to the reference implementation by its known-answer vectors
//! (Random123's `kat_vectors`, tested below), so a stream is the same on every machine and build.

use rand::{RngCore, SeedableRng};

/// Philox2x64's round multiplier (Random123's `PHILOX_M2x64_0`).
const M: u64 = 0xd2b7_4407_b1ce_6e93;
/// The key's Weyl increment between rounds (Random123's `PHILOX_W64_0`, the golden ratio).
const W: u64 = 0x9e37_79b9_7f4a_7c15;
/// Rounds: the authors' recommended default; they report Philox2x64 Crush-resistant from 6 on.
const ROUNDS: usize = 10;

/// Philox2x64-10's block function: the 128-bit output for counter `ctr` under `key`.
#[inline(always)]
pub fn block(ctr: [u64; 2], key: u64) -> [u64; 2] {
    let [mut x0, mut x1] = ctr;
    let mut k = key;
    for round in 0..ROUNDS {
        if round > 0 {
            k = k.wrapping_add(W);
        }
        let p = u128::from(M) * u128::from(x0);
        let (hi, lo) = ((p >> 64) as u64, p as u64);
        (x0, x1) = (hi ^ k ^ x1, lo);
    }
    [x0, x1]
}

/// A stream of Philox2x64-10 blocks: key `key`, counters `(0, word)`, `(1, word)`, … — the words
/// of each block in order, low word first.
///
/// Period: 2⁶⁴ blocks (2⁶⁵ draws of 64 bits), after which the block counter wraps.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Philox2x64 {
    key: u64,
    /// The counter's high word, fixed for the stream.
    word: u64,
    /// The next block's counter (low word).
    next: u64,
    /// The current block and how many of its words were handed out (2 = none left).
    buf: [u64; 2],
    used: u8,
}

impl Philox2x64 {
    /// The stream of `key` whose counters carry `word` in their high word.
    #[inline]
    pub fn new(key: u64, word: u64) -> Self {
        Self {
            key,
            word,
            next: 0,
            buf: [0; 2],
            used: 2,
        }
    }
}

impl RngCore for Philox2x64 {
    #[inline]
    fn next_u32(&mut self) -> u32 {
        // A whole 64-bit word per draw keeps the word order simple; 32-bit draws are rare here.
        (self.next_u64() >> 32) as u32
    }

    #[inline]
    fn next_u64(&mut self) -> u64 {
        if self.used >= 2 {
            self.buf = block([self.next, self.word], self.key);
            self.next = self.next.wrapping_add(1);
            self.used = 0;
        }
        let v = self.buf[usize::from(self.used)];
        self.used += 1;
        v
    }

    fn fill_bytes(&mut self, dest: &mut [u8]) {
        for chunk in dest.chunks_mut(8) {
            let v = self.next_u64().to_le_bytes();
            chunk.copy_from_slice(&v[..chunk.len()]);
        }
    }

    fn try_fill_bytes(&mut self, dest: &mut [u8]) -> Result<(), rand::Error> {
        self.fill_bytes(dest);
        Ok(())
    }
}

impl SeedableRng for Philox2x64 {
    /// The key (bytes 0–7) and the counter's high word (bytes 8–15), little-endian.
    type Seed = [u8; 16];

    fn from_seed(seed: Self::Seed) -> Self {
        let word = |i: usize| {
            let mut b = [0u8; 8];
            b.copy_from_slice(&seed[8 * i..8 * i + 8]);
            u64::from_le_bytes(b)
        };
        Self::new(word(0), word(1))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Random123's known-answer vectors for philox2x64 with 10 rounds: (counter, key) → output.
    #[test]
    fn block_matches_the_reference_known_answers() {
        let kat = [
            ([0, 0], 0, [0xca00_a045_9843_d731, 0x66c2_4222_c9a8_45b5]),
            (
                [u64::MAX, u64::MAX],
                u64::MAX,
                [0x65b0_21d6_0cd8_310f, 0x4d02_f322_2f86_df20],
            ),
            (
                [0x243f_6a88_85a3_08d3, 0x1319_8a2e_0370_7344],
                0xa409_3822_299f_31d0,
                [0x0a5e_742c_2997_341c, 0xb0f8_83d3_8000_de5d],
            ),
        ];
        for (ctr, key, out) in kat {
            assert_eq!(block(ctr, key), out, "counter {ctr:x?} key {key:x}");
        }
    }

    /// The stream hands out block 0's words, then block 1's, …; 32-bit draws take a whole word.
    #[test]
    fn stream_walks_the_counter() {
        let mut s = Philox2x64::new(7, 9);
        let words: Vec<u64> = (0..6).map(|_| s.next_u64()).collect();
        let want: Vec<u64> = (0..3).flat_map(|i| block([i, 9], 7)).collect();
        assert_eq!(words, want);
        let mut t = Philox2x64::new(7, 9);
        assert_eq!(t.next_u32(), (want[0] >> 32) as u32);
        assert_eq!(t.next_u64(), want[1]);
        let mut bytes = [0u8; 12];
        Philox2x64::new(7, 9).fill_bytes(&mut bytes);
        assert_eq!(bytes[..8], want[0].to_le_bytes());
        assert_eq!(bytes[8..], want[1].to_le_bytes()[..4]);
    }

    #[test]
    fn seed_holds_key_then_word() {
        let mut seed = [0u8; 16];
        seed[..8].copy_from_slice(&7u64.to_le_bytes());
        seed[8..].copy_from_slice(&9u64.to_le_bytes());
        assert_eq!(Philox2x64::from_seed(seed), Philox2x64::new(7, 9));
    }
}
