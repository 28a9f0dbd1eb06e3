//! Sample points with normals: on a scene's surfaces at a chosen spacing, or read from a user's CSV
//! (to compare with another renderer at chosen spots).
//!
//! Triangles are split into m² congruent sub-triangles (m = ⌈√area / spacing⌉: one point per
//! spacing² of area) and get a point at each sub-triangle's centroid, so points cover the surface
//! evenly; spheres get a Fibonacci lattice of ≈ area / spacing² points. Normals are the light-receiving
//! side's. Emitting surfaces get no points.
//!
//! [`open_surface_points`] drops the lattice points that other geometry covers — floor under a box
//! standing on it, ceiling behind a lamp — where the true irradiance is 0 but a disc of radius d
//! reaches past the cover and reads leaked light. A point is covered when
//! - another surface lies within δ of it along its normal (contact: a box's bottom on the floor;
//!   δ = 10⁻⁶ of the scene's scale, [`crate::lt::precision::Precision::contact`]), or
//! - every probe of a fixed fan over its hemisphere (the normal and six directions 60° from it)
//!   meets the *back* of a surface first (the point lies inside a solid, or under an open-bottomed
//!   box). One probe meeting a front face or escaping the scene keeps the point, so a single
//!   surface wound the wrong way cannot hide open floor.

use std::f64::consts::PI;
use std::path::Path;

use glam::DVec3;

use crate::error::InputError;

use crate::lt::shapes::{Ball, Triangle};
use crate::lt::{Prim, Scene, Surface};

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
    let (p, n, _) = points_with_prims(triangles, balls, surfaces, spacing);
    (p, n)
}

/// The static surface points of [`surface_points`] without those other geometry covers (see the
/// module doc), and how many were dropped.
pub fn open_surface_points(scene: &Scene, spacing: f64) -> (Vec<DVec3>, Vec<DVec3>, u64) {
    let (t, b) = scene.static_geometry();
    let (pts, nrm, prims) = points_with_prims(t, b, &scene.surfaces, spacing);
    let keep: Vec<bool> = pts
        .iter()
        .zip(&nrm)
        .zip(&prims)
        .map(|((&p, &n), &own)| !covered(scene, p, n, own))
        .collect();
    let dropped = keep.iter().filter(|&&k| !k).count() as u64;
    let pick = |v: Vec<DVec3>| -> Vec<DVec3> {
        v.into_iter()
            .zip(&keep)
            .filter_map(|(x, &k)| k.then_some(x))
            .collect()
    };
    (pick(pts), pick(nrm), dropped)
}

/// Is the point `p` with unit normal `n` on primitive `own` covered by other geometry? (See the
/// module doc.)
pub fn covered(scene: &Scene, p: DVec3, n: DVec3, own: Prim) -> bool {
    let precision = scene.precision();
    let (delta, offset) = (precision.contact(), precision.offset());
    // Contact: from δ behind the point (a coplanar cover sits at t ≈ δ), skipping its own
    // triangle; a sphere's own surface is left behind by starting at the point.
    let contact = match own {
        Prim::Triangle(_) => scene.first_hit(p - n * delta, n, 0.0, Some(own)),
        Prim::Ball(_) => scene.first_hit(p, n, offset, None),
    };
    if contact.is_some_and(|h| {
        let reach = if matches!(own, Prim::Triangle(_)) {
            2.0 * delta
        } else {
            delta
        };
        h.prim != own && h.t <= reach
    }) {
        return true;
    }
    // Inside a solid: every probe of the fan meets a back face first.
    let (a, b) = n.any_orthonormal_pair();
    let (s, c) = (60f64.to_radians().sin(), 60f64.to_radians().cos());
    let fan = std::iter::once(n).chain((0..6).map(|k| {
        let phi = k as f64 * PI / 3.0;
        (a * phi.cos() + b * phi.sin()) * s + n * c
    }));
    let skip = matches!(own, Prim::Triangle(_)).then_some(own);
    for d in fan {
        let Some(h) = scene.first_hit(p, d, offset, skip) else {
            return false;
        };
        let q = p + d * h.t;
        if scene.normal(h.prim, q).dot(d) <= 0.0 {
            return false;
        }
    }
    true
}

/// Points, unit normals and the primitive each lies on.
fn points_with_prims(
    triangles: &[Triangle],
    balls: &[Ball],
    surfaces: &[Surface],
    spacing: f64,
) -> (Vec<DVec3>, Vec<DVec3>, Vec<Prim>) {
    let (mut pts, mut nrm, mut prims) = (Vec::new(), Vec::new(), Vec::new());
    for (ti, t) in triangles.iter().enumerate() {
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
                prims.push(Prim::Triangle(ti as u32));
                if i + j + 1 < m {
                    pts.push(a + e1 * (i as f64 + 2.0 / 3.0) + e2 * (j as f64 + 2.0 / 3.0));
                    nrm.push(n);
                    prims.push(Prim::Triangle(ti as u32));
                }
            }
        }
    }
    for (bi, b) in balls.iter().enumerate() {
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
            prims.push(Prim::Ball(bi as u32));
        }
    }
    (pts, nrm, prims)
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

#[cfg(test)]
mod tests {
    use std::path::Path;

    use super::*;

    /// A 4 × 4 floor, a cube's bottom face lying on it (coplanar, facing down), a box open at the
    /// bottom standing on it elsewhere (faces wound outward), and a light above.
    const SCENE: &str = r#"
[[surface]]
name = "floor"
kind = "quad"
vertices = [[-2, 0, -2], [-2, 0, 2], [2, 0, 2], [2, 0, -2]]
albedo = 0.5
[[surface]]
name = "cube bottom"
kind = "quad"
vertices = [[-1.5, 0, -1.5], [-0.5, 0, -1.5], [-0.5, 0, -0.5], [-1.5, 0, -0.5]]
albedo = 0.5
[[surface]]
name = "open box top"
kind = "quad"
vertices = [[0.5, 1, 0.5], [0.5, 1, 1.5], [1.5, 1, 1.5], [1.5, 1, 0.5]]
albedo = 0.5
[[surface]]
name = "open box side"
kind = "quad"
vertices = [[0.5, 0, 0.5], [0.5, 1, 0.5], [1.5, 1, 0.5], [1.5, 0, 0.5]]
albedo = 0.5
[[surface]]
name = "open box side"
kind = "quad"
vertices = [[0.5, 0, 1.5], [1.5, 0, 1.5], [1.5, 1, 1.5], [0.5, 1, 1.5]]
albedo = 0.5
[[surface]]
name = "open box side"
kind = "quad"
vertices = [[0.5, 0, 0.5], [0.5, 0, 1.5], [0.5, 1, 1.5], [0.5, 1, 0.5]]
albedo = 0.5
[[surface]]
name = "open box side"
kind = "quad"
vertices = [[1.5, 0, 0.5], [1.5, 1, 0.5], [1.5, 1, 1.5], [1.5, 0, 1.5]]
albedo = 0.5
[[light]]
kind = "point"
position = [0, 3, 0]
power = 10.0
"#;

    #[test]
    fn floor_under_a_box_or_in_contact_with_a_face_is_covered_and_open_floor_is_not() {
        let s = Scene::parse(SCENE, Path::new("t.toml")).expect("scene");
        let (all, _) = surface_points(&s, 0.25, 0);
        let (open, normals, covered) = open_surface_points(&s, 0.25);
        let floor_under = |p: &DVec3, lo: f64, hi: f64, zlo: f64, zhi: f64| {
            p.y == 0.0 && p.x > lo && p.x < hi && p.z > zlo && p.z < zhi
        };
        // Floor under the cube (contact with its bottom face) and under the open box.
        let under_cube = |p: &DVec3| floor_under(p, -1.5, -0.5, -1.5, -0.5);
        let under_box = |p: &DVec3| floor_under(p, 0.5, 1.5, 0.5, 1.5);
        assert!(all.iter().any(under_cube) && all.iter().any(under_box));
        assert!(
            !open.iter().any(under_cube),
            "floor in contact with the cube's bottom"
        );
        assert!(!open.iter().any(under_box), "floor inside the open box");
        // The open box's top faces up (its points stay); its sides face out (their points stay).
        assert!(open.iter().any(|p| p.y == 1.0));
        assert!(open.iter().any(|p| p.x == 1.5 && p.y > 0.0));
        // Open floor stays, and nothing else was dropped: the cube bottom's own points (facing down,
        // into the floor) are covered too.
        let floor_open = open
            .iter()
            .zip(&normals)
            .filter(|(p, n)| p.y == 0.0 && n.y > 0.0)
            .count();
        assert!(floor_open > 100, "{floor_open}");
        assert_eq!(open.len() as u64 + covered, all.len() as u64);
        let expected = all.iter().filter(|p| under_cube(p) || under_box(p)).count() as u64;
        assert_eq!(covered, expected, "only the points under the two boxes");
    }
}
