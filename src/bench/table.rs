//! One bench table for engines that report different things: the grid's rows carry rounds and
//! N_I/N_S, the DETP rows tests per second. Rows are written with the union of all columns, in
//! first-appearance order, NaN where a row has nothing to say, so `bench.csv` has one header.

use super::detp::DetpBenchRow;
use crate::output::row::{Row, Value};

/// A DETP engine's bench row (CONTRACT: `engine, n, threads, rays_per_s, build_s, peak_mem_bytes,
/// mismatches`, plus `ray_sphere_tests_per_s`, `ray_disc_tests_per_s`).
pub fn detp_row(r: &DetpBenchRow) -> Row {
    let mut row = Row::default();
    row.s("engine", r.engine)
        .u("n", r.points)
        .u("threads", r.threads as u64)
        .u("rays", r.rays)
        .f("rays_per_s", r.rays as f64 / r.wall_s)
        .f("wall_s", r.wall_s)
        .f("build_s", r.build_s)
        .u("peak_mem_bytes", r.peak_mem_bytes)
        .u("mismatches", r.mismatches)
        .u("ray_sphere_tests", r.ray_sphere_tests)
        .u("ray_disc_tests", r.ray_disc_tests)
        .f("ray_sphere_tests_per_s", r.ray_sphere_tests_per_s)
        .f("ray_disc_tests_per_s", r.ray_disc_tests_per_s)
        .s("filter_path", r.filter_path);
    row
}

/// The rows with every column of every row, in first-appearance order (missing cells NaN).
pub fn union_columns(rows: &[Row]) -> Vec<Row> {
    let mut cols: Vec<&str> = Vec::new();
    for r in rows {
        for (c, _) in &r.0 {
            if !cols.contains(&c.as_str()) {
                cols.push(c);
            }
        }
    }
    rows.iter()
        .map(|r| {
            Row(cols
                .iter()
                .map(|&c| {
                    let v = r.get(c).cloned().unwrap_or(Value::F(f64::NAN));
                    (c.to_string(), v)
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
        a.s("engine", "grid").u("n", 10).f("cell_s", 1.0);
        let mut b = Row::default();
        b.s("engine", "sphere-cache")
            .u("n", 5)
            .f("ray_disc_tests_per_s", 2.0);
        let u = union_columns(&[a, b]);
        let names: Vec<&str> = u[1].0.iter().map(|(c, _)| c.as_str()).collect();
        assert_eq!(names, ["engine", "n", "cell_s", "ray_disc_tests_per_s"]);
        assert!(matches!(u[1].get("cell_s"), Some(Value::F(x)) if x.is_nan()));
        assert!(matches!(u[0].get("ray_disc_tests_per_s"), Some(Value::F(x)) if x.is_nan()));
        assert_eq!(u[1].get("n"), Some(&Value::U(5)));
    }
}
