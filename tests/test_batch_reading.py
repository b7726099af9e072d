"""Reading a scenes file column by column (vectorised) builds, row for row, the scene each row
describes on its own: the same model and excitation as `scene_model` and the pulse constructors,
defaults filled in the same way; and a bad cell anywhere is named by its row and column."""

from __future__ import annotations

import numpy as np
import pytest

import jaxrock as jr
from jaxrock import JaxrockInputError
from jaxrock.io.scenes_file import read_scenes, scene_model
from jaxrock.scene import PULSES

ROWS = """id,height,tan_alpha,width,tan_alpha_base,model,pulse,a_p,accel_ratio,omega_p,omega_ratio,scale,eta,cbar,E,rho,zeta
a,10,0.2,,,rigid,symmetric,,3,,2,,,,,,
b,4,,1.2,0.4,rigid,antisymmetric,5.5,,7,,,0.8,,,,
c,25,0.15,,,spring,symmetric,,2.5,,4,,,0.03,,,
d,50,0.1,,0.12,spring-flexible,antisymmetric,,1.5,3,,,,,2e10,2400,0.02
e,10,0.25,,,spring-flexible,symmetric,-4,,,6,,,,,,
f,8,0.3,,,rigid,rec.txt,,,,,2.5,,,,,
g,12,0.2,,,rigid,rec.txt,,,,,,0.9,,,,
"""


def _expected(values: dict, base):
    """The scene of one row, built alone with the public constructors."""
    num = lambda k: float(values[k]) if values.get(k, "") != "" else None  # noqa: E731
    h = num("height")
    tan_a = num("tan_alpha") if num("tan_alpha") is not None else num("width") / h
    block = jr.Block.from_slenderness(h, tan_a, num("tan_alpha_base"))
    model = scene_model(values["model"], block, eta=num("eta"), cbar=num("cbar"), E=num("E"), rho=num("rho"), zeta=num("zeta"))
    if values["pulse"] in PULSES:
        a = num("a_p") if num("a_p") is not None else num("accel_ratio") * float(block.uplift_acceleration)
        w = num("omega_p") if num("omega_p") is not None else num("omega_ratio") * float(block.p_r)
        return model, PULSES[values["pulse"]](a, w)
    return model, jr.read_record(base / values["pulse"]).scaled(num("scale") or 1.0)


def test_vectorised_reading_builds_each_row_as_built_alone(tmp_path):
    (tmp_path / "rec.txt").write_text("0 0.1\n0.01 0.3\n0.02 -0.2\n0.03 0.05\n")
    (tmp_path / "s.csv").write_text(ROWS)
    scenes = read_scenes(tmp_path / "s.csv")
    assert len(scenes) == 7 and sorted(len(i) for i in scenes.groups.values()) == [1, 1, 1, 1, 1, 2]
    for (kind, exc), idx in scenes.groups.items():
        models, excs = scenes.model(kind, idx), scenes.excitation(exc, idx)
        for lane, i in enumerate(idx):
            want_m, want_e = _expected(scenes.values[i], tmp_path)
            for got, want in ((models, want_m), (excs, want_e)):
                import jax

                got_leaves = jax.tree_util.tree_leaves(jax.tree_util.tree_map(lambda x: x[lane], got))
                want_leaves = jax.tree_util.tree_leaves(want)
                assert len(got_leaves) == len(want_leaves)
                for g, w in zip(got_leaves, want_leaves):
                    np.testing.assert_allclose(np.asarray(g), np.asarray(w), rtol=1e-14, atol=0, err_msg=scenes.values[i]["id"])


@pytest.mark.parametrize(
    "cell, value, needle",
    [
        ("tan_alpha", "abc", "row 5 (line 6), column 'tan_alpha': 'abc' is not a number"),
        ("tan_alpha", "0.0001", "row 5 (line 6), column 'tan_alpha': tan_alpha = 0.0001 is outside the valid range [0.001, 1)"),
        ("omega_ratio", "-2", "row 5 (line 6), column 'omega_ratio': omega_ratio = -2 is outside"),
        ("E", "1e3", "row 5 (line 6): E (Young's modulus) [Pa] = 1000 is outside the valid range [1e+06, 1e+15]"),
        ("a_p", "0", "row 5 (line 6), column 'a_p': a_p = 0; valid: any non-zero value"),
    ],
)
def test_a_bad_cell_in_a_long_file_is_named_by_row_and_column(tmp_path, cell, value, needle):
    header = "height,tan_alpha,model,a_p,omega_ratio,E"
    rows = [f"10,0.2,spring-flexible,3,2,3e10"] * 8
    cols = header.split(",")
    bad = rows[4].split(",")
    bad[cols.index(cell)] = value
    rows[4] = ",".join(bad)
    (tmp_path / "s.csv").write_text("\n".join([header, *rows]) + "\n")
    with pytest.raises(JaxrockInputError, match=needle.replace("(", r"\(").replace(")", r"\)").replace("[", r"\[").replace("+", r"\+")):
        read_scenes(tmp_path / "s.csv")
