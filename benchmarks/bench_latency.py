"""Latency of whole commands, as a user runs them: one process per run, wall time from start to exit.

    python benchmarks/bench_latency.py [--runs 3] [--commands spectrum,simulate,batch,help,refused]

Each command runs `--runs` times with a fresh (empty) compilation cache folder and `--runs` times
with a cache its first run filled (`JAXROCK_CACHE_DIR`, `jaxrock.cache`); min and median of each.
Per command, also the kernels a run compiled (XLA compilations, counted by JAX's monitoring
events) and how many of them a second run loaded from the cache. `--no-cache` adds a column with
the cache switched off (`JAXROCK_CACHE_DIR=off`), as every run was before the cache.

The commands (defaults: what a new user runs first):
- `spectrum`: `jaxrock spectrum -q` (48 × 48 rigid cells, boundaries refined), into a temporary folder;
- `simulate`: `jaxrock simulate --height 10 --tan-alpha 0.2 --a-p 3 --omega-p 6`;
- `batch`: `jaxrock batch` on a 12-row scenes file (rigid, quasi-rigid, flexible);
- `help`: `jaxrock --help`; `refused`: `jaxrock simulate --tan-alpha 2` (exit code 2).

Written to benchmarks/results/bench_latency.txt.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
LINES: list[str] = []

# Runs the CLI in this process, counting JAX's compilations and cache hits from the moment JAX is
# imported (a command that imports no JAX, such as --help, is timed without it).
_COUNTED = """
import json, os, sys
from jaxrock.cli import app
from jaxrock.runtime import on_jax_import
counts = {"compiled": 0, "loaded": 0}
def listen(event, **kw):
    if event == "/jax/compilation_cache/compile_requests_use_cache": counts["compiled"] += 1
    if event == "/jax/compilation_cache/cache_hits": counts["loaded"] += 1
def count():
    import jax
    jax.monitoring.register_event_listener(listen)
on_jax_import(count)
try:
    app(sys.argv[1:], standalone_mode=False)
finally:
    with open(os.environ["BENCH_COUNTS"], "w") as fh:
        json.dump(counts, fh)
"""

BATCH_CSV = """height,tan_alpha,model,accel_ratio,omega_ratio
{rows}
"""


def out(line: str = "") -> None:
    print(line, flush=True)
    LINES.append(line)


def commands(work: Path) -> dict[str, list[str]]:
    rows = [f"{h},{t},{m},{a},{w}" for m in ("rigid", "spring", "spring-flexible") for h, t, a, w in
            ((4, 0.2, 2, 3), (8, 0.15, 3, 5), (12, 0.25, 4, 8), (20, 0.1, 6, 12))]
    (work / "scenes.csv").write_text(BATCH_CSV.format(rows="\n".join(rows)))
    return {
        "spectrum": ["spectrum", "-q", "--out", str(work / "spectrum")],
        "simulate": ["simulate", "--height", "10", "--tan-alpha", "0.2", "--a-p", "3", "--omega-p", "6"],
        "batch": ["batch", str(work / "scenes.csv"), "--out", str(work / "results.csv"), "-q"],
        "help": ["--help"],
        "refused": ["simulate", "--tan-alpha", "2"],
    }


def run(args: list[str], cache: str, counted: bool, work: Path) -> tuple[float, dict | None, int]:
    """One whole process; (wall seconds, compile counts or None, exit code)."""
    env = {**os.environ, "JAXROCK_CACHE_DIR": cache, "BENCH_COUNTS": str(work / "counts.json")}
    env.pop("JAX_COMPILATION_CACHE_DIR", None)
    cmd = [sys.executable, "-c", _COUNTED, *args] if counted else [str(Path(sys.executable).parent / "jaxrock"), *args]
    (work / "counts.json").unlink(missing_ok=True)
    t = time.perf_counter()
    p = subprocess.run(cmd, env=env, cwd=work, capture_output=True, text=True, timeout=900)
    seconds = time.perf_counter() - t
    counts = json.loads((work / "counts.json").read_text()) if counted and (work / "counts.json").exists() else None
    return seconds, counts, p.returncode


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--commands", default="spectrum,simulate,batch,help,refused")
    ap.add_argument("--no-cache", action="store_true", help="also time each command with the cache switched off")
    a = ap.parse_args()
    work = Path(tempfile.mkdtemp(prefix="jaxrock-latency-"))
    cmds = commands(work)
    out(f"# whole-command latency, {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
        f"python {platform.python_version()}; {a.runs} runs each; seconds, min / median")
    out(f"{'command':<10} {'empty cache':>14} {'second run':>14}" + (f" {'no cache':>14}" if a.no_cache else "")
        + f" {'kernels compiled':>17} {'loaded by a 2nd':>16}  exit")
    for name in a.commands.split(","):
        args = cmds[name]
        cold, warm, off = [], [], []
        for _ in range(a.runs):
            cache = work / "cache"
            shutil.rmtree(cache, ignore_errors=True)
            seconds, _, rc = run(args, str(cache), False, work)
            cold.append(seconds)
            warm.append(run(args, str(cache), False, work)[0])
            if a.no_cache:
                off.append(run(args, "off", False, work)[0])
        # the kernel counts: once more, in-process counting, empty cache then filled
        cache = work / "cache-counted"
        shutil.rmtree(cache, ignore_errors=True)
        _, first, _ = run(args, str(cache), True, work)
        _, second, _ = run(args, str(cache), True, work)
        fmt = lambda xs: f"{min(xs):5.2f} / {statistics.median(xs):5.2f}"
        n1 = "-" if first is None else str(first["compiled"])
        n2 = "-" if second is None else f"{second['loaded']} of {second['compiled']}"
        out(f"{name:<10} {fmt(cold):>14} {fmt(warm):>14}" + (f" {fmt(off):>14}" if a.no_cache else "")
            + f" {n1:>17} {n2:>16}  {rc}")
    shutil.rmtree(work, ignore_errors=True)
    (HERE / "results").mkdir(exist_ok=True)
    (HERE / "results" / "bench_latency.txt").write_text("\n".join(LINES) + "\n")


if __name__ == "__main__":
    main()
