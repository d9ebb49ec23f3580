#!/usr/bin/python3
"""Runs a registration method on every pair of a Learn2Reg task (`phantasm task`) and writes a
results folder that `phantasm eval TASK --results DIR` scores.

The method is a command template run once per pair, with these placeholders (each a whole
argument of the command; the template is split as a shell would split it, then filled in):

  {fixed}           the fixed image of the pair (TASK/imagesTr/NAME_CCCC_0000.nii.gz)
  {moving}          the moving image
  {output}          where the method writes its displacement field (fixed grid, fixed point x
                    sampled at x + u(x) in the moving image)
  {inverse_output}  optional: where it writes the reverse direction (moving image fixed); then
                    eval also scores the pair's inverse consistency
  {work}            an empty folder for the method's own files (kept with --keep-work)

--convention names how the method stores its field (learn2reg, itk, mrtrix-displacement,
mrtrix-deformation; docs/benchmark-tasks.md); the runner turns it into the Learn2Reg convention,
so that eval reads the folder with its default. Three baselines are built in (--baseline):

  none     no registration: a zero field (scripts/baselines/identity.py, learn2reg)
  elastix  Debian's elastix, affine then B-spline (scripts/baselines/elastix.py, itk)
  syn      dipy's symmetric normalization with cross-correlation (scripts/baselines/dipy_syn.py,
           mrtrix-displacement; both directions)

Writes OUT/disp_<fixed>_<moving>.nii.gz per pair (and disp_<moving>_<fixed>.nii.gz for the
reverse direction) and OUT/register_task.json (the command, convention, and each pair's wall and
processor seconds). OUT is made only when every pair succeeded. Exit 2 for bad input (a task
folder without its dataset JSON, a template without {output}, an unknown placeholder, an
occupied OUT), 1 when the method fails on a pair (its output is shown).

Usage: scripts/register_task.py TASK -o OUT (--baseline NAME [--baseline-args ARGS]
                                             | --command TEMPLATE [--convention C]) [--keep-work]
"""

import argparse
import glob
import json
import os
import resource
import shlex
import shutil
import string
import subprocess
import sys
import tempfile
import time

import nibabel
import numpy

HERE = os.path.dirname(os.path.abspath(__file__))
BASELINES = os.path.join(HERE, "baselines")
PYTHON = "/usr/bin/python3"
CONVENTIONS = ("learn2reg", "itk", "mrtrix-displacement", "mrtrix-deformation")
PLACEHOLDERS = ("fixed", "moving", "output", "inverse_output", "work")


def bad_input(message):
    print(f"register_task: {message}", file=sys.stderr)
    sys.exit(2)


# Each built-in baseline: its command template (the script's path quoted, options appended by
# --baseline-args) and the convention it writes.
BASELINE_TEMPLATES = {
    "none": ("identity.py {fixed} {output} {inverse_output}", "learn2reg"),
    "elastix": ("elastix.py {fixed} {moving} {output} {work}", "itk"),
    "syn": ("dipy_syn.py {fixed} {moving} {output} --inverse {inverse_output}", "mrtrix-displacement"),
}


def baseline_template(name, options):
    """The command template and convention of a built-in baseline, with its extra options."""
    template, convention = BASELINE_TEMPLATES[name]
    return f"{PYTHON} {shlex.quote(BASELINES)}/{template} {options}".strip(), convention


def parse_template(template):
    """The template split into arguments; bad input for a missing or unknown placeholder."""
    try:
        words = shlex.split(template)
    except ValueError as error:
        bad_input(f"--command: expected a command as a shell splits it, found '{template}' ({error})")
    names = set()
    for word in words:
        try:
            names.update(field for _, field, _, _ in string.Formatter().parse(word) if field is not None)
        except ValueError:
            bad_input(f"--command: expected placeholders such as {{fixed}}, found '{word}' (a lone brace: "
                      "write {{ or }} for a literal one)")
    unknown = sorted(names - set(PLACEHOLDERS))
    if unknown:
        bad_input(f"--command: expected placeholders among {', '.join('{' + p + '}' for p in PLACEHOLDERS)}, "
                  f"found {', '.join('{' + u + '}' for u in unknown)}")
    if "output" not in names:
        bad_input(f"--command: expected the placeholder {{output}} (where the method writes its field), found "
                  f"none in '{template}'")
    return words, "inverse_output" in names


def task_pairs(task):
    """(fixed id, moving id, fixed path, moving path) of every pair of the task's dataset JSON."""
    found = glob.glob(os.path.join(task, "*_dataset.json"))
    if len(found) != 1:
        bad_input(f"{task}: expected a task folder of phantasm task with one NAME_dataset.json, "
                  f"found {len(found)}")
    try:
        with open(found[0]) as f:
            dataset = json.load(f)
        pairs = dataset["registration_val"]
        result = []
        for number, pair in enumerate(pairs, start=1):
            paths = [os.path.normpath(os.path.join(task, pair[role])) for role in ("fixed", "moving")]
            ids = [os.path.basename(p)[:-len(".nii.gz")].rsplit("_", 2) for p in paths]
            if any(len(i) != 3 or not p.endswith(".nii.gz") or not os.path.isfile(p) for i, p in zip(ids, paths)):
                raise ValueError(f"registration_val[{number - 1}]: expected existing images NAME_CCCC_MMMM.nii.gz, "
                                 f"found {pair}")
            result.append(("_".join(ids[0][1:]), "_".join(ids[1][1:]), paths[0], paths[1]))
    except (OSError, ValueError, KeyError, TypeError) as error:
        bad_input(f"{found[0]}: expected the pairs phantasm task writes (registration_val), found a problem: "
                  f"{error}")
    if not result:
        bad_input(f"{found[0]}: registration_val: expected at least one pair, found none")
    return result


def voxel_displacement(path, convention, fixed_affine, shape):
    """The field of a file in `convention` as Learn2Reg stores it: (X, Y, Z, 3) voxels along i, j, k."""
    image = nibabel.load(path)
    data = numpy.asarray(image.dataobj, dtype=numpy.float64)
    if convention == "itk" and data.ndim == 5 and data.shape[3] == 1:
        data = data[:, :, :, 0, :]
    if data.shape != tuple(shape) + (3,):
        raise ValueError(f"expected a {convention} field of {shape[0]} x {shape[1]} x {shape[2]} voxels and 3 "
                         f"components, found the array shape {data.shape}")
    if not numpy.all(numpy.isfinite(data)):
        raise ValueError("expected finite displacements, found NaN or infinity")
    if convention == "learn2reg":
        return data
    if not numpy.allclose(image.affine, fixed_affine, atol=1e-3):
        raise ValueError(f"expected a {convention} field on the fixed image's voxel-to-world matrix, found another")
    if convention == "itk":
        data = data * numpy.array([-1.0, -1.0, 1.0])  # LPS to RAS
    elif convention == "mrtrix-deformation":
        ijk = numpy.stack(numpy.meshgrid(*(numpy.arange(n) for n in shape), indexing="ij"), axis=-1)
        data = data - (ijk @ fixed_affine[:3, :3].T + fixed_affine[:3, 3])
    return data @ numpy.linalg.inv(fixed_affine[:3, :3]).T


def children_cpu_seconds():
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("task", help="a task folder made by phantasm task")
    parser.add_argument("-o", "--output", required=True, help="the results folder to make (new or empty)")
    method = parser.add_mutually_exclusive_group(required=True)
    method.add_argument("--baseline", choices=("none", "elastix", "syn"))
    method.add_argument("--command", help="the method's command template (placeholders above)")
    parser.add_argument("--convention", choices=CONVENTIONS, default="learn2reg",
                        help="how the method writes its field (with --command; default learn2reg)")
    parser.add_argument("--keep-work", action="store_true", help="keep each pair's {work} folder in OUT/work")
    parser.add_argument("--baseline-args", default="",
                        help="options appended to the baseline's command, e.g. '--iterations 100 --grid-spacing 20' "
                             "(elastix) or '--levels 20,10' (syn); see each script's --help")
    args = parser.parse_args()

    if args.baseline:
        template, convention = baseline_template(args.baseline, args.baseline_args)
    else:
        template, convention = args.command, args.convention
    words, both_directions = parse_template(template)
    pairs = task_pairs(args.task)
    if os.path.exists(args.output) and (not os.path.isdir(args.output) or os.listdir(args.output)):
        bad_input(f"-o: expected a new or empty folder, found {args.output} holding files")

    parent = os.path.dirname(os.path.abspath(args.output))
    os.makedirs(parent, exist_ok=True)
    staging = tempfile.mkdtemp(prefix=".register_task-", dir=parent)
    record = {"task": os.path.abspath(args.task), "command": template, "convention": convention,
              "written_as": "learn2reg", "baseline": args.baseline, "pairs": []}
    try:
        for fixed_id, moving_id, fixed, moving in pairs:
            name = f"disp_{fixed_id}_{moving_id}.nii.gz"
            reverse = f"disp_{moving_id}_{fixed_id}.nii.gz"
            work = os.path.join(staging, "work", f"{fixed_id}_{moving_id}")
            os.makedirs(work)
            raw = {"output": os.path.join(work, "method-" + name), "inverse_output": os.path.join(work, "method-" + reverse)}
            values = {"fixed": fixed, "moving": moving, "work": work, **raw}
            command = [word.format(**values) for word in words]
            start, start_cpu = time.monotonic(), children_cpu_seconds()
            run = subprocess.run(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
            seconds, cpu = time.monotonic() - start, children_cpu_seconds() - start_cpu
            if run.returncode != 0:
                sys.exit(f"register_task: the method failed on the pair {fixed_id} -> {moving_id} (exit "
                         f"{run.returncode}): {' '.join(shlex.quote(c) for c in command)}\n{run.stdout[-3000:]}")
            fixed_image = nibabel.load(fixed)
            outputs = [("output", name)] + ([("inverse_output", reverse)] if both_directions else [])
            for key, target in outputs:
                if not os.path.isfile(raw[key]):
                    sys.exit(f"register_task: the method wrote no {{{key}}} for the pair {fixed_id} -> {moving_id}: "
                             f"expected {raw[key]}")
                try:
                    u = voxel_displacement(raw[key], convention, fixed_image.affine, fixed_image.shape[:3])
                except ValueError as error:
                    sys.exit(f"register_task: {raw[key]} (the method's {{{key}}} for {fixed_id} -> {moving_id}): "
                             f"{error}")
                nibabel.save(nibabel.Nifti1Image(u.astype(numpy.float32), fixed_image.affine),
                             os.path.join(staging, target))
            record["pairs"].append({"fixed": fixed_id, "moving": moving_id, "result": name,
                                    "reverse": reverse if both_directions else None,
                                    "wall_seconds": round(seconds, 2), "cpu_seconds": round(cpu, 2)})
            print(f"register_task: {fixed_id} -> {moving_id}: {seconds:.1f} s", file=sys.stderr)
        if not args.keep_work:
            shutil.rmtree(os.path.join(staging, "work"))
        with open(os.path.join(staging, "register_task.json"), "w") as f:
            json.dump(record, f, indent=2)
            f.write("\n")
        if os.path.isdir(args.output):
            os.rmdir(args.output)
        os.rename(staging, args.output)
    finally:
        shutil.rmtree(staging, ignore_errors=True)


if __name__ == "__main__":
    main()
