#!/usr/bin/python3
"""The plots to look at before choosing settings, as PNG: solver relative error against
iterations and against time (energy and position definitions, docs/method.md section 6; the paper's
Fig. 5 and 6), tissue volume error against voxel size and voxelization time, and patch fit error
against base mesh size. Runs the benchmark programs of a Release build, keeps their CSV next to
the plots, and prints what it wrote.

Usage: scripts/accuracy_plots.py -o OUT [--build build/release] [--threads 2] [--skip-voxel] [--quick]
(--quick: a tenth of the solvers' iterations and the fit without its largest base mesh, for a
test of the command; the plots of docs/performance.md are made without it)
"""

import argparse
import csv
import os
import subprocess
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))


def run_to_csv(command, target):
    print("running " + " ".join(command), flush=True)
    result = subprocess.run(command, capture_output=True, text=True)
    if result.returncode != 0:
        sys.exit(f"accuracy_plots: {command[0]} failed (exit {result.returncode}):\n{result.stderr}")
    if target is not None:
        with open(target, "w") as f:
            f.write(result.stdout)
    return result.stdout


def read_csv(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def save(figure, path):
    figure.tight_layout()
    figure.savefig(path + ".tmp.png", dpi=100)
    os.replace(path + ".tmp.png", path)
    plt.close(figure)
    print("wrote " + path)


def solver_plots(rows, out):
    solvers = []
    for r in rows:
        if r["solver"] not in solvers:
            solvers.append(r["solver"])
    for x_key, x_label, name in (("iteration", "iteration", "solver_error_vs_iterations.png"),
                                 ("seconds", "solver time (s)", "solver_error_vs_time.png")):
        figure, axes = plt.subplots(1, 2, figsize=(11, 4.2), sharey=True)
        for axis, error, title in ((axes[0], "energy_error", "energy: (E - E*) / (E0 - E*)"),
                                   (axes[1], "position_error", "position: |p - p*| / |p0 - p*|")):
            for solver in solvers:
                points = [(float(r[x_key]), float(r[error])) for r in rows
                          if r["solver"] == solver and float(r[error]) > 0]
                if points:
                    axis.semilogy(*zip(*points), marker="." if len(points) < 40 else None, label=solver)
            for level in (1e-1, 1e-2, 1e-3):
                axis.axhline(level, color="grey", lw=0.5, ls=":")
            axis.set_xlabel(x_label)
            axis.set_title(title)
            axis.grid(alpha=0.3)
        axes[0].set_ylabel("relative error (twisting bar, one frame)")
        axes[1].legend(fontsize=8)
        save(figure, os.path.join(out, name))


def voxel_plot(rows, out):
    voxel = [float(r["voxel_mm"]) for r in rows]
    seconds = [float(r["seconds"]) for r in rows]
    error = [100 * float(r["largest_volume_error"]) for r in rows]
    figure, (by_size, by_time) = plt.subplots(1, 2, figsize=(10, 4))
    by_size.loglog(voxel, error, "o-")
    by_size.set_xlabel("voxel size (mm)")
    by_size.set_ylabel("largest tissue volume error (%)")
    by_size.set_title("Head, reference state")
    by_time.loglog(seconds, error, "o-")
    for v, s, e in zip(voxel, seconds, error):
        by_time.annotate(f"{v:g} mm", (s, e), textcoords="offset points", xytext=(5, 5), fontsize=8)
    by_time.set_xlabel("voxelization time (s)")
    by_time.set_ylabel("largest tissue volume error (%)")
    by_time.set_title("Accuracy for time")
    for axis in (by_size, by_time):
        axis.grid(alpha=0.3, which="both")
    save(figure, os.path.join(out, "volume_error_vs_voxel_size.png"))


def fit_plot(rows, out):
    rows = [r for r in rows if r["shape"] == "ellipsoid" and r["base_mesh"] == "icosphere"]
    triangles = [int(r["base_triangles"]) for r in rows]
    figure, axis = plt.subplots(figsize=(5.5, 4))
    axis.loglog(triangles, [float(r["plain_hausdorff_mm"]) for r in rows], "s--", label="plain base mesh")
    axis.loglog(triangles, [float(r["fitted_hausdorff_mm"]) for r in rows], "o-", label="fitted patches")
    axis.set_xlabel("base mesh triangles")
    axis.set_ylabel("Hausdorff distance to the shape (mm)")
    axis.set_title("Ellipsoid 60 x 45 x 30 mm")
    axis.legend()
    axis.grid(alpha=0.3, which="both")
    save(figure, os.path.join(out, "fit_error_vs_base_mesh.png"))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("-o", "--output", required=True)
    parser.add_argument("--build", default=os.path.join(HERE, "..", "build", "release"))
    parser.add_argument("--threads", default="2")
    parser.add_argument("--skip-voxel", action="store_true", help="leave out the voxel-size sweep (slowest)")
    parser.add_argument("--quick", action="store_true",
                        help="a tenth of the solvers' iterations, the fit without its largest base mesh")
    args = parser.parse_args()
    os.makedirs(args.output, exist_ok=True)
    bench = os.path.join(args.build, "bench")
    traces = os.path.join(args.output, "solver_traces.csv")
    quick = ["quick"] if args.quick else []
    run_to_csv([os.path.join(bench, "solver_convergence"), args.threads, traces] + quick, None)
    solver_plots(read_csv(traces), args.output)
    fit = os.path.join(args.output, "fit_error.csv")
    run_to_csv([os.path.join(bench, "fit_error_curve"), "ellipsoid"] + quick, fit)
    fit_plot(read_csv(fit), args.output)
    if not args.skip_voxel:
        voxel = os.path.join(args.output, "volume_error.csv")
        run_to_csv([os.path.join(bench, "voxel_size_accuracy")], voxel)
        voxel_plot(read_csv(voxel), args.output)


if __name__ == "__main__":
    main()
