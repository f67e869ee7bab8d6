//! The constraint types, one file each. A type file imports the contract and the kit, never
//! another type.
//!
//! The `types!` list below is the one list of them, in the order menus show them: each line names a
//! type's module, its [`ConstraintType`] and the other names it exports. From it come the
//! `mod` declarations, the re-exports (`shapeup_core::constraints::EdgeSpring`, …) and
//! [`ALL`], which [`registry`](super::registry) returns.

use super::contract::ConstraintType;

/// Declares each type module, re-exports its public names and lists its type in [`ALL`].
macro_rules! types {
    ($($module:ident => $ty:ident $(, $other:ident)*;)*) => {
        $(
            mod $module;
            pub use $module::{$ty $(, $other)*};
        )*
        /// Every constraint type, in the order menus list them.
        pub(crate) const ALL: &[&dyn ConstraintType] = &[$(&$ty),*];
    };
}

types! {
    // Shape models (keep lengths, strains, curvature, details).
    edge_spring => EdgeSpringType, EdgeSpring;
    edge_strain => EdgeStrainType, EdgeStrain;
    triangle_strain => TriangleStrainType, TriangleStrain;
    area => AreaType, Area;
    tet_strain => TetStrainType, TetStrain;
    volume => VolumeType, Volume;
    bending => BendingType, Bending;
    hinge_bending => HingeBendingType, HingeBending;
    iso_one_ring => IsoOneRingType, IsoOneRing;
    laplacian_displacement => LaplacianDisplacementType, LaplacianDisplacement;
    smoothing => SmoothingType, Smoothing;
    laplacian => LaplacianType, Laplacian;
    // Geometric sets of ShapeUp / ShapeOp (faces, parts).
    plane => PlaneType, Plane;
    circle => CircleType, Circle;
    sphere => SphereType, Sphere;
    line => LineType, Line;
    rectangle => RectangleType, Rectangle;
    parallelogram => ParallelogramType, Parallelogram;
    angle => AngleType, Angle;
    rigid => RigidType, Rigid;
    similarity => SimilarityType, Similarity;
    attachment => AttachmentType, Attachment;
    // Handles, contact and loads.
    position => PositionType, Position;
    surface_closeness => SurfaceClosenessType, SurfaceCloseness;
    floor => FloorType, Floor;
    force => ForceType, Force;
    gravity => GravityType;
}
