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


_STATE_FILES = ("mesh_rest", "mesh_posed", "cage_rest", "cage_posed")


def _state_names(prefix: str) -> list[str]:
    """The file names of one state, after checking that ``prefix`` is a plain name."""
    if not prefix or prefix.startswith(".") or "/" in prefix or os.sep in prefix or "\0" in prefix:
        raise ValueError(
            f"prefix must be a plain file-name prefix (not empty, no path separator, not "
            f"starting with '.'), got {prefix!r}"
        )
    return [f"{prefix}_{what}.obj" for what in _STATE_FILES] + [f"{prefix}_joints.json"]


def _write_snapshot(snapshot: dict, directory: PathLike, prefix: str) -> list[Path]:
    """Writes one state's five files into ``directory`` as a set.

    Every file is first written in full to a temporary file beside its target; only when all
    five are written are they renamed into place (each rename atomic), so a failure while
    writing leaves the state of an earlier call with this prefix as it was and no temporary
    file behind. Other files in ``directory`` are not touched.
    """
    out = Path(directory)
    names = _state_names(prefix)
    for name in names:
        target = out / name
        if target.exists() and not target.is_file():
            raise IsADirectoryError(
                f"{target}: expected a file (or nothing) to write the state into, found a "
                f"directory or special file; nothing was written"
            )
    out.mkdir(parents=True, exist_ok=True)
    temps = [out / f".{name}.tmp{os.getpid()}" for name in names]
    try:
        for what, temp in zip(_STATE_FILES, temps):
            write_obj(temp, *snapshot[what])
        with open(temps[-1], "w", encoding="utf-8") as f:
            f.write(json.dumps(snapshot["joints"], indent=2))
            f.flush()
            os.fsync(f.fileno())
        written = []
        for name, temp in zip(names, temps):
            os.replace(temp, out / name)
            written.append(out / name)
        return written
    finally:
        for temp in temps:
            try:
                temp.unlink()
            except FileNotFoundError:
                pass


def save_state(rig: Rig, directory: PathLike, prefix: str) -> list[Path]:
    """Write the rig's current state as ``cagerig edit`` names it.

    Files ``{prefix}_mesh_rest.obj`` (M), ``{prefix}_mesh_posed.obj`` (M'),
    ``{prefix}_cage_rest.obj`` (C), ``{prefix}_cage_posed.obj`` (C') and
    ``{prefix}_joints.json`` (name, parent, rest and posed position of every joint).

    ``directory`` may hold other files by design (call it once per state with its own prefix);
    they are left alone. The five files are written as a set: each in full to a temporary
    file first, then all renamed into place, so a failure (disk full, an exception) leaves the
    files an earlier call wrote with this prefix as they were, never a mix of old and new.
    For a folder that appears complete or not at all, use :func:`replay_script`,
    :meth:`Rig.save` or :class:`OutputFolder`.

    Parameters
    ----------
    rig : Rig
    directory : str or os.PathLike
        Created if needed.
    prefix : str
        E.g. ``"step3"``: a plain name (no path separator, not starting with ``.``).

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
