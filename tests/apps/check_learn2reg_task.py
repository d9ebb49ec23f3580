#!/usr/bin/python3
"""Reads a task `phantasm task` made as a Learn2Reg method and scorer would, written only from the
format's description (docs/benchmark-tasks.md): the dataset JSON's registration_val pairs, images
named TASK_CCCC_MMMM.nii.gz with labels, masks and keypoints beside them, and results named
disp_<fixed CCCC_MMMM>_<moving CCCC_MMMM>.nii.gz holding (X, Y, Z, 3) displacements in voxels on
the fixed grid, the moving image sampled at grid + displacement.

  check_learn2reg_task.py load TASK TRUTH
      checks the task and scores the ground truth as a Learn2Reg scorer would (labels warped by
      nearest neighbour, keypoints carried by trilinear displacement); prints JSON; exit 1 on a
      failed check.
  check_learn2reg_task.py dipy FIXED_LABELS MOVING_LABELS FIELD OUT
      warps the moving labels onto the fixed grid with dipy's DiffeomorphicMap, its forward field
      the given (X, Y, Z, 3) displacement in world (RAS) mm; writes OUT.
  check_learn2reg_task.py bad TRUTH_DISP OUT
      writes results that must be refused: OUT/int16, OUT/nan, OUT/shape (one folder each).
"""

import glob
import json
import os
import sys

import nibabel as nib
import numpy as np
from scipy.ndimage import map_coordinates


def fail(message):
    print(message, file=sys.stderr)
    sys.exit(1)


def load(task, truth):
    jsons = glob.glob(os.path.join(task, "*_dataset.json"))
    if len(jsons) != 1:
        fail(f"expected one *_dataset.json in {task}, found {jsons}")
    with open(jsons[0]) as f:
        dataset = json.load(f)
    name = dataset["name"]
    shape = tuple(dataset["tensorImageShape"]["0"])
    pairs = dataset["registration_val"]
    if dataset["numRegistration_val"] != len(pairs) or not pairs:
        fail("numRegistration_val does not count registration_val")
    if dataset["numTraining"] != len(dataset["training"]):
        fail("numTraining does not count training")
    report = {"pairs": []}
    for pair in pairs:
        fixed_path = os.path.join(task, pair["fixed"])
        moving_path = os.path.join(task, pair["moving"])
        for path in (fixed_path, moving_path):
            base = os.path.basename(path)
            parts = base[: -len(".nii.gz")].split("_")
            if not (base.startswith(name + "_") and len(parts) == 3 and len(parts[1]) == 4 and len(parts[2]) == 4):
                fail(f"{base}: expected {name}_CCCC_MMMM.nii.gz")
        fixed = nib.load(fixed_path)
        moving = nib.load(moving_path)
        if fixed.shape != shape or moving.shape != shape:
            fail(f"{fixed_path}: shape {fixed.shape}, tensorImageShape {shape}")
        labels = [np.asarray(nib.load(p.replace("imagesTr", "labelsTr")).dataobj).astype(int)
                  for p in (fixed_path, moving_path)]
        masks = [np.asarray(nib.load(p.replace("imagesTr", "masksTr")).dataobj) for p in (fixed_path, moving_path)]
        for label, mask in zip(labels, masks):
            if not np.array_equal(mask > 0, label > 0):
                fail("a mask is not the foreground of its labels")
        keypoints = [np.loadtxt(p.replace("imagesTr", "keypointsTr").replace(".nii.gz", ".csv"), delimiter=",", ndmin=2)
                     for p in (fixed_path, moving_path)]
        if keypoints[0].shape != keypoints[1].shape or keypoints[0].shape[1] != 3:
            fail("fixed and moving keypoints do not correspond row by row")

        # The result name as the Learn2Reg scorer makes it: the 9 characters CCCC_MMMM of each image.
        disp_name = "disp_{}_{}.nii.gz".format(pair["fixed"][-16:-7], pair["moving"][-16:-7])
        disp = np.asarray(nib.load(os.path.join(truth, disp_name)).dataobj, dtype=np.float64)
        if disp.shape != shape + (3,):
            fail(f"{disp_name}: shape {disp.shape}, expected {shape + (3,)}")
        grid = np.stack(np.meshgrid(*[np.arange(n) for n in shape], indexing="ij"))
        target = grid + np.moveaxis(disp, -1, 0)
        warped = map_coordinates(labels[1], target, order=0, mode="constant", cval=0)

        def mean_dice(a, b):
            values = []
            for label in np.unique(labels[0]):
                if label == 0 or not (labels[1] == label).any():
                    continue
                x, y = a == label, b == label
                values.append(2.0 * (x & y).sum() / (x.sum() + y.sum()))
            return float(np.mean(values))

        moved = keypoints[0] + np.stack(
            [map_coordinates(disp[..., c], keypoints[0].T, order=1, mode="nearest") for c in range(3)], axis=1)
        tre = np.linalg.norm(moved - keypoints[1], axis=1)
        identity_tre = np.linalg.norm(keypoints[0] - keypoints[1], axis=1)
        report["pairs"].append({
            "fixed": pair["fixed"], "moving": pair["moving"], "result": disp_name,
            "dice_truth": mean_dice(labels[0], warped), "dice_identity": mean_dice(labels[0], labels[1]),
            "tre_truth_voxels_max": float(tre.max()), "tre_identity_voxels_max": float(identity_tre.max()),
            "keypoints": int(len(tre))})
    print(json.dumps(report))


def dipy_warp(fixed_labels, moving_labels, field, out):
    from dipy.align.imwarp import DiffeomorphicMap
    fixed = nib.load(fixed_labels)
    moving = nib.load(moving_labels)
    disp = np.asarray(nib.load(field).dataobj, dtype=np.float64)
    mapping = DiffeomorphicMap(3, fixed.shape, fixed.affine, fixed.shape, fixed.affine, moving.shape, moving.affine)
    mapping.forward = disp.astype(np.float64)
    mapping.backward = np.zeros_like(mapping.forward)
    mapping.is_inverse = False
    warped = mapping.transform(np.asarray(moving.dataobj).astype(np.float64), interpolation="nearest")
    nib.save(nib.Nifti1Image(np.rint(warped).astype(np.int16), fixed.affine), out)


def bad(truth_disp, out):
    image = nib.load(truth_disp)
    disp = np.asarray(image.dataobj, dtype=np.float32)
    name = os.path.basename(truth_disp)
    variants = {"int16": np.rint(disp).astype(np.int16), "nan": disp.copy(), "shape": disp[:-1]}
    variants["nan"][3, 4, 5, 1] = np.nan
    for folder, values in variants.items():
        os.makedirs(os.path.join(out, folder), exist_ok=True)
        nib.save(nib.Nifti1Image(values, image.affine), os.path.join(out, folder, name))


if __name__ == "__main__":
    if len(sys.argv) == 4 and sys.argv[1] == "load":
        load(sys.argv[2], sys.argv[3])
    elif len(sys.argv) == 6 and sys.argv[1] == "dipy":
        dipy_warp(*sys.argv[2:6])
    elif len(sys.argv) == 4 and sys.argv[1] == "bad":
        bad(sys.argv[2], sys.argv[3])
    else:
        fail(__doc__)
