//! AFF reader (in progress).
