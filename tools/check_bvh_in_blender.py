"""Import BVH files with Blender's own importer and compare its joints with posekit's reader.

Not part of the tests (Blender is not a dependency): run it where the ``bpy`` wheel is installed,
``python3.11 -m venv /tmp/bpy && /tmp/bpy/bin/pip install bpy numpy scipy && /tmp/bpy/bin/pip install -e .``,
then ``/tmp/bpy/bin/python tools/check_bvh_in_blender.py notebooks/studio_exports/*.bvh``. For each file it
prints whether the import finished, the bone and frame counts, and the largest distance (mm) between
Blender's bone heads and posekit's FK of the same file, every frame. Blender turns BVH's Y-up into Z-up:
a BVH point (x, y, z) is Blender's (x, -z, y).
"""

from __future__ import annotations

import sys

import numpy as np


def check(path: str) -> float:
    import bpy

    from posekit.io.bvh import read_bvh

    expected = read_bvh(path).global_positions()  # (F, J, 3), metres
    names = list(read_bvh(path).skeleton.names)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    result = bpy.ops.import_anim.bvh(filepath=path, global_scale=1.0, axis_forward="-Z", axis_up="Y",
                                     rotate_mode="NATIVE", use_fps_scale=False, update_scene_fps=False)
    arm = next(o for o in bpy.context.scene.objects if o.type == "ARMATURE")
    first, last = (int(round(f)) for f in arm.animation_data.action.frame_range)
    got = np.zeros((last - first + 1, len(names), 3))
    for i, f in enumerate(range(first, last + 1)):
        bpy.context.scene.frame_set(f)
        for j, n in enumerate(names):
            x, y, z = arm.matrix_world @ arm.pose.bones[n].head
            got[i, j] = (x, z, -y)  # Blender's Z-up back to BVH's Y-up
    n = min(len(got), len(expected))
    err = float(np.abs(got[:n] - expected[:n]).max() * 1000)
    print(f"{path}: import {sorted(result)[0]}, {len(arm.data.bones)} bones, {last - first + 1} frames "
          f"(file: {len(expected)}), largest joint difference {err:.4f} mm")
    return err


if __name__ == "__main__":
    worst = max(check(p) for p in sys.argv[1:])
    sys.exit(0 if worst < 0.01 else 1)
