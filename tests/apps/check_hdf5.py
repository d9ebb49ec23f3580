"""Checks a phantasm HDF5 export against the dataset's NIfTI files with h5py and nibabel: every
image, label map, field, mask and Jacobian of every subject is there with the file's values,
shape and affine, and the metadata attributes are present. Exit 0 when all agree.

Usage: check_hdf5.py EXPORT.h5 DATASET
"""
import json
import os
import sys

import h5py
import nibabel as nib
import numpy as np

path, dataset = sys.argv[1], sys.argv[2]
problems = []
checked = 0
with h5py.File(path, "r") as f:
    for key in ("format", "label_table", "conventions"):
        if key not in f.attrs:
            problems.append(f"/ lacks attribute {key}")
    subjects = sorted(k for k in f.keys() if k.startswith("sub-"))
    expected = sorted(d for d in os.listdir(os.path.join(dataset, "derivatives", "phantasm"))
                      if d.startswith("sub-"))
    if subjects != expected:
        problems.append(f"subjects {subjects} != {expected}")
    for subject in subjects:
        provenance = json.loads(f[subject].attrs["provenance"])
        for relative in provenance["files"]:
            name = os.path.basename(relative)
            if not name.endswith(".nii.gz") or "_probseg" in name or "map.nii" in name:
                continue
            image = nib.load(os.path.join(dataset, relative))
            data = image.get_fdata(dtype=np.float32)
            if name.endswith("_xfm.nii.gz"):
                key = f"{subject}/xfm/" + name.split("_", 1)[1].replace("_mode-image_xfm.nii.gz", "")
                data = data[:, :, :, 0, :]
            elif name.endswith("_desc-exact_mask.nii.gz"):
                key = f"{subject}/xfm/" + name.split("_", 1)[1].replace("_desc-exact_mask.nii.gz", "_exact_mask")
            elif name.endswith("_jacobian.nii.gz"):
                key = f"{subject}/xfm/" + name.split("_", 1)[1].replace(".nii.gz", "")
            elif name.endswith("_dseg.nii.gz"):
                key = f"{subject}/{name.split('_')[1]}/dseg"
            else:
                session, suffix = name[:-7].split("_")[1:3]
                key = f"{subject}/{session}/{suffix}"
            if key not in f:
                problems.append(f"{key} missing (from {relative})")
                continue
            array = f[key][...]
            if array.shape != data.shape or not np.array_equal(array.astype(np.float32), data):
                problems.append(f"{key}: values differ from {relative}")
            if not np.allclose(f[key].attrs["affine"], image.affine, atol=1e-5):
                problems.append(f"{key}: affine differs from {relative}")
            if f[key].compression != "gzip" or f[key].chunks is None:
                problems.append(f"{key}: not chunked and compressed")
            checked += 1
print(f"checked {checked} arrays")
for p in problems:
    print(p)
sys.exit(1 if problems or checked == 0 else 0)
