//! Shared helpers for the cross-crate vectors.
