"""Regolith from Python: deformable soil (SPH, the continuum representation model) coupled to
rigid bodies.

    import regolith
    scene = regolith.load_scene("examples/scenes/cone_probe.toml", overrides={"sph.spacing": 0.006})
    sim = regolith.Simulation(scene)
    cone = sim.body("cone")
    cone.set_velocity([0.0, 0.0, -0.03])
    while sim.time < 0.5:
        sim.step()
    print(cone.fsi_force, sim.particles()["x"].shape)

Errors are exceptions carrying the one line the command-line tool prints: ``SceneError`` (a
wrong scene file or override), ``InputError`` (any wrong input; ``SceneError`` is one),
``BuildError``, ``SolverError``, ``RunError``, ``ElementError``, all ``RegolithError``.
Sweeps (grid or Latin hypercube, on Ray, threads or SLURM shards) are in ``regolith.sweep``.
"""

from __future__ import annotations

import json as _json
import os as _os
from typing import Any, Dict, Mapping, Optional, Union

import numpy as _np

from . import _regolith
from ._regolith import (
    Body,
    BuildError,
    ElementError,
    InputError,
    RegolithError,
    RunError,
    Scene,
    SceneError,
    Simulation,
    SolverError,
    load_scene,
)

__all__ = [
    "Body",
    "BuildError",
    "ElementError",
    "InputError",
    "RegolithError",
    "RunError",
    "Scene",
    "SceneError",
    "Simulation",
    "SolverError",
    "element",
    "load_scene",
    "run",
    "__version__",
]

__version__: str = _regolith.version()

PathLike = Union[str, "_os.PathLike[str]"]


def run(scene: Union[Scene, PathLike], out: PathLike, overrides: Optional[Mapping[str, Any]] = None) -> Dict[str, Any]:
    """Runs a scene end to end as ``regolith run`` does (its rig, or the terrain to the end
    time), writes ``summary.json``, ``series.csv``, ``particles_final.csv``, the recording and
    the plots to ``out``, and returns the summary as a dict. ``scene`` is a ``Scene`` or a
    path; ``overrides`` (with a path only) maps dotted keys to values, as ``--set``. The GIL is
    released while it runs."""
    if isinstance(scene, Scene):
        text = _regolith.run_json(scene, _os.fspath(out), dict(overrides) if overrides else None)
    else:
        text = _regolith.run_json(_os.fspath(scene), _os.fspath(out), dict(overrides) if overrides else None)
    return _json.loads(text)


_ARRAYS = ("p", "q", "pc", "v", "eps_axial", "eps_vol", "sigma_axial", "sigma_radial")


def element(
    material: PathLike,
    test: str,
    p0: float,
    *,
    ocr: Optional[float] = None,
    axial_strain: Optional[float] = None,
    p_end: Optional[float] = None,
    p_unload: Optional[float] = None,
    steps: int = 2000,
    precision: str = "f64",
) -> Dict[str, Any]:
    """Drives one material point through a laboratory test, as ``regolith element``: ``test``
    is ``"isotropic"`` (needs ``p_end``), ``"drained-triaxial"``, ``"undrained-triaxial"``
    (need ``axial_strain``) or ``"oedometer"``. Returns ``element.json`` as a dict, its paths
    (``p``, ``q``, ``pc``, ``v``, ``eps_axial``, ``eps_vol``, ``sigma_axial``,
    ``sigma_radial``) as float64 numpy arrays."""
    d = _json.loads(
        _regolith.element_json(
            _os.fspath(material),
            test,
            float(p0),
            ocr=ocr,
            axial_strain=axial_strain,
            p_end=p_end,
            p_unload=p_unload,
            steps=int(steps),
            precision=precision,
        )
    )
    for k in _ARRAYS:
        if d.get(k) is not None:
            d[k] = _np.asarray(d[k], dtype=_np.float64)
    return d
