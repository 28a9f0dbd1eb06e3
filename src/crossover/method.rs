//! The methods `raycost crossover` compares and the configuration a row describes.

use crate::experiment::detp::estimators::{Crossover, EngineChoice};
use crate::output::column::Column;
use crate::stats::fit::ErrorModel;

/// An estimator `raycost crossover` compares: one of kind detp's registry that declares how it is
/// compared ([`Crossover`]); its name and column member are the estimator's own, so adding an
/// estimator adds a method without touching this layer. Ordered as registered.
#[derive(Clone, Copy)]
pub struct Method {
    /// Its place in the registry (the order of `crossover.csv`'s rows).
    rank: usize,
    estimator: EngineChoice,
    how: Crossover,
}

impl Method {
    /// Every method, in registry order.
    pub fn all() -> Vec<Method> {
        EngineChoice::all()
            .enumerate()
            .filter_map(|(rank, estimator)| {
                estimator.crossover().map(|how| Method {
                    rank,
                    estimator,
                    how,
                })
            })
            .collect()
    }

    /// The method of the estimator named `name` in specs, if the crossover compares it.
    pub fn named(name: &str) -> Option<Method> {
        Self::all().into_iter().find(|m| m.label() == name)
    }

    /// The DETP engines (exact, bit-identical errors; their costs differ).
    pub fn detp() -> Vec<Method> {
        Self::all()
            .into_iter()
            .filter(|m| m.how == Crossover::Detp)
            .collect()
    }

    /// The photon maps, each with the points-table family of its per-replica estimates.
    pub fn maps() -> Vec<(Method, &'static Column)> {
        Self::all()
            .into_iter()
            .filter_map(|m| match m.how {
                Crossover::PhotonMap { replica } => Some((m, replica)),
                _ => None,
            })
            .collect()
    }

    /// The method DETP's errors are filed under (the first DETP engine registered: every DETP
    /// engine's errors are the same).
    pub fn detp_errors() -> Method {
        Self::detp()[0]
    }

    /// Per-point path tracing.
    pub fn path_tracing() -> Method {
        Self::all()
            .into_iter()
            .find(|m| m.how == Crossover::PathTracing)
            .expect("the registry has a path tracer")
    }

    /// Is it per-point path tracing?
    pub fn is_path_tracing(self) -> bool {
        self.how == Crossover::PathTracing
    }

    /// Is it a DETP engine?
    pub fn is_detp(self) -> bool {
        self.how == Crossover::Detp
    }

    /// The engine's name in specs and in `crossover.csv`.
    pub fn label(self) -> &'static str {
        self.estimator.as_str()
    }

    /// Its member in column families (`cost_{}_s` → `cost_sphere_cache_s`).
    pub fn member(self) -> &'static str {
        self.estimator.column()
    }
}

impl PartialEq for Method {
    fn eq(&self, o: &Self) -> bool {
        self.rank == o.rank
    }
}

impl Eq for Method {}

impl PartialOrd for Method {
    fn partial_cmp(&self, o: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(o))
    }
}

impl Ord for Method {
    fn cmp(&self, o: &Self) -> std::cmp::Ordering {
        self.rank.cmp(&o.rank)
    }
}

impl std::fmt::Debug for Method {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.label())
    }
}

/// How a DETP configuration chose its disc radii (`docs/theory.md`, "A disc radius per point and
/// per photon count"), read from the tables' parameter columns: a column absent (a table written
/// before the rule existed) or NaN (the key not given) is the rule's default, so older tables read
/// as they always did. Each rule is one optional part; a rule added later is one more part here,
/// read in [`super::fronts::settings`] and named in [`RadiusRule::describe`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RadiusRule {
    /// κ of an edge-clamping remedy, d_i = clamp(κ·s_i, r_min·d, d) (`detp.edge_radius_factor`),
    /// where it is not the default 1 (`None`: κ = 1, or no clamping remedy).
    pub edge_factor: Option<f64>,
    /// The schedule d(N) = d·(N/N_ref)^(−β) with β > 0 (`None`: d fixed; β = 0 is d fixed).
    pub schedule: Option<Schedule>,
}

/// A disc radius schedule's parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Schedule {
    /// N_ref (`detp.radius_schedule_photons`).
    pub photons: f64,
    /// β (`detp.radius_schedule_exponent`).
    pub exponent: f64,
}

impl RadiusRule {
    /// The rule of one table row: κ (NaN: the default 1), N_ref (NaN: no schedule) and β (NaN:
    /// the default 1/6), normalised so that one rule has one value: κ = 1 and β = 0 are the
    /// defaults they equal.
    pub fn read(kappa: f64, schedule_photons: f64, exponent: f64) -> RadiusRule {
        let exponent = if exponent.is_nan() {
            crate::experiment::detp::spec::RADIUS_SCHEDULE_EXPONENT
        } else {
            exponent
        };
        RadiusRule {
            edge_factor: (kappa.is_finite() && kappa != 1.0).then_some(kappa),
            schedule: (schedule_photons.is_finite() && exponent > 0.0).then_some(Schedule {
                photons: schedule_photons,
                exponent,
            }),
        }
    }

    /// How the error falls with N under this rule: a radius fixed per point keeps a floor, a
    /// schedule does not.
    pub fn error_model(&self) -> ErrorModel {
        match self.schedule {
            Some(_) => ErrorModel::PowerLaw,
            None => ErrorModel::Floor,
        }
    }

    /// γ the theory gives for the relative RMSE ∝ N^(−γ) under the schedule: the bias falls as
    /// N^(−2β), the standard error as N^(−(1−2β)/2), so the slower of the two, min(2β, (1−2β)/2)
    /// (1/3 at β = 1/6); NaN without a schedule.
    pub fn derived_error_slope(&self) -> f64 {
        self.schedule.map_or(f64::NAN, |s| {
            (2.0 * s.exponent).min(0.5 * (1.0 - 2.0 * s.exponent))
        })
    }

    /// ` kappa=0.5 d(N)=d*(N/25000)^-0.1667`: the rule's part of a configuration's label, empty for a
    /// fixed d (so older tables' labels stay as they were; no comma, no quotes needed).
    pub fn describe(&self) -> String {
        let mut s = String::new();
        if let Some(k) = self.edge_factor {
            s.push_str(&format!(" kappa={k}"));
        }
        if let Some(x) = self.schedule {
            s.push_str(&format!(" d(N)=d*(N/{})^-{:.4}", x.photons, x.exponent));
        }
        s
    }
}

/// What a row of `crossover.csv` is about: a method and the DETP settings it depends on (`None`
/// where it does not depend on them: the photon maps ignore d, edge and the radius rule, path
/// tracing all four).
#[derive(Clone, Debug, PartialEq)]
pub struct Config {
    /// The method.
    pub method: Method,
    /// `detp.direct`.
    pub direct: Option<String>,
    /// `detp.edge`.
    pub edge: Option<String>,
    /// `detp.disc_radius`.
    pub disc_radius: Option<f64>,
    /// How the radius follows from d: fixed, per point, per photon count.
    pub radius_rule: Option<RadiusRule>,
}

impl Config {
    /// Whether a cost sweep's configuration `cost` measures this one's seconds: same method and
    /// the same settings wherever this one depends on them (d to 10⁻⁹ relative), the radius rule
    /// included (another rule's seconds are not this one's).
    pub fn matches(&self, cost: &Config) -> bool {
        let d = match (self.disc_radius, cost.disc_radius) {
            (Some(a), Some(b)) => (a - b).abs() <= 1e-9 * a.abs().max(b.abs()),
            (None, _) => true,
            (Some(_), None) => false,
        };
        self.method == cost.method
            && (self.direct.is_none() || self.direct == cost.direct)
            && (self.edge.is_none() || self.edge == cost.edge)
            && (self.radius_rule.is_none() || self.radius_rule == cost.radius_rule)
            && d
    }

    /// `sphere-cache direct=photons edge=paper d=15` (with a radius rule ` kappa=0.5`, ` d(N)=…`): one
    /// label for `best.csv` (no comma, so the
    /// CSV cell needs no quotes).
    pub fn describe(&self) -> String {
        let mut s = self.method.label().to_string();
        if let Some(x) = &self.direct {
            s.push_str(&format!(" direct={x}"));
        }
        if let Some(x) = &self.edge {
            s.push_str(&format!(" edge={x}"));
        }
        if let Some(x) = self.disc_radius {
            s.push_str(&format!(" d={x}"));
        }
        if let Some(r) = self.radius_rule {
            s.push_str(&r.describe());
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_methods_are_the_estimators_that_declare_a_crossover_in_registry_order() {
        let names: Vec<(&str, &str)> = Method::all()
            .iter()
            .map(|m| (m.label(), m.member()))
            .collect();
        assert_eq!(
            names,
            [
                ("sphere-cache", "sphere_cache"),
                ("disc-index", "disc_index"),
                ("photon-map", "photon_map"),
                ("photon-map-growing", "photon_map_growing"),
                ("path-tracing", "path_tracing"),
            ]
        );
        let all = Method::all();
        assert!(all.windows(2).all(|w| w[0] < w[1]));
        assert!(Method::path_tracing().is_path_tracing());
        assert_eq!(Method::detp_errors().label(), "sphere-cache");
        assert!(Method::detp().iter().all(|m| m.is_detp()));
        assert_eq!(Method::maps().len(), 2);
        assert!(Method::named("reference").is_none());
        assert!(Method::named("brute-force").is_none());
    }

    fn detp(rule: RadiusRule) -> Config {
        Config {
            method: Method::named("sphere-cache").unwrap(),
            direct: Some("photons".into()),
            edge: Some("clamp-first-hit".into()),
            disc_radius: Some(15.0),
            radius_rule: Some(rule),
        }
    }

    /// The same d under three rules is three configurations: different labels, and no rule's
    /// seconds stand in for another's; the defaults a table leaves NaN read as the values they
    /// equal (κ = 1, β = 1/6 with a schedule, β = 0 is d fixed).
    #[test]
    fn two_rules_with_the_same_d_are_different_configurations() {
        let fixed = RadiusRule::read(f64::NAN, f64::NAN, f64::NAN);
        assert_eq!(fixed, RadiusRule::default());
        assert_eq!(RadiusRule::read(1.0, 5e4, 0.0), fixed);
        let kappa = RadiusRule::read(0.5, f64::NAN, f64::NAN);
        let schedule = RadiusRule::read(f64::NAN, 5e4, f64::NAN);
        assert_eq!(
            schedule.schedule,
            Some(Schedule {
                photons: 5e4,
                exponent: 1.0 / 6.0
            })
        );
        let configs = [detp(fixed), detp(kappa), detp(schedule)];
        for (i, a) in configs.iter().enumerate() {
            for (j, b) in configs.iter().enumerate() {
                assert_eq!(a == b, i == j);
                assert_eq!(a.matches(b), i == j, "{a:?} {b:?}");
                assert_eq!(a.describe() == b.describe(), i == j);
            }
        }
        assert_eq!(
            configs[0].describe(),
            "sphere-cache direct=photons edge=clamp-first-hit d=15",
            "a fixed d keeps the label it always had"
        );
        assert!(configs[1].describe().ends_with(" kappa=0.5"));
        assert!(configs[2].describe().ends_with(" d(N)=d*(N/50000)^-0.1667"));
        assert_eq!(schedule.error_model(), ErrorModel::PowerLaw);
        assert_eq!(kappa.error_model(), ErrorModel::Floor);
        assert!((schedule.derived_error_slope() - 1.0 / 3.0).abs() < 1e-15);
        let quarter = RadiusRule::read(f64::NAN, 5e4, 0.25);
        assert!((quarter.derived_error_slope() - 0.25).abs() < 1e-15);
        assert!(fixed.derived_error_slope().is_nan());
        // A photon map (no rule) is timed whatever rule the cost sweep's row had.
        let map = Config {
            method: Method::named("photon-map").unwrap(),
            edge: None,
            disc_radius: None,
            radius_rule: None,
            ..detp(fixed)
        };
        let timed = Config {
            radius_rule: Some(kappa),
            ..map.clone()
        };
        assert!(map.matches(&timed));
    }
}
