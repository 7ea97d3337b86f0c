"""Print the points of one Mesh of a USD file (usd-core) at its default time as a JSON list.

Usage: usd_points.py FILE.usd[a|c|z] PRIM_PATH
"""
import json
import sys

from pxr import Usd, UsdGeom

stage = Usd.Stage.Open(sys.argv[1])
mesh = UsdGeom.Mesh(stage.GetPrimAtPath(sys.argv[2]))
print(json.dumps([list(p) for p in mesh.GetPointsAttr().Get()]))
