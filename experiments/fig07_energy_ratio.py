"""Figure 7 and the c̄ calibration (issue 4): `python experiments/fig07_energy_ratio.py [--out out]`.

Writes <out>/fig07_energy_ratio.png, <out>/calibration_cbar.png and <out>/calibration.csv and
prints the calibration table; see `jaxrock.analyses.calibration`.
"""

import argparse
import time

from jaxrock.reports import calibration_report

ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
ap.add_argument("--out", default="out", help="output folder (default: out)")


def main(out_dir: str = "out") -> None:
    t0 = time.perf_counter()
    rep = calibration_report(out_dir)
    print(rep.format_table())
    for k, v in rep.seconds.items():
        print(f"{k}: {v:.1f} s (incl. compilation)")
    print(f"total: {time.perf_counter() - t0:.1f} s; files: " + ", ".join(str(p) for p in rep.files.values()))


if __name__ == "__main__":
    main(ap.parse_args().out)
