//! One integration binary (ripgrep/xsv style): CLI end to end, brute-force oracles, bad input.

mod bad_input;
mod bench;
mod cli;
mod common;
mod conventions;
mod detp_competitors;
mod detp_edge;
mod detp_engines;
mod detp_runs;
mod layers;
mod lt;
mod merge;
mod never_panics;
mod oracle;
mod photon_shards;
mod protocol;
mod quasi_static;
mod reference;
mod render;
mod report;
mod reproducible;
mod resume;
mod runs;
mod sanity;
mod slurm;
mod stability;
