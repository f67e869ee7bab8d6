"""The old single module of the API, split by concept (mesh, types, groups, solver,
simulation, scene, _checks): it re-exports those names for code that imported them from here."""

from ._checks import PathLike, _count, _indices, _json, _polygons, _tetrahedra, _vertices
from ._shapeup import SolveFailed
from .groups import Group, GroupRef, _Groups
from .mesh import Mesh, _mesh_of, read_mesh, write_mesh
from .scene import Scene
from .simulation import Simulation
from .solver import Solver
from .types import ConstraintType, _types_doc, constraint_types

__all__ = [
    "ConstraintType",
    "Group",
    "Mesh",
    "Scene",
    "Simulation",
    "SolveFailed",
    "Solver",
    "constraint_types",
    "read_mesh",
    "write_mesh",
]
