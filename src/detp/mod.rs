//! Density Estimation on the Tangent Plane (DETP): photon segments are stored, and the irradiance at
//! a sample point is the power of the segments that cross a disc of radius d on its tangent plane,
//! over πd².
//!
//! Every engine here answers the same question — which (segment, disc) pairs cross — and all of them
//! decide a pair with the one exact function [`disc::crosses`]. Engines differ only in which pairs
//! they *test*; their culling is conservative (never drops a crossing pair). Powers are integers
//! ([`fixed`]), so the per-disc sums are the same whatever the order, the engine, the thread count or
//! an add-then-remove sequence: agreement between engines is bit for bit by construction, and the
//! tests check it.
//!
//! Modules:
//! - [`fixed`]: integer power units and per-disc accumulators;
//! - [`store`]: the ray store (segments with photon ids, ≤ 64 B each);
//! - [`disc`]: sample points with normals, their discs, the exact crossing test;
//! - [`edge`]: `detp.edge`, what a disc does where it reaches past an edge (the paper's method or a
//!   remedy: per-disc radii, or crossings cut at the first impact);
//! - [`tally`]: what an engine does with a crossing (add its power, or keep the k nearest);
//! - [`nearest`]: a disc radius from its k nearest crossings (exact, order-free selection);
//! - [`brute`]: every segment against every disc (the oracle);
//! - [`order`]: point orderings (none, Morton/Lebesgue, Hilbert);
//! - [`sphere_cache`]: the hierarchy of spheres with ratio Q;
//! - [`disc_index`]: discs in a spatial index (grid, octree) that segments traverse, adding or removing;
//! - [`photon`]: photon tracing into the store, one keyed stream per photon;
//! - [`surface_points`]: sample points on a scene's surfaces at spacing ≈ d;
//! - [`quasi_static`]: frame-by-frame incremental recalculation as dynamic objects move;
//! - [`photon_map`]: Jensen's k-nearest-neighbour estimate over the same photons (the baseline);
//! - [`indirect`]: the store's segments after the first bounce, for DETP of indirect light only;
//! - [`stability`]: the same irradiance wherever the scene is placed (the stability suite and its table).

pub mod brute;
pub mod disc;
pub mod disc_index;
pub mod edge;
pub mod fixed;
pub mod indirect;
pub mod nearest;
pub mod order;
pub mod photon;
pub mod photon_map;
pub mod quasi_static;
pub mod sphere_cache;
pub mod stability;
pub mod store;
pub mod surface_points;
pub mod tally;
