//! The handle gizmo in the viewport (placeholder, being written).
