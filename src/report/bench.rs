//! The speed table of `raycost bench` (`RESULTS/bench/bench.csv`) as the page shows it: the columns
//! that say what was timed and how fast it went, in the order below, and only those that hold a
//! value in some row (the table has ~40 columns, most of them for one engine each); the full table
//! is linked beside it.

use super::table::{display, Table};
use crate::bench::columns as bc;
use crate::output::column::Column;

/// The columns shown, in this order, when present: named by the bench's own declarations, so a
/// renamed column is followed here (and a removed one fails to compile) instead of silently
/// dropping out of the page.
const SHOWN: &[Column] = &[
    bc::ENGINE,
    bc::N,
    bc::THREADS,
    bc::CELL_WIDTH,
    bc::RAYS,
    bc::ROUNDS,
    bc::RAYS_PER_S,
    bc::RAY_SPHERE_TESTS_PER_S,
    bc::RAY_DISC_TESTS_PER_S,
    bc::ROUND_MEDIAN_S,
    bc::FRAME_S,
    bc::BUILD_S,
    bc::STRUCTURE_BYTES,
    bc::PEAK_MEM_BYTES,
    bc::CHECKED,
    bc::MISMATCHES,
];

/// The shown part of a bench table: header and display cells.
#[derive(Clone, Debug, PartialEq)]
pub struct BenchTable {
    /// Column names.
    pub header: Vec<String>,
    /// Display cells.
    pub rows: Vec<Vec<String>>,
}

/// The shown columns of `t` with their display cells.
pub fn shown(t: &Table) -> BenchTable {
    let cols: Vec<&str> = SHOWN
        .iter()
        .map(|c| c.name)
        .filter(|c| {
            t.has(c) && (0..t.rows.len()).any(|r| !display(t.cell(r, c).unwrap_or("")).is_empty())
        })
        .collect();
    BenchTable {
        header: cols.iter().map(|c| c.to_string()).collect(),
        rows: (0..t.rows.len())
            .map(|r| {
                cols.iter()
                    .map(|c| display(t.cell(r, c).unwrap_or("")))
                    .collect()
            })
            .collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_known_columns_with_a_value_are_shown_in_order() {
        let t = Table::parse(
            "rays_per_s,engine,frame_s,extra,threads\n4491480.5,grid,NaN,1,2\n20744.0,brute-force,,2,2\n",
        )
        .expect("csv");
        let b = shown(&t);
        assert_eq!(b.header, ["engine", "threads", "rays_per_s"]);
        assert_eq!(b.rows[0], ["grid", "2", "4.491e6"]);
        assert_eq!(b.rows[1], ["brute-force", "2", "20744"]);
    }
}
