"""Per-call overhead of the Python binding: an edit called from Python vs the same edit looped in
Rust (``Rig._time_*_in_rust``), on the Arm; and the cost of reading M' (no copy of Φ).

    python crates/cagerig-py/bench/overhead.py [arm.obj] [--calls N] [--repeats R]

Prints, per edit, the per-call time from Python, from Rust, and the difference (the binding's
overhead: argument conversion and checks, GIL release, error mapping), each the minimum over
interleaved repeats (the host is shared: minima are the least noisy). On the Arm an edit costs
70–180 µs, so ±10 % noise hides a few µs of overhead; the built-in bar (a few µs per edit) shows
the overhead itself.
"""

import argparse
import time
import warnings
from pathlib import Path

import numpy as np

import cagerig

ARM = Path(__file__).resolve().parents[3] / "data/arm/arm.obj"


def per_call_python(edit, n):
    start = time.perf_counter()
    for i in range(n):
        edit(1.0 if i % 2 == 0 else -1.0)
    return (time.perf_counter() - start) / n


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("mesh", nargs="?", default=ARM)
    parser.add_argument("--calls", type=int, default=2000)
    parser.add_argument("--repeats", type=int, default=9)
    args = parser.parse_args()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", cagerig.RigWarning)
        arm = cagerig.Rig.load(args.mesh)
    measure(arm, "lowerarm01.R", 3, args)
    measure(cagerig.Rig.builtin("bar"), 1, 2, args)


def measure(rig, bend_joint, edit_joint, args):
    rig.move_rest_cage(0, [0.0, 0.0, 0.0])  # M := ΦC once (as the first edit of a session does)
    rig.rotate_joint(bend_joint, [1, 0, 0], 30)  # a pose, so that grabs go through CageRev
    axis = np.array([1.0, 0.0, 0.0])
    rest_idx, posed_idx = np.array([0, 2, 4, 5, 6]), np.array([10, 13, 15])
    off = np.array([0.01, -0.005, 0.0075])
    cases = {
        "rotate_joint": (
            lambda s: rig.rotate_joint(edit_joint, axis, s * 0.5),
            lambda n: rig._time_rotate_joint_in_rust(edit_joint, axis, 0.5, n),
        ),
        "move_rest_cage": (
            lambda s: rig.move_rest_cage(rest_idx, s * off),
            lambda n: rig._time_move_cage_in_rust(rest_idx, off, n),
        ),
        "move_posed_cage": (
            lambda s: rig.move_posed_cage(posed_idx, s * off),
            lambda n: rig._time_move_cage_in_rust(posed_idx, off, n, posed=True),
        ),
    }
    n = args.calls
    print(f"{rig!r}; {n} calls × {args.repeats} repeats, minimum per call")
    print(f"{'edit':<16} {'python µs':>10} {'rust µs':>10} {'overhead µs':>12}")
    for name, (python_edit, rust_loop) in cases.items():
        py_times, rust_times = [], []
        per_call_python(python_edit, n // 10)  # warm-up
        for _ in range(args.repeats):
            rust_times.append(rust_loop(n) / n)
            py_times.append(per_call_python(python_edit, n))
        py, rs = min(py_times), min(rust_times)
        print(f"{name:<16} {py * 1e6:>10.2f} {rs * 1e6:>10.2f} {(py - rs) * 1e6:>12.2f}")

    # Reading M' copies M' (#V × 3 floats) and nothing else; Φ is a view.
    reads = 2000
    start = time.perf_counter()
    for _ in range(reads):
        rig.posed_mesh
    read_mesh = (time.perf_counter() - start) / reads
    start = time.perf_counter()
    for _ in range(reads):
        rig.cage_coords
    read_phi = (time.perf_counter() - start) / reads
    start = time.perf_counter()
    for _ in range(50):
        np.array(rig.cage_coords)
    copy_phi = (time.perf_counter() - start) / 50
    assert np.shares_memory(rig.cage_coords, rig.cage_coords)
    print(
        f"read posed_mesh ({rig.num_vertices}×3 copy): {read_mesh * 1e6:.2f} µs; "
        f"read cage_coords (view of {rig.num_vertices}×{rig.num_cage_vertices}): {read_phi * 1e6:.2f} µs; "
        f"a copy of Φ would cost {copy_phi * 1e6:.1f} µs"
    )


if __name__ == "__main__":
    main()
