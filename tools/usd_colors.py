"""Print the display colours of every Mesh of a USD file (usd-core) as JSON:
[{"path", "interpolation", "color": [[r, g, b], ...], "opacity": [a, ...] or null}], prims in
path order.

Usage: usd_colors.py FILE.usd[a|c|z]
"""
import json
import sys

from pxr import Usd, UsdGeom

stage = Usd.Stage.Open(sys.argv[1])
out = []
for prim in sorted(stage.Traverse(), key=lambda p: str(p.GetPath())):
    if not prim.IsA(UsdGeom.Mesh):
        continue
    api = UsdGeom.PrimvarsAPI(prim)
    color = api.GetPrimvar("displayColor")
    opacity = api.GetPrimvar("displayOpacity")
    out.append({
        "path": str(prim.GetPath()),
        "interpolation": color.GetInterpolation() if color else None,
        "color": [list(c) for c in color.Get()] if color else None,
        "opacity": list(opacity.Get()) if opacity and opacity.HasValue() else None,
        "opacity_interpolation": opacity.GetInterpolation() if opacity and opacity.HasValue() else None,
    })
print(json.dumps(out))
