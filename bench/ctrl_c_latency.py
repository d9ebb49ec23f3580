#!/usr/bin/env python3
"""Ctrl-C latency: how long `phantasm run SCENE` takes to exit after SIGINT.

Runs the scene once to time it, then sends SIGINT at N moments spread evenly over that time
(each run into a fresh folder) and prints the exit time after the signal: each moment, the
median and the maximum. A run that had already finished when the signal came is counted apart.

Usage: bench/ctrl_c_latency.py PHANTASM SCENE [--moments N] [--signal INT|TERM] [--keep DIR]
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


def run_once(phantasm, scene, out, delay, sig):
    """Starts a run, signals it after `delay` s; returns (exit code, seconds from signal to exit)."""
    process = subprocess.Popen([phantasm, "run", scene, "-o", out, "--force", "-q"],
                               stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    time.sleep(delay)
    sent = time.monotonic()
    if process.poll() is None:
        process.send_signal(sig)
    code = process.wait()
    return code, time.monotonic() - sent


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("phantasm")
    parser.add_argument("scene")
    parser.add_argument("--moments", type=int, default=20)
    parser.add_argument("--signal", choices=["INT", "TERM"], default="INT")
    parser.add_argument("--keep", help="folder for the outputs (default: a temporary one, removed)")
    args = parser.parse_args()
    sig = getattr(signal, "SIG" + args.signal)
    root = args.keep or tempfile.mkdtemp(prefix="ctrl-c-latency-")
    try:
        start = time.monotonic()
        code = subprocess.call([args.phantasm, "run", args.scene, "-o", os.path.join(root, "full"), "--force",
                                "-q"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        full = time.monotonic() - start
        if code != 0:
            sys.exit(f"the uninterrupted run failed (exit {code})")
        print(f"uninterrupted run: {full:.2f} s")
        latencies = []
        for k in range(args.moments):
            delay = full * (k + 0.5) / args.moments
            code, latency = run_once(args.phantasm, args.scene, os.path.join(root, f"out{k}"), delay, sig)
            state = "finished before the signal" if code == 0 else f"exit {code}"
            print(f"signal at {delay:7.2f} s: exited after {latency:6.3f} s ({state})", flush=True)
            if code != 0:
                latencies.append(latency)
        if latencies:
            print(f"SIG{args.signal} latency over {len(latencies)} interrupted runs: median "
                  f"{statistics.median(latencies):.3f} s, max {max(latencies):.3f} s")
    finally:
        if not args.keep:
            shutil.rmtree(root, ignore_errors=True)


if __name__ == "__main__":
    main()
