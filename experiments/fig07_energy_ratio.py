"""Figure 7 and the c̄ calibration (issue 4): `python experiments/fig07_energy_ratio.py [out_dir]`.

Writes out_dir/fig07_energy_ratio.png, out_dir/calibration_cbar.png and out_dir/calibration.csv
(default out_dir: out/) and prints the calibration table; see `jaxrock.calibration`.
"""

import sys
import time

from jaxrock.calibration import calibration_report


def main(out_dir: str = "out") -> None:
    t0 = time.perf_counter()
    rep = calibration_report(out_dir)
    print(rep.format_table())
    for k, v in rep.seconds.items():
        print(f"{k}: {v:.1f} s (incl. compilation)")
    print(f"total: {time.perf_counter() - t0:.1f} s; files: " + ", ".join(str(p) for p in rep.files.values()))


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "out")
