"""Print every prim of a USD file (usd-core) as JSON: its path and its displayName (null
where it shows its own name).

Usage: usd_names.py FILE.usd[a|c|z]
"""
import json
import sys

from pxr import Usd

stage = Usd.Stage.Open(sys.argv[1])
out = {}
for prim in stage.Traverse():
    out[str(prim.GetPath())] = prim.GetDisplayName() or None
print(json.dumps(out, ensure_ascii=False))
