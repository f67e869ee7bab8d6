//! The shape-model presets: the groups over the whole mesh that keep its shape (the editor's
//! choice, the benchmarks' scenarios), each at its type's default multiplier.

use super::contract::ConstraintType;
use super::types::{BendingType, EdgeSpringType, IsoOneRingType, TriangleStrainType};

/// The constraints that keep the shape, over the whole mesh (math reference, "Notes": the
/// editor's default multipliers).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, serde::Serialize, serde::Deserialize)]
pub enum ShapeModel {
    /// Edge springs, g = 10.
    EdgeSprings,
    /// Triangle strain (g = 10) and bending (g = 10).
    #[default]
    StrainBending,
    /// Isometric one-rings, g = 100.
    IsoOneRing,
}

impl ShapeModel {
    /// Every model, in menu order.
    pub const ALL: [ShapeModel; 3] = [ShapeModel::EdgeSprings, ShapeModel::StrainBending, ShapeModel::IsoOneRing];

    /// Its constraint types, one group each.
    pub fn types(self) -> &'static [&'static dyn ConstraintType] {
        match self {
            ShapeModel::EdgeSprings => &[&EdgeSpringType],
            ShapeModel::StrainBending => &[&TriangleStrainType, &BendingType],
            ShapeModel::IsoOneRing => &[&IsoOneRingType],
        }
    }

    /// Its groups: (constraint type, default multiplier g).
    pub fn groups(self) -> Vec<(&'static str, f64)> {
        self.types().iter().map(|t| (t.name(), t.default_multiplier())).collect()
    }

    /// Name for menus.
    pub fn label(self) -> &'static str {
        match self {
            ShapeModel::EdgeSprings => "Edge springs",
            ShapeModel::StrainBending => "Strain + bending",
            ShapeModel::IsoOneRing => "Iso 1-ring",
        }
    }

    /// The model whose groups have exactly these types (in any order), if any.
    pub fn from_kinds(kinds: &[&str]) -> Option<ShapeModel> {
        let mut kinds = kinds.to_vec();
        kinds.sort_unstable();
        ShapeModel::ALL.into_iter().find(|m| {
            let mut own: Vec<&str> = m.types().iter().map(|t| t.name()).collect();
            own.sort_unstable();
            own == kinds
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_presets_are_the_editors() {
        assert_eq!(ShapeModel::EdgeSprings.groups(), [("edge_spring", 10.0)]);
        assert_eq!(ShapeModel::StrainBending.groups(), [("triangle_strain", 10.0), ("bending", 10.0)]);
        assert_eq!(ShapeModel::IsoOneRing.groups(), [("iso_one_ring", 100.0)]);
        assert_eq!(ShapeModel::from_kinds(&["bending", "triangle_strain"]), Some(ShapeModel::StrainBending));
        assert_eq!(ShapeModel::from_kinds(&["bending"]), None);
    }
}
