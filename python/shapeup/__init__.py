"""shapeup: constraint-based shape modelling (ShapeUp, Bouaziz et al. SGP 2012) and Projective
Dynamics (Bouaziz et al. SIGGRAPH 2014) for numpy meshes.

>>> import shapeup
>>> m = shapeup.read_mesh("data/stanford-bunny.obj")   # doctest: +SKIP
>>> s = shapeup.Solver(m.V, m.F)                         # doctest: +SKIP

Arrays follow libigl / trimesh / meshio: V float64 (n, 3), F int (m, 3) or a list of polygons,
T int (t, 4). :mod:`shapeup.batch` runs scene files on a Dask cluster.

One module per concept: ``mesh`` (Mesh, read_mesh, write_mesh), ``types`` (ConstraintType,
constraint_types), ``groups`` (Group), ``contact`` (the colliders and contact settings Solver
and Simulation share), ``solver`` (Solver), ``simulation`` (Simulation),
``scene`` (Scene); ``_checks`` holds the argument checks they share.
"""

from ._shapeup import SolveFailed, __version__, catalogue_markdown, set_threads
from ._checks import MeshWarning, RoundOffWarning, UnconvergedWarning
from .groups import Group
from .mesh import Mesh, read_mesh, write_mesh
from .scene import Scene
from .simulation import Simulation
from .solver import Solver
from .types import ConstraintType, constraint_types

from . import _api

__all__ = [
    "ConstraintType",
    "Group",
    "Mesh",
    "MeshWarning",
    "RoundOffWarning",
    "Scene",
    "Simulation",
    "SolveFailed",
    "Solver",
    "UnconvergedWarning",
    "constraint_types",
    "read_mesh",
    "write_mesh",
    "__version__",
    "batch",
    "catalogue_markdown",
    "set_threads",
]


def __getattr__(name: str):
    # `shapeup.batch` imports Dask, which takes a second: only when asked for.
    if name == "batch":
        import importlib

        return importlib.import_module(".batch", __name__)
    raise AttributeError(f"module 'shapeup' has no attribute {name!r}")
