"""Exit 0 when usd-core exports the two USD files as the same text (same specs and values)."""
import sys

from pxr import Sdf

a, b = (Sdf.Layer.FindOrOpen(p).ExportToString() for p in sys.argv[1:3])
if a != b:
    import difflib

    sys.stdout.writelines(list(difflib.unified_diff(a.splitlines(True), b.splitlines(True)))[:40])
    sys.exit(1)
