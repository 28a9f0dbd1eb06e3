//! One bench table for engines that report different things: the grid's rows carry rounds and
//! N_I/N_S, the DETP rows tests per second. Rows are written with the union of all columns, in
//! first-appearance order, NaN where a row has nothing to say, so `bench.csv` has one header.

use super::columns as bc;
use super::detp::DetpBenchRow;
use crate::output::row::{Cell, Row, Value};

/// A DETP engine's bench row (CONTRACT: `engine, n, threads, rays_per_s, build_s, peak_mem_bytes,
/// mismatches`, plus `ray_sphere_tests_per_s`, `ray_disc_tests_per_s`).
pub fn detp_row(r: &DetpBenchRow) -> Row {
    let mut row = Row::default();
    row.put(&bc::ENGINE, r.engine)
        .put(&bc::N, r.points)
        .put(&bc::THREADS, r.threads as u64)
        .put(&bc::RAYS, r.rays)
        .put(&bc::RAYS_PER_S, r.rays as f64 / r.wall_s)
        .put(&bc::WALL_S, r.wall_s)
        .put(&bc::BUILD_S, r.build_s)
        .put(&bc::PEAK_MEM_BYTES, r.peak_mem_bytes)
        .put(&bc::MISMATCHES, r.mismatches)
        .put(&bc::RAY_SPHERE_TESTS, r.ray_sphere_tests)
        .put(&bc::RAY_DISC_TESTS, r.ray_disc_tests)
        .put(&bc::RAY_SPHERE_TESTS_PER_S, r.ray_sphere_tests_per_s)
        .put(&bc::RAY_DISC_TESTS_PER_S, r.ray_disc_tests_per_s)
        .put(&bc::FILTER_PATH, r.filter_path);
    row
}

/// The rows with every column of every row, in first-appearance order (missing cells NaN, with the
/// class of the row that declared the column).
pub fn union_columns(rows: &[Row]) -> Vec<Row> {
    let mut cols: Vec<&Cell> = Vec::new();
    for r in rows {
        for c in &r.0 {
            if !cols.iter().any(|k| k.name == c.name) {
                cols.push(c);
            }
        }
    }
    rows.iter()
        .map(|r| {
            Row(cols
                .iter()
                .map(|&k| Cell {
                    value: r.get(&k.name).cloned().unwrap_or(Value::F(f64::NAN)),
                    ..k.clone()
                })
                .collect())
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn union_keeps_order_and_fills_gaps_with_nan() {
        let mut a = Row::default();
        a.put(&bc::ENGINE, "grid")
            .put(&bc::N, 10u64)
            .put(&bc::CELL_S, 1.0);
        let mut b = Row::default();
        b.put(&bc::ENGINE, "sphere-cache")
            .put(&bc::N, 5u64)
            .put(&bc::RAY_DISC_TESTS_PER_S, 2.0);
        let u = union_columns(&[a, b]);
        let names: Vec<&str> = u[1].0.iter().map(|c| c.name.as_str()).collect();
        assert_eq!(names, ["engine", "n", "cell_s", "ray_disc_tests_per_s"]);
        assert!(matches!(u[1].get("cell_s"), Some(Value::F(x)) if x.is_nan()));
        assert!(matches!(u[0].get("ray_disc_tests_per_s"), Some(Value::F(x)) if x.is_nan()));
        assert_eq!(u[1].get("n"), Some(&Value::U(5)));
    }
}
