"""Shape-space exploration as in the paper's Figure 8: many hybrid variants of one character,
each made of random skeleton edits (bend rigid parts) and rest-cage edits (inflate or deflate
parts locally) within bounds, written as files.

Every variant is an edit script in the ``cagerig edit`` format, so it is reproducible from its
seed and replayable with the CLI; it is written beside the meshes:

- ``variant_<seed>.obj``       the posed skin M' (bones bent, volume edited),
- ``variant_<seed>_rest.obj``  the rest skin M after the cage edits,
- ``variant_<seed>.json``      the edit script.

Variants run as tasks: in a loop here (:func:`explore` without a client), or on a Dask
distributed cluster (``client=``): a local one in the tests, a studio's farm with the same
script. Each worker process loads the rig once and copies it per variant.
"""

from __future__ import annotations

import functools
import json
import time
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any, Optional

import numpy as np

from ._cagerig import Rig, write_obj


#: Dask configuration for clusters that run variants: Dask starts its worker processes with
#: glibc's ``MALLOC_TRIM_THRESHOLD_=65536``, and setting that variable at all disables glibc's
#: dynamic mmap threshold, so every block of 128 KiB or more (each rig copy: Φ alone is 1 MB
#: on the Arm) is mapped and unmapped anew. That makes a variant ≈ 3× slower (measured: a loop
#: in a worker, 73–89 variants/s with it, 389/s without). Use
#: ``with dask.config.set(DASK_CONFIG): cluster = LocalCluster(...)`` (or the same key in a
#: farm's Dask configuration) to start workers without it.
DASK_CONFIG = {"distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_": None}


@dataclass(frozen=True)
class Bounds:
    """How far a random variant may go."""

    #: Joints rotated per variant.
    joint_edits: int = 3
    #: Maximum rotation of each (degrees, about a random axis).
    max_degrees: float = 30.0
    #: Local cage edits per variant (each inflates or deflates a cage vertex and its neighbours).
    cage_edits: int = 2
    #: Cage vertices moved by one local edit (the picked vertex and its nearest neighbours).
    cage_neighbours: int = 5
    #: Maximum radial offset of a local edit, as a fraction of the cage's bounding-box diagonal.
    max_inflation: float = 0.04


def load_rig(source: str) -> Rig:
    """A rig from ``"builtin:<name>"`` or a mesh path (companions discovered beside it)."""
    if source.startswith("builtin:"):
        return Rig.builtin(source.split(":", 1)[1])  # type: ignore[arg-type]  # checked by the library
    return Rig.load(source)


@functools.lru_cache(maxsize=4)
def _base_rig(source: str) -> Rig:
    """The rig as loaded, once per (worker) process."""
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return load_rig(source)


def random_script(rig: Rig, seed: int, bounds: Bounds = Bounds()) -> dict[str, Any]:
    """A random hybrid edit: ``bounds.joint_edits`` joint rotations, then ``bounds.cage_edits``
    local rest-cage inflations/deflations (radial from the local centroid, one step per moved
    vertex). Deterministic in ``seed``; returns the script as a dict."""
    rng = np.random.default_rng(seed)
    steps: list[dict[str, Any]] = []
    names = rig.joint_names
    for j in rng.choice(len(names), size=min(bounds.joint_edits, len(names)), replace=False):
        axis = rng.normal(size=3)
        axis /= np.linalg.norm(axis)
        steps.append({
            "op": "rotate_joint",
            "joint": names[j],
            "axis": axis.tolist(),
            "degrees": float(rng.uniform(-bounds.max_degrees, bounds.max_degrees)),
        })
    cage = rig.rest_cage
    diag = float(np.linalg.norm(cage.max(0) - cage.min(0)))
    k = min(bounds.cage_neighbours, len(cage))
    for _ in range(bounds.cage_edits):
        centre_vertex = int(rng.integers(len(cage)))
        near = np.argsort(np.linalg.norm(cage - cage[centre_vertex], axis=1))[:k]
        local_centre = cage[near].mean(axis=0)
        amount = rng.uniform(-bounds.max_inflation, bounds.max_inflation) * diag
        for v in near:
            direction = cage[v] - local_centre
            length = np.linalg.norm(direction)
            if length == 0.0:
                continue
            steps.append({
                "op": "move_rest_cage",
                "vertices": [int(v)],
                "offset": (direction / length * amount).tolist(),
            })
    return {"steps": steps}


def make_variant(
    source: str, seed: int, directory: Optional[str], bounds: Bounds = Bounds()
) -> dict[str, Any]:
    """Builds variant ``seed`` of the rig ``source`` and writes its files into ``directory``
    (nothing is written when it is None: for timing the edits alone).

    Returns
    -------
    dict
        ``seed``, ``files`` (paths written), ``seconds`` (edit + write time) and ``steps``.
    """
    start = time.perf_counter()
    base = _base_rig(source)
    rig = base.copy()
    script = random_script(base, seed, bounds)
    rig.run_script(script)
    if directory is None:
        return {"seed": seed, "files": [], "seconds": time.perf_counter() - start,
                "steps": len(script["steps"])}
    out = Path(directory)
    out.mkdir(parents=True, exist_ok=True)
    stem = out / f"variant_{seed:06d}"
    posed, rest, meta = stem.with_suffix(".obj"), Path(f"{stem}_rest.obj"), stem.with_suffix(".json")
    triangles = rig.triangles
    write_obj(posed, rig.posed_mesh, triangles)
    write_obj(rest, rig.rest_mesh, triangles)
    meta.write_text(json.dumps({"source": source, "seed": seed, "bounds": asdict(bounds), **script}))
    return {
        "seed": seed,
        "files": [str(posed), str(rest), str(meta)],
        "seconds": time.perf_counter() - start,
        "steps": len(script["steps"]),
    }


def make_variants(
    source: str, seeds: list[int], directory: Optional[str], bounds: Bounds = Bounds()
) -> list[dict[str, Any]]:
    """:func:`make_variant` for several seeds: one distributed task (a variant takes a few
    milliseconds, less than a scheduler round trip)."""
    return [make_variant(source, s, directory, bounds) for s in seeds]


def explore(
    source: str,
    count: int,
    directory: Optional[str],
    *,
    client: Optional[Any] = None,
    first_seed: int = 0,
    bounds: Bounds = Bounds(),
    batch: int = 16,
) -> list[dict[str, Any]]:
    """Builds ``count`` variants (seeds ``first_seed …``) and writes them into ``directory``.

    Parameters
    ----------
    source : str
        A mesh path (its rig files discovered beside it) or ``"builtin:<name>"``; every worker
        must be able to read it.
    count : int
    directory : str or None
        Output directory, shared by the workers (None: build the variants, write nothing).
    client : dask.distributed.Client, optional
        Run the variants as tasks on this cluster; in this process when None.
    first_seed : int
    bounds : Bounds
    batch : int, default 16
        Variants per distributed task.

    Returns
    -------
    list of dict
        One :func:`make_variant` result per variant, in seed order.
    """
    seeds = list(range(first_seed, first_seed + count))
    if client is None:
        return make_variants(source, seeds, directory, bounds)
    batches = [seeds[i : i + max(batch, 1)] for i in range(0, count, max(batch, 1))]
    n = len(batches)
    futures = client.map(
        make_variants, [source] * n, batches, [directory] * n, [bounds] * n, pure=False
    )
    return [result for batch_results in client.gather(futures) for result in batch_results]
