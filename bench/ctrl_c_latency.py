#!/usr/bin/env python3
"""Ctrl-C latency: how long `phantasm run SCENE` (or `phantasm hdf5 DATASET`) takes to exit after SIGINT.

Runs the scene once to time it, then sends SIGINT at N moments spread evenly over that time
(each run into a fresh folder) and prints the exit time after the signal: each moment, the
median and the maximum. A run that had already finished when the signal came is counted apart.
With --span S the moments are spread over the first S seconds instead, and the scene is not
run to its end (for scenes whose whole run is too long to repeat N times, e.g. one organ that
CGAL meshes for minutes). With --hdf5 the second argument is a dataset, and what is timed and
interrupted is its export (`phantasm hdf5 DATASET -o OUT/dataset.h5`).

Usage: bench/ctrl_c_latency.py PHANTASM SCENE [--moments N] [--span S] [--hdf5] [--signal INT|TERM]
       [--keep DIR]
"""
import argparse
import os
import shutil
import signal
import statistics
import subprocess
import sys
import tempfile
import time


def command(phantasm, scene, out, hdf5):
    """The command timed: a run of the scene into `out`, or an export of the dataset into it."""
    if hdf5:
        os.makedirs(out, exist_ok=True)
        return [phantasm, "hdf5", scene, "-o", os.path.join(out, "dataset.h5"), "-q"]
    return [phantasm, "run", scene, "-o", out, "--force", "-q"]


def default_signals():
    """In the child: SIGINT and SIGTERM as a terminal gives them (a shell starting this script in
    the background ignores SIGINT, and children would inherit that until phantasm's handlers)."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)


def run_once(argv, delay, sig):
    """Starts a command, signals it after `delay` s; returns (exit code or None when it had ended
    before the signal, seconds from signal to exit)."""
    process = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                               preexec_fn=default_signals)
    time.sleep(delay)
    sent = time.monotonic()
    if process.poll() is not None:
        return None, 0.0
    process.send_signal(sig)
    code = process.wait()
    return code, time.monotonic() - sent


def leftovers(out):
    """What an interrupted command must not leave: temporary files, a provenance.json (a run's
    completion marker), dataset.h5 (an export's final name)."""
    found = []
    for folder, _, names in os.walk(out):
        found += [os.path.join(folder, n) for n in names
                  if ".phantasm-tmp-" in n or n in ("provenance.json", "dataset.h5")]
    return found


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("phantasm")
    parser.add_argument("scene")
    parser.add_argument("--moments", type=int, default=20)
    parser.add_argument("--span", type=float, help="spread the moments over the first SPAN seconds "
                        "(default: over an uninterrupted run, timed first)")
    parser.add_argument("--hdf5", action="store_true", help="time and interrupt `phantasm hdf5` of the "
                        "dataset SCENE instead of a run")
    parser.add_argument("--signal", choices=["INT", "TERM"], default="INT")
    parser.add_argument("--keep", help="folder for the outputs (default: a temporary one, removed)")
    args = parser.parse_args()
    sig = getattr(signal, "SIG" + args.signal)
    root = args.keep or tempfile.mkdtemp(prefix="ctrl-c-latency-")
    try:
        if args.span:
            full = args.span
            print(f"moments spread over the first {full:.2f} s")
        else:
            start = time.monotonic()
            code = subprocess.call(command(args.phantasm, args.scene, os.path.join(root, "full"), args.hdf5),
                                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            full = time.monotonic() - start
            if code != 0:
                sys.exit(f"the uninterrupted command failed (exit {code})")
            print(f"uninterrupted: {full:.2f} s")
        latencies = []
        for k in range(args.moments):
            delay = full * (k + 0.5) / args.moments
            code, latency = run_once(command(args.phantasm, args.scene, os.path.join(root, f"out{k}"), args.hdf5),
                                     delay, sig)
            if code is None:
                print(f"signal at {delay:7.2f} s: finished before the signal", flush=True)
                continue
            state = f"exit {code}" + (" (the signal did not stop it)" if code == 0 else "")
            left = leftovers(os.path.join(root, f"out{k}"))
            state += f", LEFT {left}" if left and code != 0 else ", no temporary, no provenance.json"
            print(f"signal at {delay:7.2f} s: exited after {latency:6.3f} s ({state})", flush=True)
            latencies.append(latency)
        if latencies:
            print(f"SIG{args.signal} latency over {len(latencies)} interrupted runs: median "
                  f"{statistics.median(latencies):.3f} s, max {max(latencies):.3f} s")
    finally:
        if not args.keep:
            shutil.rmtree(root, ignore_errors=True)


if __name__ == "__main__":
    main()
