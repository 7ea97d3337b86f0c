"""Import a glTF file with Blender (PyPI bpy) and print its first mesh object's evaluated
vertices (armature and shape keys applied) in glTF's axes (Y up) at each time given, as one
line "BPY_POINTS " + JSON: {"times": [...], "points": [[[x, y, z], ...] per time]}.
An independent skinning of the file: Blender's glTF importer and its armature modifier.

Usage: .venv-bpy/bin/python tools/bpy_skinned_points.py FILE.glb SECONDS...
"""
import json
import sys

import bpy

bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.import_scene.gltf(filepath=sys.argv[1])
scene = bpy.context.scene
fps = scene.render.fps / scene.render.fps_base
ob = next(o for o in sorted(bpy.data.objects, key=lambda o: o.name) if o.type == "MESH")
out = {"times": [], "points": []}
for t in map(float, sys.argv[2:]):
    frame = t * fps
    whole = int(frame // 1)
    scene.frame_set(whole, subframe=frame - whole)
    evaluated = ob.evaluated_get(bpy.context.evaluated_depsgraph_get())
    mesh = evaluated.to_mesh()
    world = evaluated.matrix_world
    # Blender is Z up: its (x, y, z) is glTF's (x, -z, y).
    points = [world @ v.co for v in mesh.vertices]
    out["times"].append(t)
    out["points"].append([[p.x, p.z, -p.y] for p in points])
    evaluated.to_mesh_clear()
print("BPY_POINTS " + json.dumps(out))
