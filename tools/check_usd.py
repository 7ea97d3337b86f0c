"""Check a USD file written by inbetween with Pixar's usd-core.

Usage: check_usd.py FILE.usd[a|c|z] DUMP.bin
Opens the stage, runs every validator of pxr.UsdValidation, checks the stage metadata and
every Mesh (one points sample per time-sampled frame, matching extent and normals sample
counts, extent == UsdGeom.PointBased.ComputeExtent of each sample), and writes the points of
every time-sampled Mesh to DUMP.bin (float32, prims in path order, samples in time order)
for the caller to compare with the glTF output. Prints one JSON object:
  {"errors": [...], "validation": [...], "meta": {...}, "meshes": [{path, samples, points,
   times, static}], "xforms": [{path, times, local}], "instancers": [{path, prototypes,
   transforms}]}
where "xforms" lists each prim whose local transform is time-sampled, with its local matrix
(16 numbers, row by row as USD prints it) at each sample time, and "instancers" each
PointInstancer with its prototypes' paths and each instance's transform (16 numbers, as
UsdGeom.PointInstancer.ComputeInstanceTransformsAtTime gives it, relative to the instancer).
"""
import json
import sys

import numpy as np
from pxr import Usd, UsdGeom, UsdValidation

path, dump = sys.argv[1], sys.argv[2]
stage = Usd.Stage.Open(path)
errors = []

ctx = UsdValidation.ValidationContext(UsdValidation.ValidationRegistry().GetOrLoadAllValidators())
validation = [
    {"name": e.GetName(), "type": str(e.GetType()), "message": e.GetMessage()}
    for e in ctx.Validate(stage)
]

meta = {
    "defaultPrim": str(stage.GetDefaultPrim().GetPath()) if stage.GetDefaultPrim() else None,
    "upAxis": UsdGeom.GetStageUpAxis(stage),
    "metersPerUnit": UsdGeom.GetStageMetersPerUnit(stage),
    "timeCodesPerSecond": stage.GetTimeCodesPerSecond(),
    "framesPerSecond": stage.GetFramesPerSecond(),
    "start": stage.GetStartTimeCode(),
    "end": stage.GetEndTimeCode(),
}
if not stage.GetDefaultPrim():
    errors.append("no defaultPrim")
if meta["upAxis"] != "Y":
    errors.append(f"upAxis {meta['upAxis']}")
if meta["metersPerUnit"] != 1:
    errors.append(f"metersPerUnit {meta['metersPerUnit']}")
if meta["timeCodesPerSecond"] != meta["framesPerSecond"]:
    errors.append("timeCodesPerSecond != framesPerSecond")

meshes = []
out = open(dump, "wb")
for prim in sorted(stage.Traverse(), key=lambda p: str(p.GetPath())):
    if not prim.IsA(UsdGeom.Mesh):
        continue
    mesh = UsdGeom.Mesh(prim)
    pts_attr = mesh.GetPointsAttr()
    times = pts_attr.GetTimeSamples()
    info = {"path": str(prim.GetPath()), "samples": len(times), "static": len(times) == 0, "times": list(times)}
    if mesh.GetSubdivisionSchemeAttr().Get() != "none":
        errors.append(f"{prim.GetPath()}: subdivisionScheme is not none")
    counts = mesh.GetFaceVertexCountsAttr().Get()
    indices = mesh.GetFaceVertexIndicesAttr().Get()
    if counts is None or indices is None or sum(counts) != len(indices):
        errors.append(f"{prim.GetPath()}: face arrays do not agree")
    sample_times = times if times else [Usd.TimeCode.Default()]
    ext_times = mesh.GetExtentAttr().GetTimeSamples()
    if times and list(ext_times) != list(times):
        errors.append(f"{prim.GetPath()}: extent samples differ from points samples")
    nrm = mesh.GetNormalsAttr()
    if nrm.HasAuthoredValue():
        n_times = nrm.GetTimeSamples()
        if times and n_times and list(n_times) != list(times):
            errors.append(f"{prim.GetPath()}: normals samples differ from points samples")
    for t in sample_times:
        pts = pts_attr.Get(t)
        info["points"] = len(pts)
        ext = mesh.GetExtentAttr().Get(t)
        want = UsdGeom.PointBased.ComputeExtent(pts)
        if ext is None or len(ext) != 2 or any(ext[i] != want[i] for i in range(2)):
            errors.append(f"{prim.GetPath()} at {t}: extent {ext} != computed {want}")
        if times:
            np.asarray(pts, dtype=np.float32).tofile(out)
            if nrm.HasAuthoredValue() and len(nrm.Get(t)) != len(pts):
                errors.append(f"{prim.GetPath()} at {t}: normals count")
        if times and (t < meta["start"] or t > meta["end"]):
            errors.append(f"{prim.GetPath()}: sample {t} outside start/end time codes")
    meshes.append(info)
out.close()

xforms = []
for prim in sorted(stage.Traverse(), key=lambda p: str(p.GetPath())):
    if not prim.IsA(UsdGeom.Xformable):
        continue
    x = UsdGeom.Xformable(prim)
    times = x.GetTimeSamples()
    if not times:
        continue
    local = [[v for row in x.GetLocalTransformation(t) for v in row] for t in times]
    xforms.append({"path": str(prim.GetPath()), "times": list(times), "local": local})
instancers = []
for prim in sorted(stage.Traverse(), key=lambda p: str(p.GetPath())):
    if not prim.IsA(UsdGeom.PointInstancer):
        continue
    pi = UsdGeom.PointInstancer(prim)
    transforms = pi.ComputeInstanceTransformsAtTime(Usd.TimeCode.Default(), Usd.TimeCode.Default())
    instancers.append({
        "path": str(prim.GetPath()),
        "prototypes": [str(t) for t in pi.GetPrototypesRel().GetTargets()],
        "transforms": [[v for row in m for v in row] for m in transforms],
    })
print(json.dumps({"errors": errors, "validation": validation, "meta": meta, "meshes": meshes,
                  "xforms": xforms, "instancers": instancers}))
