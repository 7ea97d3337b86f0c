"""Import a USD file with Blender (PyPI bpy, Python 3.11) and print what arrived, as JSON:
[{"name", "materials": [names], "base_color": "linked node type" | [r, g, b, a],
  "images": [{"name", "width", "height"}], "color_attributes": {name: {"domain", "mean": [r, g, b]}}}]
per mesh object, in name order. An image's size is read from its file, so a width of 0 means
Blender could not find or read it.

Usage: .venv-bpy/bin/python tools/bpy_import.py FILE.usd[a|c|z]
"""
import json
import sys

import bpy

bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.wm.usd_import(filepath=sys.argv[1])
out = []
for ob in sorted(bpy.data.objects, key=lambda o: o.name):
    if ob.type != "MESH":
        continue
    me = ob.data
    info = {"name": ob.name, "materials": [m.name for m in me.materials if m], "images": [],
            "base_color": None, "color_attributes": {}}
    for m in me.materials:
        if not m or not m.use_nodes:
            continue
        for n in m.node_tree.nodes:
            if n.type == "TEX_IMAGE" and n.image:
                info["images"].append({"name": n.image.name, "width": n.image.size[0], "height": n.image.size[1]})
            if n.type == "BSDF_PRINCIPLED":
                i = n.inputs["Base Color"]
                info["base_color"] = i.links[0].from_node.type if i.links else list(i.default_value)
    for a in me.color_attributes:
        k = max(len(a.data), 1)
        mean = [sum(d.color[c] for d in a.data) / k for c in range(3)]
        info["color_attributes"][a.name] = {"domain": a.domain, "mean": mean}
    out.append(info)
print("BPY_IMPORT " + json.dumps(out))
