"""Checks a phantasm HDF5 export against the dataset's files with h5py and nibabel: every image,
label map, fraction, parameter map, field, mask, Jacobian and landmark list of every subject is
there (found by its "source" attribute, so the check does not depend on file names) with the
file's values, shape and affine; each array states its kind, units, frame and axes (one name per
dimension), and a parameter map's units are its sidecar's. Exit 0 when all agree.

Usage: check_hdf5.py EXPORT.h5 DATASET
"""
import csv
import json
import os
import sys

import h5py
import nibabel as nib
import numpy as np

path, dataset = sys.argv[1], sys.argv[2]
problems = []
kinds = {}
with h5py.File(path, "r") as f:
    for key in ("format", "label_table", "conventions"):
        if key not in f.attrs:
            problems.append(f"/ lacks attribute {key}")
    subjects = sorted(k for k in f.keys() if k.startswith("sub-"))
    derivatives = os.path.join(dataset, "derivatives", "phantasm")
    expected = sorted(d for d in os.listdir(derivatives)
                      if d.startswith("sub-") and os.path.isdir(os.path.join(derivatives, d)))
    if subjects != expected:
        problems.append(f"subjects {subjects} != {expected}")
    arrays = {}
    f.visititems(lambda name, item: arrays.__setitem__(name, item) if isinstance(item, h5py.Dataset) else None)
    by_source = {}
    for name, item in arrays.items():
        for key in ("source", "kind", "units", "frame", "axes"):
            if key not in item.attrs:
                problems.append(f"{name} lacks attribute {key}")
        by_source[item.attrs["source"]] = name
    for subject in subjects:
        provenance = json.loads(f[subject].attrs["provenance"])
        for relative in provenance["files"]:
            if not (relative.endswith(".nii.gz") or relative.endswith("_landmarks.csv")):
                continue
            if relative not in by_source:
                problems.append(f"{relative} is not in the export")
                continue
            name = by_source.pop(relative)
            item = f[name]
            array = item[...]
            kind = item.attrs["kind"]
            kinds[kind] = kinds.get(kind, 0) + 1
            if len(item.attrs["axes"].split()) != array.ndim:
                problems.append(f"{name}: axes '{item.attrs['axes']}' for a {array.ndim}-D array")
            if kind == "landmarks":
                with open(os.path.join(dataset, relative)) as text:
                    rows = list(csv.DictReader(text))
                data = np.array([[float(r["x_mm"]), float(r["y_mm"]), float(r["z_mm"])] for r in rows])
                if array.shape != data.shape or not np.allclose(array, data, atol=1e-9):
                    problems.append(f"{name}: positions differ from {relative}")
                if list(item.attrs["names"]) != [r["name"] for r in rows]:
                    problems.append(f"{name}: names differ from {relative}")
                continue
            image = nib.load(os.path.join(dataset, relative))
            data = image.get_fdata(dtype=np.float32)
            if kind == "displacement_field":
                if data.ndim != 5 or array.ndim != 4:
                    problems.append(f"{name}: a {array.ndim}-D array of a {data.ndim}-D file")
                data = data[:, :, :, 0, :]
            if array.shape != data.shape or not np.array_equal(array.astype(np.float32), data):
                problems.append(f"{name}: values differ from {relative}")
            if not np.allclose(item.attrs["affine"], image.affine, atol=1e-5):
                problems.append(f"{name}: affine differs from {relative}")
            if item.compression != "gzip" or item.chunks is None:
                problems.append(f"{name}: not chunked and compressed")
            sidecar = os.path.join(dataset, relative[: -len(".nii.gz")] + ".json")
            if kind == "parameter_map":
                units = json.load(open(sidecar))["Units"]
                if item.attrs["units"] != units:
                    problems.append(f"{name}: units {item.attrs['units']} != sidecar's {units}")
    for source, name in by_source.items():
        problems.append(f"{name}: source {source} is not a file of its subject's provenance")
checked = sum(kinds.values())
print(f"checked {checked} arrays: " + ", ".join(f"{k} {n}" for k, n in sorted(kinds.items())))
for p in problems:
    print(p)
sys.exit(1 if problems or checked == 0 else 0)
