"""MVC and Green coordinates side by side on the same rest-cage edit (the README's picture).

Stretches the Arm's rest cage 1.6x along x about its centre, in a mean value rig and a Green
rig, prints the mean change of the triangles' corner angles of each (radians and degrees, with
the distance from the affine image), and writes docs/images/green-vs-mvc.png.

    python examples/green_vs_mvc.py [out.png]
"""

import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from mpl_toolkits.mplot3d.art3d import Poly3DCollection  # noqa: E402

import cagerig  # noqa: E402

REPO = Path(__file__).resolve().parents[1]
ARM = REPO / "data" / "arm" / "arm.obj"


def corner_angles(v, f):
    out = []
    for i in range(3):
        a, b, c = v[f[:, i]], v[f[:, (i + 1) % 3]], v[f[:, (i + 2) % 3]]
        u, w = b - a, c - a
        cos = np.sum(u * w, axis=1) / (np.linalg.norm(u, axis=1) * np.linalg.norm(w, axis=1))
        out.append(np.arccos(np.clip(cos, -1, 1)))
    return np.stack(out, axis=1)


def stretched(coords):
    rig = cagerig.Rig.load(ARM, coords=coords)
    cage = rig.rest_cage
    centre = cage.mean(axis=0)
    offsets = np.zeros_like(cage)
    offsets[:, 0] = 0.6 * (cage[:, 0] - centre[0])
    rig.move_rest_cage(np.arange(len(cage)), offsets)
    return rig


def shade(v, f, colour):
    n = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
    n /= np.linalg.norm(n, axis=1)[:, None]
    light = np.array([0.3, -0.5, 0.8])
    light /= np.linalg.norm(light)
    k = 0.35 + 0.65 * np.abs(n @ light)
    return np.clip(np.outer(k, colour), 0, 1)


def main():
    out = Path(sys.argv[1]) if len(sys.argv) > 1 else REPO / "docs" / "images" / "green-vs-mvc.png"
    rest = cagerig.Rig.load(ARM)
    m0, faces = rest.rest_mesh, rest.triangles
    a0 = corner_angles(m0, faces)
    centre = rest.rest_cage.mean(axis=0)
    affine = m0.copy()
    affine[:, 0] = centre[0] + 1.6 * (m0[:, 0] - centre[0])
    size = np.linalg.norm(np.ptp(rest.rest_cage, axis=0))
    results = {}
    for coords in ("mvc", "green"):
        rig = stretched(coords)
        m = rig.rest_mesh
        change = np.abs(corner_angles(m, faces) - a0).mean()
        off_affine = np.linalg.norm(m - affine, axis=1).max() / size
        results[coords] = (rig, change, off_affine)
        print(
            f"{coords:>5}: mean corner-angle change {change:.4f} rad ({np.degrees(change):.2f}°), "
            f"max distance from the affine image {off_affine:.4f} of the cage diagonal"
        )
    ratio = results["green"][1] / results["mvc"][1]
    print(f"Green / MVC angle change: {ratio:.2f}")

    fig = plt.figure(figsize=(11, 7.5), dpi=110)
    titles = {
        "mvc": "mean value coordinates",
        "green": "Green coordinates",
    }
    for i, coords in enumerate(("mvc", "green")):
        rig, change, off_affine = results[coords]
        ax = fig.add_subplot(2, 1, i + 1, projection="3d")
        v = rig.rest_mesh
        poly = Poly3DCollection(v[faces], facecolors=shade(v, faces, (0.85, 0.72, 0.6)),
                                edgecolors="none")
        ax.add_collection3d(poly)
        cage = rig.rest_cage
        for t in rig.cage_triangles:
            loop = cage[list(t) + [t[0]]]
            ax.plot(loop[:, 0], loop[:, 1], loop[:, 2], color=(0.9, 0.45, 0.1), lw=0.4, alpha=0.6)
        lo, hi = cage.min(axis=0), cage.max(axis=0)
        ax.set_xlim(lo[0], hi[0])
        ax.set_ylim(lo[1], hi[1])
        ax.set_zlim(lo[2], hi[2])
        ax.set_box_aspect(hi - lo, zoom=1.05)
        ax.view_init(elev=12, azim=-80)
        ax.set_axis_off()
        ax.set_title(
            f"{titles[coords]}\nmean corner-angle change {np.degrees(change):.2f}°",
            fontsize=11,
        )
    fig.suptitle("The Arm's rest cage stretched 1.6× along x: the same edit, two kinds of "
                 "coordinates", fontsize=12)
    fig.tight_layout()
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
