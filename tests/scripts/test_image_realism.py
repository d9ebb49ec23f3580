#!/usr/bin/python3
"""scripts/image_realism.py on a small synthetic scan and dataset whose figures are known.

* A synthetic image that is an affine function of the scan, on a grid of its own (shifted origin,
  other spacing, so the two meet only through their affines): correlation 1 over the head and
  the brain.
* The piecewise-constant ceiling equals the correlation ratio computed independently
  (sqrt(between-label sum of squares / total sum of squares)), is 1 for a scan constant on each
  label, and bounds the correlation of any image constant on each label.
* --labels: the ceiling on another label map (here one label for the whole head: 0).
"""

import json
import os
import subprocess
import sys
import tempfile
import unittest

import nibabel
import numpy

SCRIPT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts", "image_realism.py")
sys.path.insert(0, os.path.dirname(SCRIPT))
import image_realism  # noqa: E402

SHAPE = (24, 20, 16)


def scan_affine():
    a = numpy.diag([1.0, 1.0, 1.0, 1.0])
    a[:3, 3] = [-12.0, -10.0, -8.0]
    return a


def labels_on_scan():
    """Three nested boxes (head 1, 2 and brain 3) on the scan's grid."""
    labels = numpy.zeros(SHAPE, dtype=numpy.int16)
    labels[2:22, 2:18, 2:14] = 1
    labels[4:20, 4:16, 4:12] = 2
    labels[7:17, 6:14, 6:10] = 3
    return labels


def write_dataset(root, scan, synthetic_of_scan, labels):
    """A templates folder (ch2, ch2bet) and a dataset whose T1w and dseg lie on a grid of half the
    spacing, shifted by 0.2 mm, holding synthetic_of_scan(scan) and labels."""
    templates = os.path.join(root, "templates")
    os.makedirs(templates)
    nibabel.save(nibabel.Nifti1Image(scan.astype(numpy.float32), scan_affine()), os.path.join(templates, "ch2.nii.gz"))
    brain = (labels == 3).astype(numpy.uint8)
    nibabel.save(nibabel.Nifti1Image(brain, scan_affine()), os.path.join(templates, "ch2bet.nii.gz"))
    # The dataset's grid: 0.5 mm voxels, values at the scan's voxel centres repeated (nearest).
    fine = numpy.repeat(numpy.repeat(numpy.repeat(scan, 2, 0), 2, 1), 2, 2)
    fine_labels = numpy.repeat(numpy.repeat(numpy.repeat(labels, 2, 0), 2, 1), 2, 2)
    affine = numpy.diag([0.5, 0.5, 0.5, 1.0])
    # Each scan voxel centre lies between two fine voxels of its own, 0.2 and 0.3 mm away: nearest
    # and trilinear both read that scan voxel's value there.
    affine[:3, 3] = scan_affine()[:3, 3] - 0.2
    anat = os.path.join(root, "data", "sub-01", "ses-ref", "anat")
    os.makedirs(anat)
    nibabel.save(nibabel.Nifti1Image(synthetic_of_scan(fine).astype(numpy.float32), affine),
                 os.path.join(anat, "sub-01_ses-ref_T1w.nii.gz"))
    derived = os.path.join(root, "data", "derivatives", "phantasm", "sub-01", "ses-ref", "anat")
    os.makedirs(derived)
    nibabel.save(nibabel.Nifti1Image(fine_labels.astype(numpy.int16), affine),
                 os.path.join(derived, "sub-01_ses-ref_dseg.nii.gz"))
    with open(os.path.join(root, "data", "derivatives", "phantasm", "dseg.tsv"), "w") as f:
        f.write("index\tname\n0\tbackground\n1\tscalp\n2\tskull\n3\tbrain\n")
    return templates


def run(root, templates, *extra):
    out = os.path.join(root, "figures.json")
    done = subprocess.run([sys.executable, SCRIPT, os.path.join(root, "data"), "--templates", templates,
                           "--json", out, *extra], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    with open(out) as f:
        return json.load(f), done.stdout


def correlation_ratio(values, groups):
    mean = values.mean()
    between = sum(((values[groups == g].mean() - mean) ** 2) * (groups == g).sum() for g in numpy.unique(groups))
    return numpy.sqrt(between / ((values - mean) ** 2).sum())


class ImageRealism(unittest.TestCase):
    def setUp(self):
        self.folder = tempfile.TemporaryDirectory()
        self.root = self.folder.name
        rng = numpy.random.default_rng(3)
        self.labels = labels_on_scan()
        means = numpy.array([0.0, 40.0, 20.0, 100.0])
        self.scan = means[self.labels] + 8.0 * rng.standard_normal(SHAPE) * (self.labels > 0)

    def test_affine_image_correlates_fully_and_ceiling_is_the_correlation_ratio(self):
        templates = write_dataset(self.root, self.scan, lambda s: 3.0 * s + 7.0, self.labels)
        figures, printed = run(self.root, templates)
        self.assertAlmostEqual(figures["correlation_head"], 1.0, places=6)
        self.assertAlmostEqual(figures["correlation_brain"], 1.0, places=6)
        head, brain = self.labels > 0, self.labels == 3
        self.assertAlmostEqual(figures["ceiling_head"], correlation_ratio(self.scan[head], self.labels[head]), places=9)
        self.assertLess(figures["ceiling_head"], 0.999)  # the noise is no label's
        # The brain is one label: no image constant on it varies there.
        self.assertEqual(figures["ceiling_brain"], 0.0)
        self.assertIn("ceiling of an image constant on each dseg label", printed)
        # Any other constant per label does no better than the ceiling.
        rng = numpy.random.default_rng(5)
        for _ in range(20):
            other = rng.uniform(0, 100, 4)[self.labels]
            self.assertLessEqual(image_realism.correlation(self.scan[head], other[head]),
                                 figures["ceiling_head"] + 1e-12)

    def test_scan_constant_on_labels_reaches_the_ceiling_of_one(self):
        flat = numpy.array([0.0, 40.0, 20.0, 100.0])[self.labels]
        templates = write_dataset(self.root, flat, lambda s: s, self.labels)
        figures, _ = run(self.root, templates)
        self.assertAlmostEqual(figures["ceiling_head"], 1.0, places=9)

    def test_other_labels_have_their_own_ceiling(self):
        templates = write_dataset(self.root, self.scan, lambda s: s, self.labels)
        one = os.path.join(self.root, "one.nii.gz")
        nibabel.save(nibabel.Nifti1Image((self.labels > 0).astype(numpy.int16), scan_affine()), one)
        figures, printed = run(self.root, templates, "--labels", one)
        self.assertEqual(figures["labels_ceiling_head"], 0.0)
        self.assertAlmostEqual(figures["ceiling_head"], correlation_ratio(self.scan[self.labels > 0],
                                                                          self.labels[self.labels > 0]), places=9)
        self.assertIn("one.nii.gz's labels", printed)


if __name__ == "__main__":
    unittest.main()
