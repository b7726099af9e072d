"""Spring-model benchmark: jaxrock vmapped time per scene (compile separate).

Run: .venv/bin/python benchmarks/bench_spring.py
The OpenSeesPy side-by-side comparison is NOT written yet (openseespy installs and imports here
after `apt-get install libblas3 liblapack3`); only jaxrock's numbers are printed.
"""
import math
import time

import jax
import jax.numpy as jnp

import jaxrock
from jaxrock.model import simulate
from jaxrock.spring import Column, SpringModel

G = 9.81


def timed_grid(model, n_a, n_w, a_rng, w_rng, tan_alpha, p):
    A, W = jnp.meshgrid(jnp.linspace(*a_rng, n_a) * G * tan_alpha, jnp.linspace(*w_rng, n_w) * p)
    A, W = A.ravel(), W.ravel()
    f = jax.jit(jax.vmap(lambda a, w: simulate(model, jaxrock.RickerPulse(a, w))))
    t = time.perf_counter()
    out = f(A, W)
    jax.block_until_ready(out)
    t_first = time.perf_counter() - t
    t = time.perf_counter()
    out = f(A, W)
    jax.block_until_ready(out)
    t_run = time.perf_counter() - t
    ok = int(jnp.sum(out.status == jaxrock.results.Status.ok))
    return t_first - t_run, t_run / A.size, ok, A.size


def main():
    blk = jaxrock.Block.from_slenderness(10.0, 0.2)
    c, per, ok, n = timed_grid(SpringModel(blk), 32, 32, (0.5, 8.0), (1.0, 12.0), 0.2, float(blk.p))
    print(f"quasi-rigid 32x32: compile {c:.1f} s, {per*1e3:.2f} ms/scene, ok {ok}/{n}")
    blk = jaxrock.Block.from_size(50.0, 5.0)
    c, per, ok, n = timed_grid(SpringModel(blk, Column.concrete()), 8, 8, (0.5, 8.0), (1.0, 12.0), 0.1, float(blk.p))
    print(f"flexible concrete 50 m, 10 el, 8x8: compile {c:.1f} s, {per*1e3:.1f} ms/scene, ok {ok}/{n}")


if __name__ == "__main__":
    main()
