"""Load the paper's Arm, bend the elbow, inflate the forearm's cage, plot before/after (PNG)."""
import sys; from pathlib import Path; import numpy as np; import cagerig  # noqa: E401,E702
import matplotlib; matplotlib.use("Agg"); import matplotlib.pyplot as plt  # noqa: E401,E702

ARM = Path(__file__).resolve().parents[3] / "data/arm/arm.obj"  # beside the checkout
rig = cagerig.Rig.load(sys.argv[1] if len(sys.argv) > 1 else ARM)
before = rig.posed_mesh, rig.posed_cage
rig.rotate_joint("lowerarm01.R", [1, 0, 0], -50)                         # bend the elbow (skeleton)
C, a = rig.rest_cage, rig.rest_joints[rig.joint_names.index("lowerarm02.R")]
near = np.argsort(np.linalg.norm(C - a, axis=1))[:10]                      # the forearm's cage vertices
rig.move_rest_cage(near, 0.6 * (C[near] - a))                              # inflate them (rest cage)
fig = plt.figure(figsize=(10, 5))
for i, (M, G) in enumerate([before, (rig.posed_mesh, rig.posed_cage)]):
    ax = fig.add_subplot(1, 2, i + 1, projection="3d", title=["loaded", "bent + inflated"][i])
    ax.plot_trisurf(*M.T, triangles=rig.triangles, color="tan", linewidth=0)
    ax.plot_trisurf(*G.T, triangles=rig.cage_triangles, color=(0, 0, 0, 0), edgecolor="k", lw=0.3)
    ax.set_aspect("equal"), ax.view_init(0, 180), ax.set_axis_off()
fig.savefig(sys.argv[2] if len(sys.argv) > 2 else "arm.png", dpi=110, bbox_inches="tight")
