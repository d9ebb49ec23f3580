#!/usr/bin/python3
"""scripts/structure_fidelity.py on small synthetic label volumes whose figures are known.

* A plate of 6 x 20 x 20 voxels of 2 x 1 x 1 mm against the same plate 2 voxels (4 mm) further
  along x, on a derived grid of another shape and origin (so the labels meet only through the
  affines): Dice 4/6, HD95 4 mm (every surface voxel of either plate lies within 4 mm of the
  other's surface, and its face across x, a third of its surface voxels, exactly 4 mm from it),
  one 20 x 20 layer (0.8 ml) of each plate more than 3 mm from the other.
* An organ of the run's scene.yaml standing for two derived labels, less the one its tissue
  region takes as a label of its own: Dice 1 and HD95 0 for both when the voxels agree.
* A tissue region with a name of its own standing for its atlas label: the run labels standing for
  the same derived labels make one structure (the plate split between an organ and a region of
  another organ matches the derived plate whole).
* HD95 of random blobs against an independent measure (nearest surface points by a k-d tree).
* Bad input: exit 2, a message naming what is wrong, nothing written.
"""

import contextlib
import csv
import io
import json
import os
import subprocess
import sys
import tempfile
import unittest

import nibabel
import numpy
from scipy import ndimage
from scipy.spatial import cKDTree

SCRIPT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts", "structure_fidelity.py")
sys.path.insert(0, os.path.dirname(SCRIPT))
import structure_fidelity  # noqa: E402

SPACING = (2.0, 1.0, 1.0)
RUN_ORIGIN = numpy.array([10.0, -5.0, 7.0])
OFFSET = 3  # the derived grid starts 3 voxels before the run's along every axis


def affine(origin):
    a = numpy.diag(list(SPACING) + [1.0])
    a[:3, 3] = origin
    return a


def write_table(path, key, names):
    with open(path, "w", newline="") as f:
        writer = csv.writer(f, delimiter="\t")
        writer.writerow([key, "name"])
        for value, name in names.items():
            writer.writerow([value, name])


def make_inputs(folder):
    """A run dataset and a derived label volume (with its table) in folder; returns their paths."""
    run = numpy.zeros((20, 30, 30), numpy.int16)
    derived = numpy.zeros((26, 36, 36), numpy.int16)
    o = OFFSET
    run[4:10, 5:25, 5:25] = 1                            # plate
    derived[o + 6:o + 12, o + 5:o + 25, o + 5:o + 25] = 1  # the plate 2 voxels further along x
    derived[o + 13:o + 19, o + 2:o + 12, o + 2:o + 12] = 2  # grey
    derived[o + 14:o + 18, o + 4:o + 10, o + 4:o + 10] = 3  # white
    derived[o + 15:o + 17, o + 6:o + 8, o + 6:o + 8] = 4    # nuclei
    run[13:19, 2:12, 2:12] = 5                           # brain: grey and white
    run[15:17, 6:8, 6:8] = 6                             # nuclei (a tissue region of brain)
    dataset = os.path.join(folder, "run")
    anat = os.path.join(dataset, "derivatives", "phantasm", "sub-01", "ses-ref", "anat")
    os.makedirs(anat)
    nibabel.save(nibabel.Nifti1Image(run, affine(RUN_ORIGIN)), os.path.join(anat, "sub-01_ses-ref_dseg.nii.gz"))
    write_table(os.path.join(dataset, "derivatives", "phantasm", "dseg.tsv"), "index",
                {1: "plate", 5: "brain", 6: "nuclei", 7: "unrelated"})
    with open(os.path.join(dataset, "derivatives", "phantasm", "sub-01", "scene.yaml"), "w") as f:
        f.write("anatomy:\n  organs:\n"
                "    - {name: brain, shape: {type: label_volume, label: [grey, white, nuclei]}}\n"
                "tissue_regions:\n  - {organ: brain, label: nuclei, tissue: gm}\n")
    labels = os.path.join(folder, "labels.nii.gz")
    nibabel.save(nibabel.Nifti1Image(derived, affine(RUN_ORIGIN - OFFSET * numpy.array(SPACING))), labels)
    write_table(os.path.join(folder, "labels.tsv"), "label", {1: "plate", 2: "grey", 3: "white", 4: "nuclei"})
    return dataset, labels


def run_script(*args):
    return subprocess.run([sys.executable, SCRIPT, *args], capture_output=True, text=True)


def brute_force_hd95(a, b, spacing):
    """The larger directed 95th percentile of nearest surface-point distances, by k-d trees."""
    points = [numpy.argwhere(structure_fidelity.surface(m)) * numpy.array(spacing) for m in (a, b)]
    a_to_b = cKDTree(points[1]).query(points[0])[0]
    b_to_a = cKDTree(points[0]).query(points[1])[0]
    return max(numpy.percentile(a_to_b, 95), numpy.percentile(b_to_a, 95))


class StructureFidelity(unittest.TestCase):
    def test_known_figures_through_names_scene_and_affines(self):
        with tempfile.TemporaryDirectory() as folder:
            dataset, labels = make_inputs(folder)
            report_file = os.path.join(folder, "report.json")
            result = run_script(dataset, labels, "--json", report_file)
            self.assertEqual(result.returncode, 0, result.stderr)
            with open(report_file) as f:
                rows = {row["name"]: row for row in json.load(f)["structures"]}
        self.assertEqual(sorted(rows), ["brain", "nuclei", "plate"])  # "unrelated" maps to nothing
        plate = rows["plate"]
        self.assertAlmostEqual(plate["dice"], 4.0 / 6.0, places=9)
        self.assertAlmostEqual(plate["hd95_mm"], 4.0, places=9)
        self.assertAlmostEqual(plate["run_ml"], 2400 * 2 / 1000.0, places=9)
        self.assertAlmostEqual(plate["derived_far_ml"], 0.8, places=9)
        self.assertAlmostEqual(plate["run_far_ml"], 0.8, places=9)
        self.assertEqual(plate["derived_far"]["taken_by_ml"], {"background": 0.8})
        # The far layer is derived x index 3 + 11 = run index 11: world x = 10 + 2 * 11.
        self.assertEqual(plate["derived_far"]["centroid_mm"], [32.0, 9.5, 21.5])
        self.assertEqual(plate["run_far"]["taken_by_ml"], {"background": 0.8})
        self.assertEqual(plate["run_far"]["centroid_mm"], [18.0, 9.5, 21.5])
        for name, derived in (("brain", ["grey", "white"]), ("nuclei", ["nuclei"])):
            self.assertEqual(rows[name]["derived"], derived)
            self.assertAlmostEqual(rows[name]["dice"], 1.0, places=12)
            self.assertEqual(rows[name]["hd95_mm"], 0.0)
            self.assertEqual(rows[name]["derived_far_ml"], 0.0)

    def test_run_labels_of_the_same_derived_labels_make_one_structure(self):
        with tempfile.TemporaryDirectory() as folder:
            dataset, labels = make_inputs(folder)
            derivatives = os.path.join(dataset, "derivatives", "phantasm")
            dseg = os.path.join(derivatives, "sub-01", "ses-ref", "anat", "sub-01_ses-ref_dseg.nii.gz")
            run = numpy.asanyarray(nibabel.load(dseg).dataobj).copy()
            run[run == 1] = 0
            run[6:10, 5:25, 5:25] = 1  # the plate organ holds 4 of the derived plate's 6 layers
            run[10:12, 5:25, 5:25] = 8  # a region of the brain organ the other 2
            nibabel.save(nibabel.Nifti1Image(run, affine(RUN_ORIGIN)), dseg)
            write_table(os.path.join(derivatives, "dseg.tsv"), "index",
                        {1: "plate", 5: "brain", 6: "nuclei", 8: "plate_piece"})
            with open(os.path.join(derivatives, "sub-01", "scene.yaml"), "a") as f:
                f.write("  - {organ: brain, label: plate, tissue: bone, name: plate_piece}\n")
            report_file = os.path.join(folder, "report.json")
            result = run_script(dataset, labels, "--json", report_file)
            self.assertEqual(result.returncode, 0, result.stderr)
            with open(report_file) as f:
                rows = {row["name"]: row for row in json.load(f)["structures"]}
        self.assertEqual(sorted(rows), ["brain", "nuclei", "plate"])
        self.assertEqual(rows["plate"]["run"], ["plate", "plate_piece"])
        # An organ whose every label its regions take stands for nothing.
        self.assertEqual(structure_fidelity.structures({1: "plate", 2: "piece"}, {1: "plate"},
                                                       {"plate": [], "piece": ["plate"]}),
                         [([2], "piece", [1])])
        self.assertAlmostEqual(rows["plate"]["dice"], 1.0, places=12)
        self.assertEqual(rows["plate"]["hd95_mm"], 0.0)
        self.assertAlmostEqual(rows["plate"]["run_ml"], 2400 * 2 / 1000.0, places=9)

    def test_misplaced_volume_counts_what_lies_beyond_the_distance(self):
        run = numpy.zeros((20, 30, 30), bool)
        derived = numpy.zeros_like(run)
        run[4:10, 5:25, 5:25] = True
        derived[6:12, 5:25, 5:25] = True  # its last layer 4 mm (2 voxels of 2 mm) from the run's plate
        for far_mm, expected_ml in ((3.9, 0.8), (4.0, 0.0), (1.9, 1.6)):
            result, _, _ = structure_fidelity.compare(run, derived, SPACING, far_mm)
            self.assertAlmostEqual(result["derived_far_ml"], expected_ml, places=9, msg=far_mm)
            self.assertAlmostEqual(result["run_far_ml"], expected_ml, places=9, msg=far_mm)

    def test_hd95_matches_nearest_surface_points(self):
        generator = numpy.random.default_rng(5)
        for _ in range(2):
            noise = ndimage.gaussian_filter(generator.standard_normal((16, 32, 32)), 3)
            a = noise > 0.02
            b = ndimage.shift(noise, (1, -2, 3), order=1) > 0.0
            result, _, _ = structure_fidelity.compare(a, b, SPACING, 3.0)
            self.assertAlmostEqual(result["hd95_mm"], brute_force_hd95(a, b, SPACING), places=9)
            self.assertGreater(result["hd95_mm"], 1.0)
            overlap = (a & b).sum()
            self.assertAlmostEqual(result["dice"], 2.0 * overlap / (a.sum() + b.sum()), places=12)

    def test_bad_input_exits_2_and_writes_nothing(self):
        with tempfile.TemporaryDirectory() as folder:
            dataset, labels = make_inputs(folder)
            report_file = os.path.join(folder, "report.json")
            cases = [((dataset, labels, "--map", "plate=plate+bone"), "bone"),
                     ((os.path.join(folder, "nothing"), labels), "phantasm dataset"),
                     ((dataset, os.path.join(folder, "absent.nii.gz")), "absent.nii.gz"),
                     ((dataset, labels, "--map", "plate"), "NAME=LABEL")]
            for args, named in cases:
                # In this process (the command line itself is run above): main() as the script runs it.
                stderr = io.StringIO()
                with contextlib.redirect_stderr(stderr), self.assertRaises(SystemExit) as exit_status:
                    sys.argv = [SCRIPT, *args, "--json", report_file]
                    structure_fidelity.main()
                self.assertEqual(exit_status.exception.code, 2, (args, stderr.getvalue()))
                self.assertIn(named, stderr.getvalue())
                self.assertFalse(os.path.exists(report_file))


if __name__ == "__main__":
    unittest.main()
