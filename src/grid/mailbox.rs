//! Per-ray set of the spheres already tested, for mailboxing and for counting distinct tests.
//!
//! Open addressing over 64-bit ids with generation stamps: clearing between rays costs one increment,
//! and no allocation happens per ray once the table has grown to the largest ray seen.

/// A set of sphere ids, cleared per ray.
#[derive(Clone, Debug)]
pub struct Mailbox {
    keys: Vec<u64>,
    stamps: Vec<u32>,
    stamp: u32,
    len: usize,
}

impl Default for Mailbox {
    fn default() -> Self {
        Self {
            keys: vec![0; 256],
            stamps: vec![0; 256],
            stamp: 1,
            len: 0,
        }
    }
}

impl Mailbox {
    /// Forgets every id (start of a new ray).
    #[inline]
    pub fn clear(&mut self) {
        self.len = 0;
        self.stamp = self.stamp.wrapping_add(1);
        if self.stamp == 0 {
            self.stamps.iter_mut().for_each(|s| *s = 0);
            self.stamp = 1;
        }
    }

    /// Inserts `id`; returns true if it was not there yet.
    #[inline]
    pub fn insert(&mut self, id: u64) -> bool {
        if 2 * (self.len + 1) > self.keys.len() {
            self.grow();
        }
        let mask = self.keys.len() - 1;
        let mut i = (crate::sample::rng::mix64(id) as usize) & mask;
        loop {
            if self.stamps[i] != self.stamp {
                self.stamps[i] = self.stamp;
                self.keys[i] = id;
                self.len += 1;
                return true;
            }
            if self.keys[i] == id {
                return false;
            }
            i = (i + 1) & mask;
        }
    }

    fn grow(&mut self) {
        let live: Vec<u64> = (0..self.keys.len())
            .filter(|&i| self.stamps[i] == self.stamp)
            .map(|i| self.keys[i])
            .collect();
        let cap = self.keys.len() * 2;
        self.keys = vec![0; cap];
        self.stamps = vec![0; cap];
        self.stamp = 1;
        self.len = 0;
        for id in live {
            self.insert(id);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn distinct_ids_are_counted_once_per_ray_and_growth_keeps_them() {
        let mut m = Mailbox::default();
        let new: usize = (0..1000u64)
            .chain(0..1000)
            .filter(|&i| m.insert(i * 7919))
            .count();
        assert_eq!(new, 1000);
        m.clear();
        assert!(m.insert(0));
        assert!(!m.insert(0));
    }
}
