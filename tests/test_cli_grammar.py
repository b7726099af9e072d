"""One grammar for every command (issue 58, item 1): the test walks every command's options and
holds them to it — lower-case flags, one flag per quantity in every command (no plural beside a
singular), `--out` for every output location, `--model` parsed alike everywhere, `--json` and `-h`
on every command; the previous release's spellings still work, with one warning line; errors name
flags, summaries use the command line's words."""

from __future__ import annotations

import re

import pytest
import typer

from jaxrock.cli import app
from jaxrock.cli.grammar import GRIDS, RENAMED, upgrade
from helpers import invoke

COMMANDS = typer.main.get_command(app).commands
FLAG = re.compile(r"^--[a-z0-9]+(-[a-z0-9]+)*$")


def _options(cmd):
    return [p for p in cmd.params if p.param_type_name == "option"]


def _flags(cmd) -> set[str]:
    return {f for p in _options(cmd) for f in (*p.opts, *p.secondary_opts) if f.startswith("--")}


def test_every_flag_is_lower_case_and_every_command_has_json_and_h():
    for name, cmd in COMMANDS.items():
        for flag in _flags(cmd):
            assert FLAG.match(flag), (name, flag)
        assert "--json" in _flags(cmd), name
        assert invoke(name, "-h").exit_code == 0, name


def test_one_flag_per_quantity_across_commands():
    """A quantity has one spelling: no flag of one command is another's with a trailing 's'
    (--height beside --heights, --record beside --records), and a Python parameter has the same
    flag in every command that takes it."""
    every = set().union(*(_flags(c) for c in COMMANDS.values()))
    plural = sorted(f for f in every if f.endswith("s") and f[:-1] in every)
    assert plural == [], plural
    spelled: dict[str, set[str]] = {}
    for cmd in COMMANDS.values():
        for p in _options(cmd):
            spelled.setdefault(p.name, set()).add(p.opts[0])
    assert {k: v for k, v in spelled.items() if len(v) > 1} == {}


def test_every_output_location_is_out():
    """Each command that writes files names where with --out (simulate names its two optional
    files by what they hold: --plot, --save); none has --store, --results or --output."""
    for name, cmd in COMMANDS.items():
        flags = _flags(cmd)
        assert not flags & {"--store", "--results", "--output", "--out-dir"}, name
        if "--force" in flags and name != "simulate":
            assert "--out" in flags, name
        assert not [p for p in cmd.params if p.param_type_name == "argument" and not p.hidden and "result" in p.name], name


def test_model_is_one_list_type_everywhere():
    """--model is parsed by one function in every command: kinds separated by commas; a command
    that runs one kind refuses two, in one line naming the flag."""
    for name, cmd in COMMANDS.items():
        model = [p for p in _options(cmd) if p.name == "model"]
        if model:
            assert model[0].metavar in ("KIND", "KIND[,KIND...]"), name
    r = invoke("simulate", "--model", "rigid,spring")
    assert r.exit_code == 2 and "--model" in r.output and "one model kind" in r.output and len(r.output.splitlines()) == 1
    r = invoke("suite", "--model", "rigid,bogus")
    assert r.exit_code == 2 and "not a model kind: bogus" in r.output


@pytest.mark.parametrize("command, old", [(c, o) for c, table in RENAMED.items() for o in table])
def test_renamed_flags_are_gone_from_the_options_and_still_work_with_a_warning(command, old, capsys):
    new = RENAMED[command][old]
    for name, cmd in COMMANDS.items():
        if command in (None, name):
            assert old not in _flags(cmd), (name, old)
    target = command or "simulate"
    assert new in _flags(COMMANDS[target]), (target, new)
    assert upgrade([target, old, "1"]) == [target, new, "1"]
    assert upgrade([target, f"{old}=2"]) == [target, f"{new}=2"]
    assert f"Warning: {old} is deprecated; use {new}" in capsys.readouterr().err


def test_grid_flags_become_one_range_with_a_warning(capsys):
    """spectrum's --omega-min/--omega-max/--n-omega (and the a_p axis') become --omega-ratio a:b:n,
    the defaults filling what is not given; given with the new flag, refused."""
    assert upgrade(["spectrum", "--omega-min", "2", "--n-omega", "3", "-q"]) == ["spectrum", "-q", "--omega-ratio", "2:15:3"]
    assert upgrade(["spectrum", "--accel-max=8"]) == ["spectrum", "--accel-ratio", "0.5:8:48"]
    assert "--omega-min/--omega-max/--n-omega is deprecated; use --omega-ratio 2:15:3" in capsys.readouterr().err
    for new, (lo, hi, n, *_) in GRIDS["spectrum"].items():
        assert not {lo, hi, n} & _flags(COMMANDS["spectrum"])
    r = invoke("spectrum", "--omega-ratio", "1:2:2", "--n-omega", "3")
    assert r.exit_code == 2 and "not both" in r.output


def test_an_old_spelling_runs_the_same_work(tmp_path):
    """record-spectrum --heights/--scales (the previous release's) and --height/--scale give the
    same least factors; the old one says it is deprecated on stderr, one line per flag."""
    args = ["--refine", 1, "--no-sensitivity", "-q", "--json"]
    new = invoke("record-spectrum", "--height", "2,4", "--scale", "0.5,2", "--out", tmp_path / "a", *args)
    old = invoke("record-spectrum", "--heights", "2,4", "--scales", "0.5,2", "--out", tmp_path / "b", *args)
    assert new.exit_code == old.exit_code == 0, old.output
    import json

    assert json.loads(new.stdout)["least_scale"] == json.loads(old.stdout)["least_scale"]
    assert old.stderr.count("is deprecated") == 2 and "is deprecated" not in new.stderr


@pytest.mark.parametrize("args, flag", [
    (["simulate", "--tan-alpha", "2"], "--tan-alpha = 2"),
    (["simulate", "--height", "-1"], "--height (2h) [m] = -1"),
    (["simulate", "--model", "spring-flexible", "--youngs-modulus", "-1"], "--youngs-modulus"),
    (["simulate", "--omega-p", "-1"], "--omega-p"),
    (["spectrum", "--pulse", "sine", "--n-cycles", "0.3"], "--n-cycles"),
    (["record-spectrum", "--height", "0,1"], "--height"),
    (["sweep", "--tan-alpha", "0.2,3"], "--tan-alpha = 3"),
    (["simulate", "--model", "spring", "--tol", "0.5"], "--tol = 0.5"),
])
def test_errors_name_the_flag(args, flag):
    """Messages from the library name Python parameters (`tan_alpha = 2 is outside …`); the command
    line says its own flag."""
    r = invoke(*args)
    assert r.exit_code == 2 and r.output.startswith(f"Error: {flag}"), r.output


def test_summaries_use_the_command_lines_words_and_one_unit(tmp_path):
    """spectrum's summary names the model and pulse kinds as --model and --pulse do (was
    `RigidModel, RickerPulse`); suite's table prints PGA in m/s2, the unit of its fragility table."""
    r = invoke("spectrum", "--omega-ratio", "2,4", "--accel-ratio", "1,3", "--refine", 0, "--out", tmp_path / "s", "-q")
    assert r.exit_code == 0 and "spectrum: rigid model, symmetric pulse" in r.output and "RickerPulse" not in r.output
    r = invoke("suite", "--model", "rigid", "--height", 2, "--scale", "0.5,1", "--refine", 0, "--boot", 10, "--out", tmp_path / "su", "-q")
    assert r.exit_code == 0, r.output
    header, row = r.stdout.splitlines()[1:3]
    assert "PGA [m/s2]" in header and "median pga [m/s2]" in r.stdout
    assert abs(float(row.split()[-3]) - 3.069) < 1e-3  # El Centro 1940 NS: 0.313 g = 3.07 m/s² (was printed in g)
