"""Score blend reports (run.sh's OUT folders): per folder, the cells (pair x weight), how many
have a jerk ratio above issue 17's 1.15, the worst and mean, how many slide more before clean-up
than the naive blend, and how many more than 1e-3 leg/frame after it. VERBOSE=1 lists them.

Usage: python3 score.py OUT...
"""
import glob
import json
import os
import statistics
import sys

for folder in sys.argv[1:]:
    rows = []
    for path in sorted(glob.glob(os.path.join(folder, "*.json"))):
        reports = json.load(open(path))
        for r in reports if isinstance(reports, list) else [reports]:
            res = r["result"]
            after = res.get("after_cleanup")
            rows.append((
                os.path.basename(path)[:-5], r["weight"], res["jerk_ratio"],
                res["before_cleanup"]["sliding"]["mean"], r["naive"]["sliding"]["mean"],
                after["sliding"]["mean"] if after else None,
            ))
    if not rows:
        print(f"{folder}: no reports")
        continue
    jerky = [x for x in rows if x[2] > 1.15]
    above = [x for x in rows if x[3] > x[4]]
    slide = [x for x in rows if x[5] is not None and x[5] > 1e-3]
    print(f"{folder}: cells {len(rows)} jerk>1.15 {len(jerky)} worst {max(x[2] for x in rows):.3f} "
          f"mean {statistics.mean(x[2] for x in rows):.3f} before>naive {len(above)} "
          f"after>1e-3 {len(slide)}")
    if os.environ.get("VERBOSE"):
        for x in sorted(jerky, key=lambda x: -x[2]):
            print(f"   jerk {x[2]:.3f} {x[0]} @{x[1]} before {x[3]:.4f} naive {x[4]:.4f}")
        for x in above:
            print(f"   before>naive {x[0]} @{x[1]} {x[3]:.4f} > {x[4]:.4f}")
        for x in slide:
            print(f"   after {x[5]:.1e} {x[0]} @{x[1]}")
