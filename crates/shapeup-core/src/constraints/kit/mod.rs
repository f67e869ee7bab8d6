//! The shared kit of the constraint types: what several of them build on. A type file imports
//! the contract and this kit, never another type.

pub(crate) mod build;
pub(crate) mod faces;
pub(crate) mod fit;
pub(crate) mod gradient;
pub(crate) mod laplacian_row;
pub(crate) mod load;
pub(crate) mod options;
pub(crate) mod pieces;
pub(crate) mod point_set;
pub(crate) mod sets;
pub(crate) mod vertex_set;

#[cfg(test)]
pub(crate) mod test_util;
