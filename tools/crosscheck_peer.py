"""Cross-check inbetween's seed frames against ../shared/peers/ref_tween.py (numpy/scipy).

Reads a JSON job written by the Rust test: welded triangles, welded key poses, and the frames
inbetween computed ({"a": key index, "t": t, "x": positions}). Runs the peer's SeedTweener
for each key pair and prints {"max_rel": max error / bounding-box diagonal, "frames": N}.
"""
import json
import sys

import numpy as np

sys.path.insert(0, sys.argv[2])
from ref_tween import SeedTweener  # noqa: E402

job = json.load(open(sys.argv[1]))
tris = np.array(job["tris"], dtype=np.int64)
keys = [np.array(k, dtype=np.float64) for k in job["keys"]]
diag = np.linalg.norm(keys[0].max(axis=0) - keys[0].min(axis=0))
tweeners = {}
worst = 0.0
for f in job["frames"]:
    a = f["a"]
    if a not in tweeners:
        tweeners[a] = SeedTweener(keys[a], keys[a + 1], tris)
    ref = tweeners[a].frame(f["t"])
    err = np.abs(ref - np.array(f["x"])).max()
    worst = max(worst, float(err / diag))
print(json.dumps({"max_rel": worst, "frames": len(job["frames"])}))
