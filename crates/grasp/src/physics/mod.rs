//! Physics validation with rapier (being written).
