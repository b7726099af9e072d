"""Honest numerics as products: the error of every default against its cost and its stability.

- `stability`: `jaxrock stability`, the three models' defaults on stiff and extreme scenes, each
  against a refined reference of the same model, as a table and a heat map;
- `work_precision`: `jaxrock work-precision`, error against run time for the RM's and the SM's
  integrators and settings, with the peers on the same axes;
- `kept`: what both share: each finished part's rows kept on disk (a rerun resumes), files
  written whole;
- `scipy_rigid`, `opensees_sm`: the peers, the RM as a SciPy `solve_ivp` event loop and the SM in
  OpenSeesPy (the `opensees` extra), used by the work–precision diagrams, the benchmarks and the
  tests as independent references.
"""
