//! Grasp quality (being written).
