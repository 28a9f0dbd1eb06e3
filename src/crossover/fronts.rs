//! What the fronts (a kind-`detp` run with a reference, ≥ 2 replicas and a sweep over
//! detp.direct × detp.edge × detp.photons × detp.disc_radius) say about errors: per DETP
//! configuration and replica the relative MSE at each photon count; per photon map its relative MSE
//! from the main table's means; per replica the path tracer's cv².
//!
//! Relative MSE of a replica: [mean_i (E_ri − R_i)² − mean_i se_R,i²] / (mean_i R_i)², the truth's
//! variance subtracted exactly as the kind computes `irradiance_ref_rmse`
//! ([`squared_error_sum`]), over the same points.

use std::collections::BTreeMap;

use super::input::Csv;
use super::method::{Config, Method};
use crate::error::OutputError;
use crate::experiment::detp::engines::squared_error_sum;
use crate::stats::crossover::PathTracingCost;

/// One DETP configuration's errors (both engines: they agree bit for bit).
#[derive(Clone, Debug, PartialEq)]
pub struct DetpErrors {
    /// detp.direct, detp.edge, detp.disc_radius (method: the sphere cache; the disc index's row
    /// copies it).
    pub config: Config,
    /// Photon counts, increasing.
    pub photons: Vec<f64>,
    /// `mse[r][j]`: replica r's relative MSE at `photons[j]`.
    pub mse: Vec<Vec<f64>>,
}

/// A photon map's errors: only the mean over replicas is in the tables.
#[derive(Clone, Debug, PartialEq)]
pub struct MapErrors {
    /// The map and detp.direct.
    pub config: Config,
    /// Effective photons R·N of the mean over R replicas, increasing.
    pub photons: Vec<f64>,
    /// (`{}_ref_rmse_mean` / `reference_irradiance_mean`)² at each.
    pub mse: Vec<f64>,
}

/// Relative MSE of `est` against the reference `refr` (R_i, se_R,i): see the module doc.
pub fn relative_mse(est: &[f64], refr: &[(f64, f64)]) -> f64 {
    let n = est.len().min(refr.len()) as f64;
    let truth = refr.iter().map(|r| r.0).sum::<f64>() / n;
    squared_error_sum(est.iter().copied(), refr) / n / (truth * truth)
}

/// Rows of the points table per sweep point.
pub fn rows_by_point(points: &Csv) -> Result<BTreeMap<u64, Vec<usize>>, OutputError> {
    let p = points.numbers("point", "the sweep point of each sample")?;
    let mut by: BTreeMap<u64, Vec<usize>> = BTreeMap::new();
    for (i, &x) in p.iter().enumerate() {
        by.entry(x as u64).or_default().push(i);
    }
    Ok(by)
}

/// The main table's `detp.direct`, `detp.edge`, `detp.disc_radius` of each row.
pub fn settings(main: &Csv) -> Result<Vec<(String, String, f64)>, OutputError> {
    let why = "the configuration of each row";
    let direct = main.texts("detp.direct", why)?;
    let edge = main.texts("detp.edge", why)?;
    let d = main.numbers("detp.disc_radius", why)?;
    Ok((0..main.rows.len())
        .map(|i| (direct[i].clone(), edge[i].clone(), d[i]))
        .collect())
}

/// Per DETP configuration, its replicas' relative MSE at each photon count.
pub fn detp_errors(main: &Csv, points: &Csv) -> Result<Vec<DetpErrors>, OutputError> {
    let reps = points.family("irradiance_replica_");
    if reps.len() < 2 {
        return Err(OutputError::new(
            &points.path,
            "has fewer than 2 irradiance_replica_{r} columns: the crossover's bootstrap needs detp.replicas ≥ 2 in the fronts",
        ));
    }
    let why = "the truth DETP is judged against: engine reference";
    let (refe, refse) = (
        points.numbers("reference_e", why)?,
        points.numbers("reference_se", why)?,
    );
    let replica: Vec<Vec<f64>> = reps
        .iter()
        .map(|(_, c)| points.numbers(c, "DETP's value per replica"))
        .collect::<Result<_, _>>()?;
    let by = rows_by_point(points)?;
    let sweep = main.numbers("point", "the sweep point")?;
    let photons = main.numbers("detp.photons", "the photon count of each row")?;
    let mut out: Vec<DetpErrors> = Vec::new();
    for (i, (direct, edge, d)) in settings(main)?.into_iter().enumerate() {
        let rows = by.get(&(sweep[i] as u64)).ok_or_else(|| {
            OutputError::new(
                &points.path,
                format!("has no rows of sweep point {}", sweep[i]),
            )
        })?;
        let refr: Vec<(f64, f64)> = rows.iter().map(|&k| (refe[k], refse[k])).collect();
        let mse: Vec<f64> = replica
            .iter()
            .map(|v| relative_mse(&rows.iter().map(|&k| v[k]).collect::<Vec<_>>(), &refr))
            .collect();
        let config = Config {
            method: Method::SphereCache,
            direct: Some(direct),
            edge: Some(edge),
            disc_radius: Some(d),
        };
        let at = match out.iter().position(|e| e.config == config) {
            Some(at) => at,
            None => {
                out.push(DetpErrors {
                    config,
                    photons: Vec::new(),
                    mse: vec![Vec::new(); replica.len()],
                });
                out.len() - 1
            }
        };
        let e = &mut out[at];
        e.photons.push(photons[i]);
        e.mse.iter_mut().zip(mse).for_each(|(m, x)| m.push(x));
    }
    for e in &mut out {
        sort_by_photons(&mut e.photons, &mut e.mse);
    }
    Ok(out)
}

/// Sorts the photon counts increasing, each replica's values with them.
fn sort_by_photons(photons: &mut Vec<f64>, mse: &mut [Vec<f64>]) {
    let mut order: Vec<usize> = (0..photons.len()).collect();
    order.sort_by(|&a, &b| photons[a].total_cmp(&photons[b]));
    *photons = order.iter().map(|&k| photons[k]).collect();
    for m in mse {
        *m = order.iter().map(|&k| m[k]).collect();
    }
}

/// Per photon map present in the table and detp.direct: its relative MSE at R·N effective photons,
/// from the rows at the first (edge, d) of that direct in the table (a photon map does not depend
/// on either).
pub fn map_errors(main: &Csv, replicas: f64) -> Result<Vec<MapErrors>, OutputError> {
    let truth = main.numbers("reference_irradiance_mean", "the truth's mean irradiance")?;
    let photons = main.numbers("detp.photons", "the photon count of each row")?;
    let settings = settings(main)?;
    let mut out = Vec::new();
    for method in Method::MAPS {
        let col = format!("{}_ref_rmse_mean", method.member());
        if !main.has(&col) {
            continue;
        }
        let rmse = main.numbers(&col, "the photon map's error")?;
        let mut seen: Vec<(String, String, f64)> = Vec::new();
        for (direct, edge, d) in &settings {
            if seen.iter().any(|s| &s.0 == direct) {
                continue;
            }
            seen.push((direct.clone(), edge.clone(), *d));
            let mut pts: Vec<(f64, f64)> = (0..settings.len())
                .filter(|&i| settings[i] == (direct.clone(), edge.clone(), *d))
                .map(|i| (replicas * photons[i], (rmse[i] / truth[i]).powi(2)))
                .collect();
            pts.sort_by(|a, b| a.0.total_cmp(&b.0));
            out.push(MapErrors {
                config: Config {
                    method,
                    direct: Some(direct.clone()),
                    edge: None,
                    disc_radius: None,
                },
                photons: pts.iter().map(|p| p.0).collect(),
                mse: pts.iter().map(|p| p.1).collect(),
            });
        }
    }
    Ok(out)
}

/// The path tracer's cv² per replica from `NAME.path_tracing.csv` at its first sweep point (path
/// tracing is the same at every sweep point of a point set), by
/// [`PathTracingCost::cv2_from_prefix_errors`] over its checkpoints, `ref_mse` made relative by the
/// reference's mean over the points it ran on (those with a finite `path_tracing_e_{K}`). Returns
/// (sweep point used, cv² per replica).
pub fn path_tracing_cv2(side: &Csv, points: &Csv) -> Result<(u64, Vec<f64>), OutputError> {
    let why = "path tracing's errors per replica and checkpoint";
    let (point, replica) = (side.numbers("point", why)?, side.numbers("replica", why)?);
    let (paths, mse) = (side.numbers("paths", why)?, side.numbers("ref_mse", why)?);
    let Some(first) = point.iter().copied().map(|p| p as u64).min() else {
        return Err(OutputError::new(&side.path, "has no rows"));
    };
    let rows = rows_by_point(points)?;
    let at = rows.get(&first).ok_or_else(|| {
        OutputError::new(&points.path, format!("has no rows of sweep point {first}"))
    })?;
    let refe = points.numbers("reference_e", "the truth path tracing is judged against")?;
    let ran: Vec<usize> = match points.family("path_tracing_e_").last() {
        Some((_, col)) => {
            let e = points.numbers(col, why)?;
            at.iter().copied().filter(|&k| e[k].is_finite()).collect()
        }
        None => at.clone(),
    };
    let truth = ran.iter().map(|&k| refe[k]).sum::<f64>() / ran.len().max(1) as f64;
    let mut by_replica: BTreeMap<u64, (Vec<f64>, Vec<f64>)> = BTreeMap::new();
    for i in (0..point.len()).filter(|&i| point[i] as u64 == first) {
        let e = by_replica.entry(replica[i] as u64).or_default();
        e.0.push(paths[i]);
        e.1.push(mse[i] / (truth * truth));
    }
    let cv2 = by_replica
        .values()
        .map(|(n, m)| PathTracingCost::cv2_from_prefix_errors(n, m))
        .collect();
    Ok((first, cv2))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn csv(text: &str) -> Csv {
        Csv::from_text(text)
    }

    /// Two points with truth 2 ± 0 and 4 ± 0.5: a replica off by +1 and −1 has squared errors
    /// 1 and 1 − 0.25, mean 0.875, over (mean truth 3)² = 9.
    #[test]
    fn the_relative_mse_subtracts_the_truths_variance() {
        let x = relative_mse(&[3.0, 3.0], &[(2.0, 0.0), (4.0, 0.5)]);
        assert!((x - 0.875 / 9.0).abs() < 1e-15, "{x}");
    }

    #[test]
    fn detp_errors_group_configurations_and_sort_photons() {
        let main = csv(
            "point,detp.direct,detp.edge,detp.photons,detp.disc_radius\n\
             0,photons,paper,200,5\n1,photons,paper,100,5\n2,nee,paper,100,5\n",
        );
        let mut pts = String::from(
            "point,sample,irradiance_replica_0,irradiance_replica_1,reference_e,reference_se\n",
        );
        // Truth 1 at both samples; replica r of sweep point p is off by (p + 1)·(r + 1)·0.1.
        for p in 0..3 {
            for s in 0..2 {
                let off = |r: f64| 1.0 + (p as f64 + 1.0) * (r + 1.0) * 0.1;
                pts.push_str(&format!("{p},{s},{},{},1,0\n", off(0.0), off(1.0)));
            }
        }
        let e = detp_errors(&main, &csv(&pts)).expect("errors");
        assert_eq!(e.len(), 2);
        assert_eq!(e[0].photons, [100.0, 200.0]);
        // Photons 100 is sweep point 1: offsets 0.2 and 0.4.
        assert!((e[0].mse[0][0] - 0.04).abs() < 1e-12 && (e[0].mse[1][0] - 0.16).abs() < 1e-12);
        assert!((e[0].mse[0][1] - 0.01).abs() < 1e-12, "{e:?}");
        assert_eq!(e[1].config.direct.as_deref(), Some("nee"));
    }

    /// mse_n = cv²/n exactly: cv² comes back per replica, relative to the mean truth over the
    /// points path tracing ran on (sample 1 is outside its subset).
    #[test]
    fn path_tracing_cv2_per_replica() {
        let side = csv("point,replica,paths,ref_mse\n\
             3,0,1,8\n3,0,2,4\n3,1,1,18\n3,1,2,9\n4,0,1,99\n");
        let pts = csv(
            "point,reference_e,path_tracing_e_1,path_tracing_e_2\n3,2,1,1\n3,7,NaN,NaN\n4,2,1,1\n",
        );
        let (p, cv2) = path_tracing_cv2(&side, &pts).expect("cv2");
        assert_eq!(p, 3);
        assert_eq!(cv2, [2.0, 4.5]);
    }
}
