"""Print the materials of a USD file (usd-core) as JSON, with usd-core's validation:
{"validation": [...], "meshes": [{"path", "material", "primvars"}],
 "subsets": [{"path", "material", "faces"}],
 "materials": [{"path", "surface"}],
 "shaders": [{"path", "id", "inputs": {name: value | {"connect": "PATH.outputs:x"}},
              "files": {name: {"resolved", "bytes", "crc32"}}}],
 "variants": {set: {"selection", "bindings": {variant: {mesh or subset path: material}}}}}
"variants" holds the default prim's variant sets, each variant selected in turn (in the
session layer) and every Mesh's and GeomSubset's bound material then.
Values are JSON numbers, lists or strings; asset files are opened through Ar (so inside a
.usdz too) and given by size and CRC-32. Prims in path order.

Usage: usd_looks.py FILE.usd[a|c|z]
"""
import json
import sys
import zlib

from pxr import Ar, Sdf, Usd, UsdGeom, UsdShade, UsdValidation

stage = Usd.Stage.Open(sys.argv[1])
ctx = UsdValidation.ValidationContext(UsdValidation.ValidationRegistry().GetOrLoadAllValidators())
out = {
    "validation": [f"{e.GetName()}: {e.GetMessage()}" for e in ctx.Validate(stage)],
    "meshes": [],
    "subsets": [],
    "materials": [],
    "shaders": [],
}


def plain(v):
    if isinstance(v, (bool, int, float, str)):
        return v
    if isinstance(v, Sdf.AssetPath):
        return v.path
    try:
        return [plain(x) for x in v]
    except TypeError:
        return str(v)


for prim in sorted(stage.Traverse(), key=lambda p: str(p.GetPath())):
    if prim.IsA(UsdGeom.Mesh):
        mat, _ = UsdShade.MaterialBindingAPI(prim).ComputeBoundMaterial()
        out["meshes"].append({
            "path": str(prim.GetPath()),
            "material": str(mat.GetPath()) if mat else None,
            "primvars": sorted(p.GetPrimvarName() for p in UsdGeom.PrimvarsAPI(prim).GetPrimvars()),
        })
    elif prim.IsA(UsdGeom.Subset):
        mat, _ = UsdShade.MaterialBindingAPI(prim).ComputeBoundMaterial()
        out["subsets"].append({
            "path": str(prim.GetPath()),
            "material": str(mat.GetPath()) if mat else None,
            "faces": len(UsdGeom.Subset(prim).GetIndicesAttr().Get() or []),
        })
    elif prim.IsA(UsdShade.Material):
        src = UsdShade.Material(prim).ComputeSurfaceSource()
        out["materials"].append({"path": str(prim.GetPath()), "surface": str(src[0].GetPath()) if src[0] else None})
    elif prim.IsA(UsdShade.Shader):
        sh = UsdShade.Shader(prim)
        inputs, files = {}, {}
        for i in sh.GetInputs():
            conns = i.GetAttr().GetConnections()
            if conns:
                inputs[i.GetBaseName()] = {"connect": str(conns[0])}
                continue
            v = i.Get()
            inputs[i.GetBaseName()] = plain(v)
            if isinstance(v, Sdf.AssetPath):
                resolved = v.resolvedPath
                asset = Ar.GetResolver().OpenAsset(Ar.ResolvedPath(resolved)) if resolved else None
                data = bytes(asset.GetBuffer()) if asset else b""
                files[i.GetBaseName()] = {"resolved": resolved, "bytes": len(data), "crc32": zlib.crc32(data)}
        out["shaders"].append({"path": str(prim.GetPath()), "id": sh.GetShaderId(), "inputs": inputs, "files": files})


def bindings():
    return {
        str(p.GetPath()): str(UsdShade.MaterialBindingAPI(p).ComputeBoundMaterial()[0].GetPath())
        for p in stage.Traverse()
        if p.IsA(UsdGeom.Mesh) or p.IsA(UsdGeom.Subset)
    }


out["variants"] = {}
root = stage.GetDefaultPrim()
stage.SetEditTarget(stage.GetSessionLayer())
for name in root.GetVariantSets().GetNames() if root else []:
    vset = root.GetVariantSets().GetVariantSet(name)
    selection = vset.GetVariantSelection()
    chosen = {}
    for v in vset.GetVariantNames():
        vset.SetVariantSelection(v)
        chosen[v] = bindings()
    out["variants"][name] = {"selection": selection, "bindings": chosen}
print(json.dumps(out))
