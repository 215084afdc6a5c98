"""Writing rig states the way ``cagerig edit`` does (one OBJ per structure plus the joints)."""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Union

from ._cagerig import EditScript, OutputFolder, Rig, write_obj

PathLike = Union[str, "os.PathLike[str]"]


def _snapshot(rig: Rig) -> dict:
    """The arrays and joints of the rig's current state (copies)."""
    parents = rig.joint_parents
    return {
        "mesh_rest": (rig.rest_mesh, rig.triangles),
        "mesh_posed": (rig.posed_mesh, rig.triangles),
        "cage_rest": (rig.rest_cage, rig.cage_triangles),
        "cage_posed": (rig.posed_cage, rig.cage_triangles),
        "joints": [
            {
                "name": name,
                "parent": None if parents[j] < 0 else int(parents[j]),
                "rest": [float(x) for x in rest],
                "posed": [float(x) for x in posed],
            }
            for j, (name, rest, posed) in enumerate(
                zip(rig.joint_names, rig.rest_joints, rig.posed_joints)
            )
        ],
    }


def _write_snapshot(snapshot: dict, directory: PathLike, prefix: str) -> list[Path]:
    out = Path(directory)
    out.mkdir(parents=True, exist_ok=True)
    written = []
    for what in ("mesh_rest", "mesh_posed", "cage_rest", "cage_posed"):
        path = out / f"{prefix}_{what}.obj"
        write_obj(path, *snapshot[what])
        written.append(path)
    path = out / f"{prefix}_joints.json"
    tmp = path.with_name(f".{path.name}.tmp{os.getpid()}")
    tmp.write_text(json.dumps(snapshot["joints"], indent=2))
    os.replace(tmp, path)
    written.append(path)
    return written


def save_state(rig: Rig, directory: PathLike, prefix: str) -> list[Path]:
    """Write the rig's current state as ``cagerig edit`` names it.

    Files ``{prefix}_mesh_rest.obj`` (M), ``{prefix}_mesh_posed.obj`` (M'),
    ``{prefix}_cage_rest.obj`` (C), ``{prefix}_cage_posed.obj`` (C') and
    ``{prefix}_joints.json`` (name, parent, rest and posed position of every joint).

    Parameters
    ----------
    rig : Rig
    directory : str or os.PathLike
        Created if needed.
    prefix : str
        E.g. ``"step3"``.

    Returns
    -------
    list of pathlib.Path
        The files written.
    """
    return _write_snapshot(_snapshot(rig), directory, prefix)


def replay_script(rig: Rig, script, directory: PathLike, overwrite: bool = False) -> list[Path]:
    """Replay an edit script and write every state, like ``cagerig edit --out directory``.

    ``step0_*`` is the rig as given (after the script's ``skinning``, if any), then
    ``stepK_*`` after step K. The script is checked against the rig before any step runs, and,
    as with the CLI, the folder appears complete, only after every step succeeded (see
    :class:`OutputFolder`).

    Parameters
    ----------
    rig : Rig
        Edited in place.
    script : EditScript, str, dict or os.PathLike
    directory : str or os.PathLike
        New or empty; with ``overwrite=True`` also an earlier cagerig output, replaced as a
        whole. A folder holding other files raises ``FileExistsError``.
    overwrite : bool

    Returns
    -------
    list of pathlib.Path
        The files written.
    """
    if not isinstance(script, EditScript):
        script = EditScript(script)
    script.validate(rig)
    if script.skinning is not None:
        rig.set_skinning(script.skinning)
    states = [_snapshot(rig)]
    for k in range(len(script)):
        script.run_step(rig, k)
        states.append(_snapshot(rig))
    folder = OutputFolder(directory, overwrite)
    try:
        for k, state in enumerate(states):
            for what in ("mesh_rest", "mesh_posed", "cage_rest", "cage_posed"):
                folder.write_obj(f"step{k}_{what}.obj", *state[what])
            folder.write_text(f"step{k}_joints.json", json.dumps(state["joints"], indent=2))
        return [Path(p) for p in folder.finish()]
    finally:
        folder.discard()
