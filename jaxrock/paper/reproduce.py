"""`reproduce`: every figure of the paper (3–17) into one folder, and a report that sets each value
the paper reports beside jaxrock's with a verdict (`jaxrock.paper.findings`).

Each step is one function of `jaxrock.paper` with its full and its quick options (`STEPS`). A
finished step's findings are kept in `<out>/findings/<step>.json` with the mode and the jaxrock
version: an interrupted run resumes with the next step. The report is `<out>/report.md` (the
verdict table, then each figure inline) and `<out>/findings.csv`.
"""

from __future__ import annotations

import argparse
import dataclasses
import importlib
import inspect
import json
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .findings import NOT_REPRODUCED, REPRODUCED, VERDICTS, Finding
from .reported import REPORTED


@dataclass(frozen=True)
class Step:
    name: str
    title: str
    function: str  # "module:function" in jaxrock.paper
    full: dict = field(default_factory=dict)
    quick: dict = field(default_factory=dict)
    files: tuple[str, ...] = ()  # the prefixes of its figures and tables in the output folder (default: its name)
    extra: bool = False  # beyond the paper: a section of the report, no row of the paper's table (`REPORTED`)


STEPS = (
    Step("fig02", "Notation: p of the Temple of Apollo's column", "rigid_blocks:temple_of_apollo"),
    Step("fig03", "Figure 3: top displacements of the RM and the SM", "kinematics:fig03", {}, {"n_points": 41}),
    Step("fig04", "Figure 4: pushover, RM and SM", "kinematics:fig04", {}, {"n_points": 21}),
    Step("fig05", "Figures 5, 8: time histories of rigid blocks", "rigid_blocks:fig05_08", files=("fig05", "fig08")),
    Step("fig06", "Figures 6, 9: spectra of rigid blocks", "rigid_blocks:fig06_09", {"n": 32}, {"n": 8}, files=("fig06", "fig09")),
    Step("fig07", "Figure 7 and eq. 17: energy ratio and the calibrated c̄", "rigid_blocks:fig07", {}, {"quick": True},
         files=("fig07", "calibration")),
    Step("fig10", "Figure 10: El Centro, least overturning factor", "rigid_blocks:fig10",
         {"heights": (1, 2, 4, 8, 16), "scales": np.linspace(0.5, 10, 20), "refine": 8},
         {"heights": (2, 8), "scales": np.linspace(0.5, 10, 10), "refine": 4}),
    Step("eq21", "Eq. 21: the first period of a concrete column", "flexible:eq21"),
    Step("fig11", "Figures 11, 12: quasi-rigid and concrete columns", "flexible:fig11_12",
         {"n": 24, "heights": (10, 30, 50, 100), "n_elements": 10, "refine": 4},
         {"n": 12, "heights": (10, 50), "n_elements": 4, "refine": 4}, files=("fig11", "fig12")),
    Step("fig13", "Figure 13: a flexible against a rigid column under two pulses", "flexible:fig13",
         {"n_elements": 10}, {"n_elements": 10, "quick": True}),
    Step("fig15", "Figures 15, 16: columns on an extended base", "extended_base:fig15_16",
         {"n": 24, "heights": (10, 50, 100), "n_elements": 10}, {"n": 8, "heights": (10, 100), "n_elements": 4},
         files=("fig15", "fig16")),
    Step("fig17", "Figure 17: the Christchurch chimney", "chimney:fig17", {"n_elements": 10}, {"n_elements": 10, "quick": True}),
    Step("frame", "Beyond the paper: rocking frame spectra (Makris & Vassiliou 2013)", "beyond:frame_spectra", {"n": 32},
         {"n": 12, "refine": 4}, extra=True),
)
STEP_NAMES = tuple(s.name for s in STEPS)
PAPER_STEPS = tuple(s.name for s in STEPS if not s.extra)  # those the paper's table (`REPORTED`) covers


def _version() -> str:
    from ..cache import package_version

    return package_version()


def run_step(step: Step, out: Path, quick: bool, **overrides) -> list[Finding]:
    module, function = step.function.split(":")
    fn = getattr(importlib.import_module(f"jaxrock.paper.{module}"), function)
    kwargs = {**(step.quick if quick else step.full), **overrides}
    return fn(out, **kwargs) if "out" in inspect.signature(fn).parameters else fn(**kwargs)  # fig02, eq21 write no file


@dataclass
class Report:
    findings: dict[str, list[Finding]]  # step name → its findings
    seconds: dict[str, float]
    quick: bool
    files: dict[str, Path]

    def counts(self) -> dict[str, int]:
        rows = [f for fs in self.findings.values() for f in fs]
        return {v: sum(f.verdict == v for f in rows) for v in VERDICTS}


def _kept(path: Path, mode: str) -> tuple[list[Finding], float] | None:
    """A step's kept findings, or None where they are of another mode or version, or the file is
    damaged (truncated, keys missing): the step then runs again."""
    from ..numerics.kept import read_kept

    def check(data):
        if data["mode"] != mode or data["version"] != _version():
            return None
        return [Finding(**row) for row in data["findings"]], float(data["seconds"])

    return read_kept(path, check)


def reproduce(out="out/reproduce", *, quick: bool = False, only=None, progress: bool = True) -> Report:
    """Run the steps (`only`: names of `STEPS`, default all) into `out` and write the report, which
    also shows the steps kept in `out` by earlier runs of the same mode."""
    from tqdm.auto import tqdm

    from ..interrupt import stop_point
    from ..io.files import write_atomically

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "findings").mkdir(exist_ok=True)
    selected = [s.name for s in STEPS if only is None or s.name in only]
    mode = "quick" if quick else "full"
    findings, seconds = {}, {}
    with tqdm(total=len(selected), desc="reproduce", unit="step", disable=not progress) as bar:
        for step in STEPS:  # a step not selected joins the report where an earlier run of the same mode kept it
            kept_path = out / "findings" / f"{step.name}.json"
            kept = _kept(kept_path, mode)
            if kept is None and step.name in selected:
                bar.set_postfix_str(step.name)
                t0 = time.perf_counter()
                fs = run_step(step, out, quick)
                secs = time.perf_counter() - t0
                # the steps share few programs: free each step's compiled ones (the full run, all
                # of them kept in one process, ended in 'LLVM compilation error: Cannot allocate
                # memory' and a segmentation fault at its last step, which passes alone)
                import jax

                jax.clear_caches()
                text = json.dumps({"mode": mode, "version": _version(), "seconds": secs, "findings": [f.row() for f in fs]},
                                  ensure_ascii=False, indent=1)
                write_atomically(kept_path, lambda tmp, text=text: Path(tmp).write_text(text, encoding="utf-8"))
                kept = fs, secs
                stop_point()  # a signal stops the run here, with this step kept
            if kept is not None:
                findings[step.name], seconds[step.name] = kept
            bar.update(step.name in selected)
    report = Report(findings, seconds, quick, {})
    report.files = write_report(report, out)
    return report


def _md(text: str) -> str:
    return str(text).replace("|", "\\|").replace("\n", " ")


def write_report(report: Report, out: Path) -> dict[str, Path]:
    """`<out>/report.md` and `<out>/findings.csv`."""
    from ..io.tables import write_table

    out = Path(out)
    rows = [f.row() for fs in report.findings.values() for f in fs]
    csv = write_table(out / "findings.csv", rows, columns=[f.name for f in dataclasses.fields(Finding)])
    counts = report.counts()
    total = sum(report.seconds.values())
    lines = [
        f"# jaxrock against the paper ({'quick' if report.quick else 'full'} run)", "",
        "Vassiliou, Mackie, Stojadinović (2014), *Dynamic response analysis of solitary flexible rocking bodies*. "
        f"jaxrock {_version()}; {total:.0f} s of computation. Verdicts: "
        + ", ".join(f"{n} {v}" for v, n in counts.items()) + ".", "",
        "A verdict is *reproduced* when jaxrock's value meets the criterion beside it, *differs, explained* when it does not "
        "and a computation run with the figure says why (the reason), *not reproduced* when nothing computed explains it "
        "(the reason says what was tried).", "",
        "| figure | quantity | paper | jaxrock | difference | criterion | verdict | reason |",
        "| --- | --- | --- | --- | --- | --- | --- | --- |",
    ]
    lines += [f"| {_md(r['figure'])} | {_md(r['quantity'])} | {_md(r['paper'])} | {_md(r['jaxrock'])} | {_md(r['difference'])} | "
              f"{_md(r['criterion'])} | **{r['verdict']}** | {_md(r['reason'])} |" for r in rows]
    by_name = {s.name: s for s in STEPS}
    for name, fs in report.findings.items():
        step = by_name[name]
        lines += ["", f"## {step.title}", ""]
        lines += [f"The paper reports (figure {r.figures}; {r.scene}): {r.reported}." for r in REPORTED if r.step == name]
        lines += ["", f"{report.seconds[name]:.1f} s" + ("; " + ", ".join(f"{f.verdict}: {f.quantity}" for f in fs) if fs else "") + "."]
        for prefix in step.files or (name,):
            for extra in sorted(out.glob(f"{prefix}*.md")):
                lines += ["", extra.read_text(encoding="utf-8").replace("# ", "### ", 1).strip()]
            for png in sorted(out.glob(f"{prefix}*.png")):
                lines += ["", f"![{png.stem}]({png.name})"]
    from ..numerics.kept import write_text

    md = out / "report.md"
    write_text(md, "\n".join(lines) + "\n")
    return {"report": md, "findings": csv}


def script(*names: str, doc: str) -> None:
    """The command line of an `experiments/` script: the steps `names`, `--out`, `--quick`, and each
    full option of theirs (an integer, or a comma-separated list of numbers) as `--<option>`."""
    ap = argparse.ArgumentParser(description=doc, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", default="out/figures", help="output folder (default: out/figures)")
    ap.add_argument("--quick", action="store_true", help="the coarse grids of `jaxrock reproduce --quick`")
    steps = [s for s in STEPS if s.name in names]
    options = {}
    for s in steps:
        for k, v in s.full.items():
            if isinstance(v, (int, tuple)) and not isinstance(v, bool) and k not in options:
                options[k] = v
                ap.add_argument(f"--{k.replace('_', '-')}", default=None,
                                help=f"default {','.join(f'{x:g}' for x in v) if isinstance(v, tuple) else v}")
    args = ap.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    for s in steps:
        given = {}
        for k in s.full:
            text = getattr(args, k, None)
            if text is not None:
                given[k] = tuple(float(x) for x in text.split(",")) if isinstance(options[k], tuple) else int(text)
        for f in run_step(s, out, args.quick, **given):
            mark = "✓" if f.verdict == REPRODUCED else ("✗" if f.verdict == NOT_REPRODUCED else "~")
            print(f"{mark} figure {f.figure}: {f.quantity}\n    paper: {f.paper}\n    jaxrock: {f.jaxrock}"
                  + (f"\n    {f.verdict}: {f.reason}" if f.reason else ""))
    print(f"files in {out}")
