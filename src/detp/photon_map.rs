//! (to be built: see detp/mod.rs)
