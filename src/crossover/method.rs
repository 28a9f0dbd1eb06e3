//! The methods `raycost crossover` compares and the configuration a row describes.

/// An estimator a user could pick.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Method {
    /// DETP, sphere-cache engine.
    SphereCache,
    /// DETP, disc-index engine.
    DiscIndex,
    /// Photon map, fixed k.
    PhotonMap,
    /// Photon map, k growing with N.
    PhotonMapGrowing,
    /// Per-point path tracing with NEE.
    PathTracing,
}

impl Method {
    /// The DETP engines (exact, bit-identical errors; their costs differ).
    pub const DETP: [Method; 2] = [Method::SphereCache, Method::DiscIndex];
    /// The photon maps.
    pub const MAPS: [Method; 2] = [Method::PhotonMap, Method::PhotonMapGrowing];

    /// The engine's name in specs and in `crossover.csv`.
    pub fn label(self) -> &'static str {
        match self {
            Method::SphereCache => "sphere-cache",
            Method::DiscIndex => "disc-index",
            Method::PhotonMap => "photon-map",
            Method::PhotonMapGrowing => "photon-map-growing",
            Method::PathTracing => "path-tracing",
        }
    }

    /// Its member in column families (`cost_{}_s` → `cost_sphere_cache_s`).
    pub fn member(self) -> &'static str {
        match self {
            Method::SphereCache => "sphere_cache",
            Method::DiscIndex => "disc_index",
            Method::PhotonMap => "photon_map",
            Method::PhotonMapGrowing => "photon_map_growing",
            Method::PathTracing => "path_tracing",
        }
    }
}

/// What a row of `crossover.csv` is about: a method and the DETP settings it depends on (`None`
/// where it does not depend on them: the photon maps ignore d and edge, path tracing all three).
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
}

impl Config {
    /// Whether a cost sweep's configuration `cost` measures this one's seconds: same method and
    /// the same settings wherever this one depends on them (d to 10⁻⁹ relative).
    pub fn matches(&self, cost: &Config) -> bool {
        let d = match (self.disc_radius, cost.disc_radius) {
            (Some(a), Some(b)) => (a - b).abs() <= 1e-9 * a.abs().max(b.abs()),
            (None, _) => true,
            (Some(_), None) => false,
        };
        self.method == cost.method
            && (self.direct.is_none() || self.direct == cost.direct)
            && (self.edge.is_none() || self.edge == cost.edge)
            && d
    }

    /// `sphere-cache direct=photons edge=paper d=15`: one label for `best.csv` (no comma, so the
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
        s
    }
}
