//! Memory latency of this machine by pointer chasing (how the bench's prefetch distances were
//! reasoned about): `cargo run --release --example mem_latency -- MB...`. Each MB size is a random
//! cyclic chain of cache lines on huge pages; the time per dependent load is the latency of the
//! level that size fits in (L2, L3, DRAM).
use raycost::grid::huge::HugeSlice;

fn main() {
    let sizes: Vec<usize> = std::env::args()
        .skip(1)
        .map(|a| a.parse().expect("a size in MB"))
        .collect();
    for mb in if sizes.is_empty() {
        vec![1, 8, 24, 64, 512]
    } else {
        sizes
    } {
        let lines = (mb << 20) / 64;
        let mut chain = HugeSlice::<u64>::zeroed(lines * 8);
        // A random cyclic order of the lines (Sattolo's shuffle, xorshift64).
        let mut order: Vec<usize> = (0..lines).collect();
        let mut x = 0x9e37_79b9_7f4a_7c15u64;
        for i in (1..lines).rev() {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            order.swap(i, (x % i as u64) as usize);
        }
        for i in 0..lines {
            chain[order[i] * 8] = (order[(i + 1) % lines] * 8) as u64;
        }
        let steps = 10_000_000usize;
        let mut p = 0usize;
        let start = std::time::Instant::now();
        for _ in 0..steps {
            p = chain[p] as usize;
        }
        let ns = start.elapsed().as_secs_f64() * 1e9 / steps as f64;
        println!("{mb:>6} MB: {ns:6.1} ns per dependent load (end {p})");
    }
}
