#!/usr/bin/python3
"""Draws a dataset's reference image, deformed image and their difference side by side.

For one image of one subject (default T1w of sub-01), three rows (axial, coronal, sagittal slices
through one point, by default the voxel where the ground-truth displacement is largest, so the
slices cross the deformation) and three columns: the reference state, the deformed state, and
deformed minus reference (a symmetric colour scale). A last column shows the displacement's length
(mm) in the same slices. Writes one PNG.

Usage: scripts/state_figure.py DATASET -o FIGURE.png [--image T1w] [--subject 01] [--title TEXT]
"""

import argparse
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import nibabel
import numpy as np


def load(path):
    if not os.path.exists(path):
        sys.exit(f"state_figure: {path}: no such file (was the dataset written by phantasm run?)")
    image = nibabel.load(path)
    return np.asanyarray(image.dataobj), image.header.get_zooms()


def slices(volume, point):
    """Axial, coronal and sagittal slices through `point` (voxel indices), oriented for display
    (RAS voxel axes: superior and anterior up)."""
    i, j, k = point
    return [np.rot90(volume[:, :, k]), np.rot90(volume[:, j, :]), np.rot90(volume[i, :, :])]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("dataset")
    parser.add_argument("-o", "--output", required=True)
    parser.add_argument("--image", default="T1w")
    parser.add_argument("--subject", default="01")
    parser.add_argument("--title", default=None)
    args = parser.parse_args()

    sub = f"sub-{args.subject}"
    ref, zooms = load(os.path.join(args.dataset, sub, "ses-ref", "anat", f"{sub}_ses-ref_{args.image}.nii.gz"))
    deformed, _ = load(os.path.join(args.dataset, sub, "ses-def", "anat", f"{sub}_ses-def_{args.image}.nii.gz"))
    field, _ = load(os.path.join(args.dataset, "derivatives", "phantasm", sub, "xfm",
                                 f"{sub}_from-def_to-ref_mode-image_xfm.nii.gz"))
    ref = ref.astype(np.float32)
    deformed = deformed.astype(np.float32)
    motion = np.sqrt((field.reshape(field.shape[:3] + (3,)).astype(np.float32) ** 2).sum(axis=3))
    point = np.unravel_index(int(np.argmax(motion)), motion.shape)

    high = float(np.percentile(ref, 99.5))
    difference = deformed - ref
    spread = float(np.percentile(np.abs(difference), 99.9)) or 1.0
    columns = [("reference", slices(ref, point), dict(cmap="gray", vmin=0, vmax=high)),
               ("deformed", slices(deformed, point), dict(cmap="gray", vmin=0, vmax=high)),
               ("deformed - reference", slices(difference, point), dict(cmap="RdBu_r", vmin=-spread, vmax=spread)),
               ("displacement (mm)", slices(motion, point), dict(cmap="magma", vmin=0, vmax=float(motion.max())))]
    aspects = [zooms[1] / zooms[0], zooms[2] / zooms[0], zooms[2] / zooms[1]]
    figure, axes = plt.subplots(3, len(columns), figsize=(3.2 * len(columns), 9.0), constrained_layout=True)
    for c, (name, planes, style) in enumerate(columns):
        for r, plane in enumerate(planes):
            shown = axes[r][c].imshow(plane, aspect=aspects[r], interpolation="nearest", **style)
            axes[r][c].set_xticks([])
            axes[r][c].set_yticks([])
            if r == 0:
                axes[r][c].set_title(name)
        figure.colorbar(shown, ax=[axes[r][c] for r in range(3)], shrink=0.6)
    for r, plane_name in enumerate(["axial", "coronal", "sagittal"]):
        axes[r][0].set_ylabel(plane_name)
    figure.suptitle(args.title or f"{args.dataset}: {args.image}, slices through the largest displacement "
                    f"(voxel {tuple(int(v) for v in point)})")
    temporary = args.output + ".part.png"
    figure.savefig(temporary, dpi=80)
    os.replace(temporary, args.output)


if __name__ == "__main__":
    main()
