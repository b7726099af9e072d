"""What a process keeps for the next (`jaxrock.cache`): the persistent compilation cache's folder
and switch, and the invariant that keeps it useful — no kernel jaxrock compiles holds a host
callback (JAX writes no such kernel to its cache), so a second identical run in a fresh process
loads every kernel instead of compiling it."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap

import equinox as eqx
import jax
import jax.extend as jex
import jax.numpy as jnp
import pytest

import jaxrock as jr
from jaxrock import cache
from jaxrock.analyses import engine
from jaxrock.io.scenes_file import scene_model


def _callbacks(jaxpr) -> list[str]:
    """Host-callback primitives anywhere in a jaxpr, its loops and branches included."""
    found = []
    for eqn in jaxpr.eqns:
        if "callback" in eqn.primitive.name:
            found.append(eqn.primitive.name)
        for param in eqn.params.values():
            for sub in param if isinstance(param, (list, tuple)) else (param,):
                if isinstance(sub, jex.core.ClosedJaxpr):
                    found += _callbacks(sub.jaxpr)
                elif isinstance(sub, jex.core.Jaxpr):
                    found += _callbacks(sub)
    return found


SCENES = {  # model kind (scenes-file name), integrator (None: the kind's default), whether its history is checked
    "rigid": ("rigid", None, True),
    # a history by diffrax keeps diffrax's check of the save times (within [t0, t1], increasing):
    # jaxrock clips them to the run and `Save` refuses others, so it never fires, but it is compiled
    "spring": ("spring", None, False),
    "spring, generalized-α": ("spring", jr.GeneralizedAlpha(1e-6, 1e-6), True),
    "flexible": ("spring-flexible", None, True),
}


@pytest.mark.parametrize("scene", SCENES)
def test_no_host_callback_in_the_kernels(scene):
    """`simulate` (summary and history) and the batch engine's kernels of every model kind hold no
    host callback (but a diffrax history's, above): diffrax's sign check on a traced first step (`FirstStepController`) and any
    runtime error check of jaxrock's own would put one there."""
    kind, integ, history = SCENES[scene]
    model = scene_model(kind, jr.Block.from_slenderness(10.0, 0.2))
    exc = jr.RickerPulse(a_p=3.0, omega_p=6.0)
    save = jr.Save(jnp.linspace(-1.0, 3.0, 5), ("theta",))
    kernels = {
        "simulate": lambda m, e: jr.simulate(m, e, integrator=integ),
    }
    if history:
        kernels["history"] = lambda m, e: jr.simulate(m, e, save=save, integrator=integ)
    stepper = engine.make_stepper(model, model.default_integrator() if integ is None else integ, False)
    excs = jax.vmap(jr.RickerPulse)(jnp.array([2.0, 3.0]), jnp.array([6.0, 8.0]))
    if stepper.schedule.passes:
        state = engine._init(stepper, excs, False)[0]
        kernels["advance"] = lambda m, e: engine._vmap(lambda s, es: s.advance(es[0], es[1], 3), False)(stepper, (excs, state))
    else:
        kernels["batch"] = lambda m, e: engine._solve(stepper, excs, False)
    for name, fn in kernels.items():
        jaxpr = eqx.filter_make_jaxpr(fn)(model, exc)[0]
        assert _callbacks(jaxpr.jaxpr) == [], f"{scene} {name}: host callbacks keep this kernel out of the persistent cache"


def test_cache_folder_moves_and_switches_off(monkeypatch, tmp_path):
    """`JAXROCK_CACHE_DIR` moves the cache (one subfolder per jaxrock and JAX version) and `off`
    switches it off; unset, it is the user's cache folder."""
    monkeypatch.setenv(cache.VARIABLE, str(tmp_path))
    path = cache.compilation_cache_dir()
    assert path.parent == tmp_path / "xla"
    assert jax.__version__ in path.name and path.name.startswith("jaxrock-")
    for off in ("off", "0", ""):
        monkeypatch.setenv(cache.VARIABLE, off)
        assert cache.compilation_cache_dir() is None
    monkeypatch.delenv(cache.VARIABLE)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert cache.cache_root() == tmp_path / "xdg" / "jaxrock"


_COUNTING_RUN = textwrap.dedent("""
    import json, sys
    import jax
    counts = {"requests": 0, "hits": 0}
    names = {"/jax/compilation_cache/compile_requests_use_cache": "requests", "/jax/compilation_cache/cache_hits": "hits"}
    jax.monitoring.register_event_listener(lambda event, **kw: names.get(event) and counts.__setitem__(names[event], counts[names[event]] + 1))
    import jax.numpy as jnp
    import jaxrock as jr
    from jaxrock.cli import app
    app(["simulate", "--height", "4", "--tan-alpha", "0.25", "--accel-ratio", "3", "--omega-ratio", "4"], standalone_mode=False)
    model = jr.RigidModel(jr.Block.from_slenderness(4.0, 0.25))
    jr.run_batch(model, jax.vmap(jr.RickerPulse)(jnp.linspace(1.0, 5.0, 6), jnp.full(6, 8.0)))
    print(json.dumps(counts))
""")


def test_second_process_loads_every_kernel(tmp_path):
    """A command and a batch run twice, each in a fresh process with an empty cache folder at first:
    the first compiles and writes its kernels, the second loads every kernel it needs (none is
    compiled again). It needs fewer: the stored kernels (`kernels.simulate`, `kernels.advance`) are
    not traced again, and the small kernels their traces ran eagerly are not asked for."""
    env = {**os.environ, cache.VARIABLE: str(tmp_path / "cache")}
    env.pop("JAX_COMPILATION_CACHE_DIR", None)
    runs = []
    for _ in range(2):
        out = subprocess.run([sys.executable, "-c", _COUNTING_RUN], env=env, capture_output=True, text=True, timeout=280)
        assert out.returncode == 0, out.stderr[-2000:]
        runs.append(json.loads(out.stdout.strip().splitlines()[-1]))
    first, second = runs
    assert first["requests"] > 10 and first["hits"] == 0
    assert second["hits"] == second["requests"] and 10 < second["requests"] <= first["requests"], (first, second)


def test_stored_pass_is_the_jitted_pass(monkeypatch, tmp_path):
    """The engine's pass through its exported kernel (`jaxrock.analyses.kernels`: traced once with a
    symbolic batch size, stored, read back) gives the jitted pass's numbers bit for bit at every
    batch size, and is stored once per structure."""
    from jaxrock.analyses import kernels

    monkeypatch.setenv(cache.VARIABLE, str(tmp_path))
    kernels._store.cache_clear()
    monkeypatch.setattr(kernels, "_KERNELS", {})
    model = scene_model("rigid", jr.Block.from_slenderness(6.0, 0.2))
    stepper = engine.make_stepper(model, model.default_integrator(), False)
    direct = eqx.filter_jit(lambda s, e, c: engine._vmap(lambda s, es: (lambda c: (c, s.done(c)))(s.advance(es[0], es[1], 4)), False)(s, (e, c)))
    for size in (3, 5):
        excs = jax.vmap(jr.RickerPulse)(jnp.linspace(2.0, 5.0, size), jnp.linspace(4.0, 9.0, size))
        state = engine._init(stepper, excs, False)[0]
        got, want = kernels.advance(stepper, excs, state, 4, False), direct(stepper, excs, state)
        for a, b in zip(jax.tree_util.tree_leaves(got), jax.tree_util.tree_leaves(want)):
            assert a.shape == b.shape and bool(jnp.all((a == b) | (jnp.isnan(a) & jnp.isnan(b)))), (size, a, b)
        monkeypatch.setattr(kernels, "_KERNELS", {})  # the next size reads the stored kernel back
    assert len(list((tmp_path / "kernels").rglob("advance-*.jax"))) == 1
    kernels._store.cache_clear()


@pytest.mark.parametrize("kind", ["rigid", "spring", "spring-flexible"])
def test_stored_simulate_is_simulate(kind, monkeypatch, tmp_path):
    """One scene through its stored kernel (`kernels.simulate`, what `jaxrock simulate` runs) gives
    `jaxrock.simulate`'s `Solution` bit for bit — a summary and a time history — whether the kernel
    was just traced or read back from the store (structure and static part from its template), and
    refuses what `simulate` refuses."""
    from jaxrock.analyses import kernels

    monkeypatch.setenv(cache.VARIABLE, str(tmp_path))
    kernels._store.cache_clear()
    model = scene_model(kind, jr.Block.from_slenderness(6.0, 0.2))
    exc = jr.RickerPulse(a_p=3.0, omega_p=7.0)
    requests = {"summary": {}, "history": {"save": jr.Save(jnp.linspace(-0.5, 4.0, 7), ("theta",))}}
    for name, kw in requests.items():
        want = jr.simulate(model, exc, **kw)
        for source in ("traced", "stored"):
            monkeypatch.setattr(kernels, "_KERNELS", {})
            got = kernels.simulate(model, exc, **kw)
            assert jax.tree_util.tree_structure(got) == jax.tree_util.tree_structure(want), (name, source)
            for a, b in zip(jax.tree_util.tree_leaves(got), jax.tree_util.tree_leaves(want)):  # arrays, and static ints
                a, b = jnp.asarray(a), jnp.asarray(b)
                assert a.shape == b.shape and bool(jnp.all((a == b) | (jnp.isnan(a) & jnp.isnan(b)))), (name, source, a, b)
            assert got.status == want.status and got.ok == want.ok
    # a quasi-rigid history by diffrax keeps a host callback (above), which JAX cannot export: it runs jitted, unstored
    assert len(list((tmp_path / "kernels").rglob("simulate-*.jax"))) == (1 if kind == "spring" else 2)
    with pytest.raises(jr.JaxrockInputError, match="t1"):
        kernels.simulate(model, exc, t1=3.0)
    kernels._store.cache_clear()


def test_a_kernel_kept_for_another_platform_is_exported_again(monkeypatch, tmp_path):
    """After a GPU run, a `JAX_PLATFORMS=cpu` run in the same cache folder once loaded the GPU's
    kernel ("exported for platforms ('cuda',) but it is used on ('cpu',)"). The kept kernels'
    folder is named by the platform too, and a kernel file that holds another platform's code
    (copied, or from before the key had the platform) is exported again and replaced, not called."""
    from jax import export

    from jaxrock.analyses import kernels

    monkeypatch.setenv(cache.VARIABLE, str(tmp_path))
    kernels._store.cache_clear()
    here = kernels._store()
    monkeypatch.setattr(export, "default_export_platform", lambda: "cuda")
    kernels._store.cache_clear()
    assert kernels._store() != here and kernels._store().parent == here.parent
    monkeypatch.undo()
    kernels._store.cache_clear()

    fn = jax.jit(lambda x: 2.0 * jnp.sin(x))
    spec = jax.ShapeDtypeStruct((3,), jnp.float64)
    path = tmp_path / "k.jax"
    path.write_bytes(bytes(kernels._EXPORT(fn, platforms=("cuda",))(spec).serialize()))
    exported, _ = kernels._load_or_export(path, lambda: (kernels._EXPORT(fn)(spec), None))
    assert exported.platforms == (export.default_export_platform(),)
    x = jnp.arange(3.0)
    assert bool(jnp.all(exported.call(x) == fn(x)))
    assert export.deserialize(bytearray(path.read_bytes())).platforms == exported.platforms  # replaced
    again, _ = kernels._load_or_export(path, lambda: pytest.fail("a kernel of this platform is read back, not exported"))
    assert again.platforms == exported.platforms
