//! A mesh with the attributes its file carried, as the I/O tests hold it: readers return the
//! attributes beside the mesh ([`LoadedMesh`]) and writers take them beside it, so a test that
//! reads, moves and writes back keeps both in one value.
#![allow(dead_code)]

use std::ops::{Deref, DerefMut};

use glam::DVec3;
use shapeup_core::io::{Attributes, LoadedMesh};
use shapeup_core::mesh::Mesh;

/// A mesh and its file's attributes; derefs to the mesh.
#[derive(Debug, Clone, PartialEq)]
pub struct FileMesh {
    /// The mesh.
    pub mesh: Mesh,
    /// What its file carried ([`Attributes::None`] for a mesh made in memory).
    pub attributes: Attributes,
}

impl FileMesh {
    /// The same mesh and attributes at other positions (what `Mesh::with_positions` did when
    /// the mesh held its attributes).
    pub fn with_positions(&self, positions: Vec<DVec3>) -> FileMesh {
        FileMesh { mesh: self.mesh.with_positions(positions), attributes: self.attributes.clone() }
    }
}

impl From<LoadedMesh> for FileMesh {
    fn from(loaded: LoadedMesh) -> Self {
        FileMesh { mesh: loaded.mesh, attributes: loaded.attributes }
    }
}

impl From<Mesh> for FileMesh {
    fn from(mesh: Mesh) -> Self {
        FileMesh { mesh, attributes: Attributes::None }
    }
}

impl Deref for FileMesh {
    type Target = Mesh;

    fn deref(&self) -> &Mesh {
        &self.mesh
    }
}

impl DerefMut for FileMesh {
    fn deref_mut(&mut self) -> &mut Mesh {
        &mut self.mesh
    }
}
