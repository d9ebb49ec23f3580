"""The Python module from Debian's /usr/bin/python3: build a phantom, change the seed, run it,
and read the deformed T1-weighted image as a numpy array with the grid's shape and affine; the
arrays equal what the dataset writer puts in the NIfTI files (read with nibabel)."""

import os
import sys
import tempfile
import unittest

import nibabel as nib
import numpy as np

import phantasm

SOURCE = os.environ["PHANTASM_SOURCE_DIR"]
SMALL = os.path.join(SOURCE, "tests", "data", "scenes", "small-head.yaml")


class PythonModule(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.scene = phantasm.load_scene(SMALL)
        cls.scene.seed = 42
        # The whole run, heard by a progress callback (test_progress_callback_... reads what it
        # heard, rather than running the scene a second time).
        cls.progress_calls = []
        cls.simulation = phantasm.simulate(
            cls.scene, progress=lambda stage, fraction, detail: cls.progress_calls.append((stage, fraction, detail)))

    def test_deformed_t1w_has_the_grid_shape_and_affine(self):
        image = self.simulation.image("T1w", "def")
        self.assertEqual(image.shape, (48, 56, 52))  # 96 x 112 x 104 mm at 2 mm
        self.assertEqual(image.dtype, np.float32)
        expected = np.array([[2, 0, 0, -47], [0, 2, 0, -55], [0, 0, 2, -51], [0, 0, 0, 1]], float)
        np.testing.assert_allclose(self.simulation.affine, expected)
        self.assertGreater(float(image.max()), 0.0)
        self.assertTrue(self.simulation.deformed)

    def test_the_seed_changes_the_anatomy(self):
        self.assertEqual(self.scene.seed, 42)
        self.assertEqual(self.scene.settings()["seed"], 42)
        other = phantasm.simulate(phantasm.load_scene(SMALL), until="voxelization")
        self.assertFalse(np.array_equal(other.labels("ref"), self.simulation.labels("ref")))

    def test_arrays_equal_the_written_nifti_files(self):
        with tempfile.TemporaryDirectory() as out:
            files = self.simulation.write(out)
            self.assertIn("derivatives/phantasm/sub-01/provenance.json", files)
            t1 = nib.load(os.path.join(out, "sub-01", "ses-def", "anat", "sub-01_ses-def_T1w.nii.gz"))
            np.testing.assert_array_equal(t1.get_fdata(dtype=np.float32), self.simulation.image("T1w", "def"))
            np.testing.assert_allclose(t1.affine, self.simulation.affine)
            xfm = os.path.join(out, "derivatives", "phantasm", "sub-01", "xfm")
            for name in ("from-def_to-ref", "from-ref_to-def"):
                field = nib.load(os.path.join(xfm, "sub-01_" + name + "_mode-image_xfm.nii.gz"))
                np.testing.assert_array_equal(field.get_fdata(dtype=np.float32)[:, :, :, 0, :],
                                              self.simulation.field(name))
                jacobian = nib.load(os.path.join(xfm, "sub-01_" + name + "_jacobian.nii.gz"))
                np.testing.assert_array_equal(jacobian.get_fdata(dtype=np.float32), self.simulation.jacobian(name))
            with self.assertRaises(ValueError):
                self.simulation.field("ref_to_def")
            labels = nib.load(os.path.join(out, "derivatives", "phantasm", "sub-01", "ses-def", "anat",
                                           "sub-01_ses-def_dseg.nii.gz"))
            np.testing.assert_array_equal(np.asarray(labels.dataobj), self.simulation.labels("def"))

    def test_values_by_key_path_and_clear_errors(self):
        scene = phantasm.load_scene(SMALL)
        scene.set("acquisition.noise_percent", 2.5)
        scene.set("deformation.scale", 2)
        settings = scene.settings()
        self.assertEqual(settings["acquisition"]["noise_percent"], 2.5)
        self.assertEqual(settings["deformation"]["loads"][0]["displacement_mm"], [-4.0, 0.0, -6.0])
        with self.assertRaises(phantasm.InputError) as raised:
            scene.set("acquisition.noise_percent", 500)
        self.assertIn("setting acquisition.noise_percent = 500", str(raised.exception))
        self.assertIn("expected a number in percent in [0, 100]", str(raised.exception))
        # A key path the scene cannot take is named as the caller wrote it, not as a sweep's vary key.
        with self.assertRaises(phantasm.InputError) as raised:
            scene.set("deformation.loads[9].displacement_mm", 1)
        self.assertIn("\ndeformation.loads[9].displacement_mm: expected list element [9] of 'loads'",
                      str(raised.exception))
        self.assertNotIn("vary.", str(raised.exception))
        with self.assertRaises(ValueError):
            self.simulation.image("T1w", "sideways")
        with self.assertRaises(KeyError):
            self.simulation.image("FLAIR", "ref")

    def test_progress_callback_hears_every_stage_and_can_stop_the_run(self):
        # The callback given to the class's whole run (setUpClass) heard every stage.
        for _, _, detail in self.progress_calls:
            self.assertIsInstance(detail, str)
        calls = [(stage, fraction) for stage, fraction, _ in self.progress_calls]
        stages = [stage for stage, _ in calls]
        for stage in ("anatomy", "deform", "voxelize", "mri"):
            self.assertIn(stage, stages)
        self.assertTrue(all(0.0 <= fraction <= 1.0 for _, fraction in calls))
        self.assertIn(("mri", 1.0), calls)  # each stage's end is reported

        # An exception raised by the callback stops the run and comes out of simulate; so does
        # KeyboardInterrupt (what Ctrl-C raises in the callback on the main thread).
        class Stop(Exception):
            pass

        def stop_in_voxelization(stage, fraction, detail):
            if stage == "voxelize":
                raise Stop("enough")

        with self.assertRaises(Stop):
            phantasm.simulate(self.scene, progress=stop_in_voxelization)

        def interrupt(stage, fraction, detail):
            raise KeyboardInterrupt

        with self.assertRaises(KeyboardInterrupt):
            phantasm.simulate(self.scene, progress=interrupt)
        with self.assertRaises(TypeError):
            phantasm.simulate(self.scene, progress=3)
        # The module is usable again after a stopped run.
        again = phantasm.simulate(self.scene, until="anatomy", progress=lambda *args: None)
        self.assertEqual(again.stages[0]["status"], "done")


if __name__ == "__main__":
    unittest.main(verbosity=2)
