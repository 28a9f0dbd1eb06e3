//! The memory layout traversal reads: 8-wide nodes with f32 boxes rounded outward, and leaves of
//! triangle packets (four triangles as structure-of-arrays f64, their edges precomputed with the
//! same f64 subtractions as [`Triangle::intersect`], so a packet test is bit for bit that test).

use glam::DVec3;

use crate::lt::shapes::Triangle;

/// Children per node.
pub const WIDTH: usize = 8;
/// Triangles per packet.
pub const LANES: usize = 4;

/// A child reference: a node index, or (bit 31 set) a leaf of `count` packets from `start`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ChildRef(pub u32);

/// Leaf bit of a [`ChildRef`].
const LEAF: u32 = 1 << 31;
/// Bits of a leaf's packet start (the count takes bits 24..31).
const START_BITS: u32 = 24;
/// Packets a leaf holds at most.
pub const MAX_LEAF_PACKETS: u32 = (1 << (31 - START_BITS)) - 1;

impl ChildRef {
    /// An empty slot (its box is empty too, so traversal never reaches it).
    pub const EMPTY: Self = Self(u32::MAX);

    /// An inner node.
    pub fn node(index: usize) -> Self {
        assert!(index < LEAF as usize, "too many BVH nodes");
        Self(index as u32)
    }

    /// A leaf of `count` packets from `start`.
    pub fn leaf(start: usize, count: usize) -> Self {
        assert!(
            start < (1 << START_BITS) && (1..=MAX_LEAF_PACKETS as usize).contains(&count),
            "BVH leaf out of range"
        );
        Self(LEAF | ((count as u32) << START_BITS) | start as u32)
    }

    /// Is it a leaf?
    #[inline(always)]
    pub fn is_leaf(self) -> bool {
        self.0 & LEAF != 0
    }

    /// A leaf's packets, as a range of indices.
    #[inline(always)]
    pub fn packets(self) -> std::ops::Range<usize> {
        let start = (self.0 & ((1 << START_BITS) - 1)) as usize;
        let count = ((self.0 & !LEAF) >> START_BITS) as usize;
        start..start + count
    }

    /// An inner node's index.
    #[inline(always)]
    pub fn index(self) -> usize {
        self.0 as usize
    }
}

/// Eight children's boxes (f32, rounded outward from the padded f64 boxes) and references. An
/// empty slot has the empty box lo = +∞, hi = −∞, which no finite ray meets.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub struct Node {
    /// Lower corners, per axis, per child.
    pub lo: [[f32; WIDTH]; 3],
    /// Upper corners.
    pub hi: [[f32; WIDTH]; 3],
    /// What each child is.
    pub child: [ChildRef; WIDTH],
}

impl Node {
    /// A node with every slot empty.
    pub fn empty() -> Self {
        Self {
            lo: [[f32::INFINITY; WIDTH]; 3],
            hi: [[f32::NEG_INFINITY; WIDTH]; 3],
            child: [ChildRef::EMPTY; WIDTH],
        }
    }

    /// Sets slot `k` to `child` with the f64 box `(lo, hi)`, rounded outward to f32.
    pub fn set(&mut self, k: usize, child: ChildRef, lo: DVec3, hi: DVec3) {
        for a in 0..3 {
            self.lo[a][k] = f32_down(lo[a]);
            self.hi[a][k] = f32_up(hi[a]);
        }
        self.child[k] = child;
    }
}

/// Four triangles: vertex 0 and the edges v1 − v0, v2 − v0 (f64, as `Triangle::intersect` computes
/// them), and their indices. Unused lanes have zero edges (determinant 0: never a hit) and index
/// `u32::MAX`.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(32))]
pub struct Packet {
    /// Vertex 0, per axis, per lane.
    pub v0: [[f64; LANES]; 3],
    /// Edge v1 − v0.
    pub e1: [[f64; LANES]; 3],
    /// Edge v2 − v0.
    pub e2: [[f64; LANES]; 3],
    /// Triangle indices (`u32::MAX`: unused lane).
    pub id: [u32; LANES],
}

impl Packet {
    /// Up to four triangles `(index, triangle)`.
    pub fn new(tris: &[(u32, Triangle)]) -> Self {
        assert!(tris.len() <= LANES, "a packet holds four triangles");
        let mut p = Self {
            v0: [[0.0; LANES]; 3],
            e1: [[0.0; LANES]; 3],
            e2: [[0.0; LANES]; 3],
            id: [u32::MAX; LANES],
        };
        for (l, (id, t)) in tris.iter().enumerate() {
            let e1 = t.v[1] - t.v[0];
            let e2 = t.v[2] - t.v[0];
            for a in 0..3 {
                p.v0[a][l] = t.v[0][a];
                p.e1[a][l] = e1[a];
                p.e2[a][l] = e2[a];
            }
            p.id[l] = *id;
        }
        p
    }
}

/// Magnitudes above this (2³⁰) turn a packet's f32 pre-test off (see [`PacketF32`]).
pub const F32_DOMAIN: f64 = (1u64 << 30) as f64;

/// A packet's four triangles in f32, for the conservative pre-test that spares the exact f64 test
/// the lanes it can prove missed (`kernel::avx2::keep`; the proof is in the kernel's doc):
/// vertex 0 and the two edges, each f64 value of [`Packet`] rounded to the nearest f32, and per lane
/// the largest |component| of each of the three, rounded up. A lane whose magnitudes exceed
/// [`F32_DOMAIN`] (or are not finite) gets +∞ magnitudes, which make every error bound +∞ or NaN:
/// the pre-test then never rejects it. Unused lanes are not live (their bit in `live` is clear).
#[derive(Clone, Copy, Debug)]
#[repr(C, align(16))]
pub struct PacketF32 {
    /// Vertex 0, per axis, per lane.
    pub v0: [[f32; LANES]; 3],
    /// Edge v1 − v0.
    pub e1: [[f32; LANES]; 3],
    /// Edge v2 − v0.
    pub e2: [[f32; LANES]; 3],
    /// Per lane: max |v0ᵢ|, max |e1ᵢ|, max |e2ᵢ|, rounded up.
    pub mag: [[f32; LANES]; 3],
    /// Bit l set if lane l holds a triangle.
    pub live: u32,
}

impl PacketF32 {
    /// The f32 copy of `p`.
    pub fn new(p: &Packet) -> Self {
        let mut f = Self {
            v0: [[0.0; LANES]; 3],
            e1: [[0.0; LANES]; 3],
            e2: [[0.0; LANES]; 3],
            mag: [[0.0; LANES]; 3],
            live: 0,
        };
        for l in 0..LANES {
            if p.id[l] != u32::MAX {
                f.live |= 1 << l;
            }
            let rows = [&p.v0, &p.e1, &p.e2];
            let mut mags = [0.0f64; 3];
            for (r, row) in rows.iter().enumerate() {
                for a in 0..3 {
                    mags[r] = mags[r].max(row[a][l].abs());
                }
            }
            let in_domain = mags.iter().all(|m| *m <= F32_DOMAIN);
            for a in 0..3 {
                f.v0[a][l] = p.v0[a][l] as f32;
                f.e1[a][l] = p.e1[a][l] as f32;
                f.e2[a][l] = p.e2[a][l] as f32;
            }
            for (row, m) in f.mag.iter_mut().zip(mags) {
                // (A NaN component is ignored by `max` here but makes the lane's f32 values NaN, and
                // NaN fails every comparison the pre-test rejects by: the lane is kept.)
                row[l] = if in_domain { f32_up(m) } else { f32::INFINITY };
            }
        }
        f
    }
}

/// The largest f32 not above `x` (−∞ below f32's range).
pub fn f32_down(x: f64) -> f32 {
    let y = x as f32;
    if f64::from(y) > x {
        y.next_down()
    } else {
        y
    }
}

/// The smallest f32 not below `x` (+∞ above f32's range).
pub fn f32_up(x: f64) -> f32 {
    let y = x as f32;
    if f64::from(y) < x {
        y.next_up()
    } else {
        y
    }
}
