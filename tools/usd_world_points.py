"""Print one Mesh of a USD file (usd-core) in world space at each of its points' time
samples (or once, at the default time, when it has none) as JSON:
  {"times": [...], "points": [[[x, y, z], ...] per time], "normals": [...] or null}
where points are transformed by the prim's local-to-world transform at that time and normals
by its inverse transpose, renormalised.

Usage: usd_world_points.py FILE.usd[a|c|z] PRIM_PATH
"""
import json
import sys

import numpy as np
from pxr import Usd, UsdGeom

stage = Usd.Stage.Open(sys.argv[1])
prim = stage.GetPrimAtPath(sys.argv[2])
mesh = UsdGeom.Mesh(prim)
times = mesh.GetPointsAttr().GetTimeSamples() or [Usd.TimeCode.Default()]
cache = UsdGeom.XformCache()
out = {"times": [], "points": [], "normals": []}
for t in times:
    code = Usd.TimeCode(t) if not isinstance(t, Usd.TimeCode) else t
    cache.SetTime(code)
    m = np.array(cache.GetLocalToWorldTransform(prim)).reshape(4, 4)
    p = np.array(mesh.GetPointsAttr().Get(code), dtype=float)
    world = p @ m[:3, :3] + m[3, :3]
    out["times"].append(None if code.IsDefault() else code.GetValue())
    out["points"].append(world.tolist())
    n = mesh.GetNormalsAttr().Get(code)
    if n is None:
        out["normals"] = None
    elif out["normals"] is not None:
        n = np.array(n, dtype=float) @ np.linalg.inv(m[:3, :3]).T
        n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-30)
        out["normals"].append(n.tolist())
print(json.dumps(out))
