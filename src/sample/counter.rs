//! A tiny counter-based generator (SplitMix64) for the many short streams of a lazy scene.
//!
//! Why not ChaCha here: an infinite scene seeds one stream per generation block, often for a block
//! holding no sphere at all; ChaCha's 256-bit key setup would dominate. SplitMix64 seeded from the
//! hashed block key is portable, passes BigCrush, and costs a few cycles per draw.

use rand::RngCore;

/// SplitMix64 over a 64-bit state.
#[derive(Clone, Debug)]
pub struct SplitMix64 {
    state: u64,
}

impl SplitMix64 {
    /// A stream for the hashed `key` (see [`super::rng::hash_key`]).
    pub fn new(key: u64) -> Self {
        Self { state: key }
    }
}

impl RngCore for SplitMix64 {
    #[inline]
    fn next_u32(&mut self) -> u32 {
        (self.next_u64() >> 32) as u32
    }

    #[inline]
    fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.state;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
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
