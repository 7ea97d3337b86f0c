"""BVH through Blender (PyPI bpy): its own importer and exporter, for the Z-up capture test.

  bpy_bvh.py reexport SRC.bvh DST.bvh ORDER
      Import SRC (Y up, as BVH is by convention) and export it again over the same frames with
      every joint's six channels, rotations in ORDER (XYZ, ZXY, ...): Blender's exporter writes
      its own Z-up world, as a capture cleaned in Blender comes out.
  bpy_bvh.py compare A.bvh B.bvh
      Import A as Y-up and B as Z-up (Blender's own axes, no conversion) and print one line
      "BPY_BVH " + JSON: {"frames": [a, b], "worst": the largest distance between a bone's head
      in the two at one frame, "size": the largest distance between two heads of A's first
      frame}.
"""
import json
import sys

import bpy


def load(path, **axes):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.import_anim.bvh(
        filepath=path, update_scene_fps=True, update_scene_duration=True, **axes
    )
    arm = bpy.context.selected_objects[0]
    bpy.context.view_layer.objects.active = arm
    first, last = arm.animation_data.action.frame_range
    return arm, int(first), int(last)


def heads(path, **axes):
    arm, first, last = load(path, **axes)
    out = []
    for f in range(first, last + 1):
        bpy.context.scene.frame_set(f)
        out.append([(arm.matrix_world @ b.head).copy() for b in arm.pose.bones])
    return out


mode, a, b = sys.argv[1:4]
if mode == "reexport":
    arm, first, last = load(a)
    bpy.ops.export_anim.bvh(
        filepath=b, frame_start=first, frame_end=last, rotate_mode=sys.argv[4],
        root_transform_only=False,
    )
else:
    pa, pb = heads(a), heads(b, axis_forward="Y", axis_up="Z")
    worst = max((x - y).length for fa, fb in zip(pa, pb) for x, y in zip(fa, fb))
    size = max((x - y).length for x in pa[0] for y in pa[0])
    print("BPY_BVH " + json.dumps({"frames": [len(pa), len(pb)], "worst": worst, "size": size}))
