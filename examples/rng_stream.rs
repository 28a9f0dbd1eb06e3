//! Writes raycost's random streams to stdout as raw little-endian 64-bit words, for a statistical
//! battery reading raw input (`dieharder -g 200`; `scripts/rng_quality.sh` runs it):
//!
//! ```text
//! cargo run --release --example rng_stream -- photons K   # words 0..K of [PHOTON, 1, id], id = 0, 1, …
//! cargo run --release --example rng_stream -- seeds       # word 0 of [PHOTON, s, 0], s = 0, 1, …
//! cargo run --release --example rng_stream -- interleave K  # words 0..64 of K consecutive photons, side by side
//! cargo run --release --example rng_stream -- long        # one stream [RAYS, 1, 0, 0]
//! ```
//! `photons 1` is the hard case for a counter-based generator: the first word of streams whose keys
//! differ by one in their last word, as the photon tracer, the reference's samples and the line
//! batches key them. Runs until the reader closes the pipe.

use rand::RngCore;
use raycost::sample::rng::{domain, stream};
use std::io::Write;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let k = |i: usize| -> u64 { args.get(i).map_or(1, |a| a.parse().expect("a count")) };
    let mode = args.first().map_or("photons", String::as_str);
    let out = std::io::stdout();
    let mut out = std::io::BufWriter::with_capacity(1 << 16, out.lock());
    let mut buf = Vec::with_capacity(1 << 16);
    let mut next = 0u64;
    let mut long = stream(&[domain::RAYS, 1, 0, 0]);
    loop {
        buf.clear();
        while buf.len() < 1 << 16 {
            match mode {
                "photons" => {
                    let mut s = stream(&[domain::PHOTON, 1, next]);
                    for _ in 0..k(1) {
                        buf.extend_from_slice(&s.next_u64().to_le_bytes());
                    }
                }
                "seeds" => {
                    let w = stream(&[domain::PHOTON, next, 0]).next_u64();
                    buf.extend_from_slice(&w.to_le_bytes());
                }
                "interleave" => {
                    // K consecutive photons side by side: word 0 of each, then word 1, … to 63.
                    let mut group: Vec<_> = (next * k(1)..(next + 1) * k(1))
                        .map(|id| stream(&[domain::PHOTON, 1, id]))
                        .collect();
                    for _ in 0..64 {
                        for s in &mut group {
                            buf.extend_from_slice(&s.next_u64().to_le_bytes());
                        }
                    }
                }
                "long" => buf.extend_from_slice(&long.next_u64().to_le_bytes()),
                other => {
                    eprintln!("unknown mode {other}: photons K, seeds, interleave K or long");
                    std::process::exit(2);
                }
            }
            next += 1;
        }
        if out.write_all(&buf).is_err() {
            return; // the battery closed the pipe
        }
    }
}
