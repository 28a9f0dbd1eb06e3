//! Sample points with normals: on a scene's surfaces at a chosen spacing, or read from a user's CSV
//! (to compare with another renderer at chosen spots).
//!
//! Triangles are split into m² congruent sub-triangles (m = ⌈√area / spacing⌉: one point per
//! spacing² of area) and get a point at each sub-triangle's centroid, so points cover the surface
//! evenly; spheres get a Fibonacci lattice of ≈ area / spacing² points. Normals are the light-receiving
//! side's. Emitting surfaces get no points.

use std::f64::consts::PI;
use std::path::Path;

use glam::DVec3;

use crate::error::InputError;

use crate::lt::shapes::{Ball, Triangle};
use crate::lt::{Scene, Surface};

/// Points and unit normals on every non-emitting static surface, at spacing ≈ `spacing` (a dynamic
/// object's points come from [`points_on`] over its rest geometry). `seed` is kept for a jittered
/// variant; the lattice itself is deterministic.
pub fn surface_points(scene: &Scene, spacing: f64, _seed: u64) -> (Vec<DVec3>, Vec<DVec3>) {
    let (t, b) = scene.static_geometry();
    points_on(t, b, &scene.surfaces, spacing)
}

/// Points and unit normals on the non-emitting ones of `triangles` and `balls`, at spacing
/// ≈ `spacing`.
pub fn points_on(
    triangles: &[Triangle],
    balls: &[Ball],
    surfaces: &[Surface],
    spacing: f64,
) -> (Vec<DVec3>, Vec<DVec3>) {
    let (mut pts, mut nrm) = (Vec::new(), Vec::new());
    for t in triangles {
        if surfaces[t.surface as usize].emission > 0.0 {
            continue;
        }
        // m² points on area A: one per spacing² of area.
        let m = (t.area().sqrt() / spacing).ceil().max(1.0) as usize;
        let (a, e1, e2) = (
            t.v[0],
            (t.v[1] - t.v[0]) / m as f64,
            (t.v[2] - t.v[0]) / m as f64,
        );
        let n = t.normal();
        for i in 0..m {
            for j in 0..m - i {
                // Upward sub-triangle (i, j), and the downward one beside it.
                pts.push(a + e1 * (i as f64 + 1.0 / 3.0) + e2 * (j as f64 + 1.0 / 3.0));
                nrm.push(n);
                if i + j + 1 < m {
                    pts.push(a + e1 * (i as f64 + 2.0 / 3.0) + e2 * (j as f64 + 2.0 / 3.0));
                    nrm.push(n);
                }
            }
        }
    }
    for b in balls {
        if surfaces[b.surface as usize].emission > 0.0 && !b.inside {
            continue;
        }
        let count = (b.area() / (spacing * spacing)).round().max(1.0) as usize;
        let golden = PI * (3.0 - 5f64.sqrt());
        for k in 0..count {
            let z = 1.0 - (2.0 * k as f64 + 1.0) / count as f64;
            let r = (1.0 - z * z).max(0.0).sqrt();
            let phi = golden * k as f64;
            let p = b.center + DVec3::new(r * phi.cos(), r * phi.sin(), z) * b.radius;
            pts.push(p);
            nrm.push(b.normal_at(p));
        }
    }
    (pts, nrm)
}

/// Reads `x, y, z, nx, ny, nz` rows (a header line naming those columns). Errors are located in the
/// file (line, and the column's name as the key): a missing column, a value that is not a finite
/// number, a zero normal, no rows.
pub fn read_points_csv(path: &Path) -> Result<(Vec<DVec3>, Vec<DVec3>), InputError> {
    let err = |line: Option<usize>, key: Option<&str>, m: String| {
        let e = InputError::new(path.display().to_string(), m).at(line.map(|l| (l, 1)));
        match key {
            Some(k) => e.key(k),
            None => e,
        }
    };
    let mut r = csv::Reader::from_path(path).map_err(|e| err(None, None, e.to_string()))?;
    let header = r
        .headers()
        .map_err(|e| err(Some(1), None, e.to_string()))?
        .clone();
    let cols: Vec<usize> = ["x", "y", "z", "nx", "ny", "nz"]
        .iter()
        .map(|c| {
            header.iter().position(|h| h.trim() == *c).ok_or_else(|| {
                err(
                    Some(1),
                    None,
                    format!("missing column {c} (need x, y, z, nx, ny, nz)"),
                )
            })
        })
        .collect::<Result<_, _>>()?;
    let (mut pts, mut nrm) = (Vec::new(), Vec::new());
    for (i, rec) in r.records().enumerate() {
        let line = i + 2;
        let rec = rec.map_err(|e| err(Some(line), None, e.to_string()))?;
        let mut v = [0.0; 6];
        for (k, &c) in cols.iter().enumerate() {
            let cell = rec.get(c).unwrap_or("").trim();
            let name = header.get(c).unwrap_or("?");
            v[k] = cell
                .parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| {
                    err(
                        Some(line),
                        Some(name),
                        format!("got {cell:?}, expected a finite number"),
                    )
                })?;
        }
        let n = DVec3::new(v[3], v[4], v[5]);
        if n.length_squared() == 0.0 {
            return Err(err(Some(line), None, "the normal is zero".into()));
        }
        pts.push(DVec3::new(v[0], v[1], v[2]));
        nrm.push(n.normalize());
    }
    if pts.is_empty() {
        return Err(err(None, None, "no points".into()));
    }
    Ok((pts, nrm))
}
