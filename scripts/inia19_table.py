"""A names table (BIDS dseg.tsv) for the NeuroMaps labels of the INIA19 macaque template, which
Debian's mricron-data ships without names (no .txt or .lut for inia19-NeuroMaps.nii.gz).

Each label gets a name <side>_<class>_<nnnn>: nnnn its number modulo 1000 (NeuroMaps numbers a
structure n on the left and 1000 + n on the right), side `left` for n < 1000 and `right` for
n >= 1000, class `white` or `grey` from the T1 template's intensities:
  * the histogram of the T1 intensities of the labelled voxels inside the brain (label > 0,
    T1 > 0; bins of width 1 from 0) has a grey-matter mode near 90, a white-matter mode near 109
    and a long dark tail (CSF and partial volume); Otsu's method with three classes (the two
    thresholds whose classes have the largest between-class variance) puts its upper threshold t
    between the two modes (t = 99; two classes would put it in the dark tail, at 81);
  * a label is white when more than half of its voxels are brighter than t (its median above t),
    else grey. Labels whose voxels lie mostly outside the template's brain mask (T1 = 0: a few
    small labels at the brain's surface) are grey.
The side is checked against the data: every left label's voxels must have a mean x <= 0 mm and
every right label's a mean x >= 0 mm (RAS world coordinates of the template), or the script stops.

Columns: index, name, voxels (the label's voxel count, 0.5 mm voxels), white_fraction (the
fraction of its voxels brighter than t). The first line of the standard error gives t and the
counts. Deterministic: the same files give the same table, byte for byte (tests/io/
test_segmentation.cpp re-derives the shipped data-synthetic/macaque/inia19-NeuroMaps_dseg.tsv
and requires it to be equal).

Source: Rohlfing T, Kroenke CD, Sullivan EV, Dubach MF, Bowden DM, Grant KA, Pfefferbaum A
(2012) The INIA19 template and NeuroMaps atlas for primate brain image parcellation and spatial
normalization. Front Neuroinform 6:27, doi:10.3389/fninf.2012.00027.

Usage: /usr/bin/python3 scripts/inia19_table.py OUT.tsv
  [--t1 /usr/share/mricron/templates/inia19-t1-brain.nii.gz]
  [--labels /usr/share/mricron/templates/inia19-NeuroMaps.nii.gz]"""
import argparse
import sys

import nibabel as nib
import numpy as np

TEMPLATES = "/usr/share/mricron/templates"


def otsu_thresholds(values):
    """Otsu's two thresholds (three classes: the largest between-class variance) of the values
    (>= 0) on a histogram of unit bins from 0: the upper edges of the darker classes' last bins."""
    counts = np.bincount(np.floor(values).astype(np.int64)).astype(np.float64)
    centres = np.arange(counts.size) + 0.5
    weight = np.cumsum(counts)
    total = np.cumsum(counts * centres)
    best, thresholds = -1.0, (0, 0)
    for a in range(1, counts.size - 1):
        for b in range(a + 1, counts.size):
            parts = [(weight[a - 1], total[a - 1]), (weight[b - 1] - weight[a - 1], total[b - 1] - total[a - 1]),
                     (weight[-1] - weight[b - 1], total[-1] - total[b - 1])]
            if min(w for w, _ in parts) <= 0:
                continue
            score = sum(s * s / w for w, s in parts)  # the between-class variance up to constants
            if score > best:
                best, thresholds = score, (a, b)
    return float(thresholds[0]), float(thresholds[1])


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("out")
    parser.add_argument("--t1", default=TEMPLATES + "/inia19-t1-brain.nii.gz")
    parser.add_argument("--labels", default=TEMPLATES + "/inia19-NeuroMaps.nii.gz")
    args = parser.parse_args()

    t1_image = nib.load(args.t1)
    label_image = nib.load(args.labels)
    if t1_image.shape != label_image.shape or not np.allclose(t1_image.affine, label_image.affine):
        sys.exit("%s and %s: expected the same grid, found %s and %s" %
                 (args.t1, args.labels, t1_image.shape, label_image.shape))
    t1 = np.asanyarray(t1_image.dataobj).astype(np.float64)
    labels = np.asanyarray(label_image.dataobj).astype(np.int64)

    inside = labels > 0
    dark, threshold = otsu_thresholds(t1[inside & (t1 > 0)])

    present = np.unique(labels[inside])
    order = np.searchsorted(present, labels[inside])
    voxels = np.bincount(order, minlength=present.size)
    brighter = np.bincount(order, weights=(t1[inside] > threshold).astype(np.float64), minlength=present.size)
    x = (nib.affines.apply_affine(label_image.affine, np.argwhere(inside)))[:, 0]
    mean_x = np.bincount(order, weights=x, minlength=present.size) / voxels

    rows = []
    for label, count, bright, centre in zip(present, voxels, brighter, mean_x):
        left = label < 1000
        if (left and centre > 0) or (not left and centre < 0):
            sys.exit("%s: label %d: expected its voxels on the %s (mean x %s 0 mm), found mean x %.2f mm" %
                     (args.labels, label, "left" if left else "right", "<=" if left else ">=", centre))
        fraction = bright / count
        kind = "white" if fraction > 0.5 else "grey"
        rows.append("%d\t%s_%s_%04d\t%d\t%.3f" % (label, "left" if left else "right", kind, label % 1000,
                                                   count, fraction))
    with open(args.out, "w") as out:
        out.write("index\tname\tvoxels\twhite_fraction\n")
        out.write("\n".join(rows) + "\n")
    white = sum(1 for row in rows if "_white_" in row)
    print("Otsu thresholds %.0f and %.0f; %d labels: %d white, %d grey" %
          (dark, threshold, len(rows), white, len(rows) - white), file=sys.stderr)


if __name__ == "__main__":
    main()
