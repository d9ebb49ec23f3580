#!/usr/bin/python3
"""How closely a phantasm dataset of the Colin 27 head resembles the scan it was derived from.

The reference state's image (default T1w) is resampled (trilinear, through both files' affines:
the same world space, RAS mm) onto the grid of the real scan /usr/share/mricron/templates/ch2.nii.gz
and compared there:
  * the Pearson correlation of the two intensities over the head (every voxel the dataset's
    reference dseg labels, resampled nearest) and over the brain (ch2bet.nii.gz > 0);
  * per dseg label, the variation (standard deviation over mean) of the real and the synthetic
    intensities, so that piecewise-constant tissues show as such;
  * the ceiling of a piecewise-constant image on the dataset's labels: the highest correlation
    with the scan that any image constant on each dseg label can reach over the head and over
    the brain (the correlation ratio: the scan's own mean in each label). No choice of tissue
    parameters lifts an untextured image above it; only labels closer to the scan's structures
    or texture do. With --labels (a label map in the same world space, e.g. out of
    `phantasm atlas colin27`) the same ceiling on those labels, to tell the fitted anatomy's
    share from the tissue values'.
Writes the figures as JSON (--json) and prints them. See docs/anatomy-colin27.md, Realism.

Usage: scripts/image_realism.py DATASET [--subject 01] [--sequence T1w] [--templates DIR] [--labels FILE]
                                  [--json FILE]
"""

import argparse
import csv
import glob
import json
import os
import sys

import nibabel
import numpy
from scipy import ndimage


def resample(image, target, order):
    """image's voxels at the centres of target's voxels (world space through both affines)."""
    source_from_target = numpy.linalg.inv(image.affine) @ target.affine
    grid = numpy.indices(target.shape[:3]).reshape(3, -1)
    points = source_from_target[:3, :3] @ grid + source_from_target[:3, 3:4]
    values = ndimage.map_coordinates(numpy.asanyarray(image.dataobj, dtype=numpy.float64).squeeze(), points,
                                     order=order, mode="constant", cval=0.0)
    return values.reshape(target.shape[:3])


def correlation(a, b):
    a = a - a.mean()
    b = b - b.mean()
    denominator = numpy.sqrt((a * a).sum() * (b * b).sum())
    return float((a * b).sum() / denominator) if denominator > 0 else float("nan")


def piecewise_constant_ceiling(scan, labels, mask):
    """The highest correlation with scan over mask of an image constant on each label: that of
    the scan's mean in each label (the correlation ratio, sqrt(between-label variance / variance));
    0 when the mask holds one label (no image constant on it varies there)."""
    values, label = scan[mask], labels[mask]
    _, groups = numpy.unique(label, return_inverse=True)
    if groups.size == 0 or groups.max() == 0:
        return 0.0
    sums = numpy.bincount(groups, weights=values)
    counts = numpy.bincount(groups)
    return correlation(values, (sums / counts)[groups])


def dataset_file(dataset, subject, pattern):
    matches = sorted(glob.glob(os.path.join(dataset, f"sub-{subject}", "ses-ref", "anat", pattern)))
    if not matches:
        sys.exit(f"image_realism: {dataset}: no sub-{subject}/ses-ref/anat/{pattern} (a phantasm dataset?)")
    return matches[0]


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("dataset", help="a phantasm output folder (e.g. out of scripts/run.sh)")
    parser.add_argument("--subject", default="01")
    parser.add_argument("--sequence", default="T1w")
    parser.add_argument("--templates", default="/usr/share/mricron/templates")
    parser.add_argument("--labels", default=None,
                        help="a label map in the scan's world space (e.g. phantasm atlas colin27's): "
                             "its piecewise-constant ceiling too")
    parser.add_argument("--json", default=None, help="write the figures here")
    args = parser.parse_args()

    real = nibabel.load(os.path.join(args.templates, "ch2.nii.gz"))
    bet = nibabel.load(os.path.join(args.templates, "ch2bet.nii.gz"))
    image = nibabel.load(dataset_file(args.dataset, args.subject, f"*_ses-ref_{args.sequence}.nii.gz"))
    derivatives = os.path.join(args.dataset, "derivatives", "phantasm")
    dseg = nibabel.load(dataset_file(derivatives, args.subject, "*_ses-ref_dseg.nii.gz"))
    names = {}
    table = os.path.join(derivatives, "dseg.tsv")
    if os.path.exists(table):
        with open(table) as f:
            for row in csv.DictReader(f, delimiter="\t"):
                names[int(row["index"])] = row["name"]

    scan = numpy.asanyarray(real.dataobj, dtype=numpy.float64).squeeze()
    synthetic = resample(image, real, 1)
    labels = numpy.rint(resample(dseg, real, 0)).astype(int)
    brain = resample(bet, real, 0) > 0
    head = labels > 0
    result = {
        "dataset": os.path.abspath(args.dataset),
        "sequence": args.sequence,
        "correlation_head": correlation(scan[head], synthetic[head]),
        "correlation_brain": correlation(scan[brain], synthetic[brain]),
        "ceiling_head": piecewise_constant_ceiling(scan, labels, head),
        "ceiling_brain": piecewise_constant_ceiling(scan, labels, brain),
        "head_voxels": int(head.sum()),
        "brain_voxels": int(brain.sum()),
        "labels": [],
    }
    if args.labels:
        other = numpy.rint(resample(nibabel.load(args.labels), real, 0)).astype(int)
        result["labels_file"] = os.path.abspath(args.labels)
        result["labels_ceiling_head"] = piecewise_constant_ceiling(scan, other, head)
        result["labels_ceiling_brain"] = piecewise_constant_ceiling(scan, other, brain)
    for label in sorted(set(numpy.unique(labels)) - {0}):
        inside = labels == label
        if inside.sum() < 10:
            continue
        r, s = scan[inside], synthetic[inside]
        result["labels"].append({
            "label": int(label), "name": names.get(int(label), str(label)), "voxels": int(inside.sum()),
            "real_mean": float(r.mean()), "real_variation": float(r.std() / r.mean()) if r.mean() else None,
            "synthetic_mean": float(s.mean()),
            "synthetic_variation": float(s.std() / s.mean()) if s.mean() else None})
    print(f"{args.sequence} against ch2.nii.gz: correlation {result['correlation_head']:.3f} over the head "
          f"({result['head_voxels']} voxels), {result['correlation_brain']:.3f} over the brain "
          f"({result['brain_voxels']} voxels)")
    print(f"  ceiling of an image constant on each dseg label: {result['ceiling_head']:.3f} over the head, "
          f"{result['ceiling_brain']:.3f} over the brain")
    if args.labels:
        print(f"  ceiling on {args.labels}'s labels: {result['labels_ceiling_head']:.3f} over the head, "
              f"{result['labels_ceiling_brain']:.3f} over the brain")
    for row in result["labels"]:
        print(f"  {row['name']:<24} real mean {row['real_mean']:8.1f} variation {row['real_variation'] or 0:.3f}"
              f"   synthetic mean {row['synthetic_mean']:9.1f} variation {row['synthetic_variation'] or 0:.3f}")
    if args.json:
        with open(args.json, "w") as f:
            json.dump(result, f, indent=2)


if __name__ == "__main__":
    main()
