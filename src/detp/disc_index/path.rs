//! The run-time choice of SIMD path for the disc index's kernels.

/// Which implementation of the disc index's kernels runs: the eight-box slab test
/// ([`super::slab`]) and the segment–disc tests ([`super::cross`]). All decide identically.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SimdPath {
    /// 8-lane f64 vectors (x86_64 with AVX-512 F).
    Avx512,
    /// 4-lane f64 vectors (x86_64 with AVX2).
    Avx2,
    /// One lane at a time: the reference the others are tested against.
    Scalar,
}

impl SimdPath {
    /// The fastest path this CPU has, unless `RAYCOST_DISC_SIMD` (`avx512`, `avx2` or `scalar`)
    /// names another one it can run.
    pub fn detect() -> Self {
        let forced = match std::env::var("RAYCOST_DISC_SIMD").as_deref() {
            Ok("avx512") => Some(Self::Avx512),
            Ok("avx2") => Some(Self::Avx2),
            Ok("scalar") => Some(Self::Scalar),
            _ => None,
        };
        forced
            .filter(|p| p.is_available())
            .unwrap_or_else(|| Self::all_available()[0])
    }

    /// Every path this CPU can run, fastest first.
    pub fn all_available() -> Vec<Self> {
        [Self::Avx512, Self::Avx2, Self::Scalar]
            .into_iter()
            .filter(|p| p.is_available())
            .collect()
    }

    /// Can this CPU run the path?
    pub fn is_available(self) -> bool {
        match self {
            Self::Scalar => true,
            #[cfg(target_arch = "x86_64")]
            Self::Avx512 => is_x86_feature_detected!("avx512f"),
            #[cfg(target_arch = "x86_64")]
            Self::Avx2 => is_x86_feature_detected!("avx2"),
            #[cfg(not(target_arch = "x86_64"))]
            _ => false,
        }
    }

    /// Name for reports.
    pub fn name(self) -> &'static str {
        match self {
            Self::Avx512 => "avx512",
            Self::Avx2 => "avx2",
            Self::Scalar => "scalar",
        }
    }
}
