"""shapeup: constraint-based shape modelling (ShapeUp, Bouaziz et al. SGP 2012) and Projective
Dynamics (Bouaziz et al. SIGGRAPH 2014) for numpy meshes.

>>> import shapeup
>>> m = shapeup.read_mesh("data/stanford-bunny.obj")   # doctest: +SKIP
>>> s = shapeup.Solver(m.V, m.F)                         # doctest: +SKIP

Arrays follow libigl / trimesh / meshio: V float64 (n, 3), F int (m, 3) or a list of polygons,
T int (t, 4). :mod:`shapeup.batch` runs scene files on a Dask cluster.
"""

from ._api import (
    ConstraintType,
    Group,
    Mesh,
    Scene,
    Simulation,
    SolveFailed,
    Solver,
    constraint_types,
    read_mesh,
    write_mesh,
)
from ._shapeup import __version__, catalogue_markdown, set_threads

from . import _api

__all__ = [*_api.__all__, "__version__", "batch", "catalogue_markdown", "set_threads"]


def __getattr__(name: str):
    # `shapeup.batch` imports Dask, which takes a second: only when asked for.
    if name == "batch":
        import importlib

        return importlib.import_module(".batch", __name__)
    raise AttributeError(f"module 'shapeup' has no attribute {name!r}")
