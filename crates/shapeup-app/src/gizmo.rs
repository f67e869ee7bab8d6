//! The handle gizmo model (placeholder, being written).
