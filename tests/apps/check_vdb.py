"""Opens a phantasm .vdb file with OpenVDB's Python module (pyopenvdb, Debian's python3-openvdb)
and reads every grid in it: each must be of a type the module supports, carry frame, units and
description metadata, and the label grid must hold whole label values. Exit 0 when all hold.

Usage: check_vdb.py FILE.vdb
"""
import sys

import pyopenvdb as vdb

path = sys.argv[1]
problems = []
grids = vdb.readAllGridMetadata(path)
names = sorted(grid.name for grid in grids)
for name in names:
    grid = vdb.read(path, name)
    for key in ("frame", "units", "description"):
        if key not in grid:
            problems.append(f"{name}: no {key} metadata")
    if not grid["frame"].startswith("RAS"):
        problems.append(f"{name}: frame {grid['frame']}")
    low, high = grid.evalMinMax()
    if name == "labels":
        values = set()
        for item in grid.citerOnValues():
            values.add(item.value)
        if not values or any(v != int(v) or v < 1 for v in values):
            problems.append(f"labels: values {sorted(values)[:10]} are not whole positive labels")
    elif name.startswith("fraction_") and (low < 0 or high > 1):
        problems.append(f"{name}: values outside [0, 1]: {low} {high}")
    elif name.endswith("_sdf") and grid.gridClass != vdb.GridClass.LEVEL_SET:
        problems.append(f"{name}: not a level set")
print(f"read {len(names)} grids: {' '.join(names)}")
for p in problems:
    print(p)
sys.exit(1 if problems or "labels" not in names else 0)
