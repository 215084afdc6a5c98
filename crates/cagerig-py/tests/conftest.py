"""Shared fixtures: the Arm (from the repository's data/arm) and the `cagerig` CLI."""

import os
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

import cagerig

REPO = Path(__file__).resolve().parents[3]
ARM_DIR = Path(os.environ.get("CAGERIG_ARM_DIR", REPO / "data" / "arm"))
ARM = ARM_DIR / "arm.obj"
REFERENCE = ARM_DIR / "reference"

# The paper's edit scenario (reference/README.txt, steps ii–iv), as in the README.
SCENARIO = {
    "skinning": "lbs",
    "steps": [
        {"op": "rotate_joint", "joint": "lowerarm01.R", "axis": [1, 0, 0], "degrees": 60},
        {"op": "move_rest_cage", "vertices": [0, 2, 4, 5, 6], "offset": [2, -1, 1.5]},
        {"op": "move_posed_cage", "vertices": [20, 23, 25], "offset": [-1.5, 2, 0.5]},
        {"op": "set_skinning", "method": "dqs"},
        {"op": "rotate_joint", "joint": 4, "axis": [0, 0, 1], "degrees": -25},
        {"op": "reset_pose"},
    ],
}


def pytest_report_header(config):
    return f"cagerig {cagerig.__version__}; Arm data: {ARM_DIR}"


@pytest.fixture(scope="session")
def arm_path():
    if not ARM.exists():
        pytest.fail(f"the Arm rig is missing: {ARM} (set CAGERIG_ARM_DIR)")
    return ARM


@pytest.fixture(scope="session")
def arm_base(arm_path):
    with pytest.warns(cagerig.RigWarning):
        return cagerig.Rig.load(arm_path)


@pytest.fixture(scope="session")
def arm_file_coords_base(arm_path):
    """The Arm with the shipped (6-decimal) Φ kept and the paper's CageUp, as the paper tool and
    `cagerig maxvol` use them."""
    with pytest.warns(cagerig.RigWarning):
        return cagerig.Rig.load(arm_path, keep_file_coords=True, cage_fit="paper")


@pytest.fixture
def arm_file_coords(arm_file_coords_base):
    """A fresh copy of the Arm with the shipped Φ kept."""
    return arm_file_coords_base.copy()


@pytest.fixture
def arm(arm_base):
    """A fresh copy of the loaded Arm for each test."""
    return arm_base.copy()


@pytest.fixture(scope="session")
def cli():
    """The `cagerig` binary of this checkout (built with cargo when missing)."""
    exe = os.environ.get("CAGERIG_CLI")
    if exe:
        return Path(exe)
    exe = REPO / "target" / "release" / "cagerig"
    if not exe.exists():
        cargo = shutil.which("cargo")
        if cargo is None:
            pytest.fail("no cagerig CLI: build it with `cargo build --release -p cagerig-cli`")
        subprocess.run([cargo, "build", "--release", "-p", "cagerig-cli"], cwd=REPO, check=True)
    return exe


def run_cli(cli, *args):
    result = subprocess.run([str(cli), *map(str, args)], capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    return result


def read_obj_vertices(path):
    return cagerig.read_obj(path)[0]


def read_reference_obj(name):
    return read_obj_vertices(REFERENCE / name)


def read_triplets(path, shape, transpose=False):
    """Dense matrix from `i j value` lines (`j i value` with transpose)."""
    data = np.loadtxt(path, ndmin=2)
    dense = np.zeros(shape)
    a, b = data[:, 0].astype(int), data[:, 1].astype(int)
    if transpose:
        a, b = b, a
    dense[a, b] = data[:, 2]
    return dense
