//! The Dynamics panel (placeholder, being written).
