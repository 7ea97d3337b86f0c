"""Print what every prim of a USD file (usd-core) keeps of its glTF object, as JSON: per prim
path its displayName (null where it shows its own name) and its customData "extras" (null
where it has none; arrays as lists, 64-bit and 32-bit integers alike as numbers); and under
"/" (the layer) its customLayerData (the glTF asset's copyright, generator and extras).

Usage: usd_meta.py FILE.usd[a|c|z]
"""
import json
import sys

from pxr import Usd


def plain(v):
    if isinstance(v, dict):
        return {k: plain(x) for k, x in v.items()}
    if isinstance(v, (bool, int, float, str)):
        return v
    return [plain(x) for x in v]


stage = Usd.Stage.Open(sys.argv[1])
out = {"/": plain(stage.GetRootLayer().customLayerData)}
for prim in stage.Traverse():
    extras = prim.GetCustomDataByKey("extras")
    out[str(prim.GetPath())] = {
        "display": prim.GetDisplayName() or None,
        "extras": None if extras is None else plain(extras),
    }
print(json.dumps(out, ensure_ascii=False))
