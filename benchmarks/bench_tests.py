"""The default test run as a newcomer meets it: `python -m pytest -q` (the README's command), cold
(an empty compilation cache for the tests) then warm (the cache the cold run filled), its wall
time, the ten slowest tests, and the peak memory of the whole process tree (pytest, its xdist
workers and the processes the tests start: summed PSS from /proc, sampled every 0.5 s; Linux).

    python benchmarks/bench_tests.py [--runs cold,warm] [-- PYTEST ARGS]

Written to benchmarks/results/bench_tests.txt.
"""

from __future__ import annotations

import argparse
import os
import platform
import re
import shutil
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent


def _tree(pid: int) -> list[int]:
    """`pid` and its descendants (processes, not threads)."""
    children: dict[int, list[int]] = {}
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                ppid = int((entry / "stat").read_text().rsplit(")", 1)[1].split()[1])
            except (OSError, IndexError, ValueError):
                continue
            children.setdefault(ppid, []).append(int(entry.name))
    out, todo = [], [pid]
    while todo:
        p = todo.pop()
        out.append(p)
        todo += children.get(p, [])
    return out


def _pss_kb(pid: int) -> int:
    try:
        for line in Path(f"/proc/{pid}/smaps_rollup").read_text().splitlines():
            if line.startswith("Pss:"):
                return int(line.split()[1])
    except (OSError, ValueError):
        pass
    return 0


def run(args: list[str], cache: Path) -> dict:
    env = {**os.environ, "JAXROCK_CACHE_DIR": str(cache)}
    t0 = time.perf_counter()
    proc = subprocess.Popen([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "--durations=10", *args],
                            cwd=ROOT, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    peak = [0]

    def sample():
        while proc.poll() is None:
            peak[0] = max(peak[0], sum(_pss_kb(p) for p in _tree(proc.pid)))
            time.sleep(0.5)

    sampler = threading.Thread(target=sample, daemon=True)
    sampler.start()
    out = proc.communicate()[0]
    wall = time.perf_counter() - t0
    sampler.join()
    slowest = [line for line in out.splitlines() if re.match(r"^\d+\.\d+s (call|setup|teardown) ", line)]
    summary = next((line for line in reversed(out.splitlines()) if re.search(r"\d+ (passed|failed)", line)), "")
    return {"rc": proc.returncode, "wall": wall, "peak_gb": peak[0] / 1e6, "slowest": slowest, "summary": summary.strip("= ")}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--runs", default="cold,warm")
    ap.add_argument("pytest_args", nargs="*")
    opts = ap.parse_args()
    lines = [f"# bench_tests: python -m pytest -q {' '.join(opts.pytest_args)}".rstrip(),
             f"# machine: {platform.machine()} {os.cpu_count()} CPUs; peak memory: summed PSS of the process tree"]
    cache = Path(tempfile.mkdtemp(prefix="jaxrock-bench-tests-"))
    try:
        for mode in opts.runs.split(","):
            r = run(opts.pytest_args, cache)  # the first run fills the (fresh) cache the next one reads
            lines += ["", f"## {mode}: {r['wall']:.0f} s wall, peak {r['peak_gb']:.2f} GB, exit {r['rc']}: {r['summary']}", *r["slowest"]]
            print("\n".join(lines[-len(r["slowest"]) - 1:]), flush=True)
    finally:
        shutil.rmtree(cache, ignore_errors=True)
    path = HERE / "results" / "bench_tests.txt"
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
