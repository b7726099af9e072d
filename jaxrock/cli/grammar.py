"""The command line's grammar in one place (issue 58): one flag per quantity in every command
(singular, taking a value or, where the command sweeps it, a list "1,2,5" or a range "a:b:n"),
`--out` for every output, lower-case flags; and the spellings of the previous release, which keep
working for one release with a one-line deprecation warning (`upgrade` rewrites them before the
command line is parsed). `tests/test_cli_grammar.py` walks every command's options against it."""

from __future__ import annotations

import typer

# old flag → its flag now, per command (None: every command)
RENAMED: dict[str | None, dict[str, str]] = {
    None: {"--E": "--youngs-modulus"},
    "record-spectrum": {"--heights": "--height", "--scales": "--scale"},
    "calibrate": {"--tan-alphas": "--tan-alpha"},
    "sweep": {"--records": "--record", "--store": "--out"},
}
# a grid once given by three flags (smallest, largest, count), now one range option "a:b:n"
GRIDS: dict[str, dict[str, tuple[str, str, str, float, float, int]]] = {
    "spectrum": {"--omega-ratio": ("--omega-min", "--omega-max", "--n-omega", 1.0, 15.0, 48),
                 "--accel-ratio": ("--accel-min", "--accel-max", "--n-accel", 0.5, 10.0, 48)},
}
DEFAULT_GRID = {cmd: {new: f"{lo:g}:{hi:g}:{n}" for new, (_, _, _, lo, hi, n) in grids.items()} for cmd, grids in GRIDS.items()}
RELEASE = "the next release"


def _warn(old: str, new: str) -> None:
    typer.echo(f"Warning: {old} is deprecated; use {new} (the old spelling is removed in {RELEASE})", err=True)


def _split(token: str) -> tuple[str, str | None]:
    """'--flag=value' → ('--flag', 'value'); '--flag' → ('--flag', None)."""
    flag, eq, value = token.partition("=")
    return flag, (value if eq else None)


def upgrade(args: list[str]) -> list[str]:
    """`args` (the command line after `jaxrock`) with the previous release's spellings replaced by
    today's, one warning line on stderr per spelling replaced. The command is the first argument
    that is not an option."""
    from .._validate import JaxrockInputError

    command = next((a for a in args if not a.startswith("-")), None)
    renamed = {**RENAMED[None], **RENAMED.get(command, {})}
    grids = GRIDS.get(command, {})
    old_grid = {flag: (new, i) for new, spec in grids.items() for i, flag in enumerate(spec[:3])}
    out, parts, warned = [], {}, set()
    it = iter(args)
    for token in it:
        flag, value = _split(token)
        if flag in renamed:
            if flag not in warned:
                _warn(flag, renamed[flag])
                warned.add(flag)
            out.append(renamed[flag] if value is None else f"{renamed[flag]}={value}")
        elif flag in old_grid:
            new, i = old_grid[flag]
            value = next(it, None) if value is None else value
            if value is None:
                raise JaxrockInputError(f"{flag} needs a value")
            parts.setdefault(new, {})[i] = value
        else:
            out.append(token)
    for new, given in parts.items():
        lo_flag, hi_flag, n_flag, lo, hi, n = grids[new]
        if any(_split(a)[0] == new for a in out):
            raise JaxrockInputError(f"give {new} a:b:n or the deprecated {lo_flag}/{hi_flag}/{n_flag}, not both")
        text = f"{given.get(0, f'{lo:g}')}:{given.get(1, f'{hi:g}')}:{given.get(2, n)}"
        _warn(f"{lo_flag}/{hi_flag}/{n_flag}", f"{new} {text}")
        out += [new, text]
    return out


def flag_of(name: str) -> str:
    """The flag of the quantity `name` (a Python parameter or a scenes-file column): "tan_alpha" →
    "--tan-alpha"; a declared parameter's own (`jaxrock.scene.Param.flag`: "E" → "--youngs-modulus")."""
    from ..scene import model_params, pulse_params

    declared = {**model_params(), **pulse_params()}
    return declared[name].flag if name in declared else "--" + name.replace("_", "-")
