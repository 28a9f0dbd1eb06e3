//! What the fronts (a kind-`detp` run with a reference, ≥ 2 replicas and a sweep over
//! detp.direct × detp.edge × detp.photons × detp.disc_radius and the radius rules) say about
//! errors: per DETP configuration (its radius rule included, [`settings`]) and replica the relative MSE at each photon count; per photon map the same, per
//! replica at its own N photons (a map's error does not fall with the replicas: a fixed-k map's
//! variance goes as 1/k whatever N); per replica the path tracer's cv².
//!
//! Relative MSE of a replica: [mean_i (E_ri − R_i)² − mean_i se_R,i²] / (mean_i R_i)², the truth's
//! variance subtracted exactly as the kind computes `irradiance_ref_rmse`
//! ([`relative_mse`]), over the same points. The kind writes it per estimator and replica
//! (`NAME.replica_errors.csv`, and path tracing's truth as `ref_mean` in `NAME.path_tracing.csv`);
//! fronts written before those tables are judged from their points table by the same function
//! ([`Judged::from_points`]), and both give the same bits.

use std::collections::BTreeMap;

use super::input::{keys, Csv};
use super::method::{Config, Method, RadiusRule};
use crate::error::OutputError;
use crate::experiment::detp::columns::{
    POINT_BASELINE_E, POINT_BASELINE_SE, POINT_IRRADIANCE_REPLICA, POINT_PATH_TRACING_E,
};
pub use crate::experiment::detp::engines::relative_mse;
use crate::experiment::detp::estimators::path_tracing::{
    PT_PATHS, PT_REF_MEAN, PT_REF_MSE, PT_REPLICA,
};
use crate::experiment::detp::replica_errors::{DETP, ESTIMATOR, RELATIVE_MSE};
use crate::output::column::Column;
use crate::output::column::POINT;
use crate::stats::time_to_target::PathTracingCost;

/// What the fronts judged at each sweep point: per estimator (`detp` or a photon map's column
/// stem) its relative MSE in each replica, or for a photon map whose points table has no
/// per-replica values one series, the mean over replicas ([`mean_replica_mse`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Judged {
    /// (sweep point, estimator) → relative MSE per replica.
    pub mse: BTreeMap<(u64, String), Vec<f64>>,
    /// Per estimator: whether its series are the replicas (else the one mean series).
    pub per_replica: BTreeMap<String, bool>,
    /// The file the numbers came from, for errors.
    pub path: std::path::PathBuf,
}

impl Judged {
    /// From `NAME.replica_errors.csv`.
    pub fn from_table(t: &Csv) -> Result<Judged, OutputError> {
        let (point, replica) = (t.value(&POINT)?, t.value(&PT_REPLICA)?);
        let (estimator, mse) = (t.text(&ESTIMATOR)?, t.value(&RELATIVE_MSE)?);
        let mut j = Judged {
            path: t.path.clone(),
            ..Judged::default()
        };
        for i in 0..point.len() {
            let v = j
                .mse
                .entry((point[i] as u64, estimator[i].clone()))
                .or_default();
            if replica[i] as usize != v.len() {
                return Err(OutputError::new(
                    &t.path,
                    format!(
                        "row {}: replica {} of {} at sweep point {} is out of order (replicas are written 0, 1, …)",
                        i + 2,
                        replica[i],
                        estimator[i],
                        point[i]
                    ),
                ));
            }
            v.push(mse[i]);
            j.per_replica.insert(estimator[i].clone(), true);
        }
        Ok(j)
    }

    /// From a points table (fronts written before `NAME.replica_errors.csv`): DETP's
    /// `irradiance_replica_{r}` and each photon map's `{map}_replica_{r}` (or its mean and SE)
    /// against `reference_e`, `reference_se` at every sweep point.
    pub fn from_points(points: &Csv, replicas: f64) -> Result<Judged, OutputError> {
        let reps = points.family(&POINT_IRRADIANCE_REPLICA.member(""));
        if reps.len() < 2 {
            return Err(OutputError::new(
                &points.path,
                "has fewer than 2 irradiance_replica_{r} columns: the crossover's bootstrap needs detp.replicas ≥ 2 in the fronts",
            ));
        }
        let (refe, refse) = (
            points.member(&POINT_BASELINE_E, "reference")?,
            points.member(&POINT_BASELINE_SE, "reference")?,
        );
        // A replica family's members (`irradiance_replica_{r}`: r = 0, 1, …).
        let values = |c: &Column| {
            points
                .family(&c.member(""))
                .iter()
                .map(|(r, _)| points.member(c, &r.to_string()))
                .collect::<Result<Vec<_>, _>>()
        };
        let detp = values(&POINT_IRRADIANCE_REPLICA)?;
        let mut maps = Vec::new();
        for (method, replica) in Method::maps() {
            let member = method.member();
            if !points.has_member(&POINT_BASELINE_E, member) {
                continue;
            }
            let reps = values(replica)?;
            let mean_se = if reps.len() >= 2 {
                None
            } else {
                Some((
                    points.member(&POINT_BASELINE_E, member)?,
                    points.member(&POINT_BASELINE_SE, member)?,
                ))
            };
            maps.push((member.to_string(), reps, mean_se));
        }
        let mut j = Judged {
            path: points.path.clone(),
            ..Judged::default()
        };
        j.per_replica.insert(DETP.into(), true);
        for (m, _, mean_se) in &maps {
            j.per_replica.insert(m.clone(), mean_se.is_none());
        }
        for (point, rows) in rows_by_point(points)? {
            let refr: Vec<(f64, f64)> = rows.iter().map(|&k| (refe[k], refse[k])).collect();
            let pick = |v: &[f64]| rows.iter().map(|&k| v[k]).collect::<Vec<_>>();
            let per = |v: &[Vec<f64>]| v.iter().map(|v| relative_mse(&pick(v), &refr)).collect();
            j.mse.insert((point, DETP.into()), per(&detp));
            for (m, reps, mean_se) in &maps {
                let mse = match mean_se {
                    None => per(reps),
                    Some((mean, se)) => {
                        vec![mean_replica_mse(&pick(mean), &pick(se), replicas, &refr)]
                    }
                };
                j.mse.insert((point, m.clone()), mse);
            }
        }
        Ok(j)
    }

    /// Estimator `estimator`'s series at sweep point `point`.
    fn at(&self, point: f64, estimator: &str) -> Result<&Vec<f64>, OutputError> {
        self.mse
            .get(&(point as u64, estimator.to_string()))
            .ok_or_else(|| {
                OutputError::new(
                    &self.path,
                    format!("has no {estimator} rows of sweep point {point}"),
                )
            })
    }
}

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

/// A photon map's errors, as DETP's: each replica's relative MSE at the N photons it had.
#[derive(Clone, Debug, PartialEq)]
pub struct MapErrors {
    /// The map and detp.direct.
    pub config: Config,
    /// Photons N of one replica's map, increasing.
    pub photons: Vec<f64>,
    /// `mse[r][j]`: replica r's relative MSE at `photons[j]` where the points table has each
    /// replica's estimate (`{map}_replica_{r}`); else one series: the mean over replicas of their
    /// relative MSE, from the mean and its across-replica SE ([`mean_replica_mse`]).
    pub mse: Vec<Vec<f64>>,
    /// Whether `mse` holds the replicas (the bootstrap's units) or only their mean.
    pub per_replica: bool,
}

/// The mean over R replicas of their relative MSE, from the replicas' mean ē_i and its SE se_i
/// at every point: (1/R)·Σ_r (e_ri − R_i)² = (ē_i − R_i)² + (R − 1)·se_i² exactly (se_i² being
/// the replicas' sample variance over R), so this is [`relative_mse`] of the mean plus
/// (R − 1)·mean_i se_i² over the truth's mean².
pub fn mean_replica_mse(mean: &[f64], se: &[f64], replicas: f64, refr: &[(f64, f64)]) -> f64 {
    let n = mean.len().min(refr.len()) as f64;
    let truth = refr.iter().map(|r| r.0).sum::<f64>() / n;
    let spread = se.iter().map(|s| s * s).sum::<f64>() / n;
    relative_mse(mean, refr) + (replicas - 1.0) * spread / (truth * truth)
}

/// Rows of the points table per sweep point.
pub fn rows_by_point(points: &Csv) -> Result<BTreeMap<u64, Vec<usize>>, OutputError> {
    let p = points.value(&POINT)?;
    let mut by: BTreeMap<u64, Vec<usize>> = BTreeMap::new();
    for (i, &x) in p.iter().enumerate() {
        by.entry(x as u64).or_default().push(i);
    }
    Ok(by)
}

/// One row's DETP configuration.
#[derive(Clone, Debug, PartialEq)]
pub struct Setting {
    /// `detp.direct`.
    pub direct: String,
    /// `detp.edge`.
    pub edge: String,
    /// `detp.disc_radius` (the schedule's d_ref).
    pub disc_radius: f64,
    /// The radius rule.
    pub rule: RadiusRule,
}

/// The radius rules' parameter columns, read where the table has them (see [`RadiusRule::read`]).
pub const RULE_KEYS: [super::input::Key; 3] = [
    keys::EDGE_RADIUS_FACTOR,
    keys::RADIUS_SCHEDULE_PHOTONS,
    keys::RADIUS_SCHEDULE_EXPONENT,
];

/// The main table's `detp.direct`, `detp.edge`, `detp.disc_radius` and radius rule of each row.
pub fn settings(main: &Csv) -> Result<Vec<Setting>, OutputError> {
    let direct = main.param_texts(keys::DIRECT)?;
    let edge = main.param_texts(keys::EDGE)?;
    let d = main.param(keys::DISC_RADIUS)?;
    let mut rule = Vec::new();
    for k in RULE_KEYS {
        rule.push(match main.has_param(k) {
            true => main.param(k)?,
            false => vec![f64::NAN; main.rows.len()],
        });
    }
    let (kappa, photons, beta) = (&rule[0], &rule[1], &rule[2]);
    Ok((0..main.rows.len())
        .map(|i| Setting {
            direct: direct[i].clone(),
            edge: edge[i].clone(),
            disc_radius: d[i],
            rule: RadiusRule::read(kappa[i], photons[i], beta[i]),
        })
        .collect())
}

/// Per DETP configuration, its replicas' relative MSE at each photon count.
pub fn detp_errors(main: &Csv, judged: &Judged) -> Result<Vec<DetpErrors>, OutputError> {
    let sweep = main.value(&POINT)?;
    let photons = main.param(keys::PHOTONS)?;
    let mut out: Vec<DetpErrors> = Vec::new();
    for (i, set) in settings(main)?.into_iter().enumerate() {
        let mse = judged.at(sweep[i], DETP)?.clone();
        let config = Config {
            method: Method::detp_errors(),
            direct: Some(set.direct),
            edge: Some(set.edge),
            disc_radius: Some(set.disc_radius),
            radius_rule: Some(set.rule),
        };
        let at = match out.iter().position(|e| e.config == config) {
            Some(at) => at,
            None => {
                out.push(DetpErrors {
                    config,
                    photons: Vec::new(),
                    mse: vec![Vec::new(); mse.len()],
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

/// Per photon map the fronts judged and detp.direct: each replica's relative MSE at its N photons
/// (or their mean: see [`MapErrors`]), from the rows at the first (edge, d) of that direct in the
/// table (a photon map does not depend on either).
pub fn map_errors(main: &Csv, judged: &Judged) -> Result<Vec<MapErrors>, OutputError> {
    let sweep = main.value(&POINT)?;
    let photons = main.param(keys::PHOTONS)?;
    let settings = settings(main)?;
    let mut out = Vec::new();
    for (method, _) in Method::maps() {
        let member = method.member();
        let Some(&per_replica) = judged.per_replica.get(member) else {
            continue;
        };
        let mut seen: Vec<String> = Vec::new();
        for first in &settings {
            let direct = &first.direct;
            if seen.contains(direct) {
                continue;
            }
            seen.push(direct.clone());
            let mut at: Vec<(f64, Vec<f64>)> = Vec::new();
            for i in (0..settings.len()).filter(|&i| settings[i] == *first) {
                at.push((photons[i], judged.at(sweep[i], member)?.clone()));
            }
            at.sort_by(|a, b| a.0.total_cmp(&b.0));
            let series = at.first().map_or(0, |a| a.1.len());
            out.push(MapErrors {
                config: Config {
                    method,
                    direct: Some(direct.clone()),
                    edge: None,
                    disc_radius: None,
                    radius_rule: None,
                },
                photons: at.iter().map(|a| a.0).collect(),
                mse: (0..series)
                    .map(|r| at.iter().map(|a| a.1[r]).collect())
                    .collect(),
                per_replica,
            });
        }
    }
    Ok(out)
}

/// The path tracer's cv² per replica from `NAME.path_tracing.csv` at its first sweep point (path
/// tracing is the same at every sweep point of a point set), by
/// [`PathTracingCost::cv2_from_prefix_errors`] over its checkpoints, `ref_mse` made relative by the
/// reference's mean over the points it ran on: the table's `ref_mean`, or for tables written before
/// it the mean of the points table's `reference_e` over the points with a finite
/// `path_tracing_e_{K}` (the same sum in the same order). Returns (sweep point used, cv² per
/// replica).
pub fn path_tracing_cv2(side: &Csv, points: Option<&Csv>) -> Result<(u64, Vec<f64>), OutputError> {
    let (point, replica) = (side.value(&POINT)?, side.value(&PT_REPLICA)?);
    let (paths, mse) = (side.value(&PT_PATHS)?, side.value(&PT_REF_MSE)?);
    let Some(first) = point.iter().copied().map(|p| p as u64).min() else {
        return Err(OutputError::new(&side.path, "has no rows"));
    };
    let truth: Vec<f64> = match (side.has_column(&PT_REF_MEAN), points) {
        (true, _) => side.value(&PT_REF_MEAN)?,
        (false, Some(points)) => vec![points_truth(points, first)?; point.len()],
        (false, None) => {
            return Err(OutputError::new(
                &side.path,
                "has no ref_mean column and the fronts have no points table to take the truth's mean from",
            ))
        }
    };
    let mut by_replica: BTreeMap<u64, (Vec<f64>, Vec<f64>)> = BTreeMap::new();
    for i in (0..point.len()).filter(|&i| point[i] as u64 == first) {
        let e = by_replica.entry(replica[i] as u64).or_default();
        e.0.push(paths[i]);
        e.1.push(mse[i] / (truth[i] * truth[i]));
    }
    let cv2 = by_replica
        .values()
        .map(|(n, m)| PathTracingCost::cv2_from_prefix_errors(n, m))
        .collect();
    Ok((first, cv2))
}

/// The reference's mean at sweep point `first` over the points path tracing ran on (a finite
/// `path_tracing_e_{K}`; every point where the table has no such column).
fn points_truth(points: &Csv, first: u64) -> Result<f64, OutputError> {
    let rows = rows_by_point(points)?;
    let at = rows.get(&first).ok_or_else(|| {
        OutputError::new(&points.path, format!("has no rows of sweep point {first}"))
    })?;
    let refe = points.member(&POINT_BASELINE_E, "reference")?;
    let ran: Vec<usize> = match points.family(&POINT_PATH_TRACING_E.member("")).last() {
        Some((k, _)) => {
            let e = points.member(&POINT_PATH_TRACING_E, &k.to_string())?;
            at.iter().copied().filter(|&k| e[k].is_finite()).collect()
        }
        None => at.clone(),
    };
    Ok(ran.iter().map(|&k| refe[k]).sum::<f64>() / ran.len().max(1) as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn csv(text: &str) -> Csv {
        Csv::from_text(text)
    }

    fn judged(points: &str) -> Judged {
        Judged::from_points(&csv(points), 2.0).expect("judged")
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
        let e = detp_errors(&main, &judged(&pts)).expect("errors");
        assert_eq!(e.len(), 2);
        assert_eq!(e[0].photons, [100.0, 200.0]);
        // Photons 100 is sweep point 1: offsets 0.2 and 0.4.
        assert!((e[0].mse[0][0] - 0.04).abs() < 1e-12 && (e[0].mse[1][0] - 0.16).abs() < 1e-12);
        assert!((e[0].mse[0][1] - 0.01).abs() < 1e-12, "{e:?}");
        assert_eq!(e[1].config.direct.as_deref(), Some("nee"));
    }

    /// The rule's parameter columns key the configuration: the same d and photons with β = 0 and
    /// β = 1/6 are two configurations; a table without the columns reads as d fixed.
    #[test]
    fn detp_errors_key_the_radius_rule() {
        let main = csv(
            "point,detp.direct,detp.edge,detp.photons,detp.disc_radius,detp.radius_schedule_photons,detp.radius_schedule_exponent\n\
             0,photons,paper,100,5,100,0.0\n1,photons,paper,100,5,100,0.16666666666666666\n\
             2,photons,paper,200,5,100,0.0\n3,photons,paper,200,5,100,0.16666666666666666\n",
        );
        let mut pts = String::from(
            "point,sample,irradiance_replica_0,irradiance_replica_1,reference_e,reference_se\n",
        );
        for p in 0..4 {
            pts.push_str(&format!("{p},0,1.1,0.9,1,0\n"));
        }
        let e = detp_errors(&main, &judged(&pts)).expect("errors");
        assert_eq!(e.len(), 2, "{e:?}");
        assert_eq!(e[0].config.radius_rule, Some(RadiusRule::default()));
        let s = e[1]
            .config
            .radius_rule
            .and_then(|r| r.schedule)
            .expect("a schedule");
        assert_eq!((s.photons, s.exponent), (100.0, 1.0 / 6.0));
        assert_eq!((e[0].photons.len(), e[1].photons.len()), (2, 2));
        let old = csv(
            "point,detp.direct,detp.edge,detp.photons,detp.disc_radius\n0,photons,clamp-first-hit,100,5\n",
        );
        let set = settings(&old).expect("settings");
        assert_eq!(set[0].rule, RadiusRule::default());
    }

    /// Four replicas of a photon map at two points, truth 1 ± 0: per-replica columns give each
    /// replica's own MSE at N (not the mean's at 4N); without them the replicas' mean MSE follows
    /// exactly from the mean and its across-replica SE.
    #[test]
    fn photon_maps_are_judged_per_replica_at_their_own_photons() {
        let main = csv(
            "point,detp.direct,detp.edge,detp.photons,detp.disc_radius\n0,photons,paper,100,5\n",
        );
        let vals = [[1.2, 0.8, 1.1, 0.9], [0.7, 1.3, 1.0, 1.0]];
        let mut with = String::from(
            "point,sample,irradiance_replica_0,irradiance_replica_1,reference_e,reference_se,photon_map_e,photon_map_se",
        );
        for r in 0..4 {
            with.push_str(&format!(",photon_map_replica_{r}"));
        }
        with.push('\n');
        let mut without = String::from(
            "point,sample,irradiance_replica_0,irradiance_replica_1,reference_e,reference_se,photon_map_e,photon_map_se\n",
        );
        for (s, v) in vals.iter().enumerate() {
            let m = v.iter().sum::<f64>() / 4.0;
            let var = v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / 3.0;
            let se = (var / 4.0).sqrt();
            with.push_str(&format!(
                "0,{s},1,1,1,0,{m},{se},{},{},{},{}\n",
                v[0], v[1], v[2], v[3]
            ));
            without.push_str(&format!("0,{s},1,1,1,0,{m},{se}\n"));
        }
        let e =
            map_errors(&main, &Judged::from_points(&csv(&with), 4.0).expect("j")).expect("errors");
        assert_eq!(e.len(), 1);
        assert!(e[0].per_replica);
        assert_eq!(e[0].photons, [100.0]);
        let own: Vec<f64> = (0..4)
            .map(|r| (vals[0][r] - 1.0f64).powi(2) / 2.0 + (vals[1][r] - 1.0f64).powi(2) / 2.0)
            .collect();
        for (r, want) in own.iter().enumerate() {
            assert!((e[0].mse[r][0] - want).abs() < 1e-12, "{e:?}");
        }
        let f = map_errors(&main, &Judged::from_points(&csv(&without), 4.0).expect("j"))
            .expect("errors");
        assert!(!f[0].per_replica);
        let mean = own.iter().sum::<f64>() / 4.0;
        assert!(
            (f[0].mse[0][0] - mean).abs() < 1e-12,
            "{} vs {mean}",
            f[0].mse[0][0]
        );
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
        let (p, cv2) = path_tracing_cv2(&side, Some(&pts)).expect("cv2");
        assert_eq!(p, 3);
        assert_eq!(cv2, [2.0, 4.5]);
        // With the kind's ref_mean column the points table is not needed.
        let with = csv("point,replica,paths,ref_mse,ref_mean\n\
             3,0,1,8,2\n3,0,2,4,2\n3,1,1,18,2\n3,1,2,9,2\n4,0,1,99,2\n");
        assert_eq!(path_tracing_cv2(&with, None).expect("cv2").1, [2.0, 4.5]);
        assert!(path_tracing_cv2(&side, None).is_err());
    }
}
