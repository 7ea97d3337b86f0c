"""Print the cameras and lights of a USD file (usd-core) as JSON: per prim path its type, API
schemas, authored attributes, world transform (row-major, USD's row-vector convention) and, for a
camera, the vertical field of view and projection as usd-core's Gf.Camera computes them.

Usage: usd_scene.py FILE.usd[a|c|z]
"""
import json
import sys

from pxr import Gf, Usd, UsdGeom

TYPES = ("Camera", "DistantLight", "SphereLight")


def plain(v):
    if isinstance(v, (bool, int, float, str)):
        return v
    try:
        return [plain(x) for x in v]
    except TypeError:
        return str(v)


stage = Usd.Stage.Open(sys.argv[1])
out = {}
for prim in stage.Traverse():
    if prim.GetTypeName() not in TYPES:
        continue
    world = UsdGeom.Xformable(prim).ComputeLocalToWorldTransform(Usd.TimeCode.Default())
    entry = {
        "type": str(prim.GetTypeName()),
        "api_schemas": [str(s) for s in prim.GetAppliedSchemas()],
        "attrs": {
            a.GetName(): plain(a.Get())
            for a in prim.GetAttributes()
            if a.HasAuthoredValue()
        },
        "world": [list(world.GetRow(i)) for i in range(4)],
    }
    if prim.GetTypeName() == "Camera":
        cam = UsdGeom.Camera(prim).GetCamera(Usd.TimeCode.Default())
        entry["vertical_fov_degrees"] = cam.GetFieldOfView(Gf.Camera.FOVVertical)
        entry["aspect"] = cam.aspectRatio
    out[str(prim.GetPath())] = entry
print(json.dumps(out, indent=1, sort_keys=True))
