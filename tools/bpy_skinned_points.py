"""Import a glTF file with Blender (PyPI bpy) and print its largest mesh object's evaluated
vertices (armature and shape keys applied) in glTF's axes (Y up) at each time given, as one
line "BPY_POINTS " + JSON: {"times": [...], "points": [[[x, y, z], ...] per time]}.
An independent skinning of the file: Blender's glTF importer and its armature modifier.

With --action NAME the armature plays that animation (the importer's NLA tracks muted).

Usage: .venv-bpy/bin/python tools/bpy_skinned_points.py FILE.glb [--action NAME] SECONDS...
"""
import json
import sys

import bpy

args = sys.argv[1:]
action = None
if "--action" in args:
    at = args.index("--action")
    action = args[at + 1]
    del args[at : at + 2]
bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.import_scene.gltf(filepath=args[0])
if action is not None:
    arm = next(o for o in bpy.data.objects if o.type == "ARMATURE")
    arm.animation_data.action = next(a for a in bpy.data.actions if a.name.startswith(action))
    for track in arm.animation_data.nla_tracks:
        track.mute = True
scene = bpy.context.scene
fps = scene.render.fps / scene.render.fps_base
# The character: the mesh object of most vertices (the importer adds small bone shapes).
meshes = [o for o in bpy.data.objects if o.type == "MESH"]
ob = max(meshes, key=lambda o: (len(o.data.vertices), o.name))
out = {"times": [], "points": []}
for t in map(float, args[1:]):
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
